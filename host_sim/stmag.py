"""What ST's magnetometers LIS3MDL and LIS2MDL (and the LSM303AGR's magnetometer) share in the
simulator: a six-byte X, Y, Z data block LSB first, a STATUS register with ZYXDA (bit3, and
XDA/YDA/ZDA bits 0-2) and ZYXOR (bit7, and XOR/YOR/ZOR bits 4-6), block data update (BDU) and
continuous / single / idle conversion modes. host_sim/lis3mdl.py and host_sim/lis2mdl.py give
each chip's register map, scale and noise (their docstrings cite the datasheets).

Behaviour modelled (lazily, on the next transaction), the same for both chips:
- Continuous mode: set k (k = 1, 2, ...) completes at t0 + k * period, t0 being the write that
  started the mode or changed the output rate. Single mode: one set one period after the
  write, then the mode bits read idle. Idle / power-down: no sets; the registers keep theirs.
- ZYXDA (and XDA, YDA, ZDA) is set when a set reaches the output registers and cleared by a
  read of any data register. ZYXOR (and XOR, YOR, ZOR) is set when a set completes while the
  previous one was not read (ZYXDA still set: "a new set of data has overwritten the previous
  set"), and cleared with ZYXDA.
- BDU: a set is not written into the output registers while the block is part-read (some of
  its six bytes read since the last set was placed, not all): it waits, the newest one only,
  until the sixth byte is read. Without BDU a new set overwrites the registers at once (the
  model's catch-up runs only between transactions, so one transfer never sees two sets).
- Output: the sensor-frame field (host_sim.world) times the chip's sensitivity plus Gaussian
  noise, rounded, saturated to int16.
- Field faults (fault hooks; the chip's soft reset and brown_out() cure them unless sticky):
  freeze() - the output registers stop taking sets while ZYXDA keeps rising each period;
  constant(x, y, z) - every set carries these counts; brown_out() - power-on defaults;
  glitch(reg, value) - a write the driver never made. inject_raw(x, y, z) forces the counts of
  the next set (queued; saturated to int16 like real data).
"""
import math

from host_sim.bus import MagnetometerModel
from host_sim.prng import Prng
from host_sim.world import sensor_counts

ZYXDA = 0x0F   # ZYXDA | ZDA | YDA | XDA
ZYXOR = 0xF0   # ZYXOR | ZOR | YOR | XOR


def sat16(v):
    return -32768 if v < -32768 else 32767 if v > 32767 else v


class STMagModel(MagnetometerModel):
    """The shared data path; a chip model gives DATA (first data register), STATUS, and the
    methods counts_per_gauss(), period_us(), sigma_g() (3 RMS noise figures, gauss), bdu(),
    bias_g() (a field added in gauss, or None) and power_on()."""

    DATA = 0
    STATUS = 0

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.injected = []
        self.measurements = 0   # sets that reached the output registers
        self.overrun = 0        # sets that completed while the previous one was unread
        self.power_on()

    def reset_data(self):
        self.out = [0, 0, 0]
        self.da = False
        self.ovr = False
        self._read = 0          # bit i: data byte i read since the last set was placed
        self._pending = None    # BDU: a set waiting for the block to be read whole
        self._t0 = None
        self._k = 0
        self._single = False

    def start(self, single=False):
        """A conversion mode starts (or its rate changed) now."""
        self._t0 = self.now_us
        self._k = 0
        self._single = single

    def stop(self):
        self._t0 = None

    def status(self):
        return (ZYXDA if self.da else 0) | (ZYXOR if self.ovr else 0)

    def inject_raw(self, x, y, z):
        self.injected.append((int(x), int(y), int(z)))

    # --- fault hooks --------------------------------------------------------------------
    def reset_cures(self):
        if not self.sticky:
            self.fault = None

    def brown_out(self):
        self.power_on()
        self.reset_cures()

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    # --- lazy time ----------------------------------------------------------------------
    def update(self, now_us):
        if self._t0 is None:
            return
        period = self.period_us()
        k = (now_us - self._t0) // period
        if k <= self._k:
            return
        if self._single:
            k = 1
        n = k - self._k
        self._k = k
        t = self._t0 + k * period
        if self._single:
            self._t0 = None
            self.single_done()
        if self.da or n > 1:
            self.ovr = True
            self.overrun += 1
        self.da = True
        if self.fault == "freeze":
            return
        for _ in range(min(n - 1, len(self.injected))):
            self.injected.pop(0)       # the sets overwritten before anyone could read them
        raw = self._measure(t)
        if self.bdu() and self._read:
            self._pending = raw
            return
        self._place(raw)

    def single_done(self):
        """A single conversion ended: the chip's mode bits go idle (override)."""

    def _measure(self, t_us):
        if self.fault == "constant":
            return list(self.fault_value)
        if self.injected:
            return list(self.injected.pop(0))
        cpg = self.counts_per_gauss()
        g = Prng(self.seed, stream=t_us) if self.noise else None
        sig = self.sigma_g()
        bias = self.bias_g()
        v = sensor_counts(self.world, t_us, self.mount, cpg, 0.0, None, bias)
        raw = [0, 0, 0]
        for i in range(3):   # each axis with its own noise figure, one Prng stream per set
            if g is not None:
                v[i] += g.gauss(sig[i] * cpg)
            raw[i] = int(math.floor(v[i] + 0.5))
        return raw

    def _place(self, raw):
        for i in range(3):
            self.out[i] = sat16(raw[i])
        self._read = 0
        self.measurements += 1

    def read_data(self, reg):
        """A read of data register `reg` (DATA .. DATA + 5)."""
        i = reg - self.DATA
        self.da = False
        self.ovr = False
        v = self.out[i >> 1] & 0xFFFF
        self._read |= 1 << i
        if self._read == 0x3F:
            self._read = 0
            if self._pending is not None:
                raw = self._pending
                self._pending = None
                self._place(raw)
        return v >> 8 if i & 1 else v & 0xFF
