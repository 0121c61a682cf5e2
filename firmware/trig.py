"""Integer trigonometry in 16-bit angles (KANG: 65536 per turn), for AN4248's heading.

    from firmware.trig import atan2, sin, cos, kang_to_str
    a = atan2(y, x)            # int16 KANG, within 1 KANG of the exact angle
    print(kang_to_str(a & 0xFFFF))
"""
# atan2(y, x), sin(a), cos(a) (Q15), norm14(src, dst, o), isqrt(n) (fixedpoint's, so a kernel
# set offers every step the compass uses), kang_to_cdeg, cdeg_to_kang, kang_to_str. Their
# ranges and accuracy: docs/api.md (heading). Every intermediate stays below 2**30 for int16
# inputs (tests/test_heading.py) and nothing is allocated.
from firmware.compat import const
from firmware.fixedpoint import isqrt, rdiv  # noqa: F401 - isqrt is part of the kernel set
from firmware.trig_tables import ATAN_T, SIN_T

KANG_PER_TURN = const(65536)
_KANG_45 = const(8192)
_KANG_90 = const(16384)
_KANG_180 = const(32768)
_Q15_MAX = const(32767)
_ROUND15 = const(0x4000)  # half of 2**15: round a Q15 product to nearest
ZERO_VECTOR = const(-128)  # norm14's answer for (0, 0, 0)

_ATAN_T = ATAN_T
_SIN_T = SIN_T


def _atan_octant(n, d):
    """atan(n / d) in KANG for 0 <= n <= d, 0 < d <= 32768."""
    if n == d:
        return _KANG_45
    # ratio in Q15, rounded: n <= 32767 here, so n << 15 stays below 2**30
    r = ((n << 15) + (d >> 1)) // d
    n = r >> 7  # table index 0..255; the low 7 bits interpolate
    d = _ATAN_T[n]
    return ((d << 7) + (_ATAN_T[n + 1] - d) * (r & 127) + _ROUND15) >> 15


def atan2(y, x):
    """Angle of the vector (x, y) in KANG, int16: -32768..32767 (-32768 is 180 deg)."""
    n = -y if y < 0 else y
    d = -x if x < 0 else x
    if n > d:  # reflect the second octant onto the first: atan(n/d) = 90 deg - atan(d/n)
        a = _KANG_90 - _atan_octant(d, n)
    elif d == 0:
        return 0  # (0, 0): no direction; 0 as math.atan2
    else:
        a = _atan_octant(n, d)
    if x < 0:
        a = _KANG_180 - a
    if y < 0:
        return -a
    return a if a < _KANG_180 else -_KANG_180


def sin(angle_kang):
    """sin of a KANG angle in Q15, within 1 count; +-1.0 saturates to +-32767."""
    a = angle_kang & 0xFFFF
    r = a & 0x3FFF
    if a & 0x4000:  # second and fourth quadrants mirror the first
        r = 0x4000 - r
    i = r >> 6  # quarter-wave table index 0..256; the low 6 bits interpolate
    s = _SIN_T[i]
    r = ((s << 6) + (_SIN_T[i + 1] - s) * (r & 63) + 0x200) >> 10
    if r > _Q15_MAX:
        r = _Q15_MAX
    return -r if a & 0x8000 else r


def cos(angle_kang):
    """cos of a KANG angle in Q15, within 1 count; +-1.0 saturates to +-32767."""
    return sin(angle_kang + _KANG_90)


def kang_to_cdeg(angle_kang):
    """KANG -> centidegrees, rounded half away from zero (no wrap: 65535 -> 35999)."""
    return rdiv(angle_kang * 1125, 2048)  # 36000 / 65536 = 1125 / 2048


def cdeg_to_kang(cdeg):
    """Centidegrees -> KANG, rounded half away from zero (no wrap)."""
    return rdiv(cdeg * 2048, 1125)


def kang_decideg(angle_kang, signed=False):
    """Tenths of a degree, rounded: 0..3599, or -1800..1799 when signed."""
    a = angle_kang & 0xFFFF
    if signed and a >= _KANG_180:
        a -= KANG_PER_TURN
    d = rdiv(a * 225, 4096)  # decidegrees: 3600 / 65536 = 225 / 4096
    if d == 3600:  # 359.95 deg and up round to a full turn
        d = 0
    elif d == 1800 and signed:  # 179.95 deg and up: the signed range ends at 179.9
        d = -1800
    return d


def kang_to_str(angle_kang, signed=False):
    """Degrees with one decimal: '0.0'..'359.9', or '-180.0'..'179.9' when signed."""
    d = kang_decideg(angle_kang, signed)
    if d < 0:
        return "-%d.%d" % (-d // 10, -d % 10)
    return "%d.%d" % (d // 10, d % 10)


def norm14(src, dst, o):
    """dst[o:o+3] = src * 2**k, the largest |component| in [2**13, 2**14]; returns k.

    A common shift keeps the direction; 14 bits leave room for a Q15 factor below 2**30.
    Returns _ZERO_VECTOR (dst untouched) for (0, 0, 0)."""
    m = src[0]
    if m < 0:
        m = -m
    k = src[1]
    if k < 0:
        k = -k
    if k > m:
        m = k
    k = src[2]
    if k < 0:
        k = -k
    if k > m:
        m = k
    if m == 0:
        return ZERO_VECTOR
    k = 0
    while m < 0x2000:
        m <<= 1
        k += 1
    while m >= 0x4000:
        m >>= 1
        k -= 1
    if k >= 0:
        dst[o] = src[0] << k
        dst[o + 1] = src[1] << k
        dst[o + 2] = src[2] << k
    else:  # |src| >= 2**14: 1 or 2 bits go, rounded alike for both signs
        dst[o] = rshift(src[0], -k)
        dst[o + 1] = rshift(src[1], -k)
        dst[o + 2] = rshift(src[2], -k)
    return k


def rshift(v, n):
    """v / 2**n rounded half away from zero (symmetric, unlike >>)."""
    if v < 0:
        return -((-v + (1 << (n - 1))) >> n)
    return (v + (1 << (n - 1))) >> n
