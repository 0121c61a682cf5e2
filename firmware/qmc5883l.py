"""QMC5883L 3-axis magnetometer (QST), I2C address 0x0D (the chip on most GY-271 boards).

    from machine import I2C, Pin
    from firmware.qmc5883l import QMC5883L
    x, y, z = QMC5883L(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000), range=8).read()
"""
# QMC5883L(i2c, address=0x0D, *, range=2, odr=50, osr=512, delay_us=None, timeout_us=None)
# read() -> (x, y, z) raw counts in the chip's axes; read_into(buf) without allocating.
# Options and attributes: docs/api.md (drivers); how the probe tells the chip from an undriven
# bus, and the errors: docs/design.md (module notes, qmc5883l).
from firmware.compat import const

from firmware.errors import SensorNotFound
from firmware.i2cdevice import Magnetometer

# Registers (datasheet register map)
_XOUT_L = const(0x00)      # X, Y, Z int16 LSB first in 0x00..0x05
_STATUS = const(0x06)
_CTRL1 = const(0x09)
_CTRL2 = const(0x0A)
_SET_RESET = const(0x0B)
_CHIP_ID = const(0x0D)

# Bit fields
_DRDY = const(0x01)        # STATUS bit0: all three axes ready; cleared by reading data
_OVL = const(0x02)         # STATUS bit1: an axis is out of range
_DOR = const(0x04)         # STATUS bit2: a sample set was skipped (data not read in time)
_MODE_MASK = const(0x03)   # CTRL1[1:0]: 00 standby, 01 continuous
_MODE_CONTINUOUS = const(0x01)
_SOFT_RST = const(0x80)    # CTRL2 bit7
# CTRL2 in use: INT_ENB = 0 enables the DRDY pin (active-low enable) for anyone wiring it;
# ROL_PNT = 0, since every read here sets the pointer itself, so the rollover never matters.
_CTRL2_RUN = const(0x00)
_SET_RESET_PERIOD = const(0x01)  # datasheet recommended value
_POR_US = const(1000)      # after SOFT_RST; hardware.md gives no figure, 1 ms is generous

_RANGES_G = (2, 8)                         # RNG[5:4] code = index
_COUNTS_PER_GAUSS = (12000, 3000)
_ODRS_HZ = (10, 50, 100, 200)              # ODR[3:2] code = index
_PERIODS_US = (100000, 20000, 10000, 5000)
_OSRS = (512, 256, 128, 64)                # OSR[7:6] code = index


class QMC5883L(Magnetometer):
    KIND = "qmc5883l"
    OPTIONS = ("range", "odr", "osr", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _ODRS_HZ, _OSRS)
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (_DOR, _DOR | _OVL)  # DOR: a set was skipped, so this one may be old too
    REGISTERS = (_CHIP_ID, _STATUS, _DRDY, _XOUT_L, _CTRL1)
    ID = b"\xff"

    def __init__(self, i2c, address=0x0D, *, range=2, odr=50, osr=512, delay_us=None,
                 timeout_us=None):
        super().__init__(i2c, address, delay_us, timeout_us, range, odr, osr)

    @staticmethod
    def _config_of(codes):
        rng, rate, over = codes
        return (over << 6 | rng << 4 | rate << 2 | _MODE_CONTINUOUS,)  # CTRL1

    def _configure(self):
        # soft reset, standby check, then this driver's configuration, read back
        self._write_u8(_CTRL2, _SOFT_RST)
        self._delay(_POR_US)
        ctrl1 = self._read_u8(_CTRL1)
        if ctrl1 & _MODE_MASK:
            raise SensorNotFound("no QMC5883L at 0x%02X: ID reads 0xFF but CTRL1 reads 0x%02X "
                                 "after a soft reset, not standby (an undriven bus reads 0xFF)"
                                 % (self.address, ctrl1), address=self.address)
        self._write_u8(_SET_RESET, _SET_RESET_PERIOD)
        self._write_u8(_CTRL2, _CTRL2_RUN)
        self._write_u8(_CTRL1, self._want[0])
        self._check_config()

    def _alarm(self, status):
        if status & _DOR:
            self.skipped += 1
        if status & _OVL:
            self._overflow_bit("OVL", "use range=8 or move the magnet away")
