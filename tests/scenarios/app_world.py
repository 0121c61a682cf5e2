# Shared by tests/test_app.py, tests/test_reliability.py and the app_* scenarios (CPython and
# MicroPython): the simulated boards, a world with strong iron, an in-memory filesystem with
# power cuts, and small helpers to drive CompassApp through simulated time.
from host_sim import motion
from host_sim.boards import make_board
from host_sim.world import World

from firmware.app import CompassApp
from firmware.store import CalStore

# Strong iron: |V| = 64 uT, 1.3 Earth fields; W symmetric, eigenvalues ~0.83..1.22.
HARD_IRON_UT = (45.0, -35.0, 30.0)
SOFT_IRON = ((1.18, 0.09, -0.06), (0.09, 0.88, 0.07), (-0.06, 0.07, 1.04))
FIELD_UT = 50.0
INCLINATION_DEG = 60.0
DECLINATION_DEG = 4.0
DECLINATION_CDEG = 400
# host_sim.boards mounts a module's chip x forward, y left, z up (boards/breakouts.py: gy271,
# gy87); BOARD_AXES below: the others
MAG_AXES = "x,-y,-z"
ACCEL_AXES = "-x,y,z"
# (board, accel) per setup: a GY-271 (QMC5883L) with a GY-521 (MPU6050) module, and a GY-87
SETUPS = {"gy271": ("gy271", True), "gy87": ("gy87", None)}
# every other magnetometer on its board (host_sim/chips.py DEMOS): a module with a GY-521
# beside it, or the IMU that carries it
CHIP_SETUPS = {"hmc5883l": ("hmc5883l", True), "qmc5883p": ("qmc5883p", True),
               "lis3mdl": ("lis3mdl", True), "lis2mdl": ("lis2mdl", True),
               "mmc5603": ("mmc5603", True), "gy9250": ("gy9250", None),
               "icm20948": ("icm20948", None)}
# an injected raw sample each magnetometer reports as an overflow: beyond int16 (QMC5883L OVL,
# QMC5883P OVFL, the AKM chips' HOFL past +-32752, the LIS3MDL's rails), beyond the HMC5883L's
# 12 bits (-4096) or the LIS2MDL's +-16.38 G; the MMC5603's field H (16384 counts/G) past
# its 4 G range
OVERFLOW_RAW = {"qmc5883l": 40000, "hmc5883l": 3000, "qmc5883p": 40000, "ak8963": 40000,
                "ak09916": 40000, "lis3mdl": 40000, "lis2mdl": 20000, "mmc5603": 5 * 16384}
ALL_SETUPS = dict(SETUPS)
ALL_SETUPS.update(CHIP_SETUPS)
# boards only the parity across interpreters runs (tests/test_boards_tiers.py): a GY-271
# beside an MPU-6500 module (driven as an MPU-9250, firmware/mpu9250.py)
PARITY_SETUPS = {"gy271+mpu6500": ("gy271", "mpu6500")}
# the boards whose magnetometer lies otherwise than x forward, y left, z up: their maps
# (boards/breakouts.py; tests/test_app.py checks these are its maps)
BOARD_AXES = {"gy9250": ("y,-x,z", ACCEL_AXES), "icm20948": ("x,y,z", ACCEL_AXES),
              "lis2mdl": ("x,-y,z", ACCEL_AXES)}
TILTED_POSES = ((30.0, 20.0, -15.0), (135.0, -25.0, 10.0), (250.0, 10.0, 30.0),
                (300.0, -15.0, -25.0), (80.0, 0.0, 0.0))


def inject(b, ev, kind):
    """The parity sessions' fault `ev` on board b whose magnetometer driver is `kind`: a NACK
    burst, an overflowing sample, or the magnetometer reset (the GY-271's QMC5883L by its
    SOFT_RST, back in standby; any other by a brown-out: its power-on registers)."""
    if ev == "nack":
        b.bus.inject_nack(after=0, count=3)
    elif ev == "overflow":
        b.mag.inject_raw(OVERFLOW_RAW[kind], 0, 0)
    elif b.chip == "gy271":
        b.bus.writeto_mem(0x0D, 0x0A, b"\x80")
    else:
        b.mag.power_on()


def stored_calibration(fs):
    """A plausible 10-element record for this world, made by hand, saved in MemFs `fs` (so
    nothing of the calibration machinery runs to make it)."""
    from firmware.calibration import Calibration
    CalStore("/", sensor="qmc5883l", range_code=0, fs=fs).save(Calibration(
        model=10, offset=(5400, -4200, 3600), invw=(27000, -2000, 1300, -2000, 29000, -1500,
                                                    1300, -1500, 28000),
        field=6000, field_out=5900, fit_error=120, samples=220, coverage=80).to_bytes())
    return CalStore("/", fs=fs)


