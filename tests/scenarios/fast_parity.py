# firmware/fast.py against the plain functions it mirrors, function by function, and the
# whole per-sample path (correct -> axes -> Compass.update) with either kernel set:
#   correct  vs calibration.correct     apply vs axes.apply
#   atan2, sin, cos, norm14 vs trig's    isqrt vs fixedpoint.isqrt (n < 2**30)
#   measure (orient, magnitude, dip, judge) vs compass's
#   screen   vs samples.screen: two SampleBuffers offered the same samples (result, counters,
#            held samples), at several capacities and separations
# Inputs: the int16 extremes (+-32767, -32768, -4096, 0, +-1), a small-int generator (no long
# ints on a 32-bit port), and the real integer-count logs (datasets/, and build/datasets when
# `make datasets` has fetched the others: datasets/README.md) through a calibration with strong
# soft iron. Where the port has no native
# emitter the kernels are absent and only the plain path runs ("fast": false).
# Also the bytes each kernel allocates per call (micropython.mem_total: a heap frame counts).
# Prints one JSON object.
import json
from array import array

from firmware import axes, calibration, compass, fixedpoint, i2cdevice, trig
from firmware.calibrate import samples
from firmware.calibration import Calibration
from firmware.compat import kernels

try:
    import micropython
except ImportError:
    micropython = None

FAST = kernels()
EXTREMES = (32767, -32768, -32767, -4096, 4095, 0, 1, -1, 16384, -16385, 2047, -2048)
LOGS = ("qmc5883l_tomisuarez_filtered", "lsm9ds1_jremington", "icm20948_ak09916_jremington",
        "lsm303_altimu10v3_jremington", "mag3_jremington_large_offset",
        "unknown_ellipsoid_fit_python_bazhin")
_s = [12345]


def rnd16():
    # Park-Miller on 16-bit halves would make long ints; this stays below 2**23
    s = (_s[0] * 75 + 74) % 65537
    _s[0] = s
    return (s & 0xFFFF) - 32768


def vec():
    k = rnd16() & 15  # scale: from full int16 down to a few counts
    return [rnd16() >> k, rnd16() >> k, rnd16() >> k]


def extreme_vectors():
    for a in EXTREMES:
        for b in EXTREMES:
            yield [a, b, EXTREMES[(a + b) % len(EXTREMES)]]


def log_samples(limit=2000):
    for name in LOGS:
        f = None
        for folder in ("datasets", "build/datasets"):
            try:
                f = open("%s/%s.csv" % (folder, name))
                break
            except OSError:
                pass
        if f is None:
            continue
        f.readline()
        n = 0
        for line in f:
            p = line.split(",")
            if len(p) < 3:
                continue
            yield [int(p[0]), int(p[1]), int(p[2])]
            n += 1
            if n >= limit:
                break
        f.close()


bad = []
cases = {}


def check(kind, got, want, arg):
    cases[kind] = cases.get(kind, 0) + 1
    if got != want and len(bad) < 10:
        bad.append([kind, arg, got, want])


CAL = Calibration(model=10, offset=(-420, 3100, 5150),
                  invw=(29000, -2500, 1200, -2500, 26000, -900, 1200, -900, 30600),
                  field=4000, field_out=3700, fit_error=150, samples=200, coverage=80)
MAPS = [axes.AxisMap(s) for s in ("x,y,z", "x,-y,-z", "-y,x,z", "z,-x,-y", "-x,-y,z",
                                  "-z,y,x")]


def kernels_agree(v):
    a = array("h", (0, 0, 0))
    b = array("h", (0, 0, 0))
    calibration.correct(CAL.k, v, a)
    FAST.correct(CAL.k, v, b)
    check("correct", list(b), list(a), v)
    for m in MAPS:
        axes.apply(m.m, v, a)
        FAST.apply(m.m, v, b)
        check("apply", list(b), list(a), v)
    check("atan2", FAST.atan2(v[0], v[1]), trig.atan2(v[0], v[1]), v)
    check("sin", FAST.sin(v[2]), trig.sin(v[2]), v)
    check("cos", FAST.cos(v[0]), trig.cos(v[0]), v)
    d1 = [0, 0, 0, 0]
    d2 = [0, 0, 0, 0]
    check("norm14", [FAST.norm14(v, d2, 1)] + d2, [trig.norm14(v, d1, 1)] + d1, v)
    st1 = array("i", bytearray(4 * compass.STATE_SIZE))
    st2 = array("i", bytearray(4 * compass.STATE_SIZE))
    for g in (None, [v[2], v[0], v[1]], [0, 0, 0], [1, -1, 16384]):
        check("orient", FAST.orient(st2, v, g), compass.orient(st1, v, g), [v, g])
        check("state", list(st2), list(st1), [v, g])
        check("magnitude", FAST.magnitude(st2), compass.magnitude(st1), [v, g])
        check("dip", FAST.dip(st2), compass.dip(st1), [v, g])
        # measure: the windows (16..19) from the sample itself, so every flag is reached
        for st in (st1, st2):
            st[16] = abs(v[0]) * 3
            st[17] = abs(v[1]) * 3
            st[18] = v[2] >> 2
            st[19] = (v[2] >> 2) + (abs(v[0]) >> 3)
        check("measure", FAST.measure(st2, v, g), compass.measure(st1, v, g), [v, g])
        check("state", list(st2), list(st1), [v, g])
    n = (v[0] * v[0] + v[1] * v[1]) >> 2  # < 2**30, the mirror's domain
    check("isqrt", FAST.isqrt(n), fixedpoint.isqrt(n), n)
    raw = bytearray(6)
    for i in range(3):
        raw[2 * i] = v[i] & 0xFF
        raw[2 * i + 1] = (v[i] >> 8) & 0xFF
    for msb in (0, 1):
        i2cdevice.int16x3_into(raw, a, msb)
        FAST.int16x3_into(raw, b, msb)
        check("int16x3_into", list(b), list(a), [v, msb])


