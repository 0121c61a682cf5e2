"""The per-sample path, firmware (integer) against the heading guide (float).

Both paths read the SAME recorded register bytes (a simulated figure-8 session with hard and
rotated soft iron) through the same allocation-free ReplayBus, three transfers per sample
(QMC5883L status, QMC5883L data, MPU6050 accel):
  ours   QMC5883L.read_into + MPU6050.read_accel_into (the drivers' decode, error checks
         included) -> Calibration.correct (a real 10-parameter calibration of the session)
         -> AxisMap.apply x 2 -> Compass.update(b, g)
  float  the heading guide: hand decode -> ((float)raw - offset) * scale (min/max of the session)
         -> compute_heading with math.atan2/sin/cos/sqrt
Time: median over runs of n samples (gc.collect() before, collector off during), the runs of
all the paths interleaved. Stages are
differences of cumulative loops (read, + accel, + correct, + axes, + heading). The bus
stand-in's own cost (the three bare transfers) is measured and subtracted for the 'cpu'
figures. Bytes per sample: gc.mem_alloc delta (collector off) and micropython.mem_total
delta (every allocation, freed or not: a heap call frame counts there).
"""
import gc
from array import array

from desktop.benchmarks import common, floatpath
from desktop.benchmarks.common import IS_MP

from firmware import axes, calibration, i2cdevice, trig
from firmware import compass as compass_mod
from firmware.axes import AxisMap
from firmware.compass import Compass
from firmware.compat import kernels
from firmware.calibrate.calibrator import Calibrator
from firmware.mpu6050 import MPU6050
from firmware.qmc5883l import QMC5883L

SMOKE = common.smoke()
N = 50 if SMOKE else 200           # samples per timed run (the float path's garbage must fit
RUNS = 3 if SMOKE else 41          # the heap with the collector off)
FRAMES = 100 if SMOKE else 400     # recorded samples, replayed in turn
CAL_SAMPLES = 1500 if SMOKE else 6000
CAL_DT_US = 20000 if SMOKE else 5000   # both sessions span one 30 s figure-8


def setup():
    mag_cal, _ = common.session(CAL_SAMPLES, dt_us=CAL_DT_US, accel=False)
    triples = common.raw_triples(mag_cal)
    cal = Calibrator(model=10, counts_per_gauss=common.QMC_CPG)
    mm = floatpath.MinMaxCollector()
    for x, y, z in triples:
        cal.add(x, y, z)
        mm.collect(x, y, z)
    c = cal.solve(model=10)
    mag, acc = common.session(FRAMES, seed=5, dt_us=75000)   # a different stretch of motion
    return c, mm.compute(), mag, acc


c10, fcal, MAG, ACC = setup()
del setup
gc.collect()
bus = common.replay_board(MAG, ACC)
mag = QMC5883L(bus, odr=200)   # delay_us=None: the board's own wait (ticks_us)
acc = MPU6050(bus)
mmap = AxisMap("x,-y,-z")
amap = AxisMap("-x,y,z")
compass = Compass(field=c10.field_out)
fast = kernels()           # firmware.fast where the port has the native emitter, else None
kern = fast if fast is not None else False
fcorrect = kern.correct if fast is not None else calibration.correct
fapply = kern.apply if fast is not None else axes.apply
K = c10.k
MM = mmap.m
AM = amap.m
out_v = array("i", [0] * N)
raw = array("h", [0, 0, 0])
araw = array("h", [0, 0, 0])
cor = array("h", [0, 0, 0])
b = array("h", [0, 0, 0])
g = array("h", [0, 0, 0])
out_i = array("i", [0] * N)
out_f = array("d", [0.0] * N)
st = bytearray(1)
d6 = bytearray(6)
fraw = [0, 0, 0]
fm = [0.0, 0.0, 0.0]
fa = [0.0, 0.0, 0.0]


# ---- ours, cumulative ---------------------------------------------------------------------
def o1(n):
    i2cdevice.use_kernels(False)  # the plain decode
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)


def o2(n):
    i2cdevice.use_kernels(False)  # the plain decode
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)
        acc.read_accel_into(araw)


def o3(n):
    i2cdevice.use_kernels(False)  # the plain decode
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)
        acc.read_accel_into(araw)
        calibration.correct(K, raw, cor)


def o4(n):
    i2cdevice.use_kernels(False)  # the plain decode
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)
        acc.read_accel_into(araw)
        calibration.correct(K, raw, cor)
        axes.apply(MM, cor, b)
        axes.apply(AM, araw, g)


def ours(n):
    compass_mod.use_kernels(False)  # the plain path
    i2cdevice.use_kernels(False)
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)
        acc.read_accel_into(araw)
        calibration.correct(K, raw, cor)
        axes.apply(MM, cor, b)
        axes.apply(AM, araw, g)
        out_i[i] = compass.update(b, g)


# ---- ours with firmware.fast's kernels (viper on MicroPython; the plain ones elsewhere) --
def ours_fast(n):
    compass_mod.use_kernels(kern)
    i2cdevice.use_kernels(kern)
    bus.rewind()
    for i in range(n):
        mag.read_into(raw)
        acc.read_accel_into(araw)
        fcorrect(K, raw, cor)
        fapply(MM, cor, b)
        fapply(AM, araw, g)
        out_v[i] = compass.update(b, g)


