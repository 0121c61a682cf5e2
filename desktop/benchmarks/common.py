"""Shared pieces of the benchmark scripts: timers, allocation counters, an allocation-free
replay bus, and simulated sensor sessions. Runs on CPython and MicroPython.

Timers: clock() / since_us(t0) - time.ticks_us on MicroPython (1 us steps), perf_counter on
CPython (float us). Allocation: mem_alloc() (bytes in use, gc.mem_alloc) and mem_total()
(bytes ever allocated, micropython.mem_total: it also sees a call frame that MicroPython
takes from the heap and frees at return); both None on CPython.
"""
import gc
import json
import sys

try:
    from time import ticks_diff, ticks_us

    def clock():
        return ticks_us()

    def since_us(t0):
        return ticks_diff(ticks_us(), t0)
except ImportError:  # CPython
    from time import perf_counter

    def clock():
        return perf_counter()

    def since_us(t0):
        return (perf_counter() - t0) * 1000000

try:
    import micropython
    IS_MP = True
except ImportError:
    micropython = None
    IS_MP = False

QMC_ADDR = 0x0D
QMC_DATA = 0x00
QMC_STATUS = 0x06
MPU_ADDR = 0x68
MPU_ACCEL = 0x3B
QMC_CPG = 12000        # counts/G at +-2 G (QMC5883L datasheet)


def mem_alloc():
    return gc.mem_alloc() if IS_MP else None


def mem_total():
    return micropython.mem_total() if IS_MP else None


def smoke(argv=None):
    return "--smoke" in (sys.argv if argv is None else argv)