def buffers_agree(vs):
    # the same offers to a buffer screened by samples.screen and one by FAST.screen
    for cap, sep in ((300, 900), (40, 3000), (100, 1), (60, 16384), (20, 200)):
        b1 = samples.SampleBuffer(cap, sep)
        b2 = samples.SampleBuffer(cap, sep)
        for v in vs:
            samples.use_kernels(False)
            r1 = b1.offer(v[0], v[1], v[2])
            samples.use_kernels(FAST)
            r2 = b2.offer(v[0], v[1], v[2])
            check("screen", [r2, b2.last_cells, b2.last_probes, b2.count],
                  [r1, b1.last_cells, b1.last_probes, b1.count], [cap, sep, v])
        check("buffer", list(b2.data), list(b1.data), [cap, sep])
    samples.use_kernels()


def pipeline(v, g, kern):
    compass.use_kernels(kern)
    c = compass.Compass(field=3700, declination_kang=-1234)
    b = array("h", (0, 0, 0))
    fast = kern is not False
    (FAST.correct if fast else calibration.correct)(CAL.k, v, b)
    (FAST.apply if fast else axes.apply)(MAPS[1].m, b, b)
    h = c.update(b, g)
    return [h, c.pitch_kang, c.roll_kang, c.dip_kang, c.magnitude, c.flags, list(b)]


def run():
    out = {"fast": FAST is not None}
    vs = list(extreme_vectors()) + [vec() for _ in range(3000)]
    logs = list(log_samples())
    out["log_samples"] = len(logs)
    if FAST is None:
        return out
    for v in vs + logs:
        kernels_agree(v)
    # a slow figure-8 (rnd16 noise) then the generator's and the logs' samples
    walk = [[(rnd16() >> 10) + 9000 * ((i >> 6) & 3) - 12000, (rnd16() >> 10) + 70 * (i & 63),
             (rnd16() >> 10) - 50 * (i & 127)] for i in range(1200)]
    buffers_agree(walk + vs[:600] + logs[:600])
    gs = [[0, 0, 16384], [16384, 0, 0], [-11585, 300, 11585], [0, 0, 0], None, [3, -3, 3]]
    i = 0
    for v in vs + logs:
        g = gs[i % len(gs)]
        i += 1
        check("pipeline", pipeline(v, g, FAST), pipeline(v, g, False), v)
    compass.use_kernels()
    out["cases"] = cases
    out["mismatches"] = bad
    if micropython is not None and hasattr(micropython, "mem_total"):
        out["allocation"] = allocation()
    return out


def allocation():
    mt = micropython.mem_total
    v = array("h", (1234, -2345, 3456))
    o = array("h", (0, 0, 0))
    d = [0, 0, 0, 0]
    res = {}
    k = CAL.k
    m = MAPS[3].m
    st = array("i", bytearray(4 * compass.STATE_SIZE))
    g = array("h", (300, -200, 16000))
    buf = samples.SampleBuffer(300, 900)
    for i in range(300):
        buf.offer(40 * i - 6000, (i * 37) % 4000, 900)
    buf._q[0] = 123  # a candidate of its own for screen (its scratch: offer sets it)
    buf._q[1] = 456
    buf._q[2] = 789
    for name in ("correct", "apply", "atan2", "sin", "norm14", "isqrt", "orient", "magnitude",
                 "dip", "measure", "screen", "int16x3_into"):
        f = getattr(FAST, name)
        t = mt()
        for _ in range(200):
            if name == "correct":
                f(k, v, o)
            elif name == "apply":
                f(m, v, o)
            elif name == "atan2":
                f(-3000, 17000)
            elif name == "sin":
                f(12345)
            elif name == "norm14":
                f(v, d, 1)
            elif name in ("orient", "measure"):
                f(st, v, g)
            elif name in ("magnitude", "dip"):
                f(st)
            elif name == "screen":
                f(buf)
            elif name == "int16x3_into":
                f(b"\x01\x80\xff\x7f\x00\x00", o, 1)
            else:
                f(123456789)
        res[name] = (mt() - t) // 200
    return res


print(json.dumps(run()))
