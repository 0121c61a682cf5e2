"""QMC5883P register model (I2C 0x2C), the newer clone on recent GY-271 boards, built from
the QST QMC5883P datasheet's feature table.

    chip = QMC5883PSim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x2C, chip)
    i2c.writeto_mem(0x2C, 0x0B, b'\\x0c')     # RNG +-2 G (15000 counts/G)
    i2c.writeto_mem(0x2C, 0x0A, b'\\x0d')     # normal mode, 200 Hz

Registers: 0x00 chip ID 0x80; 0x01-0x06 X, Y, Z int16 LSB first; 0x09 status (bit0 DRDY,
bit1 OVFL); 0x0A CTRL1 (MODE[1:0] suspend/normal/single/continuous, ODR[3:2] 10/50/100/200 Hz,
OSR[5:4], DSR[7:6]); 0x0B CTRL2 (SET/RESET[1:0], RNG[3:2] +-30/+-12/+-8/+-2 G =
1000/2500/3750/15000 counts/G, SELF_TEST bit6, SOFT_RST bit7); 0x29 (the "axis sign"
register some sources write) is stored and read back with no effect. No temperature sensor.

The sources available to this project say little about timing and flag semantics, so these
are model choices, stated so that a driver's assumptions show up in tests:
- Power-on and SOFT_RST: every register 0 (suspend, +-30 G), no data.
- Normal (01) and continuous (11) modes both place a set every 1/ODR after the CTRL1 write.
- Single (10): one set 1/ODR after the write, then the mode bits return to suspend (00).
- DRDY is set with each new set and cleared by reading any data register; there is no data
  lock: a newer set overwrites an unread one.
- OVFL: set with a set whose value on some axis is outside int16 (the output saturates),
  cleared by the next set in range.
- SELF_TEST and OSR/DSR do not change the data.
- Noise: the datasheet's feature table gives 2 mG field resolution; the model adds 2 mG RMS
  per axis and rounds to the nearest count.
- inject_raw(x, y, z) forces the raw counts of the next set (queued).
- Field faults (host_sim.bus.MagnetometerModel, as the QMC5883L's): freeze() keeps the
  output registers while DRDY still rises with each set; constant(x, y, z) makes every set
  read those counts; brown_out() is power-on; SOFT_RST and brown_out clear a fault unless
  sticky; glitch(reg, value) a write the driver never made.
"""
import math

try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.bus import MagnetometerModel
from host_sim.prng import Prng
from host_sim.world import sensor_counts

ADDRESS = 0x2C

_REG_CHIP_ID = const(0x00)
_REG_DATA = const(0x01)
_REG_DATA_LAST = const(0x06)
_REG_STATUS = const(0x09)
_REG_CTRL1 = const(0x0A)
_REG_CTRL2 = const(0x0B)
_REG_AXIS_SIGN = const(0x29)

_CHIP_ID = const(0x80)
_STATUS_DRDY = const(0x01)
_STATUS_OVFL = const(0x02)
_CTRL2_SOFT_RST = const(0x80)
_MODE_SUSPEND = const(0x00)
_MODE_SINGLE = const(0x02)

_ODR_PERIOD_US = (100000, 20000, 10000, 5000)   # 10 / 50 / 100 / 200 Hz
_COUNTS_PER_G = (1000, 2500, 3750, 15000)        # RNG +-30 / +-12 / +-8 / +-2 G
_NOISE_G = 0.002                                 # 2 mG (datasheet feature table)


class QMC5883PSim(MagnetometerModel):
    """QMC5883P at 0x2C (see the module docstring)."""

    ADDRESS = 0x2C

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.injected = []
        self.measurements = 0
        self.power_on()

    def power_on(self):
        self.ctrl1 = 0
        self.ctrl2 = 0
        self.axis_sign = 0
        self.out = [0, 0, 0]
        self.drdy = False
        self.ovfl = False
        self._t0 = None
        self._k = 0
        self.pointer = 0

    def counts_per_gauss(self):
        return _COUNTS_PER_G[(self.ctrl2 >> 2) & 0x03]

    def period_us(self):
        """The output period CTRL1's ODR sets."""
        return _ODR_PERIOD_US[(self.ctrl1 >> 2) & 0x03]

    def status(self):
        return (_STATUS_DRDY if self.drdy else 0) | (_STATUS_OVFL if self.ovfl else 0)

    def inject_raw(self, x, y, z):
        self.injected.append((int(x), int(y), int(z)))

    def brown_out(self):
        self.power_on()
        if not self.sticky:
            self.fault = None

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    def glitch_range(self):
        """A glitch that flips CTRL2's lower RNG bit (+-2 <-> +-8 G, +-12 <-> +-30 G)."""
        self.glitch(0x0B, self.ctrl2 ^ 0x04)

    def update(self, now_us):
        if self._t0 is None:
            return
        period = _ODR_PERIOD_US[(self.ctrl1 >> 2) & 0x03]
        k = (now_us - self._t0) // period
        if k <= self._k:
            return
        self._k = k
        if self.ctrl1 & 0x03 == _MODE_SINGLE:
            self.ctrl1 &= 0xFC           # back to suspend
            self._place(self._t0 + period)
            self._t0 = None
            return
        self._place(self._t0 + k * period)

    def _place(self, t_us):
        if self.fault == "freeze":
            self.drdy = True
            self.measurements += 1
            return
        if self.fault == "constant":
            raw = self.fault_value
        elif self.injected:
            raw = self.injected.pop(0)
        else:
            cpg = self.counts_per_gauss()
            g = Prng(self.seed, stream=t_us) if self.noise else None
            v = sensor_counts(self.world, t_us, self.mount, cpg, _NOISE_G * cpg, g)
            raw = [int(math.floor(v[i] + 0.5)) for i in range(3)]
        ovfl = False
        for i in range(3):
            v = raw[i]
            if v > 32767:
                v, ovfl = 32767, True
            elif v < -32768:
                v, ovfl = -32768, True
            self.out[i] = v
        self.ovfl = ovfl
        self.drdy = True
        self.measurements += 1

    def read_reg(self, reg):
        if _REG_DATA <= reg <= _REG_DATA_LAST:
            self.drdy = False
            i = reg - _REG_DATA
            v = self.out[i >> 1] & 0xFFFF
            return v >> 8 if i & 1 else v & 0xFF
        if reg == _REG_CHIP_ID:
            return _CHIP_ID
        if reg == _REG_STATUS:
            return self.status()
        if reg == _REG_CTRL1:
            return self.ctrl1
        if reg == _REG_CTRL2:
            return self.ctrl2
        if reg == _REG_AXIS_SIGN:
            return self.axis_sign
        return 0

    def write_reg(self, reg, value):
        if reg == _REG_CTRL1:
            self.ctrl1 = value
            if value & 0x03 == _MODE_SUSPEND:
                self._t0 = None
            else:
                self._t0 = self.now_us
                self._k = 0
        elif reg == _REG_CTRL2:
            if value & _CTRL2_SOFT_RST:
                self.brown_out()
            else:
                self.ctrl2 = value
        elif reg == _REG_AXIS_SIGN:
            self.axis_sign = value
