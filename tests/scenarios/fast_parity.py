# firmware.fast against the plain firmware, case by case: Pipeline.update, FastCompass.update,
# Corrector.correct and FastAxisMap.apply must give the same outputs, return values and public
# Compass attributes as Calibration.correct, AxisMap.apply and Compass.update. On MicroPython
# the fast classes are viper kernels (fast.VIPER); on CPython they fall back to the plain code.
# Inputs: a fixed LCG (the same on both interpreters) over the whole int16 range at every
# scale (so _norm14 shifts both ways), plus edge cases: zero vectors, -32768 and 32767 on each
# axis, vertical gravity (gimbal), 45-degree ties, every signed permutation for the axis maps,
# level use (g None), declination wrap-around, interference window edges.
# Also, on MicroPython: bytes allocated per call (micropython.mem_total, so a heap call frame
# counts) and a heap_lock()ed loop. Prints one JSON object.
import json
from array import array

from firmware import fast
from firmware.axes import AxisMap
from firmware.heading import Compass
from firmware.magcal import Calibration

try:
    import micropython
except ImportError:
    micropython = None

N = 6000
ATTRS = ("heading_kang", "pitch_kang", "roll_kang", "dip_kang", "magnitude", "flags",
         "interference", "dip_high", "gimbal")
seed = 12345


def rnd16():
    global seed
    seed = (seed * 1103515245 + 12345) & 0x7FFFFFFF
    return ((seed >> 8) & 0xFFFF) - 32768


def vec():
    s = rnd16() & 15  # scale: from full int16 down to a few counts
    return [rnd16() >> s, rnd16() >> s, rnd16() >> s]


EDGES = [[0, 0, 0], [-32768, -32768, -32768], [32767, 32767, 32767], [-32768, 0, 0],
         [0, -32768, 0], [0, 0, -32768], [32767, -32768, 1], [1, 0, 0], [0, 0, 1],
         [0, 0, -1], [5, 5, 0], [-7, 7, 7], [16384, 16384, 0], [8191, -8192, 8192],
         [0, 16384, -16384], [3, -3, 0], [-1, -1, -1]]
GRAV = [[0, 0, 16384], [16384, 0, 0], [-16384, 0, 0], [0, 16384, 0], [0, 0, -16384],
        [11585, 0, 11585], [16384, 1, 0], [-16384, 0, 1], [0, 0, 0], [3, 3, 3]]

bad = []
cases = {"compass": 0, "pipeline": 0, "correct": 0, "axes": 0}


def note(kind, detail):
    if len(bad) < 10:
        bad.append([kind, detail])


def same_compass(a, b):
    for k in ATTRS:
        if getattr(a, k) != getattr(b, k):
            return k
    return None


def check_compass():
    for field, decl in ((6000, 0), (0, 1000), (12000, -40000), (40, 65535)):
        plain = Compass(field=field, declination_kang=decl)
        quick = fast.FastCompass(field=field, declination_kang=decl)
        inputs = [(b, g) for b in EDGES for g in GRAV + [None]]
        inputs += [(vec(), vec() if i % 5 else None) for i in range(N)]
        for b, g in inputs:
            h1 = plain.update(b, g)
            h2 = quick.update(array("h", b), None if g is None else array("h", g))
            cases["compass"] += 1
            k = same_compass(plain, quick)
            if h1 != h2 or k:
                note("compass", [b, g, field, decl, h1, h2, k])


