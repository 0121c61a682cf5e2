"""The calibrator: collects samples and orchestrates the solve (AN4246's pipeline)."""
#     from firmware.calibrate.calibrator import Calibrator
#     cal = Calibrator(model=10, counts_per_gauss=12000)   # QMC5883L at +-2 G
#     cal.add(x, y, z)                  # every raw sample; True when the buffer kept it
#     c = cal.solve()                   # a Calibration, or raises CalibrationRejected(.reason)
#     c.correct(raw, out)               # out = InvW (raw - V) >> 15
#
# solve_steps() is the same solve as a generator, at most solve.SLICE_OPS long-int operations
# per next() (tests/test_slices.py). The pipeline and the min/max model: docs/design.md (module
# notes, calibrator); the API: docs/api.md (calibration).
from array import array
from sys import modules

from firmware.calibrate import accum
from firmware.calibrate import acceptance
from firmware.calibrate.acceptance import (DEFAULT_MAX_FIT_ERROR, MIN_SAMPLES, MIN_SAMPLES_GEOMETRY,
                                 REASON_PLANAR, REASON_SINGULAR, reject)
from firmware.calibration import MINMAX, MODELS, UNCALIBRATED, Calibration, correct
from firmware.compat import compiled_here, const, drop, room
from firmware.errors import CalibrationRejected
from firmware.fixedpoint import rdiv
from firmware.calibrate.samples import (N_REGIONS, NOT_INT, REJECTED, REPLACED, SampleBuffer,
                              bad_sample, region, separation_for)

_RAIL_HI = const(32767)        # int16 rails: a clipping chip reads its axis as one of them
_RAIL_LO = const(-32768)
DEFAULT_CAPACITY = const(300)   # samples (ArduPilot keeps 300, NXP 340): 1.8 KB of int16
# Separation: a whole sphere saturates the buffer at 3/4 of its capacity (samples.py's
# advice), 225 samples by default, about 0.19 R apart; one great circle then holds ~33.
_FILL_NUM = const(3)
_FILL_DEN = const(4)
_EXPECTED_FIELD_MG = const(500)     # mG: mid-latitude Earth field, for the default separation
_SEPARATION_GROWTH = const(5)       # auto separation: re-set only when it grows by 5/4
_FIT_ERROR_DOUBLING_S = const(60000)  # aging: NXP's e-folding time of 24 h = 59890 s x ln 2
# solve_steps(): slices per next() by default: one slice is at most solve.SLICE_OPS long-int
# operations (~1 ms on an RP2040); the caller decides how many fit between samples (the app
# runs a quarter of the sample period's worth per step, firmware/app.py).
DEFAULT_SLICE_GROUP = const(1)
solve = None  # firmware.calibrate.solve, loaded by the first solve (release_solver() lets it go)


def _load_solver():
    global solve
    if solve is None:
        from firmware.calibrate import solve as s
        solve = s


def release_solver():
    """Let the solver's code go until the next solve loads it again: the calibration program
    does so between solves, so saving a fit never holds the solver too
    (firmware/calibrate/program.py). Not where the board compiled it from source: it would
    compile again (compat.compiled_here)."""
    global solve
    m = solve or modules.get("firmware.calibrate.solve")  # the acceptance gate loads it too
    if m is None or compiled_here(m):
        return
    solve = None
    drop("calibrate.solve")



_CONSISTENCY_CHUNK = const(2)  # newer samples per slice of the consistency sums' second pass
#                                (~14 long-int ops each once the sums pass 2**30); the first
#                                pass runs one sample through region() a slice
_NO_REGION = const(255)


def _widen(e, i, v):
    # extremes e[i] (low) and e[i + 3] (high) take v in; True when one moved
    if v < e[i]:
        e[i] = v
        return True
    if v > e[i + 3]:
        e[i + 3] = v
        return True
    return False


def _check_int(name, v, lo, unit):
    # constructor arguments: an int >= lo in the stated unit (a float such as 1.5 is ambiguous)
    if type(v) is not int:
        raise TypeError("%s=%r: expected an int in %s" % (name, v, unit))
    if v < lo:
        raise ValueError("%s=%d: expected >= %d, in %s" % (name, v, lo, unit))


