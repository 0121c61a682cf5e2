"""The calibration solvers: min/max, 4-, 7- and 10-element fits, exact to the last step."""
#     f = solve.fit(c, sums, 10)               # exact least squares from the 35 moment sums
#     w = solve.invw_from_a2(f.a2, f.det_a2)   # W^-1 = A^1/2, det 1, Q40
#     q = solve.q15_from_invw(w, solve.SQRT_FRAC_BITS)   # InvW, 9 Q15 ints
# (firmware/calibrate/calibrator.py strings these together, with the acceptance checks, time-sliced.)
#
# Models 4, 7, 10 (AN4246 eq. 5): the trace-3 quadric constraint, the exact Bareiss solution,
# W^-1 = A^1/2 by Denman-Beavers on fixed-point long ints, the fit error, Q15 and the
# degeneracy test: docs/design.md (module notes, solve).
from firmware.calibrate.accum import EXPONENTS, INDEX_TABLE, NUM_MOMENTS, index, shifted_steps
from firmware.fixedpoint import bit_length, isqrt, rdiv

from firmware.compat import const

_Q15_ROW_MAX = const(32767)     # largest row absolute sum of InvW (see module doc)
SQRT_FRAC_BITS = const(40)      # W^-1 iteration in Q40: 2**-40 << one Q15 step
_SQRT_MAX_ITER = const(40)      # Denman-Beavers: ~6 iterations for cond(A) 4, ~9 for 1000
B_FRAC_BITS = const(16)         # B kept in Q16 counts between steps
# Time slicing: every *_steps generator does at most SLICE_OPS arithmetic operations on the
# solver's numbers (long ints on a 32-bit board) between two yields. At the bench's ~20 us
# per long-int result on an RP2040 that is <= ~0.8 ms a slice, plus its bytecode (a few
# us on the unix port, x ~160 on the board): a 200 Hz sample loop keeps up while solving.
SLICE_OPS = const(40)
_TWO_256 = 1 << 256             # _bits(): long-int shifts of 256 bits, then 30, then 1
_MUL_CHUNK_BITS = const(256)    # mul_steps(): bits of the second factor per step
_MUL_CHUNK_MASK = (1 << 256) - 1

# Columns of X as polynomials in (dx, dy, dz): tuples of (coefficient, i, j, k).
_COLS = {
    4: (((1, 1, 0, 0),), ((1, 0, 1, 0),), ((1, 0, 0, 1),), ((1, 0, 0, 0),)),
    7: (((1, 2, 0, 0), (-1, 0, 0, 2)), ((1, 0, 2, 0), (-1, 0, 0, 2)),
        ((1, 1, 0, 0),), ((1, 0, 1, 0),), ((1, 0, 0, 1),), ((1, 0, 0, 0),)),
    10: (((1, 2, 0, 0), (-1, 0, 0, 2)), ((1, 0, 2, 0), (-1, 0, 0, 2)),
         ((1, 1, 1, 0),), ((1, 1, 0, 1),), ((1, 0, 1, 1),),
         ((1, 1, 0, 0),), ((1, 0, 1, 0),), ((1, 0, 0, 1),), ((1, 0, 0, 0),)),
}
_Y = ((1, 2, 0, 0), (1, 0, 2, 0), (1, 0, 0, 2))  # |d|^2
# Degree of each column (1: a centre parameter, 2: a shape parameter, 0: the constant).
_DEG = {4: (1, 1, 1, 0), 7: (2, 2, 1, 1, 1, 0), 10: (2, 2, 2, 2, 2, 1, 1, 1, 0)}

_NAMES = {4: ("Vx", "Vy", "Vz", "const"),
          7: ("dx2-dz2", "dy2-dz2", "Vx", "Vy", "Vz", "const"),
          10: ("dx2-dz2", "dy2-dz2", "dxdy", "dxdz", "dydz", "Vx", "Vy", "Vz", "const")}

MODELS = (4, 7, 10)


def column_degree(model, col):
    """1 for a centre parameter, 2 for a shape parameter, 0 for the constant."""
    return _DEG[model][col]


def column_name(model, col):
    return _NAMES[model][col]


def _dot_poly(s, p, q):
    # sum over samples of p(d) * q(d), from the moment sums
    acc = 0
    for a in p:
        for b in q:
            acc += a[0] * b[0] * s[index(a[1] + b[1], a[2] + b[2], a[3] + b[3])]
    return acc


