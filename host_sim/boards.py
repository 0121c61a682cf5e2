"""Simulated boards: a clock, a bus, the chips at their addresses and the world they sense.

    from host_sim.boards import make_board
    b = make_board('gy87', seed=3)
    b.bus.scan()            # -> [104, 119]: MPU6050 and BMP180; the HMC5883L is behind the bypass
    b.bus.writeto_mem(0x68, 0x37, b'\\x02')   # I2C_BYPASS_EN
    b.bus.scan()            # -> [30, 104, 119]

Boards and their chips' mountings (body frame AN4248: x forward, y right, z down; a mounting
is the body -> sensor signed permutation of host_sim.world):
  'qmc5883l', 'gy271'   QMC5883L at 0x0D, chip x forward, y left, z up  -> (1, -2, -3)
  'hmc5883l'            HMC5883L at 0x1E (GY-273 / older GY-271), same axes -> (1, -2, -3)
  'qmc5883p'            QMC5883P at 0x2C (newer GY-271), same axes        -> (1, -2, -3)
  'lis3mdl'             LIS3MDL at 0x1C, same axes                        -> (1, -2, -3)
  'lis2mdl'             LIS2MDL at 0x1E, x forward, y left, its z down: a left-handed set
                        (docs/hardware.md)                                -> (1, -2, 3)
  'mmc5603'             MMC5603NJ at 0x30, same axes as the QMC5883L      -> (1, -2, -3)
  'gy87'                MPU6050 at 0x68 + HMC5883L at 0x1E on the MPU's auxiliary bus (hidden
                        until the bypass is opened) + BMP180 at 0x77; MPU6050 and HMC5883L both
                        x forward, y left, z up -> (1, -2, -3)
  'gy87-qmc'            the GY-87 clone with a QMC5883L at 0x0D behind the bypass instead
  'gy9250'              MPU-9250 at 0x68 (x forward, y left, z up) with its AK8963 at 0x0C
                        behind the bypass, its axes as the MPU-9250's datasheet draws them:
                        x = the accelerometer's y, y = its x, z = -its z -> (-2, 1, 3)
  'icm20948'            ICM-20948 at 0x68 with its AK09916 at 0x0C behind the bypass:
                        x = the accelerometer's x, y = -its y, z = -its z -> (1, 2, 3)
(host_sim/chips.py BOARDS holds this list.)
`accel=True` adds a separate MPU6050 module (GY-521, 0x68, x forward, y left, z up) to a board
without one; `accel="mpu6500"` (an IMUS kind of host_sim/chips.py) adds that chip's module,
lying the same way. For these mountings the firmware's sensor -> body maps are: magnetometer
(x, -y, -z) (the LIS2MDL: (x, -y, z)); accelerometer, AN4248 gravity sign, (-x, y, z).
"""
from host_sim import chips
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.prng import mix32
from host_sim.world import World, check_mount

CHIPS = chips.BOARD_NAMES  # host_sim/chips.py BOARDS
MOUNT_X_FWD_Y_LEFT_Z_UP = (1, -2, -3)
_BMP180_ADDR = 0x77
_BMP180_ID_REG = 0xD0
_BMP180_ID = 0x55


class Board:
    """What make_board returns: .clock, .bus, .world, .mag, .accel (or None), .chip,
    .mag_address, .accel_address (or None), .mount, .accel_mount, .sleep_us (bus delay)."""

    def __init__(self, chip, clock, bus, world):
        self.chip = chip
        self.clock = clock
        self.bus = bus
        self.world = world
        self.mag = None
        self.mag_address = None
        self.accel = None
        self.accel_address = None
        self.mount = None
        self.accel_mount = None
        self.sleep_us = bus.sleep_us

    def now_us(self):
        return self.clock.now_us


def _mag(kind, world, mount, seed, noise):
    m = chips.mag(kind)
    return chips.model_class(m)(world, mount=mount, seed=seed, noise=noise), m["address"]


def make_board(chip="qmc5883l", world=None, seed=1, noise=True, freq=400000, mount=None,
               accel_mount=None, accel=None, clock=None, gyro=None):
    """Build a simulated board (see the module docstring). `world` defaults to a still
    World(seed=seed); `mount`/`accel_mount` override the chips' mountings; `noise=False`
    leaves only quantisation; `accel` None = the board's own (gy87: yes, others: no);
    `gyro` the MPU6050's gyroscope errors, a dict of MPU6050Sim's gyro_bias_dps,
    gyro_temp_dps_per_c, gyro_drift_dps_per_s (e.g. {"gyro_bias_dps": (3, 0, -1)})."""
    if chip not in CHIPS:
        raise ValueError("make_board: unknown chip %r; expected one of %s"
                         % (chip, ", ".join(CHIPS)))
    if clock is None:
        clock = SimClock()
    if world is None:
        world = World(seed=seed)
    bus = SimI2C(clock, freq)
    b = Board(chip, clock, bus, world)
    mag_seed = mix32(seed * 2 + 1)
    acc_seed = mix32(seed * 2 + 2)
    kind, imu, behind, _, own = chips.board(chip)
    b.mount = check_mount(mount if mount is not None else own)
    b.accel_mount = check_mount(accel_mount if accel_mount is not None else MOUNT_X_FWD_Y_LEFT_Z_UP)
    b.mag, b.mag_address = _mag(kind, world, b.mount, mag_seed, noise)
    if imu is None and accel:
        # a GY-521 module beside the magnetometer, or the module of the IMU `accel` names
        imu = accel if isinstance(accel, str) else "mpu6050"
    if imu is not None and (accel is None or accel):
        m = chips.imu(imu)
        kw = dict(m.get("options", {}))
        kw.update(gyro or {})
        b.accel = chips.model_class(m)(world, mount=b.accel_mount, seed=acc_seed, noise=noise,
                                       **kw)
        b.accel_address = m["addresses"][0]
        bus.attach(b.accel_address, b.accel)
    if behind:
        bus.attach(b.mag_address, b.mag, gate=b.accel.bypass_open)
        if imu == "mpu6050":  # the GY-87's barometer
            bus.attach(_BMP180_ADDR, RegisterFile({_BMP180_ID_REG: _BMP180_ID}))
    else:
        bus.attach(b.mag_address, b.mag)
    return b
