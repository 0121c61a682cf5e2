"""The solvers are exact: checked against rational arithmetic (fractions) and float64 numpy."""
from fractions import Fraction as Fr

import numpy as np

from desktop.benchmarks.reference import numpy_fit
import pytest
from hypothesis import given, strategies as st

from tests import solve_ref
from firmware.calibrate import accum
from firmware.calibrate import solve

# AN4246 Rev 4, worked example 1 (section 6), in 0.1 uT counts
AN4246_SAMPLES = [(1674, -2424, 917), (1403, -2219, 868), (1524, -2304, -6),
                  (1803, -2706, 710), (1909, -2124, 627), (1929, -2424, 171)]


def moments(pts):
    m = accum.Moments()
    for p in pts:
        m.add(*p)
    return m


def frac_solve(a, b):
    # Gauss-Jordan on Fractions: the textbook reference for beta = (X^T X)^-1 X^T Y
    n = len(a)
    m = [[Fr(v) for v in row] + [Fr(b[i])] for i, row in enumerate(a)]
    for k in range(n):
        p = next(i for i in range(k, n) if m[i][k] != 0)
        m[k], m[p] = m[p], m[k]
        for i in range(n):
            if i != k and m[i][k] != 0:
                f = m[i][k] / m[k][k]
                m[i] = [x - f * y for x, y in zip(m[i], m[k])]
    return [m[i][n] / m[i][i] for i in range(n)]


def frac_det(a):
    m = [[Fr(v) for v in row] for row in a]
    n = len(m)
    det = Fr(1)
    for k in range(n):
        p = next((i for i in range(k, n) if m[i][k] != 0), None)
        if p is None:
            return 0
        if p != k:
            m[k], m[p] = m[p], m[k]
            det = -det
        det *= m[k][k]
        for i in range(k + 1, n):
            f = m[i][k] / m[k][k]
            m[i] = [x - f * y for x, y in zip(m[i], m[k])]
    return det


def design(pts, model):
    # X and Y of AN4246 eqs. 29-30 (4 elements) and of the trace-constrained ellipsoid
    rows = []
    for x, y, z in pts:
        if model == 4:
            rows.append([x, y, z, 1])
        elif model == 7:
            rows.append([x * x - z * z, y * y - z * z, x, y, z, 1])
        else:
            rows.append([x * x - z * z, y * y - z * z, x * y, x * z, y * z, x, y, z, 1])
    return rows, [x * x + y * y + z * z for x, y, z in pts]


def normal(rows, ys):
    n = len(rows[0])
    xtx = [[sum(r[i] * r[j] for r in rows) for j in range(n)] for i in range(n)]
    xty = [sum(r[i] * y for r, y in zip(rows, ys)) for i in range(n)]
    return xtx, xty


# ---- AN4246 worked example --------------------------------------------------------------

def test_an4246_worked_example_exactly():
    rows, ys = design(AN4246_SAMPLES, 4)
    beta = frac_solve(*normal(rows, ys))
    v_ref = [b / 2 for b in beta[:3]]                              # eq. 37
    b2_ref = beta[3] + sum(v * v for v in v_ref)                   # eq. 37: B^2
    m = moments(AN4246_SAMPLES)
    f = solve_ref.fit(m.c, m.s, 4)
    assert [Fr(v, f.v_den) for v in f.v_num] == v_ref
    assert Fr(f.k2_num, f.k2_den) / (2 * f.D) == b2_ref
    # the printed values (uT, one decimal): beta (eq. 41), V (eq. 42)
    assert [round(float(b) / 10, 1) for b in beta[:3]] == [311.5, -478.2, 91.7]
    assert abs(float(beta[3]) / 100 - -81303.5) < 0.5   # exact: -81303.23; the paper rounds
    assert [round(float(v) / 10, 1) for v in v_ref] == [155.7, -239.1, 45.8]
    # B = 47.2 uT from the exact V; the paper's 47.0 comes from squaring the rounded V
    b_q16 = solve_ref.field_q16(f.k2_num, f.k2_den, f.det_a2)
    assert round(b_q16 / 65536 / 10, 1) == 47.2
    assert (Fr(b_q16, 65536)) ** 2 <= b2_ref < (Fr(b_q16 + 1, 65536)) ** 2
    paper = -81303.5 + 155.7 ** 2 + 239.1 ** 2 + 45.8 ** 2
    assert round(paper, 1) == 2205.4 and round(paper ** 0.5, 1) == 47.0


