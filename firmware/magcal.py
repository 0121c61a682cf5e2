"""Magnetic calibration: collect samples, solve, accept or refuse, correct in Q15.

    from firmware.magcal import Calibrator
    cal = Calibrator(model=10, counts_per_gauss=12000)   # QMC5883L at +-2 G
    cal.add(x, y, z)                  # every raw sample; True when the buffer kept it
    c = cal.solve()                   # a Calibration, or raises CalibrationRejected(.reason)
    c.correct(raw, out)               # out = InvW (raw - V) >> 15: allocation-free, small ints

Pipeline (AN4246): SampleBuffer (firmware/samples.py, distance-separated) -> exact moment
sums (firmware/accum.py, updated per kept/evicted sample) -> exact least squares and W^-1 =
A^1/2 (firmware/solve.py) -> named acceptance checks ("sour grapes", Judd; NXP; ArduPilot)
-> Calibration (offset V, InvW in Q15, field B). The min/max model (seed 002) takes the
running extremes of every raw sample since clear(), as users know it; its fit error and its
geometry check use the held samples like the other models.

solve_steps() is the same solve as a generator for the app's loop, bounded work per next():
at most solve.SLICE_OPS (40) operations on long ints (a few entries of the normal equations
or of one elimination row, a third of a 3x3 inverse, one power-iteration step...) or
samples.COVERAGE_CHUNK samples of the coverage count (tests/test_slices.py bounds both).

Acceptance, in this order; each refusal raises CalibrationRejected(REASON_*, detail):
  too_few_samples   fewer held samples than the model needs (_MIN_SAMPLES_*).
  planar            the samples do not determine the model (Judd's degenerate ellipsoids):
                    singular normal equations, or a parameter whose degeneracy ratio rho
                    (firmware/solve.py) is below _MIN_RHO_* - e.g. a flat spin.
  singular          the solver broke down: the quadric is not an ellipsoid, or W^-1 did not
                    converge.
  offset_out_of_range  V outside int16 (correct() could not represent it; ArduPilot also
                    bounds offsets).
  low_coverage      fewer than _MIN_COVERAGE_* percent of 100 equal-area sphere regions,
                    seen from the fitted centre V, hold a sample.
  soft_iron_out_of_range  the eigenvalues of W^-1 spread more than 5:1 (ArduPilot
                    refuses diagonal scalings outside 0.2 .. 5 for the same reason).
  field_out_of_range  B outside 10 .. 90 uT (NXP) when counts_per_gauss is known; else B
                    below _MIN_FIELD_COUNTS counts (too coarse to correct).
  fit_error_high    fit error above max_fit_error (hundredths of a percent).
  not_better        the current calibration's fit error, aged, is lower; a higher-order
                    model gets through at <= _FIT_ERROR_UPGRADE (NXP).
"""
import struct

from firmware import accum, solve
from firmware.errors import CalibrationRejected
from firmware.fixedpoint import bit_length, micropython, rdiv, sat16
from firmware.samples import REJECTED, REPLACED, SampleBuffer, separation_for

try:
    from micropython import const
except ImportError:  # CPython
    def const(x):
        return x

REASON_TOO_FEW_SAMPLES = "too_few_samples"
REASON_PLANAR = "planar"
REASON_SINGULAR = "singular"
REASON_LOW_COVERAGE = "low_coverage"
REASON_OFFSET_OUT_OF_RANGE = "offset_out_of_range"
REASON_SOFT_IRON_OUT_OF_RANGE = "soft_iron_out_of_range"
REASON_FIELD_OUT_OF_RANGE = "field_out_of_range"
REASON_FIT_ERROR_HIGH = "fit_error_high"
REASON_NOT_BETTER = "not_better"

MINMAX = "minmax"
MODELS = (MINMAX, 4, 7, 10)
_ORDER = {None: -1, MINMAX: 0, 4: 4, 7: 7, 10: 10}