class Calibrator:
    """Collects samples and solves for a Calibration (see docs/design.md, module notes)."""
    # model: 'minmax', 4, 7, 10, or 'auto' (the highest model whose sample minimum is met).
    # capacity: samples held (DEFAULT_CAPACITY on a board; the desktop tool uses more).
    # separation: counts between held samples; None derives it from counts_per_gauss
    #   (a 50 uT field) or, without it, from the running half-ranges of the raw data.
    # counts_per_gauss: the sensor's sensitivity, enabling the 10 .. 90 uT field check.
    # current: the calibration in force (e.g. loaded from storage); new fits must beat it.
    # max_fit_error: hundredths of a percent (an int: 150 = 1.5 %); TypeError otherwise.
    # .expected_field: the field model's |B| in raw counts where the board is (set by
    #   firmware/field/location.py), or None; when set, a fit whose B is off by more than
    #   acceptance.FIELD_MATCH_PCT is refused (field_mismatch).
    # overflow: a chip's overflow marker (the HMC5883L's -4096), or None. A sample with an axis
    #   at it or at the int16 rails (32767, -32768: a clipping chip) never enters a fit; add()
    #   refuses it and counts it in .railed.

    def __init__(self, model=10, capacity=DEFAULT_CAPACITY, separation=None,
                 counts_per_gauss=None, current=None, max_fit_error=DEFAULT_MAX_FIT_ERROR,
                 overflow=None):
        if model not in MODELS and model != "auto":
            raise ValueError("model %r: expected 'minmax', 4, 7, 10 or 'auto'" % (model,))
        _check_int("max_fit_error", max_fit_error, 1,
                   "hundredths of a percent, e.g. 150 for 1.5 %")
        if counts_per_gauss is not None:
            _check_int("counts_per_gauss", counts_per_gauss, 1, "counts per gauss, e.g. 12000")
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
        self._ext = array("h", (0, 0, 0, 0, 0, 0))  # raw extremes: lo x, y, z, then hi
        self.slice_group = DEFAULT_SLICE_GROUP
        self._strict = True
        self.overridden = []  # refusals a solve(checks=False) went past: (reason, detail)
        self.expected_field = None
        self.overflow = overflow if overflow is not None else _RAIL_LO
        self.railed = 0       # samples refused at the rails or the overflow marker
        room(self)  # add() runs every sample (firmware/compat.py room)

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

    def add(self, x, y, z):
        """Offer one raw sample (int16 counts). O(1); returns True if the buffer kept it."""
        # A rejected sample (the usual case) allocates nothing, not even a call frame: each
        # step below keeps its arguments, locals and stack within the 11 words MicroPython
        # keeps on the C stack. Raises ValueError for a value outside int16 and TypeError
        # naming x, y or z when one is not an int, before anything changes. A sample at a rail
        # (int16's, or the overflow marker) is refused and counted in .railed.
        o = self.overflow
        if (x == _RAIL_HI or y == _RAIL_HI or z == _RAIL_HI or x == _RAIL_LO or y == _RAIL_LO
                or z == _RAIL_LO or x == o or y == o or z == o):
            self.railed += 1
            return False
        r = self.buffer.offer(x, y, z)
        if r != REJECTED:
            if r == REPLACED:
                self._evict()
            elif r == NOT_INT:  # checked off the common (rejected) path
                raise bad_sample(x, y, z)
            self.moments.add(x, y, z)
        if self._fresh:
            self._first(x, y, z)
        elif self._extend(x, y, z) and self._auto:
            self._grow_separation()
        return r != REJECTED

    def _evict(self):
        e = self.buffer.evicted
        self.moments.sub(e[0], e[1], e[2])

    def _first(self, x, y, z):
        e = self._ext
        self._fresh = False
        e[0] = e[3] = x
        e[1] = e[4] = y
        e[2] = e[5] = z

    def _extend(self, x, y, z):
        # the running extremes (min/max model, auto separation); True when one moved
        e = self._ext
        return _widen(e, 0, x) | _widen(e, 1, y) | _widen(e, 2, z)

    def _grow_separation(self):
        # radius estimate: mean half-range of the raw data seen so far
        e = self._ext
        r = (e[3] - e[0] + e[4] - e[1] + e[5] - e[2]) // 6
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
        e = self._ext
        return ((e[0] + e[3]) >> 1, (e[1] + e[4]) >> 1, (e[2] + e[5]) >> 1)

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
                if n >= MIN_SAMPLES[m]:
                    return m
            return 4
        if model not in MODELS:
            raise ValueError("model %r: expected 'minmax', 4, 7, 10 or 'auto'" % (model,))
        return model

    def extremes(self):
        """((x, y, z) lowest, (x, y, z) highest) raw value of every sample since clear()."""
        e = self._ext
        return (e[0], e[1], e[2]), (e[3], e[4], e[5])

    def _check_rho(self, f):
        self._verify(acceptance.check_rho, f.rho_min_ppm,
                     solve.column_degree(f.model, f.rho_col) == 1, f.model,
                     solve.column_name(f.model, f.rho_col))

    def _verify(self, check, *args):
        # one acceptance check; with checks off a refusal is noted in .overridden instead
        try:
            check(*args)
        except CalibrationRejected as e:
            if self._strict:
                raise
            self.overridden.append((e.reason, e.detail))

    def solve(self, model=None, accept=True, checks=True):
        # Solve now; returns the new Calibration (also made .current) or raises
        # CalibrationRejected. accept=False runs the checks but leaves .current alone.
        # checks=False (the desktop tool's --force) returns the fit even where an acceptance
        # check refuses it, each refusal noted in .overridden as (reason, detail); a fit the
        # solver cannot compute (singular, too few samples to solve at all, V outside int16)
        # still raises.
        g = self.solve_steps(model, accept, checks=checks)
        while True:
            try:
                next(g)
            except StopIteration as e:
                return e.value

    def solve_steps(self, model=None, accept=True, group=None, checks=True):
        # The solve as a generator doing bounded work per next() (for the app's loop):
        #     job = cal.solve_steps()
        #     ... each tick:  next(job)   -> StopIteration when done (.value = Calibration),
        #                                    CalibrationRejected on refusal.
        # One next() runs `group` slices (None: .slice_group), each at most solve.SLICE_OPS
        # long-int operations or samples.COVERAGE_CHUNK samples of the coverage count
        # (tests/test_slices.py); group=1 gives the finest slices, for a caller that runs as
        # many as its sample period allows. The result does not depend on the slicing.
        # The moment sums are copied at the start, so samples added meanwhile do not disturb
        # the fit (coverage is counted on the buffer as each slot is reached, at the end).
        k = self.slice_group if group is None else group
        if k < 1:
            raise ValueError("slice group %d < 1" % k)
        job = self._solve_slices(model, accept, checks)
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

    def _solve_slices(self, model, accept, checks=True):
        # the solve as named steps; each yield ends a slice (see solve_steps)
        _load_solver()
        self._strict = checks
        self.overridden = []
        model = self._pick_model(model)
        n = self.buffer.count
        c, s = self.moments.snapshot()
        yield from self._enough_samples(model, n, c, s)
        yield
        r = [None]
        if model == MINMAX:
            yield from self._fit_minmax(c, s, r)
        else:
            yield from self._fit_model(model, c, s, r)
        offset, w, b_q16, fe = r[0]
        yield
        return (yield from self._finish(model, n, offset, w, b_q16, fe, accept))

    def _enough_samples(self, model, n, c, s):
        need = MIN_SAMPLES[model]
        if n >= need:
            return
        # A flat spin never fills the buffer: say "planar" when that is the cause, so the
        # user is told to turn the board over rather than to keep spinning.
        if n >= MIN_SAMPLES_GEOMETRY:
            for gm in ((4, model) if model in (7, 10) and n > 2 * model else (4,)):
                f = solve.Fit(gm)
                planar = False
                try:
                    yield from solve.fit_steps(c, s, gm, f)
                except solve.SolveError as e:
                    planar = e.reason == REASON_PLANAR
                if f.rho_min_ppm is not None and f.rho_min_ppm < acceptance.rho_limit(
                        solve.column_degree(f.model, f.rho_col) == 1, f.model):
                    planar = True
                if planar:
                    self._verify(acceptance.flat_spin, n, model, need)
                    break
        self._verify(acceptance.check_samples, n, model)

    def _fit_minmax(self, c, s, r):
        # the running extremes of every raw sample since clear() (what users know; unlike the
        # buffer they never forget a transient - clear() does)
        e = self._ext
        try:
            yield from solve.minmax_steps([e[0], e[1], e[2]], [e[3], e[4], e[5]], c, s, r)
        except solve.SolveError as x:
            reject(x.reason, x.detail)
        v2, h2, b_q16, fe, w, one = r[0]
        offset = [rdiv(v2[i], 2) for i in range(3)]
        yield
        # the samples' geometry, judged as for the 4-element fit of the same sums
        f = solve.Fit(4)
        try:
            yield from solve.fit_steps(c, s, 4, f, self._check_rho)
        except solve.SolveError as x:
            self._verify(reject, REASON_PLANAR, x.detail)
        r[0] = (offset, w, b_q16, fe)

    def _fit_model(self, model, c, s, r):
        # AN4246's 4-, 7- or 10-element least squares, then W^-1 = A^1/2 (eq. 33)
        f = solve.Fit(model)
        try:
            yield from solve.fit_steps(c, s, model, f, self._check_rho)
        except solve.SolveError as x:
            reject(x.reason, x.detail)
        one = 1 << solve.SQRT_FRAC_BITS
        if model == 4:
            w = [[one, 0, 0], [0, one, 0], [0, 0, one]]
        else:
            res = [None, 0]
            yield from solve.invw_steps(f.a2, f.det_a2, res)
            w = res[0]
            if w is None:
                reject(REASON_SINGULAR, "W^-1 = A^1/2 did not converge")
        yield
        yield from solve.field_q16_steps(f.k2_num, f.k2_den, f.det_a2, r)
        b_q16 = r[0]
        yield
        yield from solve.fit_error_steps(f, r)
        fe = r[0]
        r[0] = ([rdiv(f.v_num[i], f.v_den) for i in range(3)], w, b_q16, fe)

    def _consistency(self, offset, invw, field_out, n):
        # acceptance.check_consistency: the hard-iron change from the older to the newer half
        # (in the order kept), estimated where both halves saw the same directions; the sums
        # are taken on b >> s, |B| >> s < 2**11
        s = 0
        while field_out >> s >= 1 << 11:
            s += 1
        k = array("h", tuple(invw) + tuple(offset))
        r = [None]
        yield from _consistency_sums(self.buffer, k, s, field_out >> s, r)
        m, g, used, da, ee = r[0]
        # the sample noise sigma^2 = spread / (PI4_DEN (n - 1)^2): sigma from the mean absolute
        # difference of consecutive samples, (pi / 4) mean|d|^2 (d has variance 2 sigma^2)
        spread = acceptance.PI4_NUM * da * da
        # at least one unit of radius (2 f in e): the sums' resolution after >> s
        f4 = acceptance.PI4_DEN * (n - 1) * (n - 1) * 4 * (field_out >> s) * (field_out >> s)
        spread = f4 if spread < f4 else spread
        if used >= 3:
            adj = solve.adj3(m)
            yield
            det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0]
            used = 0 if acceptance.half_is_flat(det, m[0][0] + m[1][1] + m[2][2]) else used
        if used < 3:
            # fewer than 3 directions seen by both halves, or near a plane: no verdict, and
            # no fit while its residual says more than the noise (acceptance.check_comparable)
            self._verify(acceptance.check_comparable, n, ee, spread)
            return
        p = solve.mat_vec3(adj, g)
        yield
        # the change is p / (2 det) (|.|^2 = d2 / den2); its chi-square against the sample
        # noise, g^T M^-1 g / sigma^2, is chi / noise; ee is the fit's sum of squared residuals
        d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
        chi = (g[0] * p[0] + g[1] * p[1] + g[2] * p[2]) * acceptance.PI4_DEN * (n - 1) * (n - 1)
        self._verify(acceptance.check_consistency, d2, 4 * det * det, field_out >> s, n,
                     chi, spread * det, ee, spread)

    def _finish(self, model, n, offset, w, b_q16, fe, accept):
        # InvW in Q15, the checks of firmware/calibrate/acceptance.py in order, then the record
        r = [None]
        yield from solve.q15_steps(w, solve.SQRT_FRAC_BITS, r)
        invw = r[0]
        yield
        yield from solve.field_out_steps(invw, b_q16, r)
        field_out = r[0]
        field = rdiv(b_q16, 1 << solve.B_FRAC_BITS)
        yield
        acceptance.check_offset(offset)
        yield from self.buffer.coverage_steps(offset[0], offset[1], offset[2], r)
        cov = r[0]
        yield
        self._verify(acceptance.check_coverage, cov, model)
        yield from solve.cond_steps(invw, r)
        yield
        if field_out <= 0:  # not even a forced fit can correct with this InvW
            reject(REASON_SINGULAR, "W^-1 maps the fitted ellipsoid to a zero field")
        self._verify(acceptance.check_soft_iron, r[0], field_out)
        self._verify(acceptance.check_field, field, self.counts_per_gauss)
        if self.expected_field:
            self._verify(acceptance.check_expected_field, field, self.expected_field)
        self._verify(acceptance.check_fit_error, fe, self.max_fit_error)
        if self.current.model is not None:
            self._verify(acceptance.check_better, model, fe, cov, self.current,
                         self.aged_fit_error())
        if model == 10:
            yield from self._consistency(offset, invw, field_out, n)
        result = Calibration(model=model, offset=offset, invw=invw, field=field,
                             field_out=field_out, fit_error=fe, samples=n,
                             coverage=cov)
        if accept:
            self.current = result
            self._age_s = 0
        return result