def calibrations():
    out = [Calibration(model=10, offset=(1200, -800, 32767),
                       invw=(30000, -1500, 700, -1500, 28000, 2000, 700, 2000, -30000),
                       field=6000, field_out=5500),
           Calibration(model=4, offset=(-32768, 0, 32767), field=100, field_out=100),
           Calibration(model=7, offset=(5, -5, 0), invw=(32767, 0, 0, 0, 16000, 0, 0, 0, -32767),
                       field=3000, field_out=2500)]
    for _ in range(3):
        row = []
        for _ in range(9):
            row.append(rnd16() // 3)
        out.append(Calibration(model=10, offset=(rnd16(), rnd16(), rnd16()), invw=row,
                               field=5000, field_out=4000))
    return out


def check_correct():
    for cal in calibrations():
        corr = fast.Corrector(cal)
        o1 = [0, 0, 0]
        o2 = array("h", [0, 0, 0])
        for raw in EDGES + [vec() for _ in range(N // 4)]:
            cal.correct(raw, o1)
            corr.correct(raw, o2)
            cases["correct"] += 1
            if list(o2) != o1:
                note("correct", [raw, o1, list(o2)])


def specs():
    out = []
    for p in ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx"):
        for s in range(8):
            out.append(",".join(("-" if s >> i & 1 else "") + p[i] for i in range(3)))
    return out


def check_axes():
    for spec in specs():
        m1 = AxisMap(spec)
        m2 = fast.FastAxisMap(spec)
        for src in EDGES + [vec() for _ in range(60)]:
            d1 = [0, 0, 0]
            d2 = array("h", [0, 0, 0])
            m1.apply(src, d1)
            m2.apply(array("h", src), d2)
            cases["axes"] += 1
            if list(d2) != d1:
                note("axes", [spec, src, d1, list(d2)])


def check_pipeline():
    cals = calibrations()
    for n, cal in enumerate(cals[:4]):
        for mag_axes, acc_axes in (("x,-y,-z", "-x,y,z"), ("-y,x,z", "y,x,-z"),
                                   ("x,y,z", None)):
            # built on another calibration, then switched: set_calibration must take
            pipe = fast.Pipeline(cals[n + 1], mag_axes, acc_axes, field=cal.field_out,
                                 declination_kang=-300)
            pipe.set_calibration(cal)
            comp = Compass(field=cal.field_out, declination_kang=-300)
            mm = AxisMap(mag_axes)
            am = AxisMap(acc_axes) if acc_axes else None
            b2 = array("h", [0, 0, 0])
            g2 = array("h", [0, 0, 0])
            for i in range(N // 6):
                raw = vec() if i % 7 else list(cal.offset)  # V itself: zero field
                araw = vec() if i % 11 else [0, 0, 0]
                c = [0, 0, 0]
                b1 = [0, 0, 0]
                g1 = [0, 0, 0]
                cal.correct(raw, c)
                mm.apply(c, b1)
                if am is None:
                    h1 = comp.update(b1)
                else:
                    am.apply(araw, g1)
                    h1 = comp.update(b1, g1)
                h2 = pipe.update(raw, araw, b2, g2)
                cases["pipeline"] += 1
                k = same_compass(comp, pipe.compass)
                if h1 != h2 or list(b2) != b1 or (am is not None and list(g2) != g1) or k:
                    note("pipeline", [raw, araw, mag_axes, acc_axes, h1, h2, b1, list(b2), k])


def allocation():
    if micropython is None:
        return None
    cal = calibrations()[0]
    pipe = fast.Pipeline(cal, "x,-y,-z", "-x,y,z", field=cal.field_out)
    comp = fast.FastCompass(field=6000)
    corr = fast.Corrector(cal)
    amap = fast.FastAxisMap("-x,y,z")
    raw = array("h", [2400, 1700, -4600])
    araw = array("h", [-3100, 2200, 15800])
    b = array("h", [0, 0, 0])
    g = array("h", [0, 0, 0])
    mt = micropython.mem_total
    res = {}
    for _ in range(2):  # the second round measures: dictionary slots exist
        t = mt(); pipe.update(raw, araw, b, g); res["Pipeline.update"] = mt() - t
        t = mt(); comp.update(b, g); res["FastCompass.update"] = mt() - t
        t = mt(); comp.update(b); res["FastCompass.update_level"] = mt() - t
        t = mt(); corr.correct(raw, b); res["Corrector.correct"] = mt() - t
        t = mt(); amap.apply(araw, g); res["FastAxisMap.apply"] = mt() - t
    micropython.heap_lock()
    try:
        for i in range(300):
            raw[0] = 2400 + 7 * i
            araw[1] = 2200 - 50 * i
            pipe.update(raw, araw, b, g)
            comp.update(b, g)
        res["heap_locked"] = "ok"
    except MemoryError:
        res["heap_locked"] = "MemoryError"
    finally:
        micropython.heap_unlock()
    return res


check_compass()
check_correct()
check_axes()
check_pipeline()
print(json.dumps({"viper": fast.VIPER, "cases": cases, "mismatches": bad,
                  "allocation": allocation()}))
