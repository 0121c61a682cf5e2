"""MMC5603NJ 3-axis magnetometer (MEMSIC), I2C address 0x30 (Adafruit MMC5603 breakout).

    from machine import I2C, Pin
    from firmware.mmc5603 import MMC5603
    x, y, z = MMC5603(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000), range=4).read()
"""
# MMC5603(i2c, address=0x30, *, range=4, bw=0, delay_us=None, timeout_us=None)
# Each sample is a SET and a RESET measurement whose difference cancels the bridge offset.
# Options and attributes: docs/api.md (drivers); registers: docs/hardware.md (MMC5603NJ); the
# arithmetic: docs/design.md (module notes, mmc5603).
from firmware.compat import const, room

from firmware.i2cdevice import Magnetometer

_XOUT0 = const(0x00)
_STATUS1 = const(0x18)
_ODR = const(0x1A)
_CTRL0 = const(0x1B)
_CTRL1 = const(0x1C)
_CTRL2 = const(0x1D)
_PRODUCT_ID = const(0x39)

_MEAS_M_DONE = const(0x40)      # Status1 bit6
_TAKE_MEAS_M = const(0x01)      # internal control 0 bit0
_DO_SET = const(0x08)           # bit3
_DO_RESET = const(0x10)         # bit4
_SW_RST = const(0x80)           # internal control 1 bit7
_POWER_ON_US = const(20000)     # after SW_RST (datasheet: power-on time 20 ms)
_NULL2 = const(1048576)         # twice the null-field code 524288
_RAIL = const(0xFFFFF)          # the 20-bit output's top code

_RANGES_G = (4, 8, 16, 30)                  # shift s = index + 1
_COUNTS_PER_GAUSS = (8192, 4096, 2048, 1024)
_BWS = (0, 1, 2, 3)
_MEAS_US = (6600, 3500, 2000, 1200)         # measurement time per BW code
_PERIODS_US = (14400, 8200, 5200, 3600)     # two measurements, 1.2 ms of transfers at 400 kHz


class MMC5603(Magnetometer):
    KIND = "mmc5603"
    OPTIONS = ("range", "bw", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _BWS)
    UNITS = ("gauss", "bandwidth code: 6.6, 3.5, 2.0, 1.2 ms per measurement")
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (0, 0)
    REGISTERS = (_PRODUCT_ID, _STATUS1, _MEAS_M_DONE, _XOUT0, _PRODUCT_ID)
    ID = b"\x10"

    def __init__(self, i2c, address=0x30, *, range=4, bw=0, delay_us=None, timeout_us=None):
        self._d = bytearray(9)          # Xout0 .. Zout2: one measurement
        self._a = [0, 0, 0]             # the SET measurement, 20-bit codes
        self._b = [0, 0, 0]             # the RESET measurement
        self.offset = [0, 0, 0]
        self._railed = False
        super().__init__(i2c, address, delay_us, timeout_us, range, bw)

    def _config_of(self, codes):
        # config_ok() reads the product ID: the control registers cannot be read
        self._bw = codes[1]
        self._meas_us = _MEAS_US[codes[1]]
        self._shift = codes[0] + 2        # A - B = 2H, and H / 2**s with s = range code + 1
        self._round = 1 << (codes[0] + 1)  # half of 2**shift: rounded half up
        return (0x10,)

    def _configure(self):
        # software reset, then no continuous mode (ODR 0, Cmm_en 0) and the bandwidth
        self._write_u8(_CTRL1, _SW_RST)
        self._delay(_POWER_ON_US)
        self._write_u8(_ODR, 0)
        self._write_u8(_CTRL2, 0)
        self._write_u8(_CTRL1, self._bw)
        self._check_config()

    # Per-sample code in small functions: a frame of more than 11 words would come from the
    # heap on MicroPython (see firmware/i2cdevice.py).
    def _measure(self, magnetise, v):
        # SET or RESET, one measurement, its three 20-bit codes into v
        self._write_u8(_CTRL0, magnetise)
        self._write_u8(_CTRL0, _TAKE_MEAS_M)
        self._delay(self._meas_us)
        self.wait(_STATUS1, _MEAS_M_DONE)
        self.register = _XOUT0
        d = self._d
        self._i2c.readfrom_mem_into(self.address, _XOUT0, d)
        v[0] = d[0] << 12 | d[1] << 4 | d[6] >> 4
        v[1] = d[2] << 12 | d[3] << 4 | d[7] >> 4
        v[2] = d[4] << 12 | d[5] << 4 | d[8] >> 4

    def _axis(self, i):
        # the field on axis i in this driver's counts; the offset and the rails noted
        a = self._a[i]
        b = self._b[i]
        self.offset[i] = (a + b - _NULL2) >> 1
        if a == 0 or a == _RAIL or b == 0 or b == _RAIL:
            self._railed = True
        return (a - b + self._round) >> self._shift

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: the field of a SET/RESET pair."""
        self._measure(_DO_SET, self._a)
        self._measure(_DO_RESET, self._b)
        self._railed = False
        x = self._axis(0)
        y = self._axis(1)
        z = self._axis(2)
        if self._railed:
            self._beyond("a measurement on the output's rails (the chip's +-32 G)")
        if (x + 32768) >> 16 or (y + 32768) >> 16 or (z + 32768) >> 16:
            self._beyond("the field beyond +-%d G" % _RANGES_G[self.range_code])
        buf[0] = x
        buf[1] = y
        buf[2] = z

    def _beyond(self, why):
        a = tuple(self._a)
        b = tuple(self._b)
        raw = ((a[0] - b[0]) >> 1, (a[1] - b[1]) >> 1, (a[2] - b[2]) >> 1)
        raise self.overflow(raw, "%s: field %s (16384 counts/G), SET %s, RESET %s; use a larger "
                                 "range or move the magnet away" % (why, raw, a, b))


room(MMC5603)  # its methods' table too (firmware/compat.py room)