# ---- the heading guide float path, cumulative ------------------------------------------------------
def f1(n):
    bus.rewind()
    for i in range(n):
        if floatpath.read_mag(bus, st, d6, fraw):
            floatpath.read_accel_g(bus, d6, fa)


def f2(n):
    bus.rewind()
    for i in range(n):
        if floatpath.read_mag(bus, st, d6, fraw):
            floatpath.read_accel_g(bus, d6, fa)
            floatpath.mag_apply_cal(fcal, fraw, fm)


def flt(n):
    bus.rewind()
    for i in range(n):
        if floatpath.read_mag(bus, st, d6, fraw):
            floatpath.read_accel_g(bus, d6, fa)
            floatpath.mag_apply_cal(fcal, fraw, fm)
            # body frame: mag (x, -y, -z), accel already (-x, y, z)
            out_f[i] = floatpath.compute_heading(fa[0], fa[1], fa[2], fm[0], -fm[1], -fm[2],
                                                 0.0)


# ---- the bus stand-in alone, and the loop itself ------------------------------------------
def bare(n):
    bus.rewind()
    for i in range(n):
        bus.readfrom_mem_into(0x0D, 0x06, st)
        bus.readfrom_mem_into(0x0D, 0x00, d6)
        bus.readfrom_mem_into(0x68, 0x3B, d6)


def empty(n):
    for i in range(n):
        pass


def locked(fn, n):
    if not IS_MP:
        return None
    import micropython
    micropython.heap_lock()
    try:
        fn(n)
    except MemoryError:
        return "MemoryError"
    finally:
        micropython.heap_unlock()
    return "ok"


def agreement():
    """Median and max |heading difference| (degrees) between the two paths, same samples."""
    ours(N)
    ours_fast(N)
    same = 0
    for i in range(N):
        same += out_i[i] == out_v[i]
    flt(N)
    diffs = []
    for i in range(N):
        dlt = out_i[i] * 360.0 / 65536.0 - out_f[i]
        dlt = (dlt + 180.0) % 360.0 - 180.0
        diffs.append(abs(dlt))
    return common.median(diffs), max(diffs), same


def main():
    fns = (("loop", empty), ("bus", bare), ("o_read_mag", o1), ("o_read_accel", o2),
           ("o_correct", o3), ("o_axes", o4), ("ours", ours),
           ("ours_fast", ours_fast),
           ("f_read", f1), ("f_apply_cal", f2), ("float", flt))
    for _, fn in fns:
        fn(N)  # warm up: dictionaries, attribute caches
    # runs interleaved (every path once per round), so a drift of the machine's speed
    # during the measurement hits every path alike
    per = {}
    for name, _ in fns:
        per[name] = []
    for _ in range(RUNS):
        for name, fn in fns:
            per[name].append(common.timed_runs(fn, N, 1)[0])
    t = {}
    tmin = {}
    for name, _ in fns:
        t[name] = common.median(per[name])
        tmin[name] = min(per[name])
    res = {"interpreter": common.interpreter(), "n_per_run": N, "runs": RUNS,
           "us_per_sample": t, "us_per_sample_min": tmin}
    bus_us = t["bus"]
    res["ours_cpu_us"] = t["ours"] - bus_us
    res["float_cpu_us"] = t["float"] - bus_us
    res["ratio_cpu"] = res["ours_cpu_us"] / res["float_cpu_us"]
    res["ratio_with_bus"] = t["ours"] / t["float"]
    res["fast_cpu_us"] = t["ours_fast"] - bus_us
    res["ratio_fast_cpu"] = res["fast_cpu_us"] / res["float_cpu_us"]
    res["ratio_fast_with_bus"] = t["ours_fast"] / t["float"]
    res["viper"] = fast is not None
    res["stages_us"] = {
        "ours": {"read_mag": t["o_read_mag"] - t["loop"], "read_accel": t["o_read_accel"]
                 - t["o_read_mag"], "correct": t["o_correct"] - t["o_read_accel"],
                 "axes": t["o_axes"] - t["o_correct"], "heading": t["ours"] - t["o_axes"]},
        "fast": {"pipeline": t["ours_fast"] - t["o_read_accel"]},
        "float": {"read_both": t["f_read"] - t["loop"],
                  "apply_cal": t["f_apply_cal"] - t["f_read"],
                  "heading": t["float"] - t["f_apply_cal"]}}
    # the float path as it really runs: collector on, its collections included
    per = []
    for _ in range(max(3, RUNS // 4)):
        gc.collect()
        t0 = common.clock()
        for _ in range(5):
            flt(N)
        per.append(common.since_us(t0) / (5 * N))
    res["float_gc_on_us"] = common.median(per)
    alloc = {}
    for name, fn in (("bus", bare), ("ours", ours), ("ours_fast", ours_fast), ("float", flt),
                     ("o_read_mag", o1), ("o_read_accel", o2), ("o_correct", o3),
                     ("o_axes", o4)):
        a, m = common.alloc_per_call(fn, N)
        alloc[name] = {"mem_alloc": a, "mem_total": m}
    res["bytes_per_sample"] = alloc
    res["heap_locked"] = {"ours": locked(ours, N), "ours_fast": locked(ours_fast, N)}
    med, mx, same = agreement()
    res["heading_diff_deg"] = {"median": med, "max": mx}
    res["fast_identical"] = [same, N]
    res["calibration"] = {"model": c10.model, "fit_error_x100": c10.fit_error,
                          "samples": c10.samples}
    common.emit(res)


if __name__ == "__main__":
    main()
