"""Tilt-compensated compass heading (Freescale AN4248), integer-only, angles in KANG.

    from firmware.heading import Compass, cdeg_to_kang, kang_to_str
    compass = Compass(field=6000, declination_kang=cdeg_to_kang(-150))   # B in b's units, -1.5 deg
    h = compass.update(b, g)       # b: corrected field, g: accelerometer, both body frame
    print(kang_to_str(h), compass.interference, compass.dip_high, compass.gimbal)

KANG (T. Judd): 65536 per turn, so angle arithmetic wraps like an int16 (0.0055 deg resolution).
Frame: AN4248 body frame, x forward, y right, z down; a level board's accelerometer reads +1 g
on z (common.md). b is Calibration.correct's output mapped to the body frame (firmware.axes);
g is the accelerometer in the same frame and sign. Both at any scale, components int16.

atan2(y, x)    int16 KANG in [-32768, 32767] (-32768 is 180 deg), within 1 KANG of the exact
               angle for every int16 pair; atan2(0, 0) is 0, as math.atan2.
sin(a), cos(a) Q15 in [-32767, 32767] within 1 count of the exact value, for any int a
               (+-1.0 saturates to +-32767 so a result always fits an int16).
heading(b, g=None, declination=0)
               heading in KANG 0..65535, clockwise from magnetic north plus declination (KANG,
               east positive); g None means a level board. ValueError for a zero b or g.
Compass        the same heading plus pitch, roll, field magnitude and dip, and the flags below,
               all updated in place: the per-sample path allocates nothing.
kang_to_cdeg(a), cdeg_to_kang(c), kang_to_str(a, signed=False)   display helpers.

Flags (Compass.flags bits; the booleans mirror the first three):
  FLAG_INTERFERENCE  .interference: |b| is outside field * (1 +- field_tol_pct %). A magnet,
                     a motor or a steel table adds to Earth's field (seed 004); the heading is
                     suspect. Off when no reference field is set (field=0).
  FLAG_DIP_HIGH      .dip_high: |dip| > 75 deg. The horizontal field is < 26 % of B and the
                     heading noise grows by 1/cos(dip) (seed 004: use another heading source).
  FLAG_GIMBAL        .gimbal: |pitch| > 80 deg. Roll comes from Gy, Gz ~ g cos(pitch), so its
                     noise (and the heading's) grows by >= 1/cos(80 deg) = 5.8; at +-90 deg
                     (gimbal lock) roll is taken as 0 and the heading stays defined.
  FLAG_NO_FIELD      b was (0, 0, 0): no heading; update() returns -1, the last good values stay.
  FLAG_NO_GRAVITY    g was (0, 0, 0) (free fall): likewise.

Per-sample path (Compass.update, heading, atan2, sin, cos; firmware.axes.AxisMap.apply):
every intermediate stays below 2**30
(tests/test_heading.py drives tests/intcheck over the whole int16 input space) and nothing is
allocated, not even a call frame: MicroPython puts the frame of a function whose arguments,
locals and stack exceed 11 words on the heap (py/objfun.c VM_MAX_STATE_ON_STACK), so the work
is split into small methods that keep their state on the Compass object.
"""
try:
    from micropython import const
except ImportError:  # CPython
    def const(x):
        return x

from firmware.fixedpoint import isqrt, rdiv

KANG_PER_TURN = const(65536)
_KANG_45 = const(8192)
_KANG_90 = const(16384)
_KANG_180 = const(32768)
_Q15_ONE = const(32768)
_Q15_MAX = const(32767)
_ROUND15 = const(0x4000)  # half of 2**15: round a Q15 product to nearest

_DIP_LIMIT_KANG = const(13653)  # 75 deg: seed 004, heading unreliable beyond this inclination
_GIMBAL_PITCH_KANG = const(14564)  # 80 deg: roll noise x 1/cos(80 deg) = 5.8 (gimbal lock at 90)
_FIELD_TOL_PCT = const(10)  # +-10 %: twice the |B| spread MotionCal accepts (variance < 4.5 %)
_NO_LIMIT = const(0x3FFFFFFF)  # field window when no reference field is set

FLAG_INTERFERENCE = const(1)
FLAG_DIP_HIGH = const(2)
FLAG_GIMBAL = const(4)
FLAG_NO_FIELD = const(8)
FLAG_NO_GRAVITY = const(16)

_ZERO_VECTOR = const(-128)  # _norm14's answer for (0, 0, 0)

