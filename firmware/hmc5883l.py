"""HMC5883L 3-axis magnetometer (Honeywell), I2C address 0x1E (also on GY-87 boards).

    from machine import I2C, Pin
    from firmware.hmc5883l import HMC5883L
    x, y, z = HMC5883L(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000), gain=1).read()
"""
# HMC5883L(i2c, address=0x1E, *, gain=1, rate=15, averaging=8, delay_us=None, timeout_us=None)
# read() -> (x, y, z) raw counts in the chip's axes (the chip sends X, Z, Y; this reorders).
# Options and attributes: docs/api.md (drivers). Why two periods are waited and one sample
# thrown away after any configuration, and the errors: docs/design.md (module notes, hmc5883l).
from firmware.compat import const

from firmware.errors import SensorOverflow
from firmware.i2cdevice import Magnetometer, option_code

# Registers (datasheet register list)
_CRA = const(0x00)
_CRB = const(0x01)
_MODE = const(0x02)
_DATA = const(0x03)        # X, Z, Y int16 MSB first in 0x03..0x08
_STATUS = const(0x09)
_ID_A = const(0x0A)        # 'H', '4', '3' in 0x0A..0x0C

# Bit fields
_MS_NORMAL = const(0x00)   # CRA[1:0] measurement mode (01 would be positive bias)
_MODE_CONTINUOUS = const(0x00)  # MODE[1:0]; bit7 (high-speed I2C) stays 0
_RDY = const(0x01)         # STATUS bit0
_LOCK = const(0x02)        # STATUS bit1: data output locked (a partial read), new sets lost
_OVERFLOW = const(-4096)   # data register value on ADC overflow (datasheet, data output registers)

_GAINS = (0, 1, 2, 3, 4, 5, 6, 7)                                # GN[7:5] codes
_COUNTS_PER_GAUSS = (1370, 1090, 820, 660, 440, 390, 330, 230)  # per GN (datasheet CRB table)
_RATES_HZ = (3, 15, 30, 75)
_RATE_DO = (2, 4, 5, 6)                                          # CRA DO[4:2] codes
_PERIODS_US = (333334, 66667, 33334, 13334)
_AVERAGING = (1, 2, 4, 8)                                        # CRA MA[6:5] code = index

# Self test (datasheet "Self Test Operation" and spec table): positive bias at gain 5 reads
# about +452 (X, Y) / +421 (Z) counts; acceptance limits 243..575 counts on every axis.
_ST_GAIN = const(5)
_ST_CRA = const(0x71)      # MA 8 averages, DO 15 Hz, MS 01 positive bias (datasheet example)
_ST_PERIOD_US = const(66667)
_ST_LOW = const(243)
_ST_HIGH = const(575)
_SETTLE_MARGIN_US = const(2000)


class HMC5883L(Magnetometer):
    KIND = "hmc5883l"
    OPTIONS = ("gain", "rate", "averaging", "delay_us", "timeout_us")
    TABLES = (_GAINS, _RATES_HZ, _AVERAGING)
    PER_CODE = (_PERIODS_US, _COUNTS_PER_GAUSS)
    FLAGS = (_LOCK, 0)  # LOCK still set when RDY rises: the data registers hold an old set
    REGISTERS = (_ID_A, _STATUS, _RDY, _DATA, _CRA)
    ID = b"H43"
    OVERFLOW = _OVERFLOW  # the sample checks and the collector take it for a saturated axis

    def __init__(self, i2c, address=0x1E, *, gain=1, rate=15, averaging=8, delay_us=None,
                 timeout_us=None):
        super().__init__(i2c, address, delay_us, timeout_us, gain, rate, averaging)

    def _config_of(self, codes):
        # CRA (averaging, rate, normal measurement) and CRB (gain), read back in one transfer.
        # MODE is not: the datasheet sets LOCK on a MODE read, which would cost a measurement;
        # a chip that fell back to single mode stops raising RDY and the reads time out.
        gn, ri, ma = codes
        self._cra = ma << 5 | _RATE_DO[ri] << 2 | _MS_NORMAL
        return (self._cra, gn << 5)

    def _configure(self):
        # rate, averaging, gain, continuous mode; returns once samples carry them
        self._write_u8(_CRA, self._cra)
        self._set_gain_code(self.range_code)
        self._write_u8(_MODE, _MODE_CONTINUOUS)
        self._settle(self.period_us)

    def _set_gain_code(self, gn):
        self._write_u8(_CRB, gn << 5)
        self.range_code = gn
        self.counts_per_gauss = _COUNTS_PER_GAUSS[gn]
        self.set_config((self._cra, gn << 5))

    def _settle(self, period_us):
        # The first measurement after a configuration change keeps the old gain: let two
        # measurements complete, then read (all six bytes: clears LOCK) and drop one sample.
        self._delay(2 * period_us + _SETTLE_MARGIN_US)
        self.fetch()

    def set_gain(self, gain):
        """Change the GN code (0..7); returns once samples carry the new gain."""
        gn = option_code("HMC5883L", "gain", gain, _GAINS)
        with self.guard:
            self._set_gain_code(gn)
            self._settle(self.period_us)

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: the chip sends X, Z, Y MSB first."""
        self.suspect = self.fetch() & _LOCK != 0  # (hardware.md)
        d = self._buf
        x = d[0] << 8 | d[1]       # int16 MSB first, in the order X, Z, Y
        z = d[2] << 8 | d[3]
        y = d[4] << 8 | d[5]
        # Valid outputs -2048..2047 are 0x0000..0x07FF and 0xF800..0xFFFF, so (v + 0x800) & 0xF000
        # is 0 exactly for them; the overflow marker -4096 (0xF000) and anything else fail.
        if (x + 0x800) & 0xF000 or (y + 0x800) & 0xF000 or (z + 0x800) & 0xF000:
            self._overflow()
        buf[0] = x - 0x10000 if x & 0x8000 else x  # sign-extended by hand (no struct tuple)
        buf[1] = y - 0x10000 if y & 0x8000 else y
        buf[2] = z - 0x10000 if z & 0x8000 else z

    def _overflow(self):
        x, z, y = self.held(1)
        raw = (x, y, z)
        if _OVERFLOW in raw:
            msg = ("ADC overflow (-4096) in raw %s; lower the gain (set_gain(%d) or higher)"
                   % (raw, min(self.range_code + 1, 7)))
        else:
            msg = "raw %s outside the output range -2048..2047" % (raw,)
        raise self.overflow(raw, msg)

    def self_test(self):
        """Positive-bias self test; returns (passed, (x, y, z) counts at gain 5)."""
        gn = self.range_code
        with self.guard:
            self._write_u8(_CRA, _ST_CRA)
            self._write_u8(_CRB, _ST_GAIN << 5)
            self._write_u8(_MODE, _MODE_CONTINUOUS)
            self._settle(_ST_PERIOD_US)
        v = [0, 0, 0]
        try:
            self.read_into(v)
            passed = True
            for c in v:
                if c < _ST_LOW or c > _ST_HIGH:
                    passed = False
        except SensorOverflow as e:
            v = list(e.raw)
            passed = False
        finally:
            self.range_code = gn
            self.configure()
        return passed, (v[0], v[1], v[2])
