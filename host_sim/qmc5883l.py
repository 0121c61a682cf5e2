"""QMC5883L register model (I2C 0x0D), built from the QST datasheet.

    chip = QMC5883LSim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x0D, chip)
    i2c.writeto_mem(0x0D, 0x09, b'\\x0d')     # continuous, 200 Hz, +-2 G, OSR 512

Registers: 0x00-0x05 X, Y, Z int16 LSB first; 0x06 status (bit0 DRDY, bit1 OVL, bit2 DOR);
0x07-0x08 temperature int16 LSB first (100 counts/degC, arbitrary per-chip offset);
0x09 CTRL1 (MODE[1:0], ODR[3:2], RNG[5:4], OSR[7:6]); 0x0A CTRL2 (INT_ENB bit0, ROL_PNT
bit6, SOFT_RST bit7); 0x0B SET/RESET period; 0x0D chip ID 0xFF. Other addresses read 0 and
ignore writes.

Behaviour modelled (lazily: nothing is computed until a transaction reaches the chip):
- Power-on and SOFT_RST: every register 0, standby, no data (DRDY 0).
- Continuous mode (MODE 01): measurement k (k = 1, 2, ...) completes at t0 + k/ODR, t0 being
  the CTRL1 write that started the mode or changed the ODR. MODE 00 (and the reserved 1x)
  is standby: no new samples, the output registers keep their values.
- Data lock (hardware.md): when a set is latched into 0x00-0x05, DRDY is set and the set
  holds until register 0x05 has been read. Sets completed meanwhile are skipped and set DOR;
  a skipped set never reaches the registers, so a driver that never reads 0x05 sees DRDY
  stay 0 and the output frozen (the field failure). Reading any data register clears DRDY
  and DOR.
- OVL: set with a latched set whose value on some axis lies outside int16 (the output
  saturates at -32768/32767), cleared by the next latched set that is in range.
- Pointer: with ROL_PNT set, reads that reach 0x06 roll over to 0x00; otherwise (model's
  rule, not stated by the sources) the pointer just increments, 0xFF wrapping to 0x00.
- INT_ENB is active low: `drdy_pin()` is high when INT_ENB = 0 and DRDY is set.
- Sensitivity 12000 counts/G (RNG 00, +-2 G) and 3000 counts/G (RNG 01, +-8 G); the
  reserved RNG codes 1x are modelled as +-8 G.
- Noise: QST's QMC5883L datasheet (rev 1.0, features table) gives 2 mG field resolution; the
  model adds Gaussian noise of 2 mG RMS per axis at OSR 512 (24 counts at +-2 G), scaled by
  sqrt(512 / OSR) for the smaller oversampling ratios (a modelling assumption: averaging
  fewer conversions), then rounds to the nearest count and saturates.
- Field faults (fault hooks; a reset cures them unless sticky=True):
  freeze(): the output registers stop taking new sets while conversions go on: each
    completed set raises DRDY and DOR (data-skip semantics: the set was skipped) and the
    registers keep the old sample - stale data that looks fresh to a driver polling DRDY.
  constant(x, y, z): every latched set carries these counts (e.g. zeros after a bad reset).
  brown_out(): the supply dipped: power-on defaults (standby, CTRL 0, data 0, DRDY 0).
  glitch(reg, value): a write the driver never made (a bus glitch), e.g. RNG flipped to +-8 G.
  SOFT_RST (and brown_out) clear freeze/constant unless they were made sticky.
- inject_raw(x, y, z): forces the raw counts of the next set latched into the registers
  (queued, one set per call); values outside int16 saturate and set OVL like real data.
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

ADDRESS = 0x0D

_REG_DATA = const(0x00)
_REG_STATUS = const(0x06)
_REG_TEMP = const(0x07)
_REG_CTRL1 = const(0x09)
_REG_CTRL2 = const(0x0A)
_REG_SETRESET = const(0x0B)
_REG_CHIP_ID = const(0x0D)

_CHIP_ID = const(0xFF)
_STATUS_DRDY = const(0x01)
_STATUS_OVL = const(0x02)
_STATUS_DOR = const(0x04)
_CTRL2_INT_ENB = const(0x01)
_CTRL2_ROL_PNT = const(0x40)
_CTRL2_SOFT_RST = const(0x80)
_MODE_CONTINUOUS = const(0x01)

_ODR_PERIOD_US = (100000, 20000, 10000, 5000)  # ODR 10 / 50 / 100 / 200 Hz
_OSR = (512, 256, 128, 64)
_COUNTS_PER_G = (12000, 3000, 3000, 3000)       # RNG 00 +-2 G, 01 +-8 G (1x reserved)
_NOISE_G = 0.002                                # 2 mG RMS at OSR 512 (QST datasheet 1.0)
_TEMP_COUNTS_PER_C = const(100)                 # hardware.md: about 100 counts/degC
_TEMP_NOISE_COUNTS = 3.0                        # model choice: a few counts of jitter


def _sat16(v):
    if v > 32767:
        return 32767, True
    if v < -32768:
        return -32768, True
    return v, False


class QMC5883LSim(MagnetometerModel):
    """QMC5883L at 0x0D. `world` supplies the field (None: zero field); `mount` is the
    body -> sensor signed permutation (see host_sim.world); `noise=False` leaves only
    quantisation; `temp_offset` (counts) defaults to a seed-derived value in +-3000."""

    ADDRESS = 0x0D

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, temp_offset=None):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        if temp_offset is None:
            temp_offset = Prng(seed, stream=0x7E).randrange(6001) - 3000
        self.temp_offset = temp_offset
        self.injected = []
        self.latched = 0   # sets that reached the output registers
        self.skipped = 0   # sets lost to the data lock (each one sets DOR)
        self.fault = None  # None, 'freeze' or 'constant' (fault hooks below)
        self.fault_value = (0, 0, 0)
        self.sticky = False
        self.power_on()

    # --- state ------------------------------------------------------------------------
    def power_on(self):
        """Power-on / SOFT_RST: defaults everywhere, standby, no data."""
        self.ctrl1 = 0
        self.ctrl2 = 0
        self.setreset = 0
        self.out = [0, 0, 0]
        self.temp = 0
        self.drdy = False
        self.ovl = False
        self.dor = False
        self.locked = False
        self.pointer = 0
        self._t0 = None
        self._k = 0

    def mode(self):
        return self.ctrl1 & 0x03

    def counts_per_gauss(self):
        return _COUNTS_PER_G[(self.ctrl1 >> 4) & 0x03]

    def odr_period_us(self):
        return _ODR_PERIOD_US[(self.ctrl1 >> 2) & 0x03]

    period_us = odr_period_us     # the name the other models give it

    def osr(self):
        return _OSR[(self.ctrl1 >> 6) & 0x03]

    def status(self):
        return ((_STATUS_DRDY if self.drdy else 0) | (_STATUS_OVL if self.ovl else 0)
                | (_STATUS_DOR if self.dor else 0))

    def drdy_pin(self):
        """The DRDY output: INT_ENB = 0 enables it (active low enable)."""
        return self.drdy and not (self.ctrl2 & _CTRL2_INT_ENB)

    def inject_raw(self, x, y, z, latch=False):
        """Force the raw counts of the next latched set. With latch=True the set replaces the
        output registers now, as if a measurement had just completed (DRDY set, lock taken)."""
        if latch:
            self._place((int(x), int(y), int(z)))
        else:
            self.injected.append((int(x), int(y), int(z)))

    # --- fault hooks (see the module docstring) ---------------------------------------
    def _reset_cures(self):
        if not self.sticky:
            self.fault = None

    def brown_out(self):
        self.power_on()
        self._reset_cures()

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    def glitch_range(self):
        """A glitch that flips CTRL1's RNG between +-2 G and +-8 G (12000 <-> 3000 counts/G)."""
        self.glitch(0x09, self.ctrl1 ^ 0x10)

    # --- lazy time --------------------------------------------------------------------
    def update(self, now_us):
        if self._t0 is None:
            return
        period = self.odr_period_us()
        k = (now_us - self._t0) // period
        if k <= self._k:
            return
        n = k - self._k
        first = self._k + 1
        self._k = k
        if self.locked or self.fault == "freeze":
            self.skipped += n
            self.dor = True
            if self.fault == "freeze":
                self.drdy = True
            return
        self._place(self._measure(self._t0 + first * period))
        if n > 1:
            self.skipped += n - 1
            self.dor = True

    def _measure(self, t_us):
        if self.fault == "constant":
            return self.fault_value
        if self.injected:
            return self.injected.pop(0)
        cpg = self.counts_per_gauss()
        g = Prng(self.seed, stream=t_us) if self.noise else None
        sigma = _NOISE_G * cpg * math.sqrt(512 / self.osr())
        v = sensor_counts(self.world, t_us, self.mount, cpg, sigma, g)
        raw = [int(math.floor(v[i] + 0.5)) for i in range(3)]
        tc = 25.0 if self.world is None else self.world.temperature_c
        tv = tc * _TEMP_COUNTS_PER_C
        if g is not None:
            tv += g.gauss(_TEMP_NOISE_COUNTS)
        self.temp = _sat16(self.temp_offset + int(math.floor(tv + 0.5)))[0]
        return raw

    def _place(self, raw):
        ovl = False
        for i in range(3):
            v, o = _sat16(raw[i])
            self.out[i] = v
            ovl = ovl or o
        self.ovl = ovl
        self.drdy = True
        self.locked = True
        self.latched += 1

    # --- registers --------------------------------------------------------------------
    def next_pointer(self, reg):
        if self.ctrl2 & _CTRL2_ROL_PNT and reg <= _REG_STATUS:
            return 0 if reg == _REG_STATUS else reg + 1
        return (reg + 1) & 0xFF

    def read_reg(self, reg):
        if reg < _REG_STATUS:
            self.drdy = False
            self.dor = False
            if reg == 0x05:
                self.locked = False
            v = self.out[reg >> 1] & 0xFFFF
            return v >> 8 if reg & 1 else v & 0xFF
        if reg == _REG_STATUS:
            return self.status()
        if reg == _REG_TEMP:
            return self.temp & 0xFF
        if reg == _REG_TEMP + 1:
            return (self.temp >> 8) & 0xFF
        if reg == _REG_CTRL1:
            return self.ctrl1
        if reg == _REG_CTRL2:
            return self.ctrl2
        if reg == _REG_SETRESET:
            return self.setreset
        if reg == _REG_CHIP_ID:
            return _CHIP_ID
        return 0

    def write_reg(self, reg, value):
        if reg == _REG_CTRL1:
            old = self.ctrl1
            self.ctrl1 = value
            if value & 0x03 != _MODE_CONTINUOUS:
                self._t0 = None
            elif old & 0x03 != _MODE_CONTINUOUS or (old ^ value) & 0x0C:
                self._t0 = self.now_us
                self._k = 0
        elif reg == _REG_CTRL2:
            if value & _CTRL2_SOFT_RST:
                self.power_on()
                self._reset_cures()
            else:
                self.ctrl2 = value & (_CTRL2_INT_ENB | _CTRL2_ROL_PNT)
        elif reg == _REG_SETRESET:
            self.setreset = value