DEFAULT_CAPACITY = const(300)   # samples (ArduPilot keeps 300, NXP 340): 1.8 KB of int16
# Separation: a whole sphere saturates the buffer at 3/4 of its capacity (samples.py's
# advice), 225 samples by default, about 0.19 R apart; one great circle then holds ~33.
_FILL_NUM = const(3)
_FILL_DEN = const(4)
_EXPECTED_FIELD_MG = const(500)     # mG: mid-latitude Earth field, for the default separation
_SEPARATION_GROWTH = const(5)       # auto separation: re-set only when it grows by 5/4
# Minimum held samples, in units of one great circle at the default separation (~33):
# more than one circle for min/max and 4 elements, than two for 7, than three for 10
# (Judd: a 3D ellipsoid needs data from more than two independent planes).
_MIN_SAMPLES_MINMAX = const(40)
_MIN_SAMPLES_4 = const(40)
_MIN_SAMPLES_7 = const(70)
_MIN_SAMPLES_10 = const(100)
_MIN_SAMPLES_GEOMETRY = const(12)   # enough to tell a flat spin from a start (4-element fit)
# Coverage (% of 100 equal-area regions around V; one great circle crosses ~20 of them).
_MIN_COVERAGE_MINMAX = const(40)    # needs both extremes of every axis
_MIN_COVERAGE_4 = const(30)
_MIN_COVERAGE_7 = const(40)
_MIN_COVERAGE_10 = const(50)
# Degeneracy ratios rho (firmware/solve.py; parts per million). A fully covered sphere gives
# 333333 for the centre, 66667 (dx dy) and 200000 (dx^2 - dz^2) for the shape; soft iron
# lowers them as the ellipsoid flattens (roughly as 1 / axis ratio^2), so each threshold is
# half the value measured on a fully covered ellipsoid with 5:1 axes, the most anisotropic
# one accepted (_MAX_SOFT_IRON_COND). The planar wind-vane log gives 1/10 of these.
_MIN_RHO_CENTRE_PPM = const(17000)  # all models (5:1 ellipsoid: 34000)
_MIN_RHO_SHAPE_7_PPM = const(12500)  # 7 elements (5:1 ellipsoid: 25000)
_MIN_RHO_SHAPE_10_PPM = const(1400)  # 10 elements (5:1 ellipsoid: 2870)
_MAX_SOFT_IRON_COND_X100 = const(500)  # W^-1 eigenvalues within 5:1 (ArduPilot: 0.2 .. 5)
_MIN_FIELD_UT = const(10)           # NXP: plausible geomagnetic field 10 .. 90 uT
_MAX_FIELD_UT = const(90)
_MIN_FIELD_COUNTS = const(16)       # unknown sensitivity: 1 count is then >= 6 % of B
# NXP's 15 %: the definition is NXP's, so its limit carries over. It refuses a sphere fit to a
# 2:1 ellipsoid (~20 %); real 10-element fits here give 0.6-3.7 %, 9.5 % on a noisy QMC log.
DEFAULT_MAX_FIT_ERROR = const(1500) # hundredths of a percent
_FIT_ERROR_UPGRADE = const(350)     # NXP: a higher-order model is accepted at <= 3.5 %
_FIT_ERROR_DOUBLING_S = const(60000)  # aging: NXP's e-folding time of 24 h = 59890 s x ln 2
_COVERAGE_GAIN = const(15)          # points of coverage that make a wider fit "better"...
_COVERAGE_FIT_NUM = const(3)        # ...if its fit error is within 3/2 of the current's:
_COVERAGE_FIT_DEN = const(2)        # a fit over part of the sphere looks better than it is
_POWER_ITER = const(24)             # eigenvalue ratio check; see _cond_x100
# solve_steps(): slices per next() by default: one slice is at most solve.SLICE_OPS long-int
# operations (~1 ms on an RP2040); the caller decides how many fit between samples (the app
# runs a quarter of the sample period's worth per step, firmware/app.py).
DEFAULT_SLICE_GROUP = const(1)

_MIN_SAMPLES = {MINMAX: _MIN_SAMPLES_MINMAX, 4: _MIN_SAMPLES_4, 7: _MIN_SAMPLES_7,
                10: _MIN_SAMPLES_10}
_MIN_COVERAGE = {MINMAX: _MIN_COVERAGE_MINMAX, 4: _MIN_COVERAGE_4, 7: _MIN_COVERAGE_7,
                 10: _MIN_COVERAGE_10}

