"""AK8963 3-axis magnetometer (AKM), I2C address 0x0C: the compass inside the MPU-9250 and
MPU-9255 (GY-9250, GY-91 breakouts), on the main bus once the IMU's I2C bypass is open.
"""
#     from machine import I2C, Pin
#     from firmware.mpu9250 import MPU9250
#     from firmware.ak8963 import AK8963
#     i2c = I2C(0, scl=Pin(22), sda=Pin(21), freq=400000)
#     MPU9250(i2c).enable_bypass()               # the AK8963 answers at 0x0C from now on
#     x, y, z = AK8963(i2c).read()
#
# AK8963(i2c, address=0x0C, *, range=49, rate=100, delay_us=None, timeout_us=None): options
# and attributes in docs/api.md (drivers); registers, the fuse-ROM sensitivity and its integer
# form in docs/hardware.md (AK8963).
from firmware.compat import const, room

from firmware.i2cdevice import Magnetometer

# Registers
_WIA = const(0x00)
_ST1 = const(0x02)
_HXL = const(0x03)         # X, Y, Z int16 LSB first in 0x03..0x08, then ST2 at 0x09
_CNTL1 = const(0x0A)
_ASAX = const(0x10)        # ASAX, ASAY, ASAZ in 0x10..0x12 (fuse ROM access mode only)

# Bit fields
_DRDY = const(0x01)        # ST1 bit0
_DOR = const(0x02)         # ST1 bit1: a set was skipped before this one
_HOFL = const(0x08)        # ST2 bit3
_BIT16 = const(0x10)       # CNTL1 BIT: 16-bit output
_POWER_DOWN = const(0x00)
_FUSE_ROM = const(0x0F)
_TWAT_US = const(100)      # power-down -> another mode (docs/hardware.md)

_RANGES_G = (49,)
_COUNTS_PER_GAUSS = (667,)
_RATES_HZ = (8, 100)
_MODES = (0x02, 0x06)      # continuous measurement mode 1, 2
_PERIODS_US = (125000, 10000)


class AK8963(Magnetometer):
    KIND = "ak8963"
    OPTIONS = ("range", "rate", "delay_us", "timeout_us")
    TABLES = (_RANGES_G, _RATES_HZ)
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (_DOR, _DOR)  # DOR: a set was lost (.suspect: a repeat is then stale data)
    REGISTERS = (_WIA, _ST1, _DRDY, _HXL, _CNTL1)
    ID = b"\x48"

    def __init__(self, i2c, address=0x0C, *, range=49, rate=100, delay_us=None,
                 timeout_us=None):
        self._last = bytearray(6)      # the last read's data bytes (DOR: a repeat?)
        self._blk = bytearray(7)       # HXL..HZH and ST2: one transfer per sample
        self.asa = (128, 128, 128)
        super().__init__(i2c, address, delay_us, timeout_us, range, rate)

    @staticmethod
    def _config_of(codes):
        return (_BIT16 | _MODES[codes[1]],)  # CNTL1

    def _configure(self):
        self._write_u8(_CNTL1, _POWER_DOWN)
        self._delay(_TWAT_US)
        self._write_u8(_CNTL1, _FUSE_ROM)
        self._read_into(_ASAX, memoryview(self._buf)[0:3])
        b = self._buf
        self.asa = (b[0], b[1], b[2])
        self._k = (b[0] + 128, b[1] + 128, b[2] + 128)
        self._write_u8(_CNTL1, _POWER_DOWN)
        self._delay(_TWAT_US)
        self._write_u8(_CNTL1, self._want[0])
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
        """read_into() for callers already inside a guard: the data and ST2 in one transfer,
        then the fuse ROM's sensitivity applied."""
        status = self.wait(_ST1, _DRDY)
        self.register = _HXL
        d = self._blk
        self._i2c.readfrom_mem_into(self.address, _HXL, d)
        self.suspect = self._repeat(d, status & _DOR)
        if status & _DOR:
            self.skipped += 1
        if d[6] & _HOFL:
            self._hofl()
        k = self._k
        v = d[1] << 8 | d[0]
        v = ((v - 0x10000 if v & 0x8000 else v) * k[0] + 128) >> 8
        buf[0] = 32767 if v > 32767 else (-32768 if v < -32768 else v)
        v = d[3] << 8 | d[2]
        v = ((v - 0x10000 if v & 0x8000 else v) * k[1] + 128) >> 8
        buf[1] = 32767 if v > 32767 else (-32768 if v < -32768 else v)
        v = d[5] << 8 | d[4]
        v = ((v - 0x10000 if v & 0x8000 else v) * k[2] + 128) >> 8
        buf[2] = 32767 if v > 32767 else (-32768 if v < -32768 else v)

    def _hofl(self):
        d = self._blk
        self._buf[0:6] = d[0:6]
        raw = self.held(0)
        raise self.overflow(raw, "HOFL set (a magnetic sensor overflow: a magnet close by?), "
                                 "raw %s" % (raw,))


room(AK8963)  # its methods' table too (firmware/compat.py room)
