"""ICM-20948 accelerometer and gyroscope (TDK InvenSense), I2C address 0x68 (0x69 with AD0
high; most modules): tilt for the compass, and the I2C bypass behind which its AK09916
magnetometer sits (firmware/ak09916.py). The same methods as firmware/mpu6050.py's driver.
"""
#     from machine import I2C, Pin
#     from firmware.icm20948 import ICM20948
#     imu = ICM20948(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000), address=0x69)
#     ax, ay, az = imu.read_accel()
#
# ICM20948(i2c, address=0x68, *, accel_range=2, dlpf=24, gyro_range=500): docs/api.md
# (drivers). Registers and their banks: docs/hardware.md (ICM-20948); why every method leaves
# bank 0 selected: docs/design.md (module notes, icm20948).
from firmware.compat import const, room

from firmware.errors import SensorNotFound
from firmware import i2cdevice
from firmware.i2cdevice import Device, option_code

# Registers (bank 0 unless noted)
_WHO_AM_I = const(0x00)
_USER_CTRL = const(0x03)
_PWR_MGMT_1 = const(0x06)
_PWR_MGMT_2 = const(0x07)
_INT_PIN_CFG = const(0x0F)
_INT_STATUS_1 = const(0x1A)
_ACCEL_XOUT_H = const(0x2D)   # accel X, Y, Z, gyro X, Y, Z, temperature: int16 MSB first
_BANK_SEL = const(0x7F)
_GYRO_CONFIG_1 = const(0x01)  # bank 2
_ACCEL_CONFIG = const(0x14)   # bank 2

# Bit fields
_BANK0 = const(0x00)
_BANK2 = const(0x20)          # USER_BANK[5:4] = 2
_I2C_MST_EN = const(1 << 5)   # USER_CTRL bit5
_BYPASS_EN = const(1 << 1)    # INT_PIN_CFG bit1
_WAKE = const(0x01)           # PWR_MGMT_1: SLEEP=0, clock auto-selected (CLKSEL 1)
_ALL_ON = const(0x00)         # PWR_MGMT_2: accelerometer and gyroscope on
_ID_VALUE = const(0xEA)

_RANGES_G = (2, 4, 8, 16)     # ACCEL_FS_SEL[2:1] code = index
_DLPF_HZ = (246, 111, 50, 24, 12, 6)  # ACCEL_DLPFCFG[5:3] = index + 1 (ACCEL_FCHOICE 1)
_GYRO_DPS = (250, 500, 1000, 2000)    # GYRO_FS_SEL[2:1] code = index
_GYRO_CPD_X10 = (1310, 655, 328, 164)


class ICM20948(Device):
    OPTIONS = ("accel_range", "dlpf", "gyro_range")
    NAME = "ICM-20948"

    def __init__(self, i2c, address=0x68, *, accel_range=2, dlpf=24, gyro_range=500):
        afs = option_code("ICM20948", "accel_range", accel_range, _RANGES_G)
        cfg = option_code("ICM20948", "dlpf", dlpf, _DLPF_HZ) + 1
        fs = option_code("ICM20948", "gyro_range", gyro_range, _GYRO_DPS)
        super().__init__(i2c, address, 1000)  # no data-ready wait: outputs update continuously
        who = self._probe(_WHO_AM_I, 1, "ICM20948")[0]
        if who != _ID_VALUE:
            raise SensorNotFound("no ICM20948 at 0x%02X: WHO_AM_I (0x00, bank 0) reads 0x%02X, "
                                 "expected 0xEA" % (address, who), address=address)
        self._accel_cfg = cfg << 3 | afs << 1 | 1   # ACCEL_CONFIG, filter on
        self._gyro_cfg = cfg << 3 | fs << 1 | 1     # GYRO_CONFIG_1, filter on
        self.dlpf = dlpf
        self.accel_range = accel_range
        self.gyro_range = gyro_range
        self.counts_per_g = 16384 >> afs
        self.counts_per_dps_x10 = _GYRO_CPD_X10[fs]
        self.temp_raw = 0
        self.gyro_into = None
        self._all = bytearray(14)  # the burst: accel, gyro, temperature
        self._gyro6 = memoryview(self._all)[6:12]
        self.configure()

    def configure(self):
        """Wake the chip and write this driver's ranges and filters (also after a reset)."""
        with self.guard:
            self._write_u8(_BANK_SEL, _BANK0)
            self._write_u8(_PWR_MGMT_1, _WAKE)
            self._write_u8(_PWR_MGMT_2, _ALL_ON)
            self._write_u8(_BANK_SEL, _BANK2)
            self._write_u8(_ACCEL_CONFIG, self._accel_cfg)
            self._write_u8(_GYRO_CONFIG_1, self._gyro_cfg)
            self._write_u8(_BANK_SEL, _BANK0)

    def config_ok(self):
        """True when the chip is awake in bank 0 with this driver's ranges: False after a
        reset (power-on PWR_MGMT_1 0x41, asleep) or a glitch write."""
        with self.guard:
            if self._read_u8(_BANK_SEL) != _BANK0 or self._read_u8(_PWR_MGMT_1) != _WAKE:
                return False
            self._write_u8(_BANK_SEL, _BANK2)
            ok = (self._read_u8(_ACCEL_CONFIG) == self._accel_cfg
                  and self._read_u8(_GYRO_CONFIG_1) == self._gyro_cfg)
            self._write_u8(_BANK_SEL, _BANK0)
            return ok

    def data_ready(self):
        """INT_STATUS_1.RAW_DATA_0_RDY_INT: a new sample since the last call (reading clears
        it)."""
        with self.guard:
            return self._read_u8(_INT_STATUS_1) & 1 == 1

    def enable_bypass(self):
        """Clear I2C_MST_EN, set BYPASS_EN: the AK09916 appears on the main bus."""
        with self.guard:
            self._write_u8(_BANK_SEL, _BANK0)
            self._write_u8(_USER_CTRL, self._read_u8(_USER_CTRL) & ~_I2C_MST_EN)
            self._write_u8(_INT_PIN_CFG, self._read_u8(_INT_PIN_CFG) | _BYPASS_EN)

    def read_accel_into(self, buf):
        """Read the accelerometer (counts) into buf[0..2]. Allocates nothing."""
        with self.guard:
            self.sample_into(buf)

    def sample_into(self, buf):
        """read_accel_into() for callers already inside a guard; with .gyro_into set,
        sample_all_into(buf, gyro_into)."""
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
        """Accelerometer into acc[0..2], gyroscope into gyro[0..2] (one burst), temperature
        into .temp_raw. Allocates nothing."""
        with self.guard:
            self.sample_all_into(acc, gyro)

    def sample_all_into(self, acc, gyro):
        """read_all_into() for callers already inside a guard."""
        self.register = _ACCEL_XOUT_H
        b = self._all
        self._i2c.readfrom_mem_into(self.address, _ACCEL_XOUT_H, b)
        i2cdevice.decode(b, acc, 1)
        i2cdevice.decode(self._gyro6, gyro, 1)
        t = b[12] << 8 | b[13]
        self.temp_raw = t - 0x10000 if t & 0x8000 else t

    def read_gyro(self):
        """(x, y, z) raw counts, the chip's axes."""
        a = [0, 0, 0]
        v = [0, 0, 0]
        self.read_all_into(a, v)
        return (v[0], v[1], v[2])

    def temp_cdeg(self):
        """The die temperature of the last read_all_into() in 0.01 C (raw / 333.87 + 21)."""
        return self.temp_raw * 2995 // 10000 + 2100


room(ICM20948)  # its methods' table too (firmware/compat.py room)