room(Calibrator)  # its methods' table too (firmware/compat.py room)


def _consistency_sums(buf, k, s, f, out):
    # The change of hard iron c between the older and the newer half of the held samples (in
    # the order kept), corrected with k (InvW, V: calibration.correct), shifted right by s,
    # compared within each equal-area sphere region (samples.region) that both halves saw:
    # e = |b|^2 - f^2 = a_r + 2 b.c [newer] + noise, a free level a_r per region absorbing
    # whatever misfit depends on the direction (least squares with region effects). Pass 1
    # sums, per region, the samples, the newer ones, sum e and the newer ones' sum b, and
    # da = sum |e' - e| over consecutive samples (the noise) and ee = sum e^2; pass 2, over
    # the newer samples in shared regions, S = sum b b^T and G = sum e b. Then
    # M = S - sum_r P P^T / N_r and g = G - sum_r P E_r / N_r give M c = g / 2.
    # out[0] = (M, g, shared regions, da, ee); _CONSISTENCY_CHUNK samples a slice.
    n = buf.count
    h = n // 2
    reg = bytearray(n)                     # each sample's region (_NO_REGION: none)
    cnt = array("H", bytes(2 * N_REGIONS))  # samples per region
    new = array("H", bytes(2 * N_REGIONS))  # newer samples per region
    pb = array("i", bytes(12 * N_REGIONS))  # sum b of the newer samples, per region
    es = [0] * N_REGIONS                   # sum e, per region
    raw = array("h", (0, 0, 0))
    b = array("h", (0, 0, 0))
    f2 = f * f
    da = 0
    ee = 0
    prev = 0
    for age in range(n):
        buf.sample(buf.slot_by_age(age), raw)
        correct(k, raw, b)
        x = b[0] >> s
        y = b[1] >> s
        z = b[2] >> s
        e = x * x + y * y + z * z - f2
        ee += e * e
        if age:
            da += e - prev if e > prev else prev - e
        prev = e
        r = region(x, y, z)
        if r < 0:
            reg[age] = _NO_REGION
        else:
            reg[age] = r
            cnt[r] += 1
            es[r] += e
            if age >= h:
                new[r] += 1
                j = 3 * r
                pb[j] += x
                pb[j + 1] += y
                pb[j + 2] += z
        yield
    t = [0, 0, 0, 0, 0, 0, 0, 0, 0]  # S: xx xy xz yy yz zz, then G: x y z
    j = 0
    for age in range(h, n):
        r = reg[age]
        if r != _NO_REGION and cnt[r] > new[r]:
            buf.sample(buf.slot_by_age(age), raw)
            correct(k, raw, b)
            x = b[0] >> s
            y = b[1] >> s
            z = b[2] >> s
            e = x * x + y * y + z * z - f2
            t[0] += x * x
            t[1] += x * y
            t[2] += x * z
            t[3] += y * y
            t[4] += y * z
            t[5] += z * z
            t[6] += e * x
            t[7] += e * y
            t[8] += e * z
            j += 1
            if j == _CONSISTENCY_CHUNK:
                j = 0
                yield
    used = 0
    for r in range(N_REGIONS):
        c = cnt[r]
        if new[r] == 0 or c == new[r]:
            continue
        used += 1
        q = 3 * r
        px = pb[q]
        py = pb[q + 1]
        pz = pb[q + 2]
        t[0] -= rdiv(px * px, c)
        t[1] -= rdiv(px * py, c)
        t[2] -= rdiv(px * pz, c)
        t[3] -= rdiv(py * py, c)
        t[4] -= rdiv(py * pz, c)
        t[5] -= rdiv(pz * pz, c)
        t[6] -= rdiv(px * es[r], c)
        t[7] -= rdiv(py * es[r], c)
        t[8] -= rdiv(pz * es[r], c)
        yield
    m, g = _sym(t)
    out[0] = (m, g, used, da, ee)


