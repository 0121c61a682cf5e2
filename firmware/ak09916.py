"""AK09916 3-axis magnetometer (AKM), I2C address 0x0C: the compass inside the ICM-20948, on
the main bus once the IMU's I2C bypass is open.
"""
#     from machine import I2C, Pin
#     from firmware.icm20948 import ICM20948
#     from firmware.ak09916 import AK09916
#     i2c = I2C(0, scl=Pin(22), sda=Pin(21), freq=400000)
#     ICM20948(i2c, address=0x69).enable_bypass()  # the AK09916 answers at 0x0C from now on
#     x, y, z = AK09916(i2c).read()
#
# AK09916(i2c, address=0x0C, *, range=49, rate=100, delay_us=None, timeout_us=None): options
# and attributes in docs/api.md (drivers); registers and sequences from the datasheet in
# docs/hardware.md (AK09916).
from firmware.compat import const

from firmware import i2cdevice
from firmware.i2cdevice import Magnetometer

# Registers
_WIA1 = const(0x00)        # WIA1 0x48, WIA2 0x09
_ST1 = const(0x10)
_HXL = const(0x11)         # X, Y, Z int16 LSB first in 0x11..0x16, TMPS 0x17, ST2 0x18
_CNTL2 = const(0x31)
_CNTL3 = const(0x32)

# Bit fields
_DRDY = const(0x01)        # ST1 bit0
_DOR = const(0x02)         # ST1 bit1
_HOFL = const(0x08)        # ST2 bit3
_SRST = const(0x01)        # CNTL3 bit0
_RESET_US = const(1000)    # after SRST and power-down (100 us is the datasheet's least)

_RANGES_G = (49,)
_COUNTS_PER_GAUSS = (667,)
_RATES_HZ = (10, 20, 50, 100)
_MODES = (0x02, 0x04, 0x06, 0x08)  # continuous measurement mode 1..4
_PERIODS_US = (100000, 50000, 20000, 10000)


class AK09916(Magnetometer):
    KIND = "ak09916"
    OPTIONS = ("range", "rate", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _RATES_HZ)
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (_DOR, _DOR)  # DOR: a set was lost (.suspect: a repeat is then stale data)
    REGISTERS = (_WIA1, _ST1, _DRDY, _HXL, _CNTL2)
    ID = b"\x48\x09"

    def __init__(self, i2c, address=0x0C, *, range=49, rate=100, delay_us=None,
                 timeout_us=None):
        self._last = bytearray(6)      # the last read's data bytes (DOR: a repeat?)
        self._blk = bytearray(8)       # HXL..HZH, TMPS, ST2: one transfer per sample
        super().__init__(i2c, address, delay_us, timeout_us, range, rate)

    @staticmethod
    def _config_of(codes):
        return (_MODES[codes[1]],)  # CNTL2

    def _configure(self):
        self._write_u8(_CNTL3, _SRST)
        self._delay(_RESET_US)
        self._write_u8(_CNTL2, self._want[0])
        self._check_config()

    def _repeat(self, d, dor):
        # in continuous mode the data registers hold the newest set after lost ones (DOR);
        # only the last read's bytes again are old data (held: a read never ended). Its own
        # method: sample_into's frame stays small enough for the C stack
        p = self._last
        same = dor != 0 and d[0] == p[0] and d[1] == p[1] and d[2] == p[2] and \
            d[3] == p[3] and d[4] == p[4] and d[5] == p[5]
        p[0] = d[0]
        p[1] = d[1]
        p[2] = d[2]
        p[3] = d[3]
        p[4] = d[4]
        p[5] = d[5]
        return same

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: the data, TMPS and ST2 in one
        transfer."""
        status = self.wait(_ST1, _DRDY)
        self.register = _HXL
        d = self._blk
        self._i2c.readfrom_mem_into(self.address, _HXL, d)
        self.suspect = self._repeat(d, status & _DOR)
        if status & _DOR:
            self.skipped += 1
        if d[7] & _HOFL:
            self._buf[0:6] = d[0:6]
            raw = self.held(0)
            raise self.overflow(raw, "HOFL set (a magnetic sensor overflow: a magnet close "
                                     "by?), raw %s" % (raw,))
        i2cdevice.decode(d, buf, 0)
