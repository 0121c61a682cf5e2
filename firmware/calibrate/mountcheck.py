"""The mounting check: do MAG_AXES and ACCEL_AXES describe how the two chips sit? Loaded after
a calibration is accepted and dropped after the check (firmware.compat.drop).
"""
#     from firmware.calibrate.mountcheck import check, WRONG
#     v, axes, sigma, best = check(pairs, cal, "x,-y,-z", "-x,y,z")
#     if v == WRONG: print('MAG_AXES = "%s"' % axes)     # v: "ok", "wrong", "spread", "unsteady"
#
# judge(app) runs it for a calibration session. Why a steady angle between field and gravity
# names the right rotation, the verdicts and their limits: docs/design.md (module notes,
# mountcheck). Every intermediate stays below 2**30 (tests/test_mounting.py).
import sys
from array import array

from firmware.axes import AXES, AxisMap, apply
from firmware.calibration import correct
from firmware.compat import const, drop
from firmware.fixedpoint import isqrt, rdiv
from firmware.calibrate.mounting import BINS, MIN_BINS, WIDTH

OK = "ok"
WRONG = "wrong"
SPREAD = "spread"
UNSTEADY = "unsteady"

_STEADY_Q10 = const(102)  # sigma <= 0.10 (1024 = 1): 6 deg RMS of dip at 0 deg, 11 at 60
_UNSTEADY_Q10 = const(205)  # sigma >= 0.20: twice that; no right mapping is this unsteady
_SHIFT_Q10 = const(4)      # Q14 cosine -> Q10: |c| <= 1025, so _sigma stays below 2**30
_ACC = const(15)           # the work array: unit b 0..2, unit g 3..5, products 6..14, then
#                            each rotation's sum and sum of squares

# the 6 permutations, even ones first: rotation k = 4 * perm + sign set takes body axis
# _PERMS[3 * perm + i], negated where bit i of _SIGNS[k] is set, as body axis i
# (det +1: an even permutation with an even number of negations, an odd one with an odd)
_PERMS = b"\x00\x01\x02\x01\x02\x00\x02\x00\x01\x00\x02\x01\x01\x00\x02\x02\x01\x00"
_SIGNS = b"\x00\x06\x05\x03\x00\x06\x05\x03\x00\x06\x05\x03\x07\x01\x02\x04\x07\x01\x02\x04" \
    b"\x07\x01\x02\x04"


def _unit(t, w, o, trig):
    # w[o:o+3] = the vector t as a unit vector in Q14 (|component| <= 16384); False for 0
    if trig.norm14(t, w, o) == trig.ZERO_VECTOR:
        return False
    x = w[o]
    y = w[o + 1]
    z = w[o + 2]
    n = isqrt(x * x + y * y + z * z)  # >= 2**13: the largest component is in [2**13, 2**14]
    w[o] = rdiv(x << 14, n)
    w[o + 1] = rdiv(y << 14, n)
    w[o + 2] = rdiv(z << 14, n)
    return True


def _body(d, o, k, mm, am, w, t, trig):
    # the pair at d[o:]: its field (calibrated, body frame) in w[0:3] and gravity in w[3:6],
    # as unit vectors; t: a 3-element scratch array
    t[0] = d[o]
    t[1] = d[o + 1]
    t[2] = d[o + 2]
    correct(k, t, t)  # the field, sensor axes (correct reads all of t before it writes)
    apply(mm, t, t)
    if not _unit(t, w, 0, trig):
        return False
    t[0] = d[o + 3]
    t[1] = d[o + 4]
    t[2] = d[o + 5]
    apply(am, t, t)
    return _unit(t, w, 3, trig)


