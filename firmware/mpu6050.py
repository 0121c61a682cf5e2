"""MPU6050 accelerometer (InvenSense), I2C address 0x68 (0x69 with AD0 high): tilt for the compass.

    from machine import I2C, Pin
    from firmware.mpu6050 import MPU6050
    ax, ay, az = MPU6050(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000)).read_accel()

MPU6050(i2c, address=0x68, *, accel_range=2, dlpf=21)  accel_range in g: 2, 4, 8, 16;
    dlpf: the digital low-pass filter's bandwidth in Hz, 260 (off), 184, 94, 44, 21, 10, 5.
    The default 21 Hz cuts the noise from ~6.4 mg RMS (power-on, 260 Hz) to ~1.8 mg (400 ug/
    sqrt(Hz), datasheet) - at 60 deg dip 6 mg of tilt noise is ~0.6 deg of heading - with a lag
    of ~8 ms, nothing for a hand-held compass.
read_accel() -> (x, y, z) raw counts in the chip's axes (specific force: +1 g on an axis that
points up); read_accel_into(buf) fills buf[0..2] without allocating. .counts_per_g.
config_ok() reads PWR_MGMT_1 and ACCEL_CONFIG back (awake, this range?).
enable_bypass() connects the auxiliary I2C bus to the main one (GY-87/GY-86: the magnetometer
sits there). The constructor wakes the chip and sets the range; it leaves the bypass alone.
Errors: SensorNotFound (WHO_AM_I is not 0x68), BusError.
"""
from firmware.compat import const

from firmware.errors import SensorNotFound
from firmware import i2cdevice
from firmware.i2cdevice import Device, option_code

# Registers (register map rev 4.2)
_CONFIG = const(0x1A)         # DLPF_CFG[2:0]
_ACCEL_CONFIG = const(0x1C)
_INT_PIN_CFG = const(0x37)
_ACCEL_XOUT_H = const(0x3B)   # X, Y, Z int16 MSB first in 0x3B..0x40
_USER_CTRL = const(0x6A)
_PWR_MGMT_1 = const(0x6B)
_WHO_AM_I = const(0x75)

# Bit fields
_I2C_BYPASS_EN = const(1 << 1)  # INT_PIN_CFG bit1
_I2C_MST_EN = const(1 << 5)  # USER_CTRL bit5
_WAKE_PLL_X = const(0x01)     # PWR_MGMT_1: SLEEP=0, clock from the X gyro PLL
_ID_VALUE = const(0x68)       # WHO_AM_I reads 0x68 whatever AD0 is

_RANGES_G = (2, 4, 8, 16)     # ACCEL_CONFIG AFS_SEL[4:3] code = index; 16384 >> code counts/g
_DLPF_HZ = (260, 184, 94, 44, 21, 10, 5)  # CONFIG DLPF_CFG code = index (accelerometer bandwidth)


class MPU6050(Device):
    OPTIONS = ("accel_range", "dlpf")

    def __init__(self, i2c, address=0x68, *, accel_range=2, dlpf=21):
        if accel_range not in _RANGES_G:
            raise ValueError("MPU6050 accel_range=%s: expected one of 2, 4, 8, 16" % accel_range)
        afs = _RANGES_G.index(accel_range)
        cfg = option_code("MPU6050", "dlpf", dlpf, _DLPF_HZ)
        super().__init__(i2c, address, 1000)  # no data-ready wait: outputs update continuously
        who = self._probe(_WHO_AM_I, 1, "MPU6050")[0]
        if who != _ID_VALUE:
            raise SensorNotFound("no MPU6050 at 0x%02X: WHO_AM_I (0x75) reads 0x%02X, expected "
                                 "0x68" % (address, who), address=address)
        self._afs = afs
        self._dlpf_cfg = cfg
        self.dlpf = dlpf
        self.accel_range = accel_range
        self.counts_per_g = 16384 >> afs
        self.configure()

    def configure(self):
        """Wake the chip and write this driver's range and filter (also after a chip reset)."""
        with self.guard:
            self._write_u8(_PWR_MGMT_1, _WAKE_PLL_X)
            self._write_u8(_ACCEL_CONFIG, self._afs << 3)
            self._write_u8(_CONFIG, self._dlpf_cfg)

    def config_ok(self):
        """True when the chip is awake with this driver's range (PWR_MGMT_1, ACCEL_CONFIG read
        back): False after a reset (power-on value 0x40, asleep) or a glitch write."""
        with self.guard:
            if self._read_u8(_PWR_MGMT_1) != _WAKE_PLL_X:
                return False
            return self._read_u8(_ACCEL_CONFIG) == self._afs << 3

    def enable_bypass(self):
        """Clear I2C_MST_EN, set I2C_BYPASS_EN: the aux-bus chips appear on the main bus."""
        with self.guard:
            self._write_u8(_USER_CTRL, self._read_u8(_USER_CTRL) & ~_I2C_MST_EN)
            self._write_u8(_INT_PIN_CFG, self._read_u8(_INT_PIN_CFG) | _I2C_BYPASS_EN)

    def read_accel_into(self, buf):
        """Read the accelerometer (counts) into buf[0..2]. Allocates nothing."""
        with self.guard:
            self.sample_into(buf)

    def sample_into(self, buf):
        """read_accel_into() for callers already inside a guard (the app's read guard)."""
        self.register = _ACCEL_XOUT_H
        self._i2c.readfrom_mem_into(self.address, _ACCEL_XOUT_H, self._buf)
        i2cdevice.decode(self._buf, buf, 1)

    def read_accel(self):
        """(x, y, z) raw counts, the chip's axes."""
        v = [0, 0, 0]
        self.read_accel_into(v)
        return (v[0], v[1], v[2])
