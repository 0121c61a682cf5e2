"""LIS2MDL 3-axis magnetometer (ST), I2C address 0x1E; also the LSM303AGR's magnetometer.

    from machine import I2C, Pin
    from firmware.lis2mdl import LIS2MDL
    x, y, z = LIS2MDL(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000)).read()
"""
# LIS2MDL(i2c, address=0x1E, *, range=16, odr=20, delay_us=None, timeout_us=None)
# read() -> (x, y, z): 3 x the chip's value, 0.5 mG per count (2000 counts/G exactly).
# Options and attributes: docs/api.md (drivers); registers: docs/hardware.md (LIS2MDL); the
# counts and what the driver sets: docs/design.md (module notes, lis2mdl).
from firmware.compat import const, room

from firmware.i2cdevice import Magnetometer

_WHO_AM_I = const(0x4F)
_CFG_REG_A = const(0x60)
_CFG_REG_B = const(0x61)
_CFG_REG_C = const(0x62)
_STATUS = const(0x67)
_OUTX_L = const(0x68)
_OUT_BLOCK = const(0xE8)        # OUTX_L | SUB(7)
_CFG_BLOCK = const(0xE0)        # CFG_REG_A | SUB(7)

_ZYXDA = const(0x08)            # STATUS bit3
_ZYXOR = const(0x80)            # STATUS bit7
_COMP_TEMP_EN = const(0x80)     # CFG_REG_A bit7
_SOFT_RST = const(0x20)         # CFG_REG_A bit5
_MD_CONTINUOUS = const(0x00)
_OFF_CANC = const(0x02)         # CFG_REG_B bit1
_BDU = const(0x10)              # CFG_REG_C bit4
_RESET_US = const(10000)        # after SOFT_RST: no figure in the datasheet; generous
_SCALE = const(3)               # counts per chip LSB: 1.5 mG -> 0.5 mG
_LIMIT = const(10922)           # |chip LSB| whose 3x still fits int16

_RANGES_G = (16,)
_COUNTS_PER_GAUSS = (2000,)
_ODRS_HZ = (10, 20, 50, 100)               # ODR[1:0] code = index
_PERIODS_US = (100000, 50000, 20000, 10000)


class LIS2MDL(Magnetometer):
    KIND = "lis2mdl"
    OPTIONS = ("range", "odr", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _ODRS_HZ)
    UNITS = ("gauss", "Hz")
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (0, _ZYXOR)
    REGISTERS = (_WHO_AM_I, _STATUS, _ZYXDA, _OUT_BLOCK, _CFG_REG_A)
    ID = b"\x40"
    MIRROR = True   # its axes are a left-handed set (docs/hardware.md, LIS2MDL handedness)

    def __init__(self, i2c, address=0x1E, *, range=16, odr=20, delay_us=None,
                 timeout_us=None):
        super().__init__(i2c, address, delay_us, timeout_us, range, odr)

    @staticmethod
    def _config_of(codes):
        return (_COMP_TEMP_EN | codes[1] << 2 | _MD_CONTINUOUS, _OFF_CANC, _BDU)

    def _configure(self):
        # soft reset, CFG_REG_B and C, then A (continuous mode), read back in one transfer
        self._write_u8(_CFG_REG_A, _SOFT_RST)
        self._delay(_RESET_US)
        w = self._want
        self._write_u8(_CFG_REG_B, w[1])
        self._write_u8(_CFG_REG_C, w[2])
        self._write_u8(_CFG_REG_A, w[0])
        self._check_config()

    def config_matches(self):
        """config_ok() for callers already inside a guard: CFG_REG_A..C in one transfer."""
        self.register = _CFG_REG_A
        self._i2c.readfrom_mem_into(self.address, _CFG_BLOCK, self._back)
        return self._back == self._want

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: 3 x the chip's X, Y, Z."""
        if self.wait(_STATUS, _ZYXDA) & _ZYXOR:   # counted first: fewer locals per frame
            self.skipped += 1
        self.register = _OUTX_L
        self._i2c.readfrom_mem_into(self.address, _OUT_BLOCK, self._buf)
        d = self._buf
        x = d[1] << 8 | d[0]
        y = d[3] << 8 | d[2]
        z = d[5] << 8 | d[4]
        x = x - 0x10000 if x & 0x8000 else x   # sign-extended by hand (no struct tuple)
        y = y - 0x10000 if y & 0x8000 else y
        z = z - 0x10000 if z & 0x8000 else z
        if (x + _LIMIT) & 0xFFFF > 2 * _LIMIT or (y + _LIMIT) & 0xFFFF > 2 * _LIMIT \
                or (z + _LIMIT) & 0xFFFF > 2 * _LIMIT:
            self._beyond()
        buf[0] = x * _SCALE
        buf[1] = y * _SCALE
        buf[2] = z * _SCALE

    def _beyond(self):
        raw = self.held(0)
        raise self.overflow(raw, "raw %s (1.5 mG each) beyond +-%d counts: the field exceeds "
                                 "+-16 G; move the magnet away" % (raw, _LIMIT))


room(LIS2MDL)  # its methods' table too (firmware/compat.py room)
