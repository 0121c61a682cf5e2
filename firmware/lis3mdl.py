"""LIS3MDL 3-axis magnetometer (ST), I2C address 0x1C (SA1 low) or 0x1E (SA1 high).

    from machine import I2C, Pin
    from firmware.lis3mdl import LIS3MDL
    x, y, z = LIS3MDL(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000), range=4).read()
"""
# LIS3MDL(i2c, address=0x1C, *, range=4, odr=20, mode="uhp", delay_us=None, timeout_us=None)
# Options and attributes: docs/api.md (drivers); registers: docs/hardware.md (LIS3MDL); why an
# axis at the rail is an overflow: docs/design.md (module notes, lis3mdl).
from firmware.compat import const, room

from firmware.i2cdevice import Magnetometer, decode

_WHO_AM_I = const(0x0F)
_CTRL_REG1 = const(0x20)
_CTRL_REG2 = const(0x21)
_CTRL_REG3 = const(0x22)
_CTRL_REG4 = const(0x23)
_CTRL_REG5 = const(0x24)
_STATUS = const(0x27)
_OUT_X_L = const(0x28)
_AUTO_INC = const(0x80)         # SUB(7): advance the address in a multi-byte transfer
_OUT_BLOCK = const(0xA8)        # OUT_X_L | SUB(7): the six data bytes in one transfer
_CTRL_BLOCK = const(0xA0)       # CTRL_REG1 | SUB(7): the five control registers

_ZYXDA = const(0x08)            # STATUS bit3: a new X, Y, Z set
_ZYXOR = const(0x80)            # STATUS bit7: a set overwrote one not yet read
_SOFT_RST = const(0x04)         # CTRL_REG2 bit2: registers to their defaults
_MD_CONTINUOUS = const(0x00)    # CTRL_REG3 MD[1:0] = 00
_BDU = const(0x40)              # CTRL_REG5 bit6
_RESET_US = const(10000)        # after SOFT_RST: no figure in the datasheet; generous

_RANGES_G = (4, 8, 12, 16)                 # FS[1:0] code = index
_COUNTS_PER_GAUSS = (6842, 3421, 2281, 1711)
_ODRS_HZ = (5, 10, 20, 40, 80)             # DO[2:0] codes 3..7
_DO = (3, 4, 5, 6, 7)
_PERIODS_US = (200000, 100000, 50000, 25000, 12500)
_MODES = ("lp", "mp", "hp", "uhp")         # OM[1:0] / OMZ[1:0] code = index


class LIS3MDL(Magnetometer):
    KIND = "lis3mdl"
    OPTIONS = ("range", "odr", "mode", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _ODRS_HZ, _MODES)
    UNITS = ("gauss", "Hz", "operating mode: low power, medium, high, ultra-high performance")
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (0, _ZYXOR)   # an overrun: the set read is the newest, one before it was lost
    REGISTERS = (_WHO_AM_I, _STATUS, _ZYXDA, _OUT_BLOCK, _CTRL_REG1)
    ID = b"\x3d"

    def __init__(self, i2c, address=0x1C, *, range=4, odr=20, mode="uhp", delay_us=None,
                 timeout_us=None):
        super().__init__(i2c, address, delay_us, timeout_us, range, odr, mode)

    @staticmethod
    def _config_of(codes):
        # CTRL_REG1..5: TEMP_EN 0, OM, DO, FAST_ODR 0, ST 0 | FS | MD continuous, LP 0 |
        # OMZ, BLE 0 (LSB first) | BDU
        fs, rate, om = codes
        return (om << 5 | _DO[rate] << 2, fs << 5, _MD_CONTINUOUS, om << 2, _BDU)

    def _configure(self):
        # soft reset, the five control registers, read back in one transfer
        self._write_u8(_CTRL_REG2, _SOFT_RST)
        self._delay(_RESET_US)
        w = self._want
        self._write_u8(_CTRL_REG1, w[0])
        self._write_u8(_CTRL_REG2, w[1])
        self._write_u8(_CTRL_REG4, w[3])
        self._write_u8(_CTRL_REG5, w[4])
        self._write_u8(_CTRL_REG3, w[2])   # last: conversions start with the rest in place
        self._check_config()

    def config_matches(self):
        """config_ok() for callers already inside a guard: CTRL_REG1..5 in one transfer."""
        self.register = _CTRL_REG1
        self._i2c.readfrom_mem_into(self.address, _CTRL_BLOCK, self._back)
        return self._back == self._want

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: X, Y, Z int16 LSB first."""
        if self.wait(_STATUS, _ZYXDA) & _ZYXOR:   # counted first: fewer locals per frame
            self.skipped += 1
        self.register = _OUT_X_L
        self._i2c.readfrom_mem_into(self.address, _OUT_BLOCK, self._buf)
        d = self._buf
        # 0x7FFF and 0x8000 are the two values v with (v - 0x7FFF) & 0xFFFF <= 1
        if (((d[1] << 8 | d[0]) - 0x7FFF) & 0xFFFF <= 1
                or ((d[3] << 8 | d[2]) - 0x7FFF) & 0xFFFF <= 1
                or ((d[5] << 8 | d[4]) - 0x7FFF) & 0xFFFF <= 1):
            self._saturated()
        decode(d, buf, 0)

    def _saturated(self):
        raw = self.held(0)
        raise self.overflow(raw, "an axis at the output's limit (-32768 or 32767) in raw %s: "
                                 "beyond +-%d G; use a larger range or move the magnet away"
                            % (raw, _RANGES_G[self.range_code]))


room(LIS3MDL)  # its methods' table too (firmware/compat.py room)