def make_world(m=None, hard_iron_ut=HARD_IRON_UT, soft_iron=SOFT_IRON):
    return World(field_ut=FIELD_UT, inclination_deg=INCLINATION_DEG,
                 declination_deg=DECLINATION_DEG, hard_iron_ut=hard_iron_ut,
                 soft_iron=soft_iron, motion=m if m is not None else motion.figure8())


def make_sim(setup="gy271", m=None, seed=3, world=None):
    chip, accel = ALL_SETUPS[setup] if setup in ALL_SETUPS else PARITY_SETUPS[setup]
    return make_board(chip, world=world if world is not None else make_world(m), seed=seed,
                      accel=accel)


def axes(b):
    """(MAG_AXES, ACCEL_AXES) of board `b`."""
    return BOARD_AXES.get(b.chip, (MAG_AXES, ACCEL_AXES))


def make_app(b, store=None, **kw):
    mag_axes, accel_axes = axes(b)
    return CompassApp(b.bus, mag_axes=mag_axes, accel_axes=accel_axes,
                      declination_cdeg=DECLINATION_CDEG, store=store, delay_us=b.sleep_us,
                      ticks_us=b.clock.ticks_us, **kw)


def run_until(app, b, t_s, each=None):
    """step() until the simulated clock reaches t_s seconds; each(app) after every step."""
    end = int(t_s * 1000000)
    n = 0
    while b.clock.now_us < end:
        app.step()
        n += 1
        if each is not None:
            each(app)
    return n


def hold(b, yaw, pitch, roll):
    b.world.motion = motion.still(yaw, pitch, roll)


def pose_headings(app, b, steps=12):
    """(pose, the app's headings over `steps` steps held still at it), each of TILTED_POSES in
    turn (the app's state is that pose's while the caller holds the pair)."""
    for pose in TILTED_POSES:
        hold(b, pose[0], pose[1], pose[2])
        hs = []
        for _ in range(steps):
            app.step()
            hs.append(app.heading_kang)
        yield pose, hs


def heading_error_cdeg(app, b):
    """The app's heading minus the world's true heading, centidegrees in -18000..17999."""
    true_cdeg = int(b.world.true_heading_deg(b.clock.now_us) * 100 + 0.5)
    h = app.heading_kang * 36000 // 65536
    return (h - true_cdeg + 18000) % 36000 - 18000


class PowerCut(OSError):
    pass


class MemFs:
    """A filesystem for CalStore in memory. budget: bytes that may still be written before
    the power fails (None: never); a cut write keeps the bytes written so far (as FAT does)
    and raises PowerCut (an OSError, EIO).

    Faults per path, in .bad (path -> kind): "eio" (open raises OSError 5), "dir" (a
    directory where the file should be: open for reading works and read() raises OSError
    21, as MicroPython's unix port does; open for writing raises 21), "write_eio" (reads
    work, every write raises OSError 5 and leaves the file empty). .nomem: writes that may
    still go through before one raises MemoryError (None: never)."""

    def __init__(self):
        self.files = {}
        self.budget = None
        self.cuts = 0
        self.bad = {}
        self.nomem = None

    def open(self, path, mode):
        kind = self.bad.get(path)
        if kind == "eio" or kind == "dir" and "w" in mode:
            raise OSError(5 if kind == "eio" else 21, kind)
        if kind == "dir":
            return _Reader(None)
        if "w" in mode:
            if self.nomem is not None:
                if self.nomem == 0:
                    raise MemoryError("no memory for a file buffer")
                self.nomem -= 1
            if kind == "write_eio":
                self.files[path] = b""
                return _Reader(None)
            self.files[path] = b""
            return _Writer(self, path)
        if path not in self.files:
            raise OSError(2, "ENOENT")
        return _Reader(self.files[path])

    def remove(self, path):
        if path not in self.files:
            raise OSError(2, "ENOENT")
        del self.files[path]


class _Reader:
    def __init__(self, data):
        self.data = data

    def read(self, n=-1):
        if self.data is None:
            raise OSError(21, "EISDIR")
        d, self.data = (self.data, b"") if n < 0 else (self.data[:n], self.data[n:])
        return d  # sequential, as a file's

    def write(self, data):
        raise OSError(5, "EIO")

    def close(self):
        pass


class _Writer:
    def __init__(self, fs, path):
        self.fs = fs
        self.path = path

    def write(self, data):
        fs = self.fs
        data = bytes(data)
        if fs.budget is not None and len(data) > fs.budget:
            fs.files[self.path] += data[:fs.budget]
            fs.budget = 0
            fs.cuts += 1
            raise PowerCut(5, "power cut")
        fs.files[self.path] += data
        if fs.budget is not None:
            fs.budget -= len(data)
        return len(data)

    def close(self):
        pass


def mem_store(fs=None):
    return CalStore("/", sensor="qmc5883l", range_code=0, fs=fs if fs is not None else MemFs())