def median(xs):
    s = sorted(xs)
    n = len(s)
    if n == 0:
        return None
    if n & 1:
        return s[n // 2]
    return (s[n // 2 - 1] + s[n // 2]) / 2


class Clock:
    """A ticks_us the benchmark advances by hand (clock.now += period), for CompassApp."""
    def __init__(self):
        self.now = 0

    def ticks(self):
        return self.now


def emit(obj):
    print(json.dumps(obj))


def interpreter():
    if IS_MP:
        v = sys.implementation.version
        return "MicroPython %d.%d.%d" % (v[0], v[1], v[2])
    return "CPython %d.%d.%d" % sys.version_info[:3]


def timed_runs(fn, n, runs):
    """Median and minimum microseconds per call of fn(n) over `runs` runs; gc.collect()
    before each run and the collector off during it (the benchmark's conditions)."""
    per = []
    for _ in range(runs):
        gc.collect()
        gc.disable()
        try:
            t0 = clock()
            fn(n)
            dt = since_us(t0)
        finally:
            gc.enable()
        per.append(dt / n)
    return median(per), min(per)


def alloc_per_call(fn, n):
    """(gc.mem_alloc delta, micropython.mem_total delta) per call of fn(n) with the collector
    off; (None, None) on CPython. fn must have run once before (warm dictionaries)."""
    if not IS_MP:
        return None, None
    gc.collect()
    gc.disable()
    try:
        a0 = gc.mem_alloc()
        t0 = micropython.mem_total()
        fn(n)
        t1 = micropython.mem_total()
        a1 = gc.mem_alloc()
    finally:
        gc.enable()
    return (a1 - a0) / n, (t1 - t0) / n


# ---- a bus that replays recorded register bytes and allocates nothing ------------------

def _copy(src, pos, buf):
    for i in range(len(buf)):
        buf[i] = src[pos + i]


class ReplayBus:
    """machine.I2C stand-in over preallocated register images (reads and writes) and, for
    the data registers, recorded streams of sample bytes served in turn (wrapping).

    Allocation-free on MicroPython (checked by the hot benchmark: its own cost and bytes
    are measured and reported as 'bus')."""

    def __init__(self):
        self.images = {}
        self.streams = {}   # addr * 256 + reg -> [bytes, next position]
        self._all = []      # the same lists: rewind() without a dict iterator (it allocates)

    def attach(self, addr, image):
        self.images[addr] = image

    def stream(self, addr, reg, data):
        s = [data, 0]
        self.streams[addr * 256 + reg] = s
        self._all.append(s)

    def rewind(self):
        a = self._all
        for i in range(len(a)):
            a[i][1] = 0

    def scan(self):
        return sorted(self.images)

    def readfrom_mem_into(self, addr, reg, buf):
        s = self.streams.get(addr * 256 + reg)
        if s is None:
            _copy(self.images[addr], reg, buf)
        else:
            _copy(s[0], s[1], buf)
            s[1] = _advance(s[1], len(buf), len(s[0]))

    def writeto_mem(self, addr, reg, buf):
        img = self.images[addr]
        for i in range(len(buf)):
            img[reg + i] = buf[i]
        if addr == QMC_ADDR and reg == 0x0A and buf[0] & 0x80:
            # QMC5883L SOFT_RST (control register 2, bit 7): its registers back to their
            # defaults (0: standby), as the chip's datasheet says
            img[0x09] = img[0x0A] = img[0x0B] = 0

    def readfrom_mem(self, addr, reg, n):
        b = bytearray(n)
        self.readfrom_mem_into(addr, reg, b)
        return bytes(b)


def _advance(pos, n, size):
    pos += n
    return 0 if pos + n > size else pos


def qmc_image():
    img = bytearray(256)
    img[0x0D] = 0xFF        # chip ID
    img[QMC_STATUS] = 0x01  # DRDY, never OVL/DOR
    return img


def mpu_image():
    img = bytearray(256)
    img[0x75] = 0x68        # WHO_AM_I
    return img


def interleaved_medians(fns, n, runs):
    """{name: median microseconds per call of fn(n)} for (name, fn) pairs: each run once to
    warm up, then `runs` rounds that time every one in turn (a slow patch of the machine
    falls on all of them alike)."""
    for _, fn in fns:
        fn(n)
    per = {name: [] for name, _ in fns}
    for _ in range(runs):
        for name, fn in fns:
            per[name].append(timed_runs(fn, n, 1)[0])
    return {name: median(per[name]) for name, _ in fns}


def app_runner(app, clock, bus, period_us, select):
    """fn(n): n steps of a CompassApp over its replay `bus` (rewound first), the clock moved a
    period each; select() first (it picks the kernel sets this app uses: they are
    module-wide)."""
    def run(n):
        select()
        bus.rewind()
        for _ in range(n):
            clock.now += period_us
            app.step()
    return run


def replay_board(mag_bytes, acc_bytes):
    """A ReplayBus with a QMC5883L (0x0D) and an MPU6050 (0x68) serving the sessions."""
    bus = ReplayBus()
    bus.attach(QMC_ADDR, qmc_image())
    bus.attach(MPU_ADDR, mpu_image())
    bus.stream(QMC_ADDR, QMC_DATA, mag_bytes)
    bus.stream(MPU_ADDR, MPU_ACCEL, acc_bytes)
    return bus


# ---- simulated sessions (host_sim) -----------------------------------------------------

HARD_IRON_UT = (120.0, -80.0, 40.0)   # 2.4x a 50 uT field (as tests/scenarios/calibrator_parity)
SOFT_IRON = ((1.1, 0.05, -0.03), (0.05, 0.92, 0.04), (-0.03, 0.04, 1.0))


def session(n, motion=None, seed=3, hard_iron_ut=HARD_IRON_UT, soft_iron=SOFT_IRON,
            noise=True, dt_us=5000, accel=True, mpu_bytes=6):
    """n samples of a simulated GY-271 + GY-521 (QMC5883L 200 Hz +-2 G, MPU6050 +-2 g) as
    the raw register bytes a driver reads: (mag bytes 6n LSB first, accel bytes 6n MSB
    first or None); mpu_bytes=14: the MPU6050's whole burst (accelerometer, temperature,
    gyroscope at +-500 deg/s), 14n bytes, as the driver reads it after use_gyro()."""
    from host_sim import motion as mo
    from host_sim.boards import make_board
    from host_sim.world import World
    if motion is None:
        motion = mo.figure8(period_s=30.0)
    w = World(field_ut=50.0, inclination_deg=60.0, hard_iron_ut=hard_iron_ut,
              soft_iron=soft_iron, motion=motion)
    b = make_board("qmc5883l", world=w, seed=seed, noise=noise, accel=accel)
    b.bus.writeto_mem(QMC_ADDR, 0x0B, b"\x01")
    b.bus.writeto_mem(QMC_ADDR, 0x09, b"\x0d")   # continuous, 200 Hz, +-2 G, OSR 512
    if accel:
        b.bus.writeto_mem(MPU_ADDR, 0x6B, b"\x01")   # wake, PLL X gyro
        b.bus.writeto_mem(MPU_ADDR, 0x1C, b"\x00")   # +-2 g
        b.bus.writeto_mem(MPU_ADDR, 0x1B, b"\x08")   # +-500 deg/s (the driver's default)
    mag = bytearray(6 * n)
    acc = bytearray(mpu_bytes * n) if accel else None
    d = bytearray(6)
    e = bytearray(mpu_bytes)
    for i in range(n):
        b.clock.advance(dt_us)
        b.bus.readfrom_mem_into(QMC_ADDR, QMC_DATA, d)
        mag[6 * i:6 * i + 6] = d
        if accel:
            b.bus.readfrom_mem_into(MPU_ADDR, MPU_ACCEL, e)
            acc[mpu_bytes * i:mpu_bytes * (i + 1)] = e
    return mag, acc


def le16(b, i):
    v = b[i + 1] << 8 | b[i]
    return v - 0x10000 if v & 0x8000 else v


def be16(b, i):
    v = b[i] << 8 | b[i + 1]
    return v - 0x10000 if v & 0x8000 else v


def raw_triples(mag_bytes):
    """The int16 counts of a mag session, as a list of (x, y, z)."""
    return [(le16(mag_bytes, j), le16(mag_bytes, j + 2), le16(mag_bytes, j + 4))
            for j in range(0, len(mag_bytes), 6)]