def test_an4246_worked_example_fit_error_is_the_app_notes_epsilon():
    rows, ys = design(AN4246_SAMPLES, 4)
    beta = frac_solve(*normal(rows, ys))
    r = [y - sum(b * x for b, x in zip(beta, row)) for row, y in zip(rows, ys)]   # eq. 32
    p = sum(v * v for v in r)                                                    # eq. 33
    b2 = beta[3] + sum((b / 2) ** 2 for b in beta[:3])
    eps = (float(p) / 6) ** 0.5 / (2 * float(b2))      # AN4246: eps = sqrt(P/M) / (2 B^2)
    m = moments(AN4246_SAMPLES)
    f = solve_ref.fit(m.c, m.s, 4)
    assert Fr(f.p_num, f.D) == p
    assert solve_ref.fit_error_x100(f) == round(eps * 10000)   # percent, in hundredths
    assert solve_ref.fit_error_x100(f) == 30                    # 0.30 %


# ---- exact linear algebra ----------------------------------------------------------------

@st.composite
def spd_system(draw):
    n = draw(st.integers(min_value=1, max_value=6))
    rows = draw(st.lists(st.lists(st.integers(-1000, 1000), min_size=n, max_size=n),
                         min_size=n, max_size=2 * n + 2))
    a = [[sum(r[i] * r[j] for r in rows) for j in range(n)] for i in range(n)]
    b = draw(st.lists(st.integers(-10 ** 9, 10 ** 9), min_size=n, max_size=n))
    return a, b


@given(spd_system())
def test_bareiss_gives_the_exact_rational_solution_times_the_determinant(sys_):
    a, b = sys_
    n = len(a)
    aug = [a[i][:] + [b[i]] for i in range(n)]
    prev = 1
    for k in range(n):
        if aug[k][k] == 0:
            # a zero leading minor of a Gram matrix means the whole matrix is singular
            assert frac_det(a) == 0
            return
        if k < n - 1:
            prev = solve.bareiss_step(aug, k, prev, n + 1)
    det = aug[n - 1][n - 1]
    assert det == frac_det(a)
    x = solve_ref.back_substitute(aug, n)
    assert [Fr(v, det) for v in x] == frac_solve(a, b)


@given(st.lists(st.lists(st.integers(-10 ** 6, 10 ** 6), min_size=3, max_size=3),
                min_size=3, max_size=3))
