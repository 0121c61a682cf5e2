"""QMC5883P 3-axis magnetometer (QST), I2C address 0x2C (newer GY-271 boards).

    from machine import I2C, Pin
    from firmware.qmc5883p import QMC5883P
    x, y, z = QMC5883P(I2C(0, scl=Pin(5), sda=Pin(4), freq=400000), range=8).read()

QMC5883P(i2c, address=0x2C, *, range=8, odr=50, osr=8, dsr=1, delay_us=None, timeout_us=None)
  range  full scale in gauss: 2 (15000 counts/G), 8 (3750), 12 (2500), 30 (1000)
  odr    output data rate in Hz: 10, 50, 100, 200
  osr    OSR1 filter ratio 8, 4, 2, 1;  dsr  OSR2 down-sampling ratio 1, 2, 4, 8
read() -> (x, y, z) raw counts in the chip's axes; read_into(buf) fills buf[0..2] without
allocating. .KIND 'qmc5883p', .range_code (RNG field), .counts_per_gauss.

Register layout from hardware.md (sources disagree on some details of this clone: the
"axis sign" write to 0x29 is left out, since they cannot agree which register it is).
The ID register 0x00 reads 0x80; the configuration must also read back.
Errors: SensorNotFound, BusError, DataReadyTimeout, SensorOverflow (status OVFL).
"""
from firmware.compat import const

from firmware.errors import SensorNotFound, SensorOverflow
from firmware.i2cdevice import Device, int16x3_into, option_code

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
_ID_VALUE = const(0x80)
_RESET_US = const(1000)    # after SOFT_RST (no figure in hardware.md; generous)

_RANGES_G = (30, 12, 8, 2)                 # RNG[3:2] code = index
_COUNTS_PER_GAUSS = (1000, 2500, 3750, 15000)
_ODRS_HZ = (10, 50, 100, 200)              # ODR[3:2] code = index
_PERIODS_US = (100000, 20000, 10000, 5000)
_OSRS = (8, 4, 2, 1)                       # OSR[5:4] code = index
_DSRS = (1, 2, 4, 8)                       # DSR[7:6] code = index


class QMC5883P(Device):
    KIND = "qmc5883p"
    OPTIONS = ("range", "odr", "osr", "dsr", "delay_us", "timeout_us")

    def __init__(self, i2c, address=0x2C, *, range=8, odr=50, osr=8, dsr=1, delay_us=None,
                 timeout_us=None):
        rng = option_code("QMC5883P", "range", range, _RANGES_G)
        rate = option_code("QMC5883P", "odr", odr, _ODRS_HZ)
        over = option_code("QMC5883P", "osr", osr, _OSRS)
        down = option_code("QMC5883P", "dsr", dsr, _DSRS)
        super().__init__(i2c, address, _PERIODS_US[rate], delay_us, timeout_us)
        self.range_code = rng
        self.counts_per_gauss = _COUNTS_PER_GAUSS[rng]

        chip_id = self._probe_u8(_CHIP_ID, "QMC5883P")
        if chip_id != _ID_VALUE:
            raise SensorNotFound("no QMC5883P at 0x%02X: chip ID register 0x00 reads 0x%02X, "
                                 "expected 0x80" % (address, chip_id), address=address)
        self._ctrl1 = down << 6 | over << 4 | rate << 2 | _MODE_NORMAL
        self._ctrl2 = rng << 2 | _SET_RESET_ON
        self.configure()

    def configure(self):
        """Soft reset, then this driver's configuration, read back (also after a chip reset)."""
        with self.guard:
            self._configure()

    def _configure(self):
        address = self.address
        self._write_u8(_CTRL2, _SOFT_RST)
        self._delay(_RESET_US)
        ctrl2 = self._ctrl2
        ctrl1 = self._ctrl1
        self._write_u8(_CTRL2, ctrl2)
        self._write_u8(_CTRL1, ctrl1)
        for reg, want in ((_CTRL1, ctrl1), (_CTRL2, ctrl2)):
            got = self._read_u8(reg)
            if got != want:
                raise SensorNotFound("no QMC5883P at 0x%02X: register 0x%02X written 0x%02X "
                                     "reads back 0x%02X" % (address, reg, want, got),
                                     address=address)

    def config_ok(self):
        """True when CTRL1 and CTRL2 still hold this driver's configuration (a 2-byte read)."""
        with self.guard:
            self._read_into(_CTRL1, self._b2)
            return self._buf[0] == self._ctrl1 and self._buf[1] == self._ctrl2

    def read_into(self, buf):
        """Wait for DRDY, read X, Y, Z (counts) into buf[0..2]. Allocates nothing."""
        with self.guard:
            self._sample_into(buf)

    def _sample_into(self, buf):
        status = self.wait(_STATUS, _DRDY)
        d = self._buf
        self._read_into(_XOUT_L, d)  # the whole block in one transaction
        if status & _OVFL:
            self._overflow()
        int16x3_into(d, buf, 0)

    def _overflow(self):
        d = self._buf
        v = [0, 0, 0]
        int16x3_into(d, v, 0)
        raw = tuple(v)
        raise SensorOverflow("QMC5883P at 0x%02X: OVFL set (an axis is beyond +-%d G), raw %s; "
                             "use a larger range" % (self.address, _RANGES_G[self.range_code],
                                                     raw), address=self.address, raw=raw)

    def read(self):
        """(x, y, z) raw counts, the chip's axes."""
        v = [0, 0, 0]
        self.read_into(v)
        return (v[0], v[1], v[2])
