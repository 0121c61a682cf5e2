"""The gyro-aided heading's construction (firmware/attitude.py), imported for it and dropped
after it: the options checked, the filter's scale factors computed (long-int arithmetic, once),
and CompassApp.use_gyro()'s attach.

scales(counts_per_dps_x10, options) -> (KI, KF, KA, KM, KB, ACC_LIM, MAG_LIM, recovery_us,
    max_uncertainty_cdeg); ValueError names a bad option and its unit.
attach(app, cls, options) -> the Attitude (cls) on the app's arrays, its MPU6050 reading the gyroscope in
    the accelerometer's burst (driver .gyro_into), app.attitude set.
"""
from firmware.trig import sin

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


def scales(counts_per_dps_x10, options):
    if counts_per_dps_x10 not in (1310, 655, 328, 164):
        raise ValueError("Attitude counts_per_dps_x10=%r: the MPU6050's 1310, 655, 328 or 164 "
                         "(10 x counts per deg/s)" % (counts_per_dps_x10,))
    o = _options(dict(options))
    c = counts_per_dps_x10
    # the half angle per 32768 us (Q28 rad) per 1/16 count: pi 2**43 / (5760 cps 10**6),
    # pi as 355/113 (8.5e-8), x 2**14, split into integer and fraction
    k = (355 * (1 << 57) * 10 + 56 * 5760 * 1000000 * c) // (113 * 5760 * 1000000 * c)
    # gain x 180/pi x cps x 4 (Q12 per Q14 of error); mag_gain x 360 x cps (Q12 per KANG);
    # bias_gain x 256 x 32768 x 64 / 10**9 (Q6: bias in 1/4096 count per correction x dt)
    s = sin(o["accel_reject_cdeg"] * 4096 // 5625) >> 1  # cdeg -> KANG: x 65536 / 36000
    return (k >> 14, k & 0x3FFF, (o["gain"] * c * 720 * 113 + 1775000) // 3550000,
            (o["mag_gain"] * 360 * c + 5000) // 10000,
            (o["bias_gain"] * 256 * 32768 * 64 + 500000000) // 1000000000,
            s * s, o["mag_reject_cdeg"] * 4096 // 2250, o["recovery_us"],
            o["max_uncertainty_cdeg"])


def attach(app, cls, options):
    from array import array
    acc = app.accel
    if acc is None or not hasattr(acc, "sample_all_into"):
        raise ValueError("use_gyro: no gyroscope - it is the MPU6050's (GY-87, GY-521) and no "
                         "MPU6050 answered on this bus")
    a = cls(array("h", (0, 0, 0)), app.gravity, app.body, app.compass,
                 acc.counts_per_dps_x10, acc.counts_per_g, **options)
    a.raw = array("h", (0, 0, 0))
    m = app._am  # the accelerometer's map negated: it turns specific force into AN4248's
    a.axes = array("b", (m[0], m[1], m[2], 1 - m[3], 1 - m[4], 1 - m[5]))  # gravity (Gp = -f)
    acc.gyro_into = a.raw  # its sample_into() reads the gyroscope in the same burst
    app.attitude = a
    return a
