"""Host-side model of what MotionCal does with the Raw lines it accepts, for tests only
(numpy floats): its point buffer, its 10-element fit and its four quality figures, as
/work/shared/notes/motioncal.md sections 2 and 3 describe them (rawdata.c, magcal.c,
quality.c, gui.cpp), re-derived here, not copied.

    m = MotionCalModel()
    for rec in parser.raw: m.add(rec)     # Raw records (9 int16) as tests/motioncal_ref.py parses
    m.fit                                 # (V uT, B uT, invW 3x3) or None
    m.send_cal_ok()                       # gaps < 15, variance < 4.5, wobble < 4, fit < 5

Simplifications (stated, and why they do not flatter the board): the buffer replaces one
point of the closest pair when full (MotionCal also sometimes drops the worst-fitting point
once gaps < 25, which only helps the fit); the solver runs every 20th line, as MotionCal's,
and a trial is accepted as its FitErrorAge rule says (no calibration yet, or a fit error at
or below the aged one, aged x1.02 per run), with B within 22..67 uT. Only the 10-element
solver is modelled: Send Cal needs a fit error < 5 %, which the 4- and 7-element solvers'
floors (12 %, 7.5 %) never reach.
"""
import numpy as np

BUF = 650                   # MAGBUFFSIZE
SOLVE_EVERY = 20            # MagCal_Run() on every 20th Raw line
MIN_POINTS_10 = 150         # 10-element solver from 150 points
B_MIN_UT, B_MAX_UT = 22.0, 67.0
AGE = 1.02
UT_PER_COUNT = 0.1


def fit10(p):
    """MotionCal's 10-element model on points p (N x 3, uT): the quadric's coefficients are
    the eigenvector of the smallest eigenvalue of the normal matrix (in centred, scaled
    units for conditioning); V = -A^-1 g / 2, A scaled to det 1, invW = A^1/2, B from the
    constant term. Returns (V, B, invW, fit error %) or None; fit error = 100 sqrt(mean r^2)
    / (2 B^2) with r = |invW (p - V)|^2 - B^2 (notes section 2's form)."""
    c = p.mean(axis=0)
    s = 50.0
    u = (p - c) / s
    x, y, z = u[:, 0], u[:, 1], u[:, 2]
    X = np.column_stack([x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, x, y, z,
                         np.ones_like(x)])
    w, vec = np.linalg.eigh(X.T @ X)
    a = vec[:, 0]
    A = np.array([[a[0], a[3], a[4]], [a[3], a[1], a[5]], [a[4], a[5], a[2]]])
    g = a[6:9]
    j = a[9]
    if np.linalg.det(A) < 0:
        A, g, j = -A, -g, -j
    ev = np.linalg.eigvalsh(A)
    if ev.min() <= 0:
        return None
    vu = -np.linalg.solve(A, g) / 2
    k = vu @ A @ vu - j
    d = np.linalg.det(A) ** (1.0 / 3)
    An = A / d
    b2 = k / d
    if b2 <= 0:
        return None
    e, q = np.linalg.eigh(An)
    invw = q @ np.diag(np.sqrt(e)) @ q.T
    invw = (invw + invw.T) / 2
    r = np.einsum("ij,jk,ik->i", u - vu, An, u - vu) - b2
    fe = 100.0 * np.sqrt(np.mean(r * r)) / (2 * b2)
    return c + s * vu, s * np.sqrt(b2), invw, fe


def _regions():
    # 100 equal-area regions: caps above |lat| 78.52 deg (1 each), bands 42.84..78.52
    # (15 each), bands within +-42.84 (34 each); (lat_lo, lat_hi, n) from south to north
    return [(-90.0, -78.52, 1), (-78.52, -42.84, 15), (-42.84, 0.0, 34), (0.0, 42.84, 34),
            (42.84, 78.52, 15), (78.52, 90.0, 1)]


_BANDS = _regions()
_IDEAL = []
for _lo, _hi, _n in _BANDS:
    for _i in range(_n):
        if _n == 1:
            _IDEAL.append((0.0, 0.0, 1.0 if _lo > 0 else -1.0))
            continue
        _lat = np.radians((_lo + _hi) / 2)
        _lon = np.radians((_i + 0.5) * 360.0 / _n - 180.0)
        _IDEAL.append((np.cos(_lat) * np.cos(_lon), np.cos(_lat) * np.sin(_lon), np.sin(_lat)))