# atan(i / 256) for i = 0..256 in KANG * 2**8 (one octant, 0..45 deg); linear interpolation
# between entries is within 0.013 KANG of atan (h**2/8 * max|atan''| = 0.65/8/65536 rad).
# Generated with math.atan and checked entry by entry in tests/test_heading.py.
_ATAN_T = (
    0, 10430, 20860, 31290, 41718, 52145, 62571, 72994, 83416, 93835,
    104251, 114664, 125073, 135479, 145880, 156277, 166669, 177056, 187438, 197815,
    208185, 218549, 228906, 239256, 249600, 259935, 270263, 280583, 290894, 301197,
    311491, 321775, 332050, 342315, 352570, 362814, 373047, 383270, 393481, 403681,
    413869, 424044, 434208, 444358, 454496, 464620, 474731, 484829, 494912, 504981,
    515035, 525075, 535100, 545109, 555103, 565081, 575043, 584989, 594918, 604831,
    614727, 624606, 634467, 644311, 654136, 663944, 673734, 683505, 693257, 702990,
    712705, 722400, 732076, 741732, 751368, 760984, 770579, 780155, 789709, 799243,
    808756, 818248, 827718, 837168, 846595, 856001, 865384, 874746, 884085, 893402,
    902696, 911968, 921217, 930443, 939645, 948825, 957981, 967114, 976223, 985308,
    994370, 1003407, 1012421, 1021410, 1030375, 1039316, 1048232, 1057123, 1065990, 1074832,
    1083649, 1092442, 1101209, 1109951, 1118668, 1127359, 1136026, 1144667, 1153282, 1161872,
    1170436, 1178975, 1187488, 1195975, 1204436, 1212871, 1221280, 1229664, 1238021, 1246352,
    1254658, 1262937, 1271189, 1279416, 1287616, 1295790, 1303938, 1312059, 1320154, 1328223,
    1336265, 1344281, 1352271, 1360234, 1368170, 1376081, 1383964, 1391822, 1399652, 1407457,
    1415234, 1422986, 1430711, 1438409, 1446081, 1453727, 1461346, 1468939, 1476505, 1484045,
    1491559, 1499046, 1506507, 1513942, 1521350, 1528733, 1536089, 1543419, 1550722, 1558000,
    1565251, 1572477, 1579676, 1586849, 1593997, 1601118, 1608214, 1615284, 1622328, 1629346,
    1636338, 1643305, 1650246, 1657162, 1664052, 1670917, 1677757, 1684570, 1691359, 1698123,
    1704861, 1711574, 1718262, 1724925, 1731563, 1738176, 1744764, 1751327, 1757866, 1764380,
    1770869, 1777334, 1783774, 1790190, 1796582, 1802949, 1809292, 1815611, 1821906, 1828177,
    1834423, 1840646, 1846846, 1853021, 1859173, 1865301, 1871405, 1877486, 1883544, 1889578,
    1895590, 1901578, 1907542, 1913484, 1919403, 1925299, 1931173, 1937023, 1942851, 1948656,
    1954439, 1960199, 1965938, 1971653, 1977347, 1983018, 1988668, 1994295, 1999901, 2005485,
    2011047, 2016588, 2022107, 2027604, 2033080, 2038535, 2043968, 2049381, 2054772, 2060142,
    2065491, 2070820, 2076127, 2081414, 2086681, 2091927, 2097152,
)