def _sym(t):
    return ([[t[0], t[1], t[2]], [t[1], t[3], t[4]], [t[2], t[4], t[5]]], [t[6], t[7], t[8]])


# --- the calibration behind the app's loop ------------------------------------------------
SOLVE_EVERY = const(25)       # kept samples between solves: ~1/9 of a full sphere (225 held)
_SOLVE_IDLE_US = const(60000000)   # 60 s without a solve: solve again on what is held
_QUIET_US = const(3000000)    # 3 s without a kept sample after some were kept: solve now
_SLICE_US = const(1000)       # budget per solver slice (make bench: ~1-2 ms on an RP2040)
_SOLVE_SHARE = const(4)       # slices per step = period / (4 x _SLICE_US), at least one
REASON_SOLVER_ERROR = "solver_error"  # the solver raised something unexpected
REASON_NO_MEMORY = "no_memory"        # MemoryError during a solve


class Collector:
    """A Calibrator run in the background of a sample loop (firmware/app.py's)."""
    # feed(raw) offers a sample; tick(dt_us) advances its timers; when due() a solve starts
    # and slice() runs one bounded slice of it, returning the accepted Calibration when one
    # comes out (else None). The solve policy, as the app documents it:
    # - a solve starts when solve_every samples have been KEPT since the last one started
    #   (new information, not time); or when samples were kept since then but none for
    #   _QUIET_US (the user stopped moving: say now why it is not enough, e.g. "planar" after
    #   half a turn); or when none ran for _SOLVE_IDLE_US and samples are held (aging can make
    #   a fit on the same samples acceptable).
    # - the configured model is tried; while no calibration of 4 elements or more is in force
    #   (or while relearning) a refusal for too_few_samples is followed by a 4-element attempt:
    #   hard iron is the largest error and a 4-element fit needs 40 samples where 10 elements
    #   need 100, so the user gets a usable heading early; the Calibrator's own rule then lets
    #   the 10-element fit replace it. Once a 4-element fit is in force the fallback stops, so
    #   .last_reason keeps saying what the configured model still lacks.
    # Attributes: calibrator, accepted, refused, solves, last_reason, last_detail, last_model,
    # relearning, job (the running solve or None), job_model.
    QUIET_US = _QUIET_US  # no new direction for 3 s: the callers' "done" and "planar" waits too

    def __init__(self, model=10, capacity=DEFAULT_CAPACITY, counts_per_gauss=None,
                 current=None, solve_every=SOLVE_EVERY, fallback=True, overflow=None):
        self.calibrator = Calibrator(model=model, capacity=capacity,
                                     counts_per_gauss=counts_per_gauss, current=current,
                                     overflow=overflow)
        self.model = model
        self.solve_every = solve_every
        self.fallback = fallback
        self.job = None
        self.job_model = None
        self.next_model = None     # a fallback model to try at the next slice
        self.kept = 0              # samples kept since the last solve started
        self.idle_us = 0
        self.quiet_us = 0          # us since the last kept sample (while kept > 0)
        self.since_kept_us = 0     # us since the buffer last kept a sample (new direction)
        self.accepted = 0
        self.refused = 0
        self.solves = 0
        self.last_reason = None
        self.last_detail = None
        self.last_model = None     # the model of the last solve attempt
        self.relearning = False
        self.pairs = None          # firmware.calibrate.mounting.Pairs, set by the session
        self._cov = 0
        self._cov_dirty = True
        room(self)

    def feed(self, raw):
        if self.calibrator.add(raw[0], raw[1], raw[2]):
            self.kept += 1
            self.quiet_us = 0
            self.since_kept_us = 0
            self._cov_dirty = True

    def tick(self, dt):
        if self.idle_us < _SOLVE_IDLE_US:
            self.idle_us += dt
        if self.kept and self.quiet_us < _QUIET_US:
            self.quiet_us += dt
        if self.since_kept_us < _SOLVE_IDLE_US:
            self.since_kept_us += dt

    @property
    def solving(self):
        """A solve runs: its slices are due at the next steps (CompassApp.solving)."""
        return self.job is not None

    def due(self):
        if self.kept >= self.solve_every or self.next_model is not None:
            return True
        if self.quiet_us >= _QUIET_US:
            return True
        return self.idle_us >= _SOLVE_IDLE_US and self.calibrator.count > 0

    def start(self, period_us):
        """Start a solve; returns the slices per step that fit a sample period."""
        m = self.next_model
        self.next_model = None
        if m is None:
            m = self.model
        self.kept = 0
        self.quiet_us = 0
        self.idle_us = 0
        self.solves += 1
        self.job_model = m
        self.last_model = m
        self.job = self.calibrator.solve_steps(m, group=1)
        n = period_us // (_SOLVE_SHARE * _SLICE_US)
        return n if n > 0 else 1

    def slice(self):
        """One bounded slice of the running solve: the accepted Calibration, or None."""
        try:
            next(self.job)
            return None
        except StopIteration as e:
            cal = e.value
        except CalibrationRejected as e:
            self._refused(e.reason, e.detail)
            return None
        except MemoryError:
            self._refused(REASON_NO_MEMORY, "heap exhausted during the solve")
            return None
        except Exception as e:  # noqa: BLE001 - the sample loop must outlive a solver bug
            self._refused(REASON_SOLVER_ERROR, repr(e))
            return None
        self.job = None
        self.idle_us = 0
        self.accepted += 1
        self.relearning = False
        self.last_reason = None  # refusals before an acceptance are no longer news
        self.last_detail = None
        return cal

    def _refused(self, reason, detail):
        self.job = None
        self.refused += 1
        self.idle_us = 0
        m = self.job_model
        cur = self.calibrator.current.model
        if reason == acceptance.REASON_INCONSISTENT:
            # the held samples mix two hard-iron states: drop them, the next fit sees one
            self.calibrator.clear()
            self._cov_dirty = True
        elif reason == acceptance.REASON_TOO_FEW_SAMPLES:
            if (m in (7, 10) and self.fallback
                    and (cur is None or cur == MINMAX or self.relearning)):
                self.next_model = 4
            elif m == 4 and self.last_reason == acceptance.REASON_TOO_FEW_SAMPLES:
                return  # keep the configured model's message: it says what is needed
        self.last_reason = reason
        self.last_detail = detail

    def relearn(self, stale_age_s):
        """The calibration in force no longer fits the board: collect afresh and let any new
        fit replace it (its fit error is aged by stale_age_s)."""
        self.relearning = True
        self.job = None
        self.pairs = None  # taken with the old iron: no mounting check in this session
        self.calibrator.clear()
        self.calibrator.age(stale_age_s)
        self._cov_dirty = True

    def coverage(self):
        """Percent of the sphere covered by the held samples (cached until one is kept)."""
        if self._cov_dirty:
            self._cov = self.calibrator.coverage()
            self._cov_dirty = False
        return self._cov
