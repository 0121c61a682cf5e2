"""Test-only companions of firmware/calibrate/solve.py and firmware/calibrate/accum.py: the sliced solver steps
run to completion, and exact reference computations the tests compare the firmware with.
The firmware itself runs only the *_steps generators (the app slices them)."""
from firmware.calibrate.accum import Moments, index, terms
from firmware.calibrate.solve import (Fit, _inv_q_steps, _sum_sq_steps, field_out_steps, field_q16_steps,
                            fit_error_steps, fit_steps, invw_steps, minmax_steps, q15_steps,
                            sqrtm_steps)
from firmware.fixedpoint import isqrt


def _run(gen):
    for _ in gen:
        pass


def fit(c, s, model, check=None):
    """fit_steps run to completion; returns the Fit."""
    out = Fit(model)
    for _ in fit_steps(c, s, model, out, check):
        pass
    return out


def back_substitute(a, col, stop=0):
    """Solve the eliminated system for right-hand side column `col`: returns x_i * det for
    i >= stop (integers by Cramer's rule; each division is exact), zeros below `stop`."""
    n = len(a)
    det = a[n - 1][n - 1]
    x = [0] * n
    for i in range(n - 1, stop - 1, -1):
        ai = a[i]
        acc = det * ai[col]
        for j in range(i + 1, n):
            acc -= ai[j] * x[j]
        x[i] = acc // ai[i]
    return x


def round_sqrt(num, den):
    """sqrt(num / den) rounded to the nearest int (num >= 0, den > 0)."""
    m = isqrt(4 * num // den)  # floor(2 sqrt(x)): nested floors of monotone roots are exact
    return (m + 1) >> 1


def _inv_q(m, one):
    # inverse of a symmetric fixed-point 3x3 (scale `one`), rounded; None if singular
    out = [None]
    _run(_inv_q_steps(m, one, out))
    return out[0]


def sqrtm_sym3(a, one):
    """sqrtm_steps run to completion: (root or None, iterations)."""
    out = [None, 0]
    _run(sqrtm_steps(a, one, out))
    return out[0], out[1]


def invw_from_a2(a2, det_a2):
    """invw_steps run to completion: W^-1 in Q40, or None."""
    out = [None, 0]
    _run(invw_steps(a2, det_a2, out))
    return out[0]


def q15_from_invw(w, frac_bits):
    """InvW in Q15, row-major 9-tuple: W^-1 (fixed point, `frac_bits`) scaled so the largest
    row absolute sum is 32767, each entry rounded toward zero so no row sum can exceed it."""
    out = [None]
    _run(q15_steps(w, frac_bits, out))
    return out[0]


def field_q16(k2_num, k2_den, det_a2):
    """B in Q16 counts: B^6 = K2^3 / det(A2), floor of the exact sixth root."""
    out = [0]
    _run(field_q16_steps(k2_num, k2_den, det_a2, out))
    return out[0]


def field_out_counts(invw_q15, b_q16):
    """|InvW (Bp - V)| >> 15 on the fitted ellipsoid: B det(InvW / 2**15)^(1/3), rounded."""
    out = [0]
    _run(field_out_steps(invw_q15, b_q16, out))
    return out[0]


def fit_error_x100(fitr):
    """Fit error in hundredths of a percent: 10000 D sqrt(P / N) / K2 (see module doc)."""
    # fe^2 = 1e8 D (P D) K2d^2 / (N K2n^2)
    out = [0]
    _run(fit_error_steps(fitr, out))
    return out[0]


def sum_sq_quadric(s, w):
    """Sum over the samples of q(d)^2 for q(d) = sum_k w[k] * monomial_k(d) over the 10
    monomials of degree <= 2 in accum.EXPONENTS order (1, x, y, z, xx, xy, xz, yy, yz, zz)."""
    out = [0]
    _run(_sum_sq_steps(s, w, out))
    return out[0]


def minmax_fit(lo, hi, c, s):
    """Min/max calibration (the min/max article, docs/references.md) of the samples whose per-axis extremes are lo, hi and
    whose moment sums about `c` are `s`.

    V = (max + min) / 2 per axis; half-ranges h; W^-1 = diag(g / h) with g the geometric
    mean of h (det W^-1 = 1, like the other models; the min/max article uses the arithmetic mean, which
    differs only by a common factor: headings are identical). B = g. The fit error uses the
    same definition as the fits: P' / B^4 = sum (sum_i ((d_i - v_i) / h_i)^2 - 1)^2.
    Returns (v_num (3, over 2), h2 (3: max - min), b_q16, fit_error_x100, w_q40) or raises
    SolveError if an axis has no range.
    """
    out = [None]
    _run(minmax_steps(lo, hi, c, s, out))
    return out[0]


def batch(samples, c):
    """The 35 sums over `samples` about centre `c` computed from scratch (tests, rebuild)."""
    m = Moments()
    m.c = (c[0], c[1], c[2])
    for p in samples:
        m.add(p[0], p[1], p[2])
    return m.s
