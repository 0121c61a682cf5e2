"""Glitch rows of a log, left out of the fit by the calibrate command (docs/calibration.md).

A least-squares fit weighs a row by its squared distance: one row far off can move it by
several percent or make it no ellipsoid at all. Left out:
- all-zero rows: a failed read (no field a magnetometer works in reads 0 on three axes);
- rows at a chip's rails: the Calibrator refuses them itself (firmware/calibrate/calibrator.py add);
- before any fit, rows far outside the others (box_outliers): more than BOX_SPAN times the
  largest half-width, on some axis, from the centre of the box holding all rows but the
  1/TRIM most extreme on each side - a row that could make the fit singular;
- after a fit, rows far off it (radius_outliers): a corrected radius more than SPREADS robust
  spreads (1.4826 x the median absolute deviation: Gaussian noise's standard deviation) from
  the median; the fit is made again without them, until none is left (ROUNDS fits at most).
Gaussian noise puts a row 6 standard deviations off once in 500 million: a clean log loses
nothing."""
from array import array

TRIM = 50          # the box ignores the 2 % most extreme rows on each side of each axis
BOX_SPAN = 3       # a row beyond 3 largest half-widths from the box's centre is far outside
SPREADS = 6        # robust spreads of the corrected radius from its median
ROUNDS = 3         # fits, at most, while rows far off are found
_MAD_SIGMA = 1.4826  # median absolute deviation -> standard deviation (Gaussian)
_MIN_REL = 0.001   # the spread is taken as at least 0.1 % of the radius (and 1 count)
_BINS = 1024       # kth(): first-level bins


def kth(a, k):
    """The k-th smallest (from 0) of the ints in a, without sorting a copy of a: a two-level
    count (a log of 20000 rows fits MicroPython's heap)."""
    lo = min(a)
    width = (max(a) - lo) // _BINS + 1
    counts = array("i", bytes(4 * (_BINS + 1)))
    for x in a:
        counts[(x - lo) // width] += 1
    b = 0
    while k >= counts[b]:
        k -= counts[b]
        b += 1
    low = lo + b * width
    v = [x for x in a if low <= x < low + width]
    v.sort()
    return v[k]


def _column(pts, keep, k):
    c = array("i", bytes(4 * sum(keep)))
    j = 0
    for i in range(len(keep)):
        if keep[i]:
            c[j] = pts[3 * i + k]
            j += 1
    return c


def box_outliers(pts, keep):
    """Indices of kept rows (keep[i] true) of pts (x, y, z of row i at 3i..3i+2) that lie
    far outside the others (module doc)."""
    n = sum(keep)
    m = n // TRIM
    if m < 1:
        return []
    c2 = [0, 0, 0]   # twice the box's centre
    h2 = 2           # twice its largest half-width: an axis the samples barely span (a flat
    for k in range(3):  # turn) has no scale of its own
        v = _column(pts, keep, k)
        lo, hi = kth(v, m), kth(v, n - 1 - m)
        c2[k] = lo + hi
        h2 = max(h2, hi - lo)
    return [i for i in range(len(keep)) if keep[i] and max(
        [abs(2 * pts[3 * i + k] - c2[k]) for k in range(3)]) > BOX_SPAN * h2]


def _median2(a):
    # twice the median of the ints in a (an int)
    n = len(a)
    return 2 * kth(a, n // 2) if n % 2 else kth(a, n // 2 - 1) + kth(a, n // 2)


def radius_outliers(cal, pts, keep):
    """Indices of kept rows whose radius corrected by Calibration `cal` is more than
    SPREADS robust spreads from the median (module doc)."""
    n = sum(keep)
    if n < 3:
        return []
    r = array("i", bytes(4 * n))   # integer radii, counts
    out = [0, 0, 0]
    j = 0
    for i in range(len(keep)):
        if keep[i]:
            cal.correct((pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]), out)
            r[j] = int((out[0] * out[0] + out[1] * out[1] + out[2] * out[2]) ** 0.5 + 0.5)
            j += 1
    med2 = _median2(r)
    dev = array("i", bytes(4 * n))
    for j in range(n):
        dev[j] = abs(2 * r[j] - med2)
    spread2 = max(_MAD_SIGMA * _median2(dev) / 2, _MIN_REL * med2, 2)  # twice the spread
    far = []
    j = 0
    for i in range(len(keep)):
        if keep[i]:
            if dev[j] > SPREADS * spread2:
                far.append(i)
            j += 1
    return far
