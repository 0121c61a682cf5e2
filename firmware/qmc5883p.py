"""QMC5883P 3-axis magnetometer (QST), I2C address 0x2C (newer GY-271 boards).

    from machine import I2C, Pin
    from firmware.qmc5883p import QMC5883P
    x, y, z = QMC5883P(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000), range=8).read()
"""
# QMC5883P(i2c, address=0x2C, *, range=8, odr=50, osr=8, dsr=1, delay_us=None, timeout_us=None)
# Options and attributes: docs/api.md (drivers); the register layout and what the sources
# disagree on: docs/design.md (module notes, qmc5883p).
from firmware.compat import const

from firmware.i2cdevice import Magnetometer

# Registers (hardware.md)
_CHIP_ID = const(0x00)
_XOUT_L = const(0x01)      # X, Y, Z int16 LSB first in 0x01..0x06
_STATUS = const(0x09)
_CTRL1 = const(0x0A)
_CTRL2 = const(0x0B)

# Bit fields
_DRDY = const(0x01)        # STATUS bit0
_OVFL = const(0x02)        # STATUS bit1
# CTRL1 MODE[1:0]: 00 suspend, 01 normal, 10 single, 11 continuous. Normal mode measures at
# the ODR; continuous mode is the free-running mode behind the datasheet's "up to 1.5 kHz"
# output rate, which `odr` would not set, so the driver uses normal mode.
_MODE_NORMAL = const(0x01)
_SOFT_RST = const(0x80)    # CTRL2 bit7
_SET_RESET_ON = const(0x00)  # CTRL2 SET/RESET[1:0] = 00: set and reset
_RESET_US = const(1000)    # after SOFT_RST (no figure in hardware.md; generous)

_RANGES_G = (30, 12, 8, 2)                 # RNG[3:2] code = index
_COUNTS_PER_GAUSS = (1000, 2500, 3750, 15000)
_ODRS_HZ = (10, 50, 100, 200)              # ODR[3:2] code = index
_PERIODS_US = (100000, 20000, 10000, 5000)
_OSRS = (8, 4, 2, 1)                       # OSR[5:4] code = index
_DSRS = (1, 2, 4, 8)                       # DSR[7:6] code = index


class QMC5883P(Magnetometer):
    KIND = "qmc5883p"
    OPTIONS = ("range", "odr", "osr", "dsr", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _ODRS_HZ, _OSRS, _DSRS)
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (0, _OVFL)
    REGISTERS = (_CHIP_ID, _STATUS, _DRDY, _XOUT_L, _CTRL1)
    ID = b"\x80"

    def __init__(self, i2c, address=0x2C, *, range=8, odr=50, osr=8, dsr=1, delay_us=None,
                 timeout_us=None):
        super().__init__(i2c, address, delay_us, timeout_us, range, odr, osr, dsr)

    @staticmethod
    def _config_of(codes):
        # CTRL1 and CTRL2 are adjacent: config_ok() reads both back in one 2-byte transfer
        rng, rate, over, down = codes
        return (down << 6 | over << 4 | rate << 2 | _MODE_NORMAL, rng << 2 | _SET_RESET_ON)

    def _configure(self):
        # soft reset, then CTRL2 (range, set/reset) before CTRL1 (mode), read back
        self._write_u8(_CTRL2, _SOFT_RST)
        self._delay(_RESET_US)
        self._write_u8(_CTRL2, self._want[1])
        self._write_u8(_CTRL1, self._want[0])
        self._check_config()

    def _alarm(self, status):
        self._overflow_bit("OVFL", "use a larger range")