# sin(i * 90 deg / 256) for i = 0..256 in Q19 (Q15 * 16), then entry 255 again (sin is even
# about 90 deg) so that interpolating at exactly 90 deg needs no branch; linear
# interpolation is within 0.16 Q15 counts (h**2/8 * 32768, h = pi/512).
_SIN_T = (
    0, 3217, 6434, 9650, 12867, 16082, 19298, 22512, 25726, 28938,
    32150, 35360, 38569, 41777, 44983, 48187, 51389, 54590, 57788, 60984,
    64178, 67370, 70559, 73745, 76929, 80110, 83287, 86462, 89633, 92801,
    95966, 99126, 102284, 105437, 108586, 111731, 114872, 118009, 121141, 124269,
    127392, 130510, 133623, 136731, 139834, 142932, 146025, 149111, 152193, 155268,
    158338, 161402, 164460, 167511, 170556, 173595, 176627, 179653, 182672, 185684,
    188689, 191687, 194677, 197660, 200636, 203605, 206565, 209518, 212463, 215400,
    218329, 221250, 224162, 227066, 229961, 232848, 235726, 238595, 241455, 244306,
    247148, 249980, 252803, 255617, 258421, 261215, 263999, 266774, 269538, 272292,
    275036, 277770, 280493, 283205, 285907, 288599, 291279, 293948, 296606, 299253,
    301889, 304514, 307127, 309728, 312318, 314896, 317462, 320016, 322559, 325089,
    327606, 330112, 332605, 335085, 337553, 340008, 342451, 344880, 347297, 349700,
    352090, 354467, 356831, 359181, 361518, 363841, 366150, 368446, 370728, 372995,
    375249, 377489, 379714, 381925, 384122, 386304, 388472, 390625, 392763, 394887,
    396996, 399089, 401168, 403232, 405280, 407313, 409331, 411334, 413321, 415292,
    417248, 419188, 421112, 423020, 424913, 426789, 428650, 430494, 432322, 434134,
    435930, 437709, 439471, 441217, 442947, 444659, 446355, 448034, 449697, 451342,
    452971, 454582, 456176, 457753, 459313, 460856, 462381, 463889, 465379, 466852,
    468307, 469744, 471164, 472566, 473951, 475317, 476666, 477997, 479309, 480604,
    481880, 483139, 484379, 485601, 486805, 487990, 489157, 490305, 491436, 492547,
    493640, 494715, 495771, 496808, 497826, 498826, 499807, 500769, 501712, 502637,
    503542, 504429, 505296, 506145, 506974, 507785, 508576, 509348, 510101, 510834,
    511549, 512244, 512920, 513577, 514214, 514832, 515430, 516010, 516569, 517109,
    517630, 518132, 518613, 519076, 519518, 519942, 520345, 520729, 521093, 521438,
    521763, 522069, 522355, 522621, 522867, 523094, 523301, 523489, 523656, 523804,
    523933, 524041, 524130, 524199, 524249, 524278, 524288, 524278,
)


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


