"""The gyro-aided heading's construction (firmware/gyro/attitude.py), imported for it and dropped
after it: the options checked, the filter's scale factors computed (long-int arithmetic, once),
and CompassApp.use_gyro()'s attach.
"""
# scales(counts_per_dps_x10, options) -> (KI, KF, KA, KM, KB, ACC_LIM, MAG_LIM, recovery_us,
#     max_uncertainty_cdeg, ((KA, KM, KB) x the options' gains 1 .. 4 times (within their
#     ranges: the start-up gains), then bias_gain 1 .. 4 times), mag_gain); ValueError names a
#     bad option and its unit.
# init(a, gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g, options): the
#     Attitude a's attributes and state array (its slots: firmware/gyro/attitude.py's numbers,
#     tests/test_attitude.py checks they agree).
# attach(app, attitude, options) -> an attitude.Attitude (the app's kernel set) on the app's
#     arrays, its MPU6050 reading the gyroscope in the accelerometer's burst (.gyro_into).
from array import array

from firmware.compat import const
from firmware.trig import sin

# firmware/gyro/attitude.py's slots
_Q = const(0)
_KI = const(23)
_KF = const(24)
_KA = const(25)
_KM = const(26)
_ACC_LIM = const(46)
_MAG_LIM = const(47)
_BLK = const(65)
_CPG = const(66)
_DPREV = const(68)
_SETTLE = const(69)
_BOOST = const(70)
_MG = const(71)
_CDPS = const(72)
_RUN = const(76)
_SIZE = const(78)
_UNKNOWN_CDPS = const(2000)  # attitude.py's
_SETTLE_US = const(6000000)  # attitude.py's

_DEFAULTS = (("gain", 500, 0, 1000, "1/1000 rad/s per rad"),
             ("mag_gain", 500, 0, 1000, "1/1000 rad/s per rad"),
             ("bias_gain", 125, 0, 1000, "1/1000 per s"),
             ("accel_reject_cdeg", 1000, 100, 9000, "0.01 deg"),
             ("mag_reject_cdeg", 1000, 100, 18000, "0.01 deg"),
             ("recovery_us", 5000000, 0, 100000000, "us"),
             ("max_uncertainty_cdeg", 500, 0, 18000, "0.01 deg"))


def _options(options):
    out = {}
    for name, default, lo, hi, unit in _DEFAULTS:
        v = options.pop(name, default)
        if not isinstance(v, int) or isinstance(v, bool) or not lo <= v <= hi:
            raise ValueError("Attitude %s=%r: expected an int in %d..%d (%s)"
                             % (name, v, lo, hi, unit))
        out[name] = v
    if options:
        raise TypeError("Attitude: unknown option %s (expected %s)" % (
            ", ".join(sorted(options)), ", ".join(d[0] for d in _DEFAULTS)))
    return out


_TIMES = const(4)  # the start-up gains: up to 4 times the options' (docs/gyro.md)


def scales(counts_per_dps_x10, options):
    if counts_per_dps_x10 not in (1310, 655, 328, 164):
        raise ValueError("Attitude counts_per_dps_x10=%r: the MPU6050's 1310, 655, 328 or 164 "
                         "(10 x counts per deg/s)" % (counts_per_dps_x10,))
    o = _options(dict(options))
    c = counts_per_dps_x10
    # the half angle per 32768 us (Q28 rad) per 1/16 count: pi 2**43 / (5760 cps 10**6),
    # pi as 355/113 (8.5e-8), x 2**14, split into integer and fraction
    k = (355 * (1 << 57) * 10 + 56 * 5760 * 1000000 * c) // (113 * 5760 * 1000000 * c)
    s = sin(o["accel_reject_cdeg"] * 4096 // 5625) >> 1  # cdeg -> KANG: x 65536 / 36000
    t = []
    for f in range(1, _TIMES + 1):  # the gains f times the options', within their ranges:
        g = o["gain"] * f       # gain x 180/pi x cps x 4 (Q12 per Q14 of error);
        m = o["mag_gain"] * f   # mag_gain x 360 x cps (Q12 per KANG); bias_gain x 256 x
        b = o["bias_gain"] * f  # 32768 x 64 / 10**9 (Q6: bias in 1/4096 count per
        g = g if g < 1000 else 1000  # correction x dt)
        m = m if m < 1000 else 1000
        b = b if b < 1000 else 1000
        t += [(g * c * 720 * 113 + 1775000) // 3550000, (m * 360 * c + 5000) // 10000,
              (b * 256 * 32768 * 64 + 500000000) // 1000000000]
    for f in range(1, _TIMES + 1):
        b = o["bias_gain"] * f
        t.append(b if b < 1000 else 1000)
    return (k >> 14, k & 0x3FFF, t[0], t[1], t[2],
            s * s, o["mag_reject_cdeg"] * 4096 // 2250, o["recovery_us"],
            o["max_uncertainty_cdeg"], tuple(t), o["mag_gain"])


def init(a, gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g, options):
    k = scales(counts_per_dps_x10, options)
    a.gyro = gyro
    a.gravity = gravity
    a.field = field
    a.compass = compass
    a.recovery_us = k[7]
    a.max_uncertainty_cdeg = k[8]
    a.base_cdeg = 100  # the field-corrected heading: ~1 deg
    a.bias_estimates = 0
    a._k = k[9]  # (KA, KM, KB) at 1 .. 4 times the options' gains (the start-up gains), then
    #              bias_gain (1/1000 per s) at 1 .. 4 times
    a.known = True  # Attitude._use() says otherwise
    a.started = False
    a.accel_rejected = True
    a._odd = False  # gravity's turn (Attitude._step)
    a._cpg = counts_per_g
    a.kb_counts = counts_per_dps_x10 * 16 * 6  # 60 deg/s in 1/16 count: the integral's limit
    a.acc_lim = k[5]
    a.st = st = array("i", bytearray(4 * _SIZE))
    st[_KI] = k[0]
    st[_KF] = k[1]
    st[_KA] = k[2]
    st[_KM] = k[3]
    st[_ACC_LIM] = k[5]
    st[_MAG_LIM] = k[6]
    st[_CPG] = counts_per_g
    st[_CDPS] = counts_per_dps_x10 * 4096 // 1000  # bias (1/4096 count) per cdeg/s
    st[_MG] = k[10] if k[10] > 0 else 1
    st[_BOOST] = -1
    st[_BLK] = -1
    st[_DPREV] = _UNKNOWN_CDPS
    st[_SETTLE] = _SETTLE_US
    st[_RUN] = -2
    st[_Q] = 0x10000000  # 1 in Q28


def attach(app, attitude, options):
    attitude.use_kernels(None if app.fast else False)  # the app's kernel set
    acc = app.accel
    if acc is None or not hasattr(acc, "sample_all_into"):
        raise ValueError("use_gyro: no gyroscope - it is the MPU6050's (GY-87, GY-521) and no "
                         "MPU6050 answered on this bus")
    a = attitude.Attitude(array("h", (0, 0, 0)), app.gravity, app.body, app.compass,
                 acc.counts_per_dps_x10, acc.counts_per_g, **options)
    a.raw = array("h", (0, 0, 0))
    m = app._am  # the accelerometer's map negated: it turns specific force into AN4248's
    a.axes = array("b", (m[0], m[1], m[2], 1 - m[3], 1 - m[4], 1 - m[5]))  # gravity (Gp = -f)
    acc.gyro_into = a.raw  # its sample_into() reads the gyroscope in the same burst
    return a