def test_adjugate_and_determinant(m):
    adj = solve.adj3(m)
    d = solve.det3(m)
    prod = [[sum(m[i][k] * adj[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    assert prod == [[d if i == j else 0 for j in range(3)] for i in range(3)]


@pytest.mark.parametrize("model", [4, 7, 10])
@given(pts=st.lists(st.tuples(*[st.integers(-3000, 3000)] * 3), min_size=12, max_size=40,
                    unique=True))
def test_normal_equations_from_moments_equal_the_direct_products(model, pts):
    m = moments(pts)
    c = m.c
    rel = [(x - c[0], y - c[1], z - c[2]) for x, y, z in pts]
    rows, ys = design(rel, model)
    xtx, xty = normal(rows, ys)
    got = solve.normal_equations(m.s, model)
    assert got[0] == xtx and got[1] == xty and got[2] == sum(y * y for y in ys)


# ---- fits -----------------------------------------------------------------------------------

def sphere_points(n, seed, centre, radius, w=None, noise=0.0, zmin=-1.0):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(4 * n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u = u[u[:, 2] >= zmin][:n]
    p = u * radius
    if w is not None:
        p = p @ np.array(w).T
    p = p + np.array(centre) + rng.normal(scale=noise, size=p.shape) if noise else p + centre
    return [tuple(int(v) for v in q) for q in np.rint(p)]


def exact_residual(pts, model, f):
    rows, ys = design([(x - f.c[0], y - f.c[1], z - f.c[2]) for x, y, z in pts], model)
    beta = [Fr(b, f.D) for b in f.beta_num]
    return sum((y - sum(b * x for b, x in zip(beta, row))) ** 2 for row, y in zip(rows, ys))


@pytest.mark.parametrize("model", [4, 7, 10])
def test_fit_is_the_exact_least_squares_solution(model):
    pts = sphere_points(60, 1, (900, -400, 250), 700, w=[[1.1, 0.1, 0], [0.1, 0.9, 0.05],
                                                         [0, 0.05, 1.0]], noise=4)
    m = moments(pts)
    f = solve_ref.fit(m.c, m.s, model)
    rows, ys = design([(x - f.c[0], y - f.c[1], z - f.c[2]) for x, y, z in pts], model)
    assert [Fr(b, f.D) for b in f.beta_num] == frac_solve(*normal(rows, ys))
    assert Fr(f.p_num, f.D) == exact_residual(pts, model, f)


@pytest.mark.parametrize("model", [4, 7, 10])
def test_fit_does_not_depend_on_the_reference_centre(model):
    pts = sphere_points(50, 2, (-5000, 7000, 300), 1200, noise=3)
    a = moments(pts)
    b = accum.Moments()
    b.rebuild(pts, centre=(12345, -23456, 111))
    fa = solve_ref.fit(a.c, a.s, model)
    fb = solve_ref.fit(b.c, accum.shifted(a.c, a.s, b.c), model)   # no re-centring differences
    fc = solve_ref.fit(b.c, b.s, model)
    for g in (fb, fc):
        assert [Fr(v, g.v_den) for v in g.v_num] == [Fr(v, fa.v_den) for v in fa.v_num]
        assert Fr(g.k2_num, g.k2_den * g.D) == Fr(fa.k2_num, fa.k2_den * fa.D)
        assert Fr(g.p_num, g.D) == Fr(fa.p_num, fa.D)


def test_nested_models_have_non_increasing_residuals():
    pts = sphere_points(80, 3, (100, 200, 300), 900, w=[[1.2, 0.1, 0.05], [0.1, 0.8, 0],
                                                        [0.05, 0, 1.0]], noise=5)
    m = moments(pts)
    p = [Fr(f.p_num, f.D) for f in (solve_ref.fit(m.c, m.s, k) for k in (4, 7, 10))]
    assert p[0] >= p[1] >= p[2] > 0


def test_ten_element_fit_commutes_with_an_axis_permutation():
    # rotation invariance of the trace constraint, exactly: permute axes, permute the fit
    pts = sphere_points(60, 4, (300, -200, 100), 800, w=[[1.1, 0.2, 0], [0.2, 0.9, 0.1],
                                                         [0, 0.1, 1.0]], noise=2)
    perm = [(z, x, y) for x, y, z in pts]
    a = moments(pts)
    b = moments(perm)
    fa = solve_ref.fit(a.c, a.s, 10)
    fb = solve_ref.fit(b.c, b.s, 10)
    va = [Fr(v, fa.v_den) for v in fa.v_num]
    vb = [Fr(v, fb.v_den) for v in fb.v_num]
    assert vb == [va[2], va[0], va[1]]
    assert Fr(fa.p_num, fa.D) == Fr(fb.p_num, fb.D)


def test_samples_on_two_planes_leave_the_ten_element_fit_singular():
    # Judd's degenerate ellipsoid: circles in x = 0 and y = 0 cannot fix the xy term
    pts = []
    for k in range(36):
        a = 2 * np.pi * k / 36
        pts.append((0, int(round(1000 * np.cos(a))), int(round(1000 * np.sin(a)))))
        pts.append((int(round(1000 * np.cos(a + 0.05))), 0, int(round(1000 * np.sin(a + 0.05)))))
    m = moments(pts)
    with pytest.raises(solve.SolveError) as e:
        solve_ref.fit(m.c, m.s, 10)
    assert e.value.reason == "planar"
    solve_ref.fit(m.c, m.s, 4)   # the centre is still determined


def test_degeneracy_ratio_matches_the_uniform_sphere_values():
    # rho = 1/3 (centre), 1/15 (dx dy), 1/5 (dx^2-dz^2) on a densely, evenly covered sphere
    pts = sphere_points(4000, 5, (0, 0, 0), 10000)
    m = moments(pts)
    assert abs(solve_ref.fit(m.c, m.s, 4).rho_min_ppm - 333333) < 20000
    f10 = solve_ref.fit(m.c, m.s, 10)
    assert abs(f10.rho_min_ppm - 66667) < 6000
    assert solve.column_name(10, f10.rho_col) in ("dxdy", "dxdz", "dydz")


# ---- W^-1 = A^1/2 and the Q15 matrix ------------------------------------------------------

@given(st.lists(st.floats(-1, 1), min_size=9, max_size=9), st.floats(0.2, 1.0))
def test_sqrtm_is_the_symmetric_root(vals, floor):
    g = np.array(vals).reshape(3, 3)
    a = g @ g.T + floor * np.eye(3)   # SPD, condition <= ~50
    one = 1 << 40
    aq = [[int(round(v * one)) for v in row] for row in (a + a.T) / 2]
    root, it = solve_ref.sqrtm_sym3(aq, one)
    assert root is not None and it < 20
    r = np.array(root, dtype=float) / one
    assert [[root[i][j] == root[j][i] for j in range(3)] for i in range(3)] == [[True] * 3] * 3
    w, v = np.linalg.eigh(np.array(aq, dtype=float) / one)
    ref = v @ np.diag(np.sqrt(w)) @ v.T
    assert np.abs(r - ref).max() < 1e-9


@given(st.lists(st.integers(-(1 << 41), 1 << 41), min_size=9, max_size=9))
def test_q15_rows_never_exceed_32767_and_the_largest_is_full(vals):
    w = [vals[0:3], vals[3:6], vals[6:9]]
    if max(sum(abs(v) for v in row) for row in w) == 0:
        return
    q = solve_ref.q15_from_invw(w, 40)
    sums = [sum(abs(v) for v in q[3 * i:3 * i + 3]) for i in range(3)]
    assert max(sums) <= 32767
    assert max(sums) >= 32767 - 3   # truncation loses < 1 per entry


@given(st.integers(1, 10 ** 30), st.integers(1, 10 ** 20), st.integers(1, 10 ** 30))
def test_field_is_the_floor_of_the_exact_sixth_root(kn, kd, det):
    b = solve_ref.field_q16(kn, kd, det)
    x = Fr(kn, kd) ** 3 / det * Fr(2) ** 96       # (B 2**16)^6
    assert b ** 6 <= x < (b + 1) ** 6


# ---- recovery of known iron, against float64 numpy -------------------------------------------

def our_fit(pts, model):
    m = moments(pts)
    f = solve_ref.fit(m.c, m.s, model)
    v = np.array([Fr(a, f.v_den) for a in f.v_num], dtype=float)
    if model == 4:
        invw = np.eye(3)
    else:
        invw = np.array(solve_ref.invw_from_a2(f.a2, f.det_a2), dtype=float) / (1 << 40)
    b = solve_ref.field_q16(f.k2_num, f.k2_den, f.det_a2) / 65536
    return v, invw, b, f


def truth(w, b):
    # the det-1 symmetric W^-1 and the B our normalisation reports for true W and field b
    w = np.array(w, dtype=float)
    a = np.linalg.inv(w).T @ np.linalg.inv(w)
    k = np.cbrt(np.linalg.det(a))
    ev, vec = np.linalg.eigh(a / k)
    return vec @ np.diag(np.sqrt(ev)) @ vec.T, b * np.sqrt(k) ** -1 * 1.0


@pytest.mark.parametrize("model,w", [
    (4, np.eye(3)),
    (7, np.diag([1.15, 0.9, 1.0])),
    (10, [[1.1, 0.12, -0.05], [0.12, 0.92, 0.08], [-0.05, 0.08, 1.03]]),
])
def test_known_iron_is_recovered_from_quantised_samples(model, w):
    # hard iron 3x the field; only int rounding as noise: V within 0.5 count, W^-1 1e-3
    centre = (18000, -12000, 9000)
    pts = sphere_points(400, 7, centre, 6000, w=w)
    v, invw, b, _ = our_fit(pts, model)
    tw, tb = truth(w, 6000)
    assert np.abs(v - centre).max() < 0.5
    assert np.abs(invw - tw).max() < 1e-3
    assert abs(b - tb) < 1.0


@pytest.mark.parametrize("model", [4, 7, 10])
def test_integer_fit_equals_the_float64_reference_on_noisy_samples(model):
    w = [[1.08, 0.1, 0.03], [0.1, 0.95, -0.06], [0.03, -0.06, 0.99]] if model == 10 else \
        (np.diag([1.1, 0.93, 1.0]) if model == 7 else np.eye(3))
    centre = (-9000, 15000, 4000)
    pts = sphere_points(300, 11, centre, 6000, w=w, noise=24)   # QMC5883L: 24 counts RMS
    v, invw, b, _ = our_fit(pts, model)
    rv, rinvw, rb = numpy_fit(pts, model)
    assert np.abs(v - rv).max() < 1e-6 * 6000
    assert np.abs(invw - rinvw).max() < 1e-9
    assert abs(b - rb) < 1e-4
    tw, tb = truth(w, 6000)
    # and as close to the truth as the reference (they are the same solution)
    assert np.abs(v - centre).max() <= np.abs(rv - centre).max() + 1e-3
    assert np.abs(v - centre).max() < 15          # 0.25 % of B
    assert np.abs(invw - tw).max() < 0.01


def test_min_max_fit_error_uses_the_same_definition():
    pts = sphere_points(500, 13, (100, 200, -300), 1000, w=np.diag([1.2, 0.9, 1.0]), noise=3)
    m = moments(pts)
    p = np.array(pts)
    lo, hi = p.min(axis=0).tolist(), p.max(axis=0).tolist()
    v2, h2, b_q16, fe, wq, one = solve_ref.minmax_fit(lo, hi, m.c, m.s)
    v = (np.array(hi) + np.array(lo)) / 2
    h = (np.array(hi) - np.array(lo)) / 2
    g = np.cbrt(h.prod())
    q = (((p - v) / h) ** 2).sum(axis=1) - 1          # |W^-1 (p - V)|^2 / B^2 - 1
    ref = 50 * np.sqrt((q ** 2).mean())               # 50 sqrt(P / N) / B^2, percent
    assert abs(fe / 100 - ref) < 0.006
    assert abs(b_q16 / 65536 - g) < 1e-3
    assert np.allclose(np.diag(np.array(wq, dtype=float) / one), g / h, atol=1e-9)


def test_min_max_refuses_an_axis_without_range():
    m = moments([(1, 2, 3), (4, 5, 3)])
    with pytest.raises(solve.SolveError) as e:
        solve_ref.minmax_fit([1, 2, 3], [4, 5, 3], m.c, m.s)
    assert e.value.reason == "planar"