def _cosines(w):
    # the 9 products u_j v_i (Q14) in w[6:15], then each rotation's cosine (Q10) added to its
    # sum and sum of squares
    for j in range(3):
        u = w[j]
        for i in range(3):
            w[6 + 3 * j + i] = (u * w[3 + i]) >> 14
    for k in range(24):
        p = 3 * (k >> 2)
        s = _SIGNS[k]
        c = w[6 + 3 * _PERMS[p]]
        if s & 1:
            c = -c
        t = w[7 + 3 * _PERMS[p + 1]]
        c = c - t if s & 2 else c + t
        t = w[8 + 3 * _PERMS[p + 2]]
        c = c - t if s & 4 else c + t
        c >>= _SHIFT_Q10
        p = _ACC + 2 * k
        w[p] += c
        w[p + 1] += c * c


def _spec(mm, k):
    # the MAG_AXES string of rotation k applied after the map mm (AxisMap.m)
    p = 3 * (k >> 2)
    s = _SIGNS[k]
    out = ""
    for i in range(3):
        j = _PERMS[p + i]
        if ((s >> i) & 1) ^ mm[3 + j]:
            out += "-"
        out += AXES[mm[j]]
        if i < 2:
            out += ","
    return out


def _map(axes):
    # AxisMap.m from an AxisMap, its .m, or a spec string
    if isinstance(axes, str):
        return AxisMap(axes).m
    return getattr(axes, "m", axes)


def check(pairs, cal, mag_axes, accel_axes):
    # (verdict, axes, sigma, best) for the pairs held (see docs/design.md, module notes): verdict
    # OK, WRONG, SPREAD or UNSTEADY, axes the MAG_AXES of the steadiest mapping, sigma and best
    # the spreads (Q10) of the mapping in use and of the steadiest.
    # cal: a firmware.calibration.Calibration, or its .k; mag_axes, accel_axes: the maps in
    # use, as spec strings ("x,-y,-z"), AxisMap objects or AxisMap.m arrays.
    k = getattr(cal, "k", cal)
    mm = _map(mag_axes)
    am = _map(accel_axes)
    w = array("i", bytes(4 * (_ACC + 48)))
    t = array("i", bytes(12))
    d = pairs.data
    n = 0
    # firmware.trig's norm14: the calibration program (firmware/calibrate/program.py) holds no
    # trig and its tables; then they are loaded for this check and let go
    loaded = "firmware.trig" in sys.modules
    from firmware import trig
    for i in range(BINS):
        o = WIDTH * i
        if d[o + 6] >= 0 and _body(d, o, k, mm, am, w, t, trig):
            _cosines(w)
            n += 1
    trig = None
    if not loaded:
        drop("trig", "trig_tables")
    best = second = 0x3FFFFFFF
    kb = 0
    for r in range(24):
        s = _sigma(w[_ACC + 2 * r], w[_ACC + 2 * r + 1], n)
        if r == 0:
            cur = s
        if s < best:
            second = best
            best = s
            kb = r
        elif s < second:
            second = s
    if n < MIN_BINS:
        v = SPREAD
    elif best > _STEADY_Q10:
        v = UNSTEADY
    elif second < _UNSTEADY_Q10:
        v = SPREAD
    elif kb == 0:
        v = OK
    else:
        v = WRONG
    return v, _spec(mm, kb), cur, best


def judge(app):
    # The check of a CompassApp's calibration session (firmware/calibrate/session.py mount_check):
    # the pairs its collector kept, the calibration in force, the app's maps. Returns
    # (verdict, axes, status) for Health.mounted: WRONG's status is shown in place of
    # "ok" (`check MAG_AXES: the data say "y,x,-z"`); OK clears it (None); SPREAD and
    # UNSTEADY leave it as it was (False).
    v, axes, sigma, best = check(app.collector.pairs, app.calibration, app._mm, app._am)
    if v == WRONG:
        return v, axes, 'check MAG_AXES: the data say "%s"' % axes
    return v, axes, None if v == OK else False


def _sigma(s, q, n):
    # the RMS spread (Q10) of n values from their sum s and sum of squares q: n q - s^2 is
    # exact (>= 0) and, with n <= 24 values of |c| <= 1025, below 24 * 24 * 1025^2 < 2**30
    if n == 0:
        return 0
    return isqrt(n * q - s * s) // n