def normal_equations(s, model):
    """(M, r, yy): X^T X (list of rows), X^T Y and Y^T Y from the moment sums `s`."""
    cols = _COLS[model]
    n = len(cols)
    m = [[0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            v = _dot_poly(s, cols[i], cols[j])
            m[i][j] = v
            m[j][i] = v
    r = [_dot_poly(s, col, _Y) for col in cols]
    return m, r, _dot_poly(s, _Y, _Y)


# ---- exact linear algebra -------------------------------------------------------------

def bareiss_step(a, k, prev, m):
    """One pivot of fraction-free elimination on the augmented rows `a` (length m each).

    Eliminates column k below row k; `prev` is the previous pivot (1 for k = 0). Every
    division is exact (Bareiss 1968). Returns the pivot a[k][k] (a leading principal minor).
    """
    p = a[k][k]
    ak = a[k]
    for i in range(k + 1, len(a)):
        ai = a[i]
        f = ai[k]
        for j in range(k + 1, m):
            ai[j] = (p * ai[j] - f * ak[j]) // prev
        ai[k] = 0
    return p


def det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def adj3(m):
    """Adjugate (transposed cofactors): m adj(m) = det(m) I."""
    return [[m[1][1] * m[2][2] - m[1][2] * m[2][1], m[0][2] * m[2][1] - m[0][1] * m[2][2],
             m[0][1] * m[1][2] - m[0][2] * m[1][1]],
            [m[1][2] * m[2][0] - m[1][0] * m[2][2], m[0][0] * m[2][2] - m[0][2] * m[2][0],
             m[0][2] * m[1][0] - m[0][0] * m[1][2]],
            [m[1][0] * m[2][1] - m[1][1] * m[2][0], m[0][1] * m[2][0] - m[0][0] * m[2][1],
             m[0][0] * m[1][1] - m[0][1] * m[1][0]]]


def mat_vec3(m, v):
    return [m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]]


# ---- fits ---------------------------------------------------------------------------------

class Fit:
    """The exact result of one least-squares fit (all integers; rationals as num / den)."""
    # model, n (samples), c (reference centre), D = det(X^T X), beta_num (beta * D),
    # p_num / D (residual sum P), rho_min_ppm (smallest degeneracy ratio rho, parts per
    # million) and rho_col (its column), a2 (3x3), b2, e2 (the quadric scaled by 2D),
    # det_a2, v_num / v_den (centre V in raw counts), k2_num / k2_den (K2).

    def __init__(self, model):
        self.model = model
        self.rho_min_ppm = None
        self.rho_col = None


def _bits(n):
    # bit_length(n), n >= 0, in few long-int shifts: 256 bits, then 30, then small ints
    b = 0
    while n >= _TWO_256:
        n >>= 256
        b += 256
    while n >= 0x40000000:
        n >>= 30
        b += 30
    return b + bit_length(n)


def _weight(nb):
    # cost of one operation on an nb-bit number, in SLICE_OPS units: 1 up to 512 bits, then
    # growing with the size (the unix port's time per long-int operation does)
    return 1 + (nb >> 9)


def isqrt_steps(n, out):
    """Generator: out[0] = fixedpoint.isqrt(n) by the same Newton iterates (from
    2**ceil(bits / 2) down), at most SLICE_OPS operations between yields."""
    if n < 0x40000000:
        out[0] = isqrt(n)  # small ints: the digit-by-digit branch
        return
    nb = _bits(n)
    x = 1 << ((nb + 1) >> 1)
    cost = 3 * _weight(nb)
    used = 24  # _bits of a number below 2**1280 and the shift
    while True:
        if used + cost > SLICE_OPS:
            yield
            used = 0
        y = (x + n // x) >> 1
        used += cost
        if y >= x:
            out[0] = x
            return
        x = y


def icbrt_steps(n, out):
    """Generator: out[0] = fixedpoint.icbrt(n) for n >= 0 by the same Newton iterates, at
    most SLICE_OPS operations between yields."""
    if n < 2:
        out[0] = n
        return
    nb = _bits(n)
    x = 1 << ((nb + 2) // 3)
    cost = 5 * _weight(nb)
    used = 24
    while True:
        if used + cost > SLICE_OPS:
            yield
            used = 0
        y = (2 * x + n // (x * x)) // 3
        used += cost
        if y >= x:
            out[0] = x
            return
        x = y


def _normal_steps(s, model, m, r, yy):
    # normal_equations() into m, r and yy[0], a few entries per slice. Every coefficient of
    # the columns is +-1, so an entry is a signed sum of moment sums: one long-int add each.
    cols = _COLS[model]
    nc = len(cols)
    used = 0
    for i in range(nc + 1):
        p = cols[i] if i < nc else _Y
        for j in range(i, nc + 1):
            if i == nc:
                q = _Y
            elif j == nc:
                q = _Y
            else:
                q = cols[j]
            k = 2 * len(p) * len(q)  # 1 long-int add a product, weighted for its bytecode
            if used + k > SLICE_OPS:
                yield
                used = 0
            acc = 0
            for a in p:
                for b in q:
                    v = s[INDEX_TABLE[(a[1] + b[1]) * 25 + (a[2] + b[2]) * 5 + a[3] + b[3]]]
                    if a[0] == b[0]:
                        acc += v
                    else:
                        acc -= v
            used += k
            if i == nc:
                yy[0] = acc
            elif j == nc:
                r[i] = acc
            else:
                m[i][j] = acc
                m[j][i] = acc


def _bareiss_steps(a, nc, width):
    # Bareiss elimination (bareiss_step per pivot) of the first nc columns of the augmented
    # rows, at most SLICE_OPS // 4 updated entries per slice (4 operations each), fewer for
    # big pivots. Raises SolveError('planar') on a pivot <= 0.
    left = 0
    prev = 1
    for k in range(nc):
        p = a[k][k]
        if p <= 0:  # X^T X is positive semi-definite: a pivot <= 0 means singular
            raise SolveError("planar", "normal matrix singular at column %d of %d" % (k, nc))
        if k == nc - 1:
            break
        # entries per slice: 4 operations each, weighted by the pivot's size (the entries
        # are minors of the same order); at least one
        per = SLICE_OPS // (4 * _weight(_bits(p) << 1))
        if per < 1:
            per = 1
        if left > per:
            left = per
        left -= 3  # _bits(p): up to 9 shifts (< 2**512) in this slice
        ak = a[k]
        for i in range(k + 1, nc):
            ai = a[i]
            f = ai[k]
            j = k + 1
            while j < width:
                if left <= 0:
                    yield
                    left = per
                e = j + left if j + left < width else width
                left -= e - j
                while j < e:
                    ai[j] = (p * ai[j] - f * ak[j]) // prev
                    j += 1
            ai[k] = 0
        prev = p


def _back_steps(a, col, stop, x):
    # back_substitute(a, col, stop) into x (zeros below stop), rows packed into slices
    n = len(a)
    det = a[n - 1][n - 1]
    wgt = _weight(_bits(det) << 1)  # x_j (= minors) and the row entries: det's size
    used = 8  # _bits(det)
    for i in range(n - 1, stop - 1, -1):
        cost = 2 * (n - i) * wgt
        if used + cost > SLICE_OPS:
            yield
            used = 0
        ai = a[i]
        acc = det * ai[col]
        for j in range(i + 1, n):
            acc -= ai[j] * x[j]
        x[i] = acc // ai[i]
        used += cost


def fit_steps(c, s, model, out, check=None):
    # Generator: the exact least-squares fit of `model` to the sums `s` about centre `c`,
    # at most SLICE_OPS operations on its numbers per step (a few entries of the normal
    # equations, ~10 entries of one elimination row, a few back-substitution rows...).
    # Fills `out` (a Fit). Raises SolveError with a reason name on a degenerate system.
    # `check(out)`, if given, runs as soon as the degeneracy ratios are known (before the
    # quadric is examined), so a caller can refuse degenerate geometry first.
    # Steps: re-centre, normal equations and elimination (beta, P), degeneracy ratios rho,
    # the quadric A2 b2 e2 (an ellipsoid?), its centre V and K2 (AN4246 eqs. 19-21).
    if model not in MODELS:
        raise ValueError("model %r: expected one of 4, 7, 10" % (model,))
    f = out
    f.n = s[0]
    s = yield from _recentre_steps(c, s, f)
    a, r = yield from _least_squares_steps(s, model, f)
    yield from _rho_steps(a, r, s, model, f)
    a = r = s = None  # the elimination's numbers: the quadric needs only f from here
    if check is not None:
        check(f)
    yield
    yield from _quadric_steps(model, f)
    yield from _centre_steps(f)


def _recentre_steps(c, s, f):
    # Re-centre at the integer mean: the fit does not change (translation invariance) and
    # the elimination's numbers shrink when the first sample was far from the others.
    n = f.n
    if n > 0:
        cm = (c[0] + rdiv(s[1], n), c[1] + rdiv(s[2], n), c[2] + rdiv(s[3], n))
        yield
        s2 = [0] * NUM_MOMENTS
        yield from shifted_steps(c, s, cm, s2, SLICE_OPS)
        s = s2
        c = cm
    f.c = c
    return s


def _least_squares_steps(s, model, f):
    # normal equations M beta = r, then one fraction-free elimination of [M | r | I]: it gives
    # beta and the diagonal of M^-1 (for rho); f.D, f.beta_num, f.p_num = P * D
    nc = len(_COLS[model])
    m = [[0] * nc for _ in range(nc)]
    r = [0] * nc
    yyo = [0]
    yield from _normal_steps(s, model, m, r, yyo)
    yield
    a = []
    for i in range(nc):
        row = m[i] + [r[i]] + [0] * nc
        row[nc + 1 + i] = 1
        a.append(row)
        m[i] = None  # its entries now live in a only: each is dropped as it is eliminated
    m = None
    yield from _bareiss_steps(a, nc, 2 * nc + 1)
    yield
    d = a[nc - 1][nc - 1]
    f.D = d
    beta = [0] * nc
    yield from _back_steps(a, nc, 0, beta)
    f.beta_num = beta
    yield
    acc = 0
    for i in range(nc):
        acc += beta[i] * r[i]
    f.p_num = yyo[0] * d - acc  # P * D, P = Y^T Y - beta . X^T Y
    return a, r


def _rho_steps(a, r, s, model, f):
    # rho_i = 1 / (N (M^-1)_ii s^deg) with s = (N sum|d|^2 - |sum d|^2) / N^2; the least
    # determined parameter's rho and column go to f.rho_min_ppm, f.rho_col
    n = f.n
    d = f.D
    nc = len(r)
    spread = n * (s[4] + s[7] + s[9]) - (s[1] * s[1] + s[2] * s[2] + s[3] * s[3])
    degs = _DEG[model]
    best = None
    for i in range(nc):
        if degs[i] == 0:
            continue
        yield
        x = [0] * nc
        yield from _back_steps(a, nc + 1 + i, i, x)
        inv_ii = x[i]  # (M^-1)_ii * D
        yield
        # rho = D n^(2 deg - 1) / (inv_ii spread^deg), in parts per million
        num = d * n ** (2 * degs[i] - 1) * 1000000
        den = inv_ii * spread ** degs[i]
        if den <= 0:
            raise SolveError("planar", "column %d has no spread" % i)
        rho = num // den
        if best is None or rho < best:
            best = rho
            f.rho_col = i
    f.rho_min_ppm = best


def _quadric_steps(model, f):
    # The quadric, scaled by 2D to integers: A2 = 2D (I - S(beta)), b2 = -2 beta_lin, e2;
    # A2 must be positive definite (an ellipsoid): leading minors > 0
    d = f.D
    bt = f.beta_num
    if model == 4:
        a2 = [[2 * d, 0, 0], [0, 2 * d, 0], [0, 0, 2 * d]]
        lin = 0
    elif model == 7:
        a2 = [[2 * d - 2 * bt[0], 0, 0], [0, 2 * d - 2 * bt[1], 0],
              [0, 0, 2 * d + 2 * bt[0] + 2 * bt[1]]]
        lin = 2
    else:
        a2 = [[2 * d - 2 * bt[0], -bt[2], -bt[3]], [-bt[2], 2 * d - 2 * bt[1], -bt[4]],
              [-bt[3], -bt[4], 2 * d + 2 * bt[0] + 2 * bt[1]]]
        lin = 5
    f.a2 = a2
    f.b2 = [-2 * bt[lin], -2 * bt[lin + 1], -2 * bt[lin + 2]]
    f.e2 = -2 * bt[lin + 3]
    yield
    da = det3(a2)
    f.det_a2 = da
    if a2[0][0] <= 0 or a2[0][0] * a2[1][1] - a2[0][1] * a2[1][0] <= 0 or da <= 0:
        raise SolveError("singular", "fitted quadric is not an ellipsoid (A not positive "
                         "definite)")
    yield


def _centre_steps(f):
    # V = c + d0, d0 = -A2^-1 b2 / 2 (eq. 19); K2 = d0^T A2 d0 - e2 (eq. 21)
    c = f.c
    b2 = f.b2
    da = f.det_a2
    adj = adj3(f.a2)
    yield
    w = mat_vec3(adj, b2)  # A2^-1 b2 = w / da
    f.v_den = 2 * da
    f.v_num = [c[0] * 2 * da - w[0], c[1] * 2 * da - w[1], c[2] * 2 * da - w[2]]
    yield
    # K2 = (b2 . w - 4 da e2) / (4 da)
    f.k2_num = b2[0] * w[0] + b2[1] * w[1] + b2[2] * w[2] - 4 * da * f.e2
    f.k2_den = 4 * da
    if f.k2_num <= 0:
        raise SolveError("singular", "fitted ellipsoid has no real points (K <= 0)")
    yield


class SolveError(Exception):
    """A fit could not be computed: .reason ('planar' or 'singular'), .detail."""

    def __init__(self, reason, detail):
        super().__init__(reason, detail)
        self.reason = reason
        self.detail = detail


# ---- from a fit to the correction ---------------------------------------------------------

def _inv_q_steps(m, one, out):
    # out[0] = the inverse of a fixed-point 3x3 (scale `one`), rounded; None if singular.
    # det from the adjugate's first column (Laplace along row 0): the same integer as det3.
    adj = adj3(m)                                    # 27 operations
    yield
    dt = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0]
    if dt == 0:
        out[0] = None
        return
    k = one * one
    inv = [None, None, None]
    for i in range(3):
        if i == 1:                                   # 6 + 18 ops, then 36
            yield
        ai = adj[i]
        inv[i] = [rdiv(ai[0] * k, dt), rdiv(ai[1] * k, dt), rdiv(ai[2] * k, dt)]
    out[0] = inv


def sqrtm_steps(a, one, out):
    # Generator: principal square root of a symmetric positive definite fixed-point 3x3
    # matrix `a` (entries scaled by `one`) by the Denman-Beavers iteration
    #     Y <- (Y + Z^-1) / 2,  Z <- (Z + Y^-1) / 2,   Y0 = A, Z0 = I  ->  Y = A^1/2,
    # at most SLICE_OPS operations per step (one iteration is ~12 steps: each inverse in
    # three, the update two entries a step). Sets out[0] = root (or None if it did not
    # settle), out[1] = iterations.
    y = [row[:] for row in a]
    z = [[one if i == j else 0 for j in range(3)] for i in range(3)]
    out[0] = None
    inv = [None]
    for it in range(1, _SQRT_MAX_ITER + 1):
        out[1] = it
        yield from _inv_q_steps(y, one, inv)
        yi = inv[0]
        yield
        yield from _inv_q_steps(z, one, inv)
        zi = inv[0]
        if yi is None or zi is None:
            return
        change = 0
        for e in range(9):
            if e & 1 == 0:  # <= 14 operations an entry
                yield
            i = e // 3
            j = e - 3 * i
            ny = rdiv(y[i][j] + zi[i][j], 2)
            dlt = ny - y[i][j]
            if dlt < 0:
                dlt = -dlt
            if dlt > change:
                change = dlt
            y[i][j] = ny
            z[i][j] = rdiv(z[i][j] + yi[i][j], 2)
        if change <= 2:
            out[0] = y
            return
        yield


def invw_steps(a2, det_a2, out):
    """Generator: W^-1 = (A2 / det(A2)^(1/3))^(1/2) in Q40 (det W^-1 = 1) into out[0]
    (None if the iteration did not converge), at most SLICE_OPS operations per step."""
    one = 1 << SQRT_FRAC_BITS
    r = [0]
    for _ in icbrt_steps(det_a2 << (3 * SQRT_FRAC_BITS), r):  # det^(1/3) in Q40
        yield
    cb = r[0]
    an = [None, None, None]
    for i in range(3):
        yield  # one row: 3 x (shift + rdiv) <= 18 operations
        an[i] = [rdiv(a2[i][j] << (2 * SQRT_FRAC_BITS), cb) for j in range(3)]
    yield
    yield from sqrtm_steps(an, one, out)


def q15_steps(w, frac_bits, out):
    """Generator: out[0] = q15_from_invw(w, frac_bits), two steps."""
    rowmax = 0
    for i in range(3):
        t = abs(w[i][0]) + abs(w[i][1]) + abs(w[i][2])
        if t > rowmax:
            rowmax = t
    yield  # 15 operations, then 9 x <= 4
    q = []
    for i in range(3):
        for j in range(3):
            v = w[i][j] * _Q15_ROW_MAX
            q.append(v // rowmax if v >= 0 else -((-v) // rowmax))
    out[0] = tuple(q)


def mul_steps(a, b, out):
    """Generator: out[0] = a * b, exactly, in pieces: b is cut into _MUL_CHUNK_BITS chunks,
    one partial product a * chunk (and a shift-add) per step, so a step's long-int work
    grows with a's size only (a 1500 x 3000-bit product is ~20 000 digit products in one
    go, several ms on a board)."""
    neg = b < 0
    if neg:
        b = -b
    nb = _bits(b)
    sh = (nb - 1) // _MUL_CHUNK_BITS * _MUL_CHUNK_BITS if nb > 0 else 0
    acc = a * (b >> sh)
    while sh > 0:
        yield
        sh -= _MUL_CHUNK_BITS
        acc = (acc << _MUL_CHUNK_BITS) + a * ((b >> sh) & _MUL_CHUNK_MASK)
    out[0] = -acc if neg else acc


def field_q16_steps(k2_num, k2_den, det_a2, out):
    """Generator: out[0] = field_q16(k2_num, k2_den, det_a2) (products of ~1000-bit numbers
    made in chunks: mul_steps)."""
    r = [0]
    yield from mul_steps(k2_num, k2_num, r)
    yield
    yield from mul_steps(r[0], k2_num, r)
    num = r[0] << (6 * B_FRAC_BITS)
    yield
    yield from mul_steps(k2_den, k2_den, r)
    yield
    yield from mul_steps(r[0], k2_den, r)
    yield
    yield from mul_steps(r[0], det_a2, r)
    yield
    x = num // r[0]
    yield
    yield from isqrt_steps(x, r)
    yield
    yield from icbrt_steps(r[0], r)
    out[0] = r[0]


def field_out_steps(invw_q15, b_q16, out):
    """Generator: out[0] = field_out_counts(invw_q15, b_q16)."""
    dq = det3([invw_q15[0:3], invw_q15[3:6], invw_q15[6:9]])
    if dq <= 0:
        out[0] = 0
        return
    # cbrt(dq) b / 2**15 / 2**16, with one extra bit for rounding
    x = dq * b_q16 ** 3 * 8
    yield
    r = [0]
    yield from icbrt_steps(x, r)
    out[0] = (r[0] + (1 << (15 + B_FRAC_BITS))) >> (16 + B_FRAC_BITS)


def round_sqrt_steps(num, den, out):
    """Generator: out[0] = round_sqrt(num, den)."""
    r = [0]
    yield from isqrt_steps(4 * num // den, r)
    out[0] = (r[0] + 1) >> 1


def fit_error_steps(fitr, out):
    """Generator: out[0] = fit_error_x100(fitr) (big products in chunks: mul_steps)."""
    r = [0]
    yield from mul_steps(100000000 * fitr.D, fitr.p_num, r)
    yield
    yield from mul_steps(r[0], fitr.k2_den, r)
    yield
    yield from mul_steps(r[0], fitr.k2_den, r)
    num = r[0]
    yield
    yield from mul_steps(fitr.n * fitr.k2_num, fitr.k2_num, r)
    den = r[0]
    if num < 0:
        num = 0
    yield
    yield from round_sqrt_steps(num, den, out)


def _sum_sq_steps(s, w, out):
    # sum_sq_quadric into out[0], one row of the 10 x 10 double sum per step (<= 30 ops)
    acc = 0
    for a in range(10):
        if w[a] == 0:
            continue
        yield
        ea = EXPONENTS[a]
        for b in range(10):
            if w[b] == 0:
                continue
            eb = EXPONENTS[b]
            acc += w[a] * w[b] * s[index(ea[0] + eb[0], ea[1] + eb[1], ea[2] + eb[2])]
    out[0] = acc


def minmax_steps(lo, hi, c, s, out):
    """Generator: out[0] = minmax_fit(lo, hi, c, s), at most SLICE_OPS operations a step."""
    h2 = [hi[i] - lo[i] for i in range(3)]
    for i in range(3):
        if h2[i] <= 0:
            raise SolveError("planar", "axis %d has no range (min = max = %d)" % (i, lo[i]))
    v2 = [hi[i] + lo[i] for i in range(3)]  # 2 V
    # q(d) = sum_i (2 d_i - m_i)^2 L / H_i^2 - L,  m_i = 2 V_i - 2 c_i, L = prod H_i^2
    big_l = h2[0] * h2[0] * h2[1] * h2[1] * h2[2] * h2[2]
    w = [0] * 10
    w[0] = -big_l
    quad = (4, 7, 9)
    lin = (1, 2, 3)
    for i in range(3):
        g = big_l // (h2[i] * h2[i])
        mi = v2[i] - 2 * c[i]
        w[quad[i]] += 4 * g
        w[lin[i]] += -4 * mi * g
        w[0] += mi * mi * g
    n = s[0]
    r = [0]
    for _ in _sum_sq_steps(s, w, r):  # = L^2 * sum(...)^2
        yield
    p = r[0]
    yield
    yield from round_sqrt_steps(25000000 * p, n * big_l * big_l, r)
    fe = r[0]
    # g = (H0 H1 H2)^(1/3) / 2 in Q16
    prod = h2[0] * h2[1] * h2[2]
    yield
    yield from icbrt_steps(prod << (3 * B_FRAC_BITS), r)
    b_q16 = r[0] >> 1
    one = 1 << SQRT_FRAC_BITS
    yield
    for _ in icbrt_steps(prod << (3 * SQRT_FRAC_BITS), r):  # cbrt(H0 H1 H2) in Q40
        yield
    gq = r[0]
    wq = [[0, 0, 0], [0, 0, 0], [0, 0, 0]]
    for i in range(3):
        wq[i][i] = rdiv(gq, h2[i])  # g / h_i = cbrt(prod) / H_i
    out[0] = (v2, h2, b_q16, fe, wq, one)


_POWER_ITER = const(24)  # power-iteration steps of cond_steps (see its opening comment)


def cond_steps(q, out):
    # Generator: out[0] = the eigenvalue ratio of InvW (9 Q15 ints, symmetric positive
    # definite), in hundredths; None if it is not positive definite. Power iteration on InvW
    # and on its adjugate (whose largest eigenvalue is det / the smallest of InvW); each
    # Rayleigh quotient is a lower bound whose error shrinks as (l2 / l1)**(2 * _POWER_ITER)
    # of the eigenvalue gap. One power step (~25 operations, long ints on a 32-bit board)
    # per next().
    out[0] = None
    m = [[q[0], q[1], q[2]], [q[3], q[4], q[5]], [q[6], q[7], q[8]]]
    dt = det3(m)
    if dt <= 0 or m[0][0] <= 0 or m[0][0] * m[1][1] - m[0][1] * m[1][0] <= 0:
        return
    r = [0]
    yield from power_steps(m, r)
    big = r[0]
    yield
    adj = adj3(m)
    yield from power_steps(adj, r)
    big_adj = r[0]
    if big <= 0 or big_adj <= 0:
        return
    # cond = big / (dt / big_adj); Rayleigh quotients in Q16
    out[0] = big * big_adj * 100 // (dt << 32)


def power_steps(m, out):
    # out[0] = Rayleigh quotient (Q16) after _POWER_ITER power steps; vectors rescaled by
    # shifts; one power step per next()
    out[0] = 0
    # the start: the column of the largest diagonal entry (a fixed vector can be nearly
    # orthogonal to the top eigenvector, and then 24 steps leave the quotient far low)
    k = 0
    if m[1][1] > m[k][k]:
        k = 1
    if m[2][2] > m[k][k]:
        k = 2
    v = [m[0][k], m[1][k], m[2][k]]
    sh = bit_length(max(abs(v[0]), abs(v[1]), abs(v[2]))) - 15
    if sh > 0:
        v = [v[0] >> sh, v[1] >> sh, v[2] >> sh]
    for _ in range(_POWER_ITER):
        yield
        u = mat_vec3(m, v)
        a = max(abs(u[0]), abs(u[1]), abs(u[2]))
        if a == 0:
            return
        sh = bit_length(a) - 15
        v = [u[0] >> sh, u[1] >> sh, u[2] >> sh] if sh > 0 else u
    yield
    u = mat_vec3(m, v)
    out[0] = ((u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) << 16) // (
        v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
