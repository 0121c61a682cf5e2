"""Exact streaming moment sums: the normal equations of every fit, without the samples."""
#     m = Moments()
#     m.add(x, y, z)            # a sample the buffer kept
#     m.sub(*evicted)           # the sample it dropped: its terms leave exactly
#     m.s[m.index(2, 1, 0)]     # sum of dx**2 * dy over the held samples
#
# The 35 sums S[i, j, k] = sum(dx**i * dy**j * dz**k), i + j + k <= 4, over d = p - c (c a fixed
# reference centre) give every normal matrix of the 4-, 7- and 10-element fits (AN4246 eqs.
# 35-36). Why exact integers and a reference centre: docs/design.md (module notes, accum).
from firmware.compat import const

NUM_MOMENTS = const(35)  # monomials of degree 0..4 in three variables
_MAX_DEGREE = const(4)


def _build_tables():
    # order: by degree, then dx power descending, then dy power descending
    exps = []
    for deg in range(_MAX_DEGREE + 1):
        for i in range(deg, -1, -1):
            for j in range(deg - i, -1, -1):
                exps.append((i, j, deg - i - j))
    table = bytearray(b"\xff" * 125)
    for n, (i, j, k) in enumerate(exps):
        table[i * 25 + j * 5 + k] = n
    return tuple(exps), bytes(table)


EXPONENTS, _INDEX = _build_tables()
INDEX_TABLE = _INDEX  # bytes: INDEX_TABLE[i * 25 + j * 5 + k] = index(i, j, k) (255: none)


def index(i, j, k):
    """Position of the sum of dx**i * dy**j * dz**k in Moments.s (i + j + k <= 4)."""
    n = _INDEX[i * 25 + j * 5 + k] if 0 <= i <= 4 and 0 <= j <= 4 and 0 <= k <= 4 else 255
    if n == 255:
        raise ValueError("no moment for exponents (%d, %d, %d): degree must be 0..4" % (i, j, k))
    return n


def terms(x, y, z):
    """The 35 monomials of (x, y, z) in EXPONENTS order, products shared (unrolled: this runs
    for every kept and every evicted sample)."""
    xx = x * x
    xy = x * y
    xz = x * z
    yy = y * y
    yz = y * z
    zz = z * z
    xxx = xx * x
    yyy = yy * y
    zzz = zz * z
    return (1, x, y, z,
            xx, xy, xz, yy, yz, zz,
            xxx, xx * y, xx * z, x * yy, xy * z, x * zz, yyy, yy * z, y * zz, zzz,
            xx * xx, xxx * y, xxx * z, xx * yy, xx * yz, xx * zz, x * yyy, xy * yz, xy * zz,
            x * zzz, yy * yy, yyy * z, yy * zz, y * zzz, zz * zz)


def _powers(v):
    v2 = v * v
    return (1, v, v2, v2 * v, v2 * v2)


class Moments:
    """The 35 exact sums over the held samples, relative to the integer centre .c."""

    def __init__(self):
        self.s = [0] * NUM_MOMENTS
        self.c = None  # (cx, cy, cz) once the first sample arrives

    @property
    def count(self):
        return self.s[0]

    index = staticmethod(index)

    def clear(self):
        for n in range(NUM_MOMENTS):
            self.s[n] = 0
        self.c = None

    def _update(self, x, y, z, sign):
        c = self.c
        t = terms(x - c[0], y - c[1], z - c[2])
        s = self.s
        if sign > 0:
            for n in range(NUM_MOMENTS):
                s[n] += t[n]
        else:
            for n in range(NUM_MOMENTS):
                s[n] -= t[n]

    def add(self, x, y, z):
        """Add one sample's terms (the first sample after clear() fixes the centre)."""
        if self.c is None:
            self.c = (x, y, z)
        self._update(x, y, z, 1)

    def sub(self, x, y, z):
        """Remove the terms of a sample previously added (exact: the sums return to batch)."""
        if self.c is None or self.s[0] <= 0:
            raise ValueError("sub(%d, %d, %d) from empty moment sums" % (x, y, z))
        self._update(x, y, z, -1)

    def rebuild(self, samples, centre=None):
        """Recompute from an iterable of (x, y, z): used after the buffer changed wholesale."""
        self.clear()
        if centre is not None:
            self.c = (centre[0], centre[1], centre[2])
        for p in samples:
            self.add(p[0], p[1], p[2])

    def snapshot(self):
        """(centre, sums) copied, so a time-sliced solve sees one consistent state."""
        return self.c, list(self.s)


def shifted(c, s, new_c):
    """The sums `s` about centre `c` re-expressed about the integer centre `new_c`, exactly."""
    # With t = new_c - c, (d - t)^a expands binomially, so each new sum is an integer
    # combination of old sums of equal or lower degree. Lets a solve re-centre at the samples'
    # mean (smaller numbers in the elimination) without touching the samples.
    tx = new_c[0] - c[0]
    ty = new_c[1] - c[1]
    tz = new_c[2] - c[2]
    mx = _powers(-tx)
    my = _powers(-ty)
    mz = _powers(-tz)
    binom = ((1,), (1, 1), (1, 2, 1), (1, 3, 3, 1), (1, 4, 6, 4, 1))
    out = [0] * NUM_MOMENTS
    n = 0
    for e in EXPONENTS:
        i, j, k = e
        acc = 0
        for a in range(i + 1):
            ca = binom[i][a] * mx[i - a]
            for b in range(j + 1):
                cb = ca * binom[j][b] * my[j - b]
                for g in range(k + 1):
                    acc += cb * binom[k][g] * mz[k - g] * s[_INDEX[a * 25 + b * 5 + g]]
        out[n] = acc
        n += 1
    return out


_BINOM = ((1,), (1, 1), (1, 2, 1), (1, 3, 3, 1), (1, 4, 6, 4, 1))
_STRIDE = (25, 5, 1)  # _INDEX key step of one unit of dx, dy, dz


def shifted_steps(c, s, new_c, out, ops=40):
    """shifted() as a generator for a time-sliced solve: out[:] = shifted(c, s, new_c),
    with at most `ops` operations on the sums between two yields.
    """
    # The binomial shift factorises by axis, so it runs as three one-axis passes: each new sum
    # is at most 5 terms of (binomial x power of -t) x (old sum), 2 long-int operations a term
    # (the integers are the same as shifted()'s, summed in another order: exact).
    cur = s
    for axis in range(3):
        t = new_c[axis] - c[axis]
        if t == 0:
            continue
        p = _powers(-t)
        coef = [[_BINOM[i][a] * p[i - a] for a in range(i + 1)] for i in range(_MAX_DEGREE + 1)]
        yield
        nxt = [0] * NUM_MOMENTS
        stride = _STRIDE[axis]
        used = 0
        for n in range(NUM_MOMENTS):
            e = EXPONENTS[n]
            i = e[axis]
            if i == 0:
                nxt[n] = cur[n]
                continue
            if used + 2 * i + 1 > ops:
                yield
                used = 0
            key = e[0] * 25 + e[1] * 5 + e[2] - i * stride  # the sum with this axis' power 0
            cf = coef[i]
            acc = cf[0] * cur[_INDEX[key]]
            for a in range(1, i + 1):
                acc += cf[a] * cur[_INDEX[key + a * stride]]
            nxt[n] = acc
            used += 2 * i + 1
        cur = nxt
        yield
    for n in range(NUM_MOMENTS):
        out[n] = cur[n]
