"""Integer primitives shared by the whole firmware: one home each."""
# sat16(v)      clamp to the int16 range.
# isqrt(n)      floor square root of any non-negative int (exact; no float).
# bit_length(n) number of bits of |n| (MicroPython ints have no .bit_length()).
# rdiv(n, d)    n / d rounded to the nearest int, halves away from zero (d != 0).
# icbrt(n)      floor cube root of any int (exact; rounds toward minus infinity; for the solvers).
#
# For n < 2**30 isqrt allocates nothing and every intermediate stays a small int, so the
# per-sample path may call it; larger n (the solvers) take the Newton branch on long ints.
from firmware.compat import const

_INT16_MIN = const(-32768)
_INT16_MAX = const(32767)
_SMALL_INT_LIMIT = const(0x40000000)  # 2**30: MicroPython's small-int bound on 32-bit ports


def sat16(v):
    if v > 32767:
        return 32767
    if v < -32768:
        return -32768
    return v


def bit_length(n):
    if n < 0:
        n = -n
    bits = 0
    while n >= 0x10000:
        n >>= 16
        bits += 16
    while n:
        n >>= 1
        bits += 1
    return bits


def isqrt(n):
    if n < 0:
        raise ValueError("isqrt of negative %d" % n)
    if n < 0x40000000:
        # digit-by-digit method: r + b <= 2**29 + 2**28 throughout
        r = 0
        b = 0x10000000
        while b > n:
            b >>= 2
        while b:
            if n >= r + b:
                n -= r + b
                r = (r >> 1) + b
            else:
                r >>= 1
            b >>= 2
        return r
    x = 1 << ((bit_length(n) + 1) >> 1)  # >= sqrt(n)
    while True:
        y = (x + n // x) >> 1
        if y >= x:
            return x
        x = y


def rdiv(n, d):
    if d < 0:
        n = -n
        d = -d
    if n >= 0:
        return (n + (d >> 1)) // d
    return -((-n + (d >> 1)) // d)


def icbrt(n):
    # Newton from above on long ints: x_{k+1} = (2x + n // x^2) // 3 decreases to floor(cbrt n)
    if n < 0:
        return -icbrt(-n - 1) - 1  # floor for negatives: cbrt(-m) = -cbrt(m)
    if n < 2:
        return n
    x = 1 << ((bit_length(n) + 2) // 3)  # 2**ceil(bits/3) > cbrt(n)
    while True:
        y = (2 * x + n // (x * x)) // 3
        if y >= x:
            return x
        x = y
