"""MPU-9250 / MPU-9255 / MPU-6500 accelerometer and gyroscope (InvenSense; WHO_AM_I 0x71 / 0x73
/ 0x70): the MPU6050 driver with the accelerometer filter of its own (firmware/mpu6050.py has
the methods); the MPU-9250's AK8963 sits behind the bypass (firmware/ak8963.py).
"""
# MPU9250(i2c, address=0x68, *, accel_range=2, dlpf=21, gyro_range=500): the MPU6050's options.
# From the MPU-9250 register map (RM-MPU-9250A-00 rev 1.4; docs/hardware.md): the
# accelerometer, gyroscope, temperature, bypass and power registers are the MPU6050's; the
# accelerometer's low-pass filter has a register of its own, ACCEL_CONFIG2 (0x1D, A_DLPF_CFG:
# 218, 218, 99, 45, 21, 10, 5 Hz for the codes 0-6), written here with the dlpf code the
# gyroscope's CONFIG gets; the temperature is raw / 333.87 + 21 C. The MPU-6500 (on many
# modules sold as GY-9250 or MPU-9250) is the MPU-9250 without its AK8963: these registers at
# these addresses (RM-MPU-6500A-00 rev 2.1). A module of its own, so that a board with an
# MPU6050 holds none of it.
from firmware.compat import const

from firmware.errors import SensorNotFound
from firmware.i2cdevice import Device
from firmware.mpu6050 import MPU6050, _DLPF_HZ, _GYRO_CPD_X10, _GYRO_DPS, _RANGES_G
from firmware.i2cdevice import option_code

_ACCEL_CONFIG2 = const(0x1D)
_WHO_AM_I = const(0x75)
_IDS = (0x70, 0x71, 0x73)  # WHO_AM_I of the MPU-6500, MPU-9250, MPU-9255 (_NAMES)
_NAMES = ("MPU-6500", "MPU-9250", "MPU-9255")


class MPU9250(MPU6050):

    def __init__(self, i2c, address=0x68, *, accel_range=2, dlpf=21, gyro_range=500):
        afs = option_code("MPU9250", "accel_range", accel_range, _RANGES_G)
        cfg = option_code("MPU9250", "dlpf", dlpf, _DLPF_HZ)
        fs = option_code("MPU9250", "gyro_range", gyro_range, _GYRO_DPS)
        Device.__init__(self, i2c, address, 1000)
        who = self._probe(_WHO_AM_I, 1, "MPU9250")[0]
        if who not in _IDS:
            raise SensorNotFound("no MPU-9250 at 0x%02X: WHO_AM_I (0x75) reads 0x%02X, expected "
                                 "0x71 (MPU-9250), 0x73 (MPU-9255) or 0x70 (MPU-6500)"
                                 % (address, who), address=address)
        self.who_am_i = who
        self.NAME = _NAMES[_IDS.index(who)]
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
        self._all = bytearray(14)
        self._gyro6 = memoryview(self._all)[8:14]
        self.configure()

    def configure(self):
        """The MPU6050's configuration, and the accelerometer's filter in ACCEL_CONFIG2."""
        MPU6050.configure(self)
        with self.guard:
            self._write_u8(_ACCEL_CONFIG2, self._dlpf_cfg)

    def temp_cdeg(self):
        """The die temperature of the last read_all_into() in 0.01 C (raw / 333.87 + 21)."""
        return self.temp_raw * 2995 // 10000 + 2100