_IDENTITY_Q15 = (32767, 0, 0, 0, 32767, 0, 0, 0, 32767)
_MODEL_CODE = {None: 0, MINMAX: 1, 4: 4, 7: 7, 10: 10}
_CODE_MODEL = {0: None, 1: MINMAX, 4: 4, 7: 7, 10: 10}
_PAYLOAD_VERSION = const(1)
_PAYLOAD = "<BBBBHH3i9hii"  # version, model, coverage, 0, fit_error, samples, V, InvW, B, B_out
PAYLOAD_SIZE = const(46)


class Calibration:
    """One calibration: V (offset, counts), InvW (9 Q15 ints, row-major), B (field, counts).

    correct(raw, out) writes InvW * sat16(raw - V) >> 15 (rounded) into out[0:3]; its
    magnitude on the calibrated sphere is .field_out counts (= .field scaled by the Q15
    normalisation of InvW). .fit_error: hundredths of a percent. .model: None
    (uncalibrated identity), 'minmax', 4, 7 or 10. .samples, .coverage (%) at solve time.
    """

    def __init__(self, model=None, offset=(0, 0, 0), invw=_IDENTITY_Q15, field=0, field_out=0,
                 fit_error=0, samples=0, coverage=0):
        if model not in _MODEL_CODE:
            raise ValueError("unknown calibration model %r" % (model,))
        if len(offset) != 3 or len(invw) != 9:
            raise ValueError("offset needs 3 ints and invw 9, got %d and %d"
                             % (len(offset), len(invw)))
        for v in offset:
            if not -32768 <= v <= 32767:
                raise ValueError("offset %d outside int16" % v)
        for i in range(3):
            t = abs(invw[3 * i]) + abs(invw[3 * i + 1]) + abs(invw[3 * i + 2])
            if t > 32767:  # the small-int bound of correct() rests on this
                raise ValueError("invw row %d absolute sum %d > 32767" % (i, t))
        self.model = model
        self.offset = (offset[0], offset[1], offset[2])
        self.invw = tuple(invw)
        self._k = self.invw + self.offset  # correct()'s single tuple: InvW (0..8), V (9..11)
        self.field = field
        self.field_out = field_out
        self.fit_error = fit_error
        self.samples = samples
        self.coverage = coverage

    def correct(self, raw, out):
        """out[0:3] = InvW sat16(raw - V) >> 15, rounded (AN4246 section 3).

        |InvW row| <= 32767 and |sat16| <= 32768 keep every partial sum below 2**30 - 2**15,
        so it stays a small int on a 32-bit board and allocates nothing - not even its call
        frame: InvW and V sit in one tuple so that locals plus stack stay within the 11
        words MicroPython keeps on the C stack (more and the frame goes to the heap).
        """
        k = self._k
        x = sat16(raw[0] - k[9])
        y = sat16(raw[1] - k[10])
        z = sat16(raw[2] - k[11])
        out[0] = (k[0] * x + k[1] * y + k[2] * z + 16384) >> 15
        out[1] = (k[3] * x + k[4] * y + k[5] * z + 16384) >> 15
        out[2] = (k[6] * x + k[7] * y + k[8] * z + 16384) >> 15

    def to_bytes(self):
        """The 46-byte little-endian payload (storage adds its own header and CRC)."""
        fe = self.fit_error if self.fit_error < 65535 else 65535
        n = self.samples if self.samples < 65535 else 65535
        return struct.pack(_PAYLOAD, _PAYLOAD_VERSION, _MODEL_CODE[self.model], self.coverage,
                           0, fe, n, self.offset[0], self.offset[1], self.offset[2],
                           *(self.invw + (self.field, self.field_out)))

    @classmethod
    def from_bytes(cls, b):
        """Inverse of to_bytes; raises ValueError naming what is wrong."""
        if len(b) != PAYLOAD_SIZE:
            raise ValueError("calibration payload is %d bytes, expected %d"
                             % (len(b), PAYLOAD_SIZE))
        f = struct.unpack(_PAYLOAD, b)
        if f[0] != _PAYLOAD_VERSION:
            raise ValueError("calibration payload version %d, expected %d"
                             % (f[0], _PAYLOAD_VERSION))
        if f[1] not in _CODE_MODEL:
            raise ValueError("calibration payload model code %d unknown" % f[1])
        return cls(model=_CODE_MODEL[f[1]], offset=f[6:9], invw=f[9:18], field=f[18],
                   field_out=f[19], fit_error=f[4], samples=f[5], coverage=f[2])

    def __eq__(self, other):
        return isinstance(other, Calibration) and self.to_bytes() == other.to_bytes()

    def __repr__(self):
        return ("Calibration(model=%r, offset=%r, invw=%r, field=%d, field_out=%d, "
                "fit_error=%d, samples=%d, coverage=%d)" % (
                    self.model, self.offset, self.invw, self.field, self.field_out,
                    self.fit_error, self.samples, self.coverage))


