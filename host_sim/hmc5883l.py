"""HMC5883L register model (I2C 0x1E), built from the Honeywell
HMC5883L datasheet.

    chip = HMC5883LSim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x1E, chip)
    i2c.writeto_mem(0x1E, 0x02, b'\\x00')    # continuous measurement

Registers: 0x00 CRA (default 0x10: MA[6:5] averages 1/2/4/8, DO[4:2] 0.75...75 Hz,
MS[1:0] normal / positive bias / negative bias); 0x01 CRB (default 0x20, GN[7:5]);
0x02 MODE (default 0x01 single; 00 continuous, 1x idle); 0x03-0x08 X, Z, Y int16 MSB first;
0x09 status (bit0 RDY, bit1 LOCK); 0x0A-0x0C ID 'H', '4', '3'. Other addresses read 0
(datasheet: "any attempt to read an invalid address location returns 0's"), writes to
read-only or invalid registers are ignored.

Behaviour modelled (lazily, on the next transaction):
- Power-on: registers at their defaults, data 0, RDY 0. MODE reads 0x01 but no measurement
  runs until MODE is written (some sources report a power-on measurement; not modelled).
- Single mode (MODE write 01): RDY clears, the measurement completes 6 ms later (datasheet
  operational example: "wait 6 ms"), the data is placed, RDY set, and MODE reads back idle
  (MD = 11) — one measurement, then idle.
- Continuous mode (MODE write 00): after a write to MODE, CRA or CRB the first set is placed
  2/fDO later, then one every 1/fDO (datasheet). DO = 111 (reserved) is modelled as 15 Hz.
  A newer set overwrites an older unread one (no flag), unless LOCK holds.
- LOCK (hardware.md): set by a partial data read (some of 0x03-0x08 read, not all six);
  cleared when all six bytes have been read, by a write to MODE, CRA or CRB, or at
  power-on. While set, new measurements are lost. RDY is cleared when all six bytes have
  been read (and when a single measurement starts). The datasheet also sets LOCK when the
  MODE register is read; hardware.md does not list it and the model does not do it.
- Pointer: auto-increments; after 0x08 it returns to 0x03 (hardware.md); past 0x0C it wraps
  to 0x00 (HMC5883 datasheet pointer rule).
- ADC range -2048...2047: an axis outside it reads -4096; the next good measurement clears it.
- Gain: counts/G 1370, 1090, 820, 660, 440, 390, 330, 230 (GN 0-7). The first measurement
  after a CRB write still uses the old gain (datasheet/hardware.md).
- Self-test: MS = 01 adds +1.16 G on X and Y and +1.08 G on Z to the measured field,
  MS = 10 subtracts it (datasheet self-test; hardware.md: about +452/+421 counts at GN 5);
  MS = 11 (reserved) measures normally.
- Noise: the datasheet's noise floor is 2 mG (standard deviation of 100 readings, GN = 0,
  no averaging); the model adds 2 mG RMS per axis divided by sqrt(averages), then rounds.
- Field faults (fault hooks): freeze() - LOCK held for good (status bit1 stays set), as
  after a partial read that never completes (hardware.md: new measurements are lost) while
  RDY keeps being raised each period: the data registers repeat the old sample; constant(x, y, z) - every
  measurement reads these counts; brown_out() - power-on defaults (single mode, no
  measurement running, gain 1); glitch(reg, value) - a write the driver never made (e.g.
  CRB to another gain). A write to MODE (the driver's re-initialisation) clears freeze and
  constant unless sticky=True.
- inject_raw(x, y, z): forces the raw counts of the next measurement (queued, one per call);
  counts outside -2048...2047 read -4096.
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

ADDRESS = 0x1E

_REG_CRA = const(0x00)
_REG_CRB = const(0x01)
_REG_MODE = const(0x02)
_REG_DATA = const(0x03)
_REG_DATA_LAST = const(0x08)
_REG_STATUS = const(0x09)
_REG_ID_A = const(0x0A)
_REG_ID_C = const(0x0C)

_CRA_DEFAULT = const(0x10)
_CRB_DEFAULT = const(0x20)
_MODE_DEFAULT = const(0x01)
_MODE_IDLE_BITS = const(0x03)
_STATUS_RDY = const(0x01)
_STATUS_LOCK = const(0x02)
_ID = b"H43"

_COUNTS_PER_G = (1370, 1090, 820, 660, 440, 390, 330, 230)
# DO[2:0] rates in quarter-Hz (0.75, 1.5, 3, 7.5, 15, 30, 75; 111 reserved -> 15 Hz)
_DO_QUARTER_HZ = (3, 6, 12, 30, 60, 120, 300, 60)
_AVERAGES = (1, 2, 4, 8)
_SINGLE_US = const(6000)            # datasheet: wait 6 ms for a single measurement
_SELF_TEST_G = (1.16, 1.16, 1.08)   # datasheet self-test bias field, X Y Z
_NOISE_G = 0.002                    # datasheet noise floor, 2 mG (1 sigma)
_ADC_MIN = const(-2048)
_ADC_MAX = const(2047)
_OVERFLOW = const(-4096)


class HMC5883LSim(MagnetometerModel):
    """HMC5883L at 0x1E (see the module docstring). `world` None means zero field."""

    ADDRESS = 0x1E

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.injected = []
        self.measurements = 0   # sets placed in the output registers
        self.lost = 0           # sets dropped because LOCK held
        self.fault = None       # None, 'freeze' or 'constant'
        self.fault_value = (0, 0, 0)
        self.sticky = False
        self.power_on()

    def power_on(self):
        self.cra = _CRA_DEFAULT
        self.crb = _CRB_DEFAULT
        self.mode_reg = _MODE_DEFAULT
        self.out = [0, 0, 0]        # X, Y, Z (sent as X, Z, Y)
        self.rdy = False
        self.lock = False
        self._read_mask = 0
        self.gain_code = _CRB_DEFAULT >> 5   # gain the next measurement uses
        self._gain_next = self.gain_code
        self._single_due = None
        self._t0 = None
        self._k = 0
        self.pointer = 0

    # --- helpers ----------------------------------------------------------------------
    def counts_per_gauss(self):
        """Counts/G of the gain setting in CRB (what later measurements will use)."""
        return _COUNTS_PER_G[self.crb >> 5]

    def period_us(self):
        return 4000000 // _DO_QUARTER_HZ[(self.cra >> 2) & 0x07]

    def averages(self):
        return _AVERAGES[(self.cra >> 5) & 0x03]

    def status(self):
        return (_STATUS_RDY if self.rdy else 0) | (_STATUS_LOCK if self.lock else 0)

    def inject_raw(self, x, y, z):
        """Force the raw counts (X, Y, Z) of the next measurement."""
        self.injected.append((int(x), int(y), int(z)))

    def _restart_continuous(self):
        if self.mode_reg & 0x03 == 0:
            self._t0 = self.now_us
            self._k = 0

    # --- fault hooks (see the module docstring) ---------------------------------------
    def brown_out(self):
        self.power_on()
        if not self.sticky:
            self.fault = None

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    def glitch_range(self):
        """A glitch that writes CRB to GN 3 (660 counts/G) or, from GN 3, to GN 1 (1090)."""
        self.glitch(0x01, 0x20 if self.crb >> 5 == 3 else 0x60)

    # --- lazy time --------------------------------------------------------------------
    def update(self, now_us):
        if self._single_due is not None and now_us >= self._single_due:
            t = self._single_due
            self._single_due = None
            self.mode_reg = (self.mode_reg & 0xFC) | _MODE_IDLE_BITS
            self._deliver(t)
        if self._t0 is not None:
            period = self.period_us()
            # set j is placed at t0 + (j + 1) * period, j = 1, 2, ... (first after 2/fDO)
            j = (now_us - self._t0) // period - 1
            if j > self._k:
                n = j - self._k
                self._k = j
                if self.lock:
                    self.lost += n
                    self._advance_gain()
                    return
                # the newest set overwrites the older ones; only it is visible
                for _ in range(n - 1):
                    self._advance_gain()
                self.lost += n - 1
                self._deliver(self._t0 + (j + 1) * period)

    def _advance_gain(self):
        self.gain_code = self._gain_next

    def _deliver(self, t_us):
        if self.fault == "freeze":
            self.lost += 1
            self._advance_gain()
            self.rdy = True
            self.lock = True
            return
        if self.lock:
            self.lost += 1
            self._advance_gain()
            return
        raw = self._measure(t_us)
        for i in range(3):
            v = raw[i]
            self.out[i] = v if _ADC_MIN <= v <= _ADC_MAX else _OVERFLOW
        self.rdy = True
        self._read_mask = 0
        self.measurements += 1

    def _measure(self, t_us):
        cpg = _COUNTS_PER_G[self.gain_code]
        self._advance_gain()   # the first measurement after a gain change used the old gain
        if self.fault == "constant":
            return self.fault_value
        if self.injected:
            return self.injected.pop(0)
        ms = self.cra & 0x03
        g = Prng(self.seed, stream=t_us) if self.noise else None
        sigma = _NOISE_G * cpg / math.sqrt(self.averages())
        ext = sensor_counts(self.world, t_us, self.mount, cpg, sigma, g)
        raw = [int(math.floor(ext[i] + 0.5)) for i in range(3)]
        if ms not in (1, 2):
            return raw
        # Self test (datasheet "Self Test Operation"): a second acquisition with the offset
        # straps excited (+-1.1 G plus the external field); the first is subtracted from it and
        # the net goes to the output. Either acquisition out of the ADC range -> -4096.
        sign = 1.0 if ms == 1 else -1.0
        bias = [sign * _SELF_TEST_G[i] for i in range(3)]
        both = sensor_counts(self.world, t_us, self.mount, cpg, sigma, g, bias)
        for i in range(3):
            b = int(math.floor(both[i] + 0.5))
            if not (_ADC_MIN <= raw[i] <= _ADC_MAX and _ADC_MIN <= b <= _ADC_MAX):
                raw[i] = _OVERFLOW
            else:
                raw[i] = b - raw[i]
        return raw

    # --- registers --------------------------------------------------------------------
    def next_pointer(self, reg):
        if reg == _REG_DATA_LAST:
            return _REG_DATA
        if reg >= _REG_ID_C:
            return 0
        return reg + 1

    def read_reg(self, reg):
        if _REG_DATA <= reg <= _REG_DATA_LAST:
            idx = reg - _REG_DATA            # 0,1 X; 2,3 Z; 4,5 Y
            v = self.out[(0, 2, 1)[idx >> 1]] & 0xFFFF
            self._read_mask |= 1 << idx
            if self._read_mask == 0x3F:
                self._read_mask = 0
                self.lock = self.fault == "freeze"   # a frozen lock does not release
                self.rdy = False
            else:
                self.lock = True
            return v & 0xFF if idx & 1 else v >> 8
        if reg == _REG_CRA:
            return self.cra
        if reg == _REG_CRB:
            return self.crb
        if reg == _REG_MODE:
            return self.mode_reg
        if reg == _REG_STATUS:
            return self.status()
        if _REG_ID_A <= reg <= _REG_ID_C:
            return _ID[reg - _REG_ID_A]
        return 0

    def write_reg(self, reg, value):
        if reg == _REG_CRA:
            self.cra = value & 0x7F
            self._unlock()
            self._restart_continuous()
        elif reg == _REG_CRB:
            self.crb = value & 0xE0
            self._gain_next = self.crb >> 5
            self._unlock()
            self._restart_continuous()
        elif reg == _REG_MODE:
            if not self.sticky:
                self.fault = None
            self.mode_reg = value & 0x83
            self._unlock()
            md = value & 0x03
            self._t0 = None
            self._single_due = None
            if md == 0:
                self._restart_continuous()
            elif md == 1:
                self.rdy = False
                self._single_due = self.now_us + _SINGLE_US

    def _unlock(self):
        self.lock = False
        self._read_mask = 0