def kang_to_str(angle_kang, signed=False):
    """Degrees with one decimal: '0.0'..'359.9', or '-180.0'..'179.9' when signed."""
    a = angle_kang & 0xFFFF
    if signed and a >= _KANG_180:
        a -= KANG_PER_TURN
    d = rdiv(a * 225, 4096)  # decidegrees: 3600 / 65536 = 225 / 4096
    if d == 3600:  # 359.95 deg and up round to a full turn
        d = 0
    if d < 0:
        return "-%d.%d" % (-d // 10, -d % 10)
    return "%d.%d" % (d // 10, d % 10)


def _norm14(src, dst, o):
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
        return _ZERO_VECTOR
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
        dst[o] = _rshift(src[0], -k)
        dst[o + 1] = _rshift(src[1], -k)
        dst[o + 2] = _rshift(src[2], -k)
    return k


def _rshift(v, n):
    """v / 2**n rounded half away from zero (symmetric, unlike >>)."""
    if v < 0:
        return -((-v + (1 << (n - 1))) >> n)
    return (v + (1 << (n - 1))) >> n


class Compass:
    """Heading, tilt and field checks for one sample at a time, updated in place.

    field            expected |b| (the calibration's B, in b's units); 0 turns the
                     interference check off.
    declination_kang added to the magnetic heading (east positive), e.g. cdeg_to_kang(1150).
    field_tol_pct    interference window around field, percent (default 10).

    update(b, g=None) -> heading_kang (0..65535), or -1 for a zero b or g (see flags).
    After update: heading_kang, pitch_kang, roll_kang (int16 KANG, AN4248 theta and phi),
    dip_kang (inclination, positive down), magnitude (|b| in b's units), flags, interference,
    dip_high, gimbal. A failed update leaves the last good values and sets only flags.
    With g None the board is taken as level: pitch = roll = 0, and dip assumes it too.
    """

    def __init__(self, field=0, declination_kang=0, field_tol_pct=_FIELD_TOL_PCT):
        self.declination_kang = declination_kang
        self.heading_kang = 0
        self.pitch_kang = 0
        self.roll_kang = 0
        self.dip_kang = 0
        self.magnitude = 0
        self.flags = 0
        self.interference = False
        self.dip_high = False
        self.gimbal = False
        self._v = [0, 0, 0, 0, 0, 0]  # b then g, normalised by _norm14
        self._kb = 0  # b's shift, to scale |b| back
        self._sphi = 0  # Q15 sin/cos of roll and pitch
        self._cphi = _Q15_ONE
        self._stheta = 0
        self._ctheta = _Q15_ONE
        self._bfx = 0  # de-rotated field, AN4248 eq. 19
        self._bfy = 0
        self._bfz = 0
        self.field = 0
        self.field_tol_pct = field_tol_pct
        self._lo = 0
        self._hi = _NO_LIMIT
        self.set_field(field, field_tol_pct)

    def set_field(self, field, field_tol_pct=None):
        """Reference |b| for the interference check (0: off), and optionally its tolerance."""
        if field_tol_pct is not None:
            if not 0 <= field_tol_pct <= 100:
                raise ValueError("field_tol_pct %d outside 0..100" % field_tol_pct)
            self.field_tol_pct = field_tol_pct
        if field < 0:
            raise ValueError("reference field %d is negative" % field)
        self.field = field
        d = field * self.field_tol_pct // 100
        self._lo = field - d if field else 0
        self._hi = field + d if field else _NO_LIMIT

    def update(self, b, g=None):
        h = self._orient(b, g)
        if h < 0:
            return h
        self._check_field()
        self._check_dip()
        h = (h + self.declination_kang) & 0xFFFF
        self.heading_kang = h
        return h

    def _orient(self, b, g):
        """Magnetic heading 0..65535 (eq. 22); -1 and a flag when b or g is zero."""
        v = self._v
        k = _norm14(b, v, 0)
        if k == _ZERO_VECTOR:
            self.flags = FLAG_NO_FIELD
            return -1
        self._kb = k
        if g is None:
            self._level()
        elif _norm14(g, v, 3) == _ZERO_VECTOR:
            self.flags = FLAG_NO_GRAVITY
            return -1
        else:
            self._tilt()
        self._derotate()
        self.flags = 0
        return atan2(-self._bfy, self._bfx) & 0xFFFF  # psi = atan2(-Bfy, Bfx), eq. 22

    def _level(self):
        self.roll_kang = 0
        self.pitch_kang = 0
        self._sphi = 0
        self._cphi = _Q15_ONE  # exact 1.0: the level path is the identity
        self._stheta = 0
        self._ctheta = _Q15_ONE

    def _tilt(self):
        v = self._v
        gy = v[4]
        gz = v[5]
        a = atan2(gy, gz)  # roll phi, eq. 13
        self.roll_kang = a
        s = sin(a)
        c = cos(a)
        self._sphi = s
        self._cphi = c
        a = (gy * s + gz * c + _ROUND15) >> 15  # = sqrt(Gy**2 + Gz**2) >= 0: eq. 15 denominator
        a = atan2(-v[3], a)  # pitch theta in [-90, 90] deg, eq. 15; defined at +-90 deg
        self.pitch_kang = a
        self._stheta = sin(a)
        self._ctheta = cos(a)

    def _derotate(self):
        """Bf = Ry(-theta) Rx(-phi) Bp, AN4248 eq. 19 (b already hard/soft-iron corrected)."""
        v = self._v
        s = self._sphi
        c = self._cphi
        t = (v[1] * s + v[2] * c + _ROUND15) >> 15  # By sin(phi) + Bz cos(phi)
        self._bfy = (v[1] * c - v[2] * s + _ROUND15) >> 15
        s = self._stheta
        c = self._ctheta
        self._bfx = (v[0] * c + t * s + _ROUND15) >> 15
        self._bfz = (t * c - v[0] * s + _ROUND15) >> 15

    def _check_field(self):
        v = self._v
        m = isqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        k = self._kb
        if k > 0:  # undo _norm14's shift, rounding
            m = (m + (1 << (k - 1))) >> k
        elif k < 0:
            m <<= -k
        self.magnitude = m
        self.interference = m < self._lo or m > self._hi
        self.flags |= FLAG_INTERFERENCE if self.interference else 0

    def _check_dip(self):
        x = self._bfx
        y = self._bfy
        x = atan2(self._bfz, isqrt(x * x + y * y))  # inclination: vertical over horizontal field
        self.dip_kang = x
        self.dip_high = x > _DIP_LIMIT_KANG or x < -_DIP_LIMIT_KANG
        x = self.pitch_kang
        self.gimbal = x > _GIMBAL_PITCH_KANG or x < -_GIMBAL_PITCH_KANG
        x = self.flags
        if self.dip_high:
            x |= FLAG_DIP_HIGH
        if self.gimbal:
            x |= FLAG_GIMBAL
        self.flags = x


_PLAIN = Compass()  # scratch for heading(): one sample at a time, like the sensor loop


def heading(b, g=None, declination=0):
    """Tilt-compensated heading in KANG 0..65535 (see the module docstring)."""
    h = _PLAIN._orient(b, g)
    if h < 0:
        if _PLAIN.flags == FLAG_NO_FIELD:
            raise ValueError("heading: zero field vector b=%r" % (b,))
        raise ValueError("heading: zero gravity vector g=%r" % (g,))
    return (h + declination) & 0xFFFF