UNCALIBRATED = Calibration()


def _reject(reason, detail):
    raise CalibrationRejected(reason, detail)


def _cond_steps(q, out):
    """Generator: out[0] = the eigenvalue ratio of InvW (9 Q15 ints, symmetric positive
    definite), in hundredths; None if it is not positive definite. Power iteration on InvW
    and on its adjugate (whose largest eigenvalue is det / the smallest of InvW); each
    Rayleigh quotient is a lower bound whose error shrinks as (l2 / l1)**(2 * _POWER_ITER)
    of the eigenvalue gap. One power step (~25 operations, long ints on a 32-bit board)
    per next()."""
    out[0] = None
    m = [[q[0], q[1], q[2]], [q[3], q[4], q[5]], [q[6], q[7], q[8]]]
    dt = solve.det3(m)
    if dt <= 0 or m[0][0] <= 0 or m[0][0] * m[1][1] - m[0][1] * m[1][0] <= 0:
        return
    r = [0]
    yield from _power_steps(m, r)
    big = r[0]
    yield
    adj = solve.adj3(m)
    yield from _power_steps(adj, r)
    big_adj = r[0]
    if big <= 0 or big_adj <= 0:
        return
    # cond = big / (dt / big_adj); Rayleigh quotients in Q16
    out[0] = big * big_adj * 100 // (dt << 32)


def _cond_x100(q):
    """_cond_steps run to completion."""
    out = [None]
    for _ in _cond_steps(q, out):
        pass
    return out[0]


def _power_steps(m, out):
    # out[0] = Rayleigh quotient (Q16) after _POWER_ITER power steps; vectors rescaled by
    # shifts; one power step per next()
    out[0] = 0
    v = [1 << 14, 1 << 13, 1 << 12]
    for _ in range(_POWER_ITER):
        yield
        u = solve.mat_vec3(m, v)
        a = max(abs(u[0]), abs(u[1]), abs(u[2]))
        if a == 0:
            return
        sh = bit_length(a) - 15
        v = [u[0] >> sh, u[1] >> sh, u[2] >> sh] if sh > 0 else u
    yield
    u = solve.mat_vec3(m, v)
    out[0] = ((u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) << 16) // (
        v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