_IDEAL = np.array(_IDEAL)


def region_of(bc):
    """The region index (0..99) of each calibrated point's direction."""
    r = np.linalg.norm(bc, axis=1)
    lat = np.degrees(np.arcsin(np.clip(bc[:, 2] / r, -1, 1)))
    lon = np.degrees(np.arctan2(bc[:, 1], bc[:, 0]))
    idx = np.zeros(len(bc), dtype=int)
    base = 0
    for lo, hi, n in _BANDS:
        inb = (lat >= lo) & (lat <= hi) if hi == 90.0 else (lat >= lo) & (lat < hi)
        k = np.minimum(((lon[inb] + 180.0) * n / 360.0).astype(int), n - 1)
        idx[inb] = base + k
        base += n
    return idx


def quality(points_ut, fit):
    """(gaps, variance %, wobble %) of the buffer calibrated with fit (V, B, invW, ...)."""
    V, B, invw = fit[0], fit[1], fit[2]
    bc = (points_ut - V) @ invw.T
    mag = np.linalg.norm(bc, axis=1)
    reg = region_of(bc)
    counts = np.bincount(reg, minlength=100)
    gaps = float(np.sum(np.where(counts == 0, 1.0, np.where(counts == 1, 0.2,
                                                             np.where(counts == 2, 0.01, 0)))))
    variance = 100.0 * mag.std() / mag.mean()
    R = mag.mean()
    occ = np.nonzero(counts)[0]
    sums = np.zeros((100, 3))
    np.add.at(sums, reg, bc)
    cent = sums[occ] / counts[occ][:, None]
    wobble = 100.0 * np.linalg.norm((cent - _IDEAL[occ] * R).mean(axis=0)) / R
    return gaps, variance, wobble


class MotionCalModel:
    """The buffer, the solver cadence and the Send Cal rule (module docstring)."""

    def __init__(self):
        self.p = np.zeros((BUF, 3))
        self.n = 0
        self.nn_d = np.full(BUF, np.inf)
        self.nn_i = np.zeros(BUF, dtype=int)
        self.lines = 0
        self.fit = None
        self.age = None
        self.figures = None

    def _nearest(self, k):
        d = np.linalg.norm(self.p[:self.n] - self.p[k], axis=1)
        d[k] = np.inf
        i = int(np.argmin(d))
        self.nn_d[k], self.nn_i[k] = d[i], i

    def _put(self, k, pt):
        self.p[k] = pt
        n = self.n
        d = np.linalg.norm(self.p[:n] - pt, axis=1)
        d[k] = np.inf
        stale = np.nonzero(self.nn_i[:n] == k)[0]
        closer = d < self.nn_d[:n]
        self.nn_d[:n][closer] = d[closer]
        self.nn_i[:n][closer] = k
        i = int(np.argmin(d))
        self.nn_d[k], self.nn_i[k] = d[i], i
        for s in stale:
            if s != k:
                self._nearest(s)

    def add(self, rec):
        """One accepted Raw record: the buffer, then the solver every 20th line."""
        pt = np.array(rec[6:9], dtype=float) * UT_PER_COUNT
        if self.n < BUF:
            self.n += 1
            self._put(self.n - 1, pt)
        else:
            self._put(int(np.argmin(self.nn_d)), pt)  # one point of the closest pair
        self.lines += 1
        if self.lines % SOLVE_EVERY == 0:
            self._solve()

    def _solve(self):
        if self.age is not None:
            self.age *= AGE
        if self.n < MIN_POINTS_10:
            return
        t = fit10(self.p[:self.n])
        if t is None or not B_MIN_UT <= t[1] <= B_MAX_UT:
            return
        if self.fit is None or t[3] <= self.age:
            self.fit = t
            self.age = t[3]
        self.figures = quality(self.p[:self.n], self.fit) + (self.fit[3],)

    def send_cal_ok(self):
        """gui.cpp's rule on the latest figures: gaps < 15, variance < 4.5, wobble < 4,
        fit error < 5 (%)."""
        f = self.figures
        return f is not None and f[0] < 15 and f[1] < 4.5 and f[2] < 4 and f[3] < 5
