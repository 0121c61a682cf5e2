"""MPU6050 accelerometer and gyroscope (InvenSense), I2C address 0x68 (0x69 with AD0 high): tilt
for the compass, rotation rate for the gyro-aided heading (firmware/gyro/attitude.py).
"""
#     from machine import I2C, Pin
#     from firmware.mpu6050 import MPU6050
#     imu = MPU6050(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000))
#     ax, ay, az = imu.read_accel()
#     gx, gy, gz = imu.read_gyro()          # counts; imu.counts_per_dps_x10 / 10 per deg/s
#
# MPU6050(i2c, address=0x68, *, accel_range=2, dlpf=21, gyro_range=500): the options, the
# methods and why the 21 Hz filter: docs/api.md (drivers, each driver's options).
from firmware.compat import const, room

from firmware.errors import SensorNotFound
from firmware import i2cdevice
from firmware.i2cdevice import Device, option_code

# Registers (register map rev 4.2)
_CONFIG = const(0x1A)         # DLPF_CFG[2:0]
_GYRO_CONFIG = const(0x1B)    # FS_SEL[4:3]
_ACCEL_CONFIG = const(0x1C)
_INT_PIN_CFG = const(0x37)
_INT_STATUS = const(0x3A)     # bit0 DATA_RDY_INT, cleared by reading
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
_GYRO_DPS = (250, 500, 1000, 2000)  # GYRO_CONFIG FS_SEL[4:3] code = index
_GYRO_CPD_X10 = (1310, 655, 328, 164)  # counts per deg/s x 10 at each FS_SEL (table 6.1)


class MPU6050(Device):
    OPTIONS = ("accel_range", "dlpf", "gyro_range")
    NAME = "MPU6050"  # the chip, as the boot line names it (firmware/runner.py)

    def __init__(self, i2c, address=0x68, *, accel_range=2, dlpf=21, gyro_range=500):
        if accel_range not in _RANGES_G:
            raise ValueError("MPU6050 accel_range=%s: expected one of 2, 4, 8, 16" % accel_range)
        afs = _RANGES_G.index(accel_range)
        cfg = option_code("MPU6050", "dlpf", dlpf, _DLPF_HZ)
        fs = option_code("MPU6050", "gyro_range", gyro_range, _GYRO_DPS)
        super().__init__(i2c, address, 1000)  # no data-ready wait: outputs update continuously
        who = self._probe(_WHO_AM_I, 1, "MPU6050")[0]
        if who != _ID_VALUE:
            raise SensorNotFound("no MPU6050 at 0x%02X: WHO_AM_I (0x75) reads 0x%02X, expected "
                                 "0x68" % (address, who), address=address)
        self._afs = afs
        self._fs = fs
        self._dlpf_cfg = cfg
        self.dlpf = dlpf
        self.accel_range = accel_range
        self.gyro_range = gyro_range
        self.counts_per_g = 16384 >> afs
        self.counts_per_dps_x10 = _GYRO_CPD_X10[fs]
        self.temp_raw = 0
        self.gyro_into = None
        self._all = bytearray(14)  # read_all_into's burst: accel, temperature, gyro
        self._gyro6 = memoryview(self._all)[8:14]
        self.configure()

    def configure(self):
        """Wake the chip and write this driver's range and filter (also after a chip reset)."""
        with self.guard:
            self._write_u8(_PWR_MGMT_1, _WAKE_PLL_X)
            self._write_u8(_ACCEL_CONFIG, self._afs << 3)
            self._write_u8(_GYRO_CONFIG, self._fs << 3)
            self._write_u8(_CONFIG, self._dlpf_cfg)

    def config_ok(self):
        """True when the chip is awake with this driver's ranges (PWR_MGMT_1, ACCEL_CONFIG,
        GYRO_CONFIG read back): False after a reset (power-on value 0x40, asleep) or a glitch
        write."""
        with self.guard:
            if self._read_u8(_PWR_MGMT_1) != _WAKE_PLL_X:
                return False
            if self._read_u8(_ACCEL_CONFIG) != self._afs << 3:
                return False
            return self._read_u8(_GYRO_CONFIG) == self._fs << 3

    def data_ready(self):
        """INT_STATUS.DATA_RDY_INT: a new sample since the last call (reading clears it)."""
        with self.guard:
            return self._read_u8(_INT_STATUS) & 1 == 1

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
        """read_accel_into() for callers already inside a guard (the app's read guard); with
        .gyro_into set (an int array of 3), sample_all_into(buf, gyro_into)."""
        g = self.gyro_into
        if g is not None:
            self.sample_all_into(buf, g)
            return
        self.register = _ACCEL_XOUT_H
        self._i2c.readfrom_mem_into(self.address, _ACCEL_XOUT_H, self._buf)
        i2cdevice.decode(self._buf, buf, 1)

    def read_accel(self):
        """(x, y, z) raw counts, the chip's axes."""
        v = [0, 0, 0]
        self.read_accel_into(v)
        return (v[0], v[1], v[2])

    def read_all_into(self, acc, gyro):
        """Accelerometer into acc[0..2], gyroscope into gyro[0..2] (counts, one burst, one
        sample instant), temperature into .temp_raw. Allocates nothing."""
        with self.guard:
            self.sample_all_into(acc, gyro)

    def sample_all_into(self, acc, gyro):
        """read_all_into() for callers already inside a guard (the app's read guard)."""
        self.register = _ACCEL_XOUT_H
        b = self._all
        self._i2c.readfrom_mem_into(self.address, _ACCEL_XOUT_H, b)
        i2cdevice.decode(b, acc, 1)
        i2cdevice.decode(self._gyro6, gyro, 1)
        t = b[6] << 8 | b[7]
        self.temp_raw = t - 0x10000 if t & 0x8000 else t

    def read_gyro(self):
        """(x, y, z) raw counts, the chip's axes (read with the accelerometer: one burst)."""
        a = [0, 0, 0]
        v = [0, 0, 0]
        self.read_all_into(a, v)
        return (v[0], v[1], v[2])

    def temp_cdeg(self):
        """The die temperature of the last read_all_into() in 0.01 C (raw / 340 + 36.53)."""
        return self.temp_raw * 5 // 17 + 3653


room(MPU6050)  # its methods' table too (firmware/compat.py room)