class Calibrator:
    """Collects samples and solves for a Calibration (see the module docstring).

    model: 'minmax', 4, 7, 10, or 'auto' (the highest model whose sample minimum is met).
    capacity: samples held (DEFAULT_CAPACITY on a board; the desktop tool uses more).
    separation: counts between held samples; None derives it from counts_per_gauss
      (a 50 uT field) or, without it, from the running half-ranges of the raw data.
    counts_per_gauss: the sensor's sensitivity, enabling the 10 .. 90 uT field check.
    current: the calibration in force (e.g. loaded from storage); new fits must beat it.
    max_fit_error: hundredths of a percent.
    """

    def __init__(self, model=10, capacity=DEFAULT_CAPACITY, separation=None,
                 counts_per_gauss=None, current=None, max_fit_error=DEFAULT_MAX_FIT_ERROR):
        if model not in MODELS and model != "auto":
            raise ValueError("model %r: expected 'minmax', 4, 7, 10 or 'auto'" % (model,))
        self.model = model
        self.counts_per_gauss = counts_per_gauss
        self.max_fit_error = max_fit_error
        self._target = capacity * _FILL_NUM // _FILL_DEN
        if self._target < 1:
            self._target = 1
        self._auto = separation is None and counts_per_gauss is None
        if separation is None:
            if counts_per_gauss is not None:
                separation = separation_for(counts_per_gauss * _EXPECTED_FIELD_MG // 1000,
                                            self._target)
            else:
                separation = 1
        self.buffer = SampleBuffer(capacity=capacity, separation=separation)
        self.moments = accum.Moments()
        self.current = current if current is not None else UNCALIBRATED
        self._age_s = 0
        self._fresh = True  # no raw sample since construction or clear()
        self._lo = [0, 0, 0]
        self._hi = [0, 0, 0]
        self.slice_group = DEFAULT_SLICE_GROUP

    @property
    def count(self):
        return self.buffer.count

    @property
    def capacity(self):
        return self.buffer.capacity

    @property
    def separation(self):
        return self.buffer.separation

    def clear(self):
        """Forget all samples and the raw extremes (the current calibration stays)."""
        self.buffer.clear()
        self.moments.clear()
        self._fresh = True
        if self._auto:
            self.buffer.set_separation(1)

    @micropython.native  # keeps its frame off the heap (see firmware.fixedpoint)
    def add(self, x, y, z):
        """Offer one raw sample (int16 counts). O(1); returns True if the buffer kept it.

        A rejected sample (the usual case) allocates nothing. Raises ValueError for a value
        outside int16 (from SampleBuffer.offer) before anything changes."""
        r = self.buffer.offer(x, y, z)
        if r != REJECTED:
            if r == REPLACED:
                e = self.buffer.evicted
                self.moments.sub(e[0], e[1], e[2])
            self.moments.add(x, y, z)
        lo = self._lo
        hi = self._hi
        if self._fresh:
            self._fresh = False
            lo[0] = hi[0] = x
            lo[1] = hi[1] = y
            lo[2] = hi[2] = z
            return r != REJECTED
        grew = False
        if x < lo[0]:
            lo[0] = x
            grew = True
        elif x > hi[0]:
            hi[0] = x
            grew = True
        if y < lo[1]:
            lo[1] = y
            grew = True
        elif y > hi[1]:
            hi[1] = y
            grew = True
        if z < lo[2]:
            lo[2] = z
            grew = True
        elif z > hi[2]:
            hi[2] = z
            grew = True
        if grew and self._auto:
            self._grow_separation()
        return r != REJECTED

    def _grow_separation(self):
        # radius estimate: mean half-range of the raw data seen so far
        r = (self._hi[0] - self._lo[0] + self._hi[1] - self._lo[1]
             + self._hi[2] - self._lo[2]) // 6
        if r <= 0:
            return
        s = separation_for(r, self._target)
        b = self.buffer
        if s * 4 >= b.separation * _SEPARATION_GROWTH:  # grew by 5/4 or more
            b.set_separation(s)
            held = b.data
            self.moments.rebuild([(held[j], held[j + 1], held[j + 2])
                                  for j in range(0, 3 * b.count, 3)])

    def centre_estimate(self):
        """Hard-iron estimate for coverage: the current V, or the raw data's mid-range."""
        if self.current.model is not None:
            return self.current.offset
        return ((self._lo[0] + self._hi[0]) >> 1, (self._lo[1] + self._hi[1]) >> 1,
                (self._lo[2] + self._hi[2]) >> 1)

    def coverage(self):
        """Percent of 100 equal-area sphere regions holding a sample, seen from the current
        hard-iron estimate (O(count))."""
        c = self.centre_estimate()
        return self.buffer.coverage(c[0], c[1], c[2])

    def age(self, seconds):
        """Let time pass for the current calibration's fit error (it doubles every
        _FIT_ERROR_DOUBLING_S), so an old calibration can eventually be replaced."""
        self._age_s += seconds

    def aged_fit_error(self):
        """The current calibration's fit error after aging, hundredths of a percent."""
        fe = self.current.fit_error
        if fe < 1:
            fe = 1  # a perfect fit must still age
        k = self._age_s // _FIT_ERROR_DOUBLING_S
        if k > 16:
            return 1 << 30
        base = fe << k
        return base + base * (self._age_s % _FIT_ERROR_DOUBLING_S) // _FIT_ERROR_DOUBLING_S

    def _pick_model(self, model):
        if model is None:
            model = self.model
        if model == "auto":
            n = self.buffer.count
            for m in (10, 7, 4):
                if n >= _MIN_SAMPLES[m]:
                    return m
            return 4
        if model not in MODELS:
            raise ValueError("model %r: expected 'minmax', 4, 7, 10 or 'auto'" % (model,))
        return model

    @staticmethod
    def _rho_limit(f):
        if solve.column_degree(f.model, f.rho_col) == 1:
            return _MIN_RHO_CENTRE_PPM
        return _MIN_RHO_SHAPE_7_PPM if f.model == 7 else _MIN_RHO_SHAPE_10_PPM

    def _check_rho(self, f):
        lim = self._rho_limit(f)
        if f.rho_min_ppm < lim:
            _reject(REASON_PLANAR, "%s is undetermined (rho %d ppm < %d, %d-element fit): "
                    "samples confined near a plane, or two?"
                    % (solve.column_name(f.model, f.rho_col), f.rho_min_ppm, lim, f.model))

    def solve(self, model=None, accept=True):
        """Solve now; returns the new Calibration (also made .current) or raises
        CalibrationRejected. accept=False runs the checks but leaves .current alone."""
        g = self.solve_steps(model, accept)
        while True:
            try:
                next(g)
            except StopIteration as e:
                return e.value

    def solve_steps(self, model=None, accept=True, group=None):
        """The solve as a generator doing bounded work per next() (for the app's loop):
            job = cal.solve_steps()
            ... each tick:  next(job)   -> StopIteration when done (.value = Calibration),
                                           CalibrationRejected on refusal.
        One next() runs `group` slices (None: .slice_group), each at most solve.SLICE_OPS
        long-int operations or samples.COVERAGE_CHUNK samples of the coverage count
        (tests/test_slices.py); group=1 gives the finest slices, for a caller that runs as
        many as its sample period allows. The result does not depend on the slicing.
        The moment sums are copied at the start, so samples added meanwhile do not disturb
        the fit (coverage is counted on the buffer as each slot is reached, at the end)."""
        k = self.slice_group if group is None else group
        if k < 1:
            raise ValueError("slice group %d < 1" % k)
        job = self._solve_slices(model, accept)
        if k == 1:
            return (yield from job)
        n = 0
        while True:
            try:
                next(job)
            except StopIteration as e:
                return e.value
            n += 1
            if n >= k:
                n = 0
                yield

    def _solve_slices(self, model, accept):
        model = self._pick_model(model)
        n = self.buffer.count
        need = _MIN_SAMPLES[model]
        c, s = self.moments.snapshot()
        if n < need:
            # A flat spin never fills the buffer: say "planar" when that is the cause, so
            # the user is told to turn the board over rather than to keep spinning.
            if n >= _MIN_SAMPLES_GEOMETRY:
                planar = False
                for gm in ((4, model) if model in (7, 10) and n > 2 * model else (4,)):
                    f = solve.Fit(gm)
                    try:
                        yield from solve.fit_steps(c, s, gm, f)
                    except solve.SolveError as e:
                        planar = e.reason == REASON_PLANAR
                    if f.rho_min_ppm is not None and f.rho_min_ppm < self._rho_limit(f):
                        planar = True
                    if planar:
                        _reject(REASON_PLANAR, "%d samples held (model %s needs %d), all near "
                                "a plane: turn the board over, not only around"
                                % (n, model, need))
            _reject(REASON_TOO_FEW_SAMPLES, "%d samples held, model %s needs %d"
                    % (n, model, need))
        yield
        r = [None]
        if model == MINMAX:
            # seed 002: the running extremes of every raw sample since clear() (what users
            # know; unlike the buffer they never forget a transient - clear() does)
            lo = self._lo[:]
            hi = self._hi[:]
            try:
                yield from solve.minmax_steps(lo, hi, c, s, r)
            except solve.SolveError as e:
                _reject(e.reason, e.detail)
            v2, h2, b_q16, fe, w, one = r[0]
            offset = [rdiv(v2[i], 2) for i in range(3)]
            yield
            # the samples' geometry, judged as for the 4-element fit of the same sums
            f = solve.Fit(4)
            try:
                yield from solve.fit_steps(c, s, 4, f, self._check_rho)
            except solve.SolveError as e:
                _reject(REASON_PLANAR, e.detail)
        else:
            f = solve.Fit(model)
            try:
                yield from solve.fit_steps(c, s, model, f, self._check_rho)
            except solve.SolveError as e:
                _reject(e.reason, e.detail)
            one = 1 << solve.SQRT_FRAC_BITS
            if model == 4:
                w = [[one, 0, 0], [0, one, 0], [0, 0, one]]
            else:
                res = [None, 0]
                yield from solve.invw_steps(f.a2, f.det_a2, res)
                w = res[0]
                if w is None:
                    _reject(REASON_SINGULAR, "W^-1 = A^1/2 did not converge")
            yield
            yield from solve.field_q16_steps(f.k2_num, f.k2_den, f.det_a2, r)
            b_q16 = r[0]
            yield
            yield from solve.fit_error_steps(f, r)
            fe = r[0]
            yield
            offset = [rdiv(f.v_num[i], f.v_den) for i in range(3)]
        yield
        yield from solve.q15_steps(w, solve.SQRT_FRAC_BITS, r)
        invw = r[0]
        yield
        yield from solve.field_out_steps(invw, b_q16, r)
        field_out = r[0]
        field = rdiv(b_q16, 1 << solve.B_FRAC_BITS)
        yield
        for i in range(3):
            if not -32768 <= offset[i] <= 32767:
                _reject(REASON_OFFSET_OUT_OF_RANGE, "V = (%d, %d, %d) counts is outside int16"
                        % (offset[0], offset[1], offset[2]))
        yield from self.buffer.coverage_steps(offset[0], offset[1], offset[2], r)
        cov = r[0]
        yield
        if cov < _MIN_COVERAGE[model]:
            _reject(REASON_LOW_COVERAGE, "%d %% of sphere regions covered around V, model %s "
                    "needs %d %%" % (cov, model, _MIN_COVERAGE[model]))
        yield from _cond_steps(invw, r)
        cond = r[0]
        yield
        if cond is None or cond > _MAX_SOFT_IRON_COND_X100 or field_out <= 0:
            _reject(REASON_SOFT_IRON_OUT_OF_RANGE, "W^-1 eigenvalue ratio %s/100 > %d/100"
                    % (cond, _MAX_SOFT_IRON_COND_X100))
        cpg = self.counts_per_gauss
        if cpg:
            # B [uT] = field * 100 / cpg
            if not _MIN_FIELD_UT * cpg <= field * 100 <= _MAX_FIELD_UT * cpg:
                _reject(REASON_FIELD_OUT_OF_RANGE, "B = %d counts = %d uT at %d counts/G, not "
                        "in %d..%d uT" % (field, rdiv(field * 100, cpg), cpg, _MIN_FIELD_UT,
                                          _MAX_FIELD_UT))
        elif field < _MIN_FIELD_COUNTS:
            _reject(REASON_FIELD_OUT_OF_RANGE, "B = %d counts < %d: too coarse to calibrate"
                    % (field, _MIN_FIELD_COUNTS))
        if fe > self.max_fit_error:
            _reject(REASON_FIT_ERROR_HIGH, "fit error %d.%02d %% > %d.%02d %%"
                    % (fe // 100, fe % 100, self.max_fit_error // 100, self.max_fit_error % 100))
        cur = self.current
        if cur.model is not None:
            aged = self.aged_fit_error()
            upgrade = _ORDER[model] > _ORDER[cur.model] and fe <= _FIT_ERROR_UPGRADE
            # A fit over more of the sphere is worth a somewhat higher fit error: the first
            # fit, on ~100 samples from part of it, would otherwise never be replaced.
            wider = (cov >= cur.coverage + _COVERAGE_GAIN and _ORDER[model] >= _ORDER[cur.model]
                     and fe * _COVERAGE_FIT_DEN <= aged * _COVERAGE_FIT_NUM)
            if fe >= aged and not upgrade and not wider:
                _reject(REASON_NOT_BETTER, "fit error %d.%02d %% at %d %% coverage is not "
                        "better than the current calibration's %d.%02d %% (aged) at %d %% "
                        "(model %s)" % (fe // 100, fe % 100, cov, aged // 100, aged % 100,
                                        cur.coverage, cur.model))
        result = Calibration(model=model, offset=offset, invw=invw, field=field,
                             field_out=field_out, fit_error=fe, samples=n, coverage=cov)
        if accept:
            self.current = result
            self._age_s = 0
        return result
