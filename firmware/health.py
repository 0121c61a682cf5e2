"""Is this sample believable? Per-sample plausibility checks of the sensors' outputs, for the app."""
#     from firmware.health import Health
#     h = Health(counts_per_gauss=12000, overflow=-32768, counts_per_g=16384)
#     h.saturated(raw)   # True: an axis at the output limit: not a measurement
#     h.mag_stale(raw)   # True: the same sample again, more times than noise allows
#     h.tilt_ok(acc)     # False: |g| outside 0.75..1.25 g, or the same reading again
#
# What each check catches and why its limits: docs/design.md (module notes, health); the fault
# campaign's figures: docs/faults.md. The field checks are firmware/fieldwatch.py; the shared
# constants (DIP_TOL_KANG, SPELL_*) are here. Allocation-free (tests/scenarios/app_alloc.py).
from array import array

from firmware.compat import const

_SAT_HI = const(32767)
_SAT_LO = const(-32768)
_G_SHIFT = const(4)          # |a|^2 on a >> 4: int16 input -> < 3 * 2**22
_G_LO_PCT = const(75)        # |g| window, percent of 1 g
_G_HI_PCT = const(125)
_ACCEL_REPEATS = const(3)    # exact repeats of all three axes that mean a frozen accelerometer
_RUN_CAP = const(0x3FFF)
DIP_TOL_KANG = const(546)       # 3 deg (65536 KANG per turn): firmware/fieldwatch.py DipCheck
SPELL_JUMP = const(1)           # FieldWatch spells, by weight: a heading jump...
SPELL_SHIFT = const(2)          # ...|B| or the dip left their short averages...
SPELL_FIELD = const(3)          # ...|B| or the dip outside their windows


def mag_repeats(counts_per_gauss):
    """The run of exact repeats that marks a magnetometer's output as stale (module doc)."""
    c = counts_per_gauss or 0
    if c >= 6000:
        return 2
    if c >= 2000:
        return 3
    if c >= 1000:
        return 8
    return 32


def _run(p, v, n):
    # the run of exact repeats after sample v: n + 1 (capped) when v repeats p, the previous
    # sample; else 0, and p takes v
    if v[0] != p[0] or v[1] != p[1] or v[2] != p[2]:
        p[0] = v[0]
        p[1] = v[1]
        p[2] = v[2]
        return 0
    return n + 1 if n < _RUN_CAP else n


class Health:
    """The state of the per-sample checks (see docs/design.md, module notes). overflow: the chip's
    overflow code besides the int16 limits (HMC5883L -4096; else -32768)."""

    def __init__(self, counts_per_gauss=None, overflow=_SAT_LO, counts_per_g=16384):
        self.last = array("h", (0, 0, 0))    # the previous magnetometer sample
        self.same = 0                        # exact repeats of it in a row
        self.repeats = mag_repeats(counts_per_gauss)
        self.overflow = overflow
        self.alast = array("h", (0, 0, 0))   # the previous accelerometer sample
        self.asame = 0
        self.g_lo = 0
        self.g_hi = 0
        self.set_accel(counts_per_g)

    def set_accel(self, counts_per_g):
        c = counts_per_g >> _G_SHIFT
        lo = c * _G_LO_PCT // 100
        hi = c * _G_HI_PCT // 100
        self.g_lo = lo * lo
        self.g_hi = hi * hi

    def reset(self):
        """Forget the runs (after a re-initialisation)."""
        self.same = 0
        self.asame = 0

    def saturated(self, raw):
        return self._sat(raw[0]) or self._sat(raw[1]) or self._sat(raw[2])

    def _sat(self, v):
        return v == _SAT_HI or v == _SAT_LO or v == self.overflow

    def mag_stale(self, raw, suspect=False):
        """suspect: the chip's status hinted at old data (QMC5883L DOR, HMC5883L LOCK): then
        one exact repeat is enough."""
        n = _run(self.last, raw, self.same)
        self.same = n
        return n > 0 and (suspect or n >= self.repeats)

    def _g2(self, a):
        x = a[0] >> _G_SHIFT
        y = a[1] >> _G_SHIFT
        z = a[2] >> _G_SHIFT
        return x * x + y * y + z * z

    def _frozen(self, a):
        n = _run(self.alast, a, self.asame)
        self.asame = n
        return n >= _ACCEL_REPEATS

    def tilt_ok(self, a):
        n = self._g2(a)
        if self._frozen(a):
            return False
        return self.g_lo <= n <= self.g_hi
