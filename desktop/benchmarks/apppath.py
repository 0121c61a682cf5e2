"""The app's per-sample path against the float path a typical MicroPython compass uses.

    micropython -m desktop.benchmarks.apppath SESSION.bin [--smoke]

ours    CompassApp.step() on a calibrated board: QMC5883L + MPU6050 reads over an
        allocation-free replay bus, Q15 correct, axis maps, tilt-compensated heading, the
        interference check, and the collector offered every sample (Calibrator.add, as
        learn=True keeps it): the whole step, with no solve starting during the timed runs.
        Once with the fast path where the port has the native emitter (the app picks it by
        itself) and once with fast=False (the plain functions).
core    the same board once its calibration session has ended (firmware/calibrate/session.py): the
        step without the collector, what a calibrated board runs every sample.
float   the heading guide's float path over the same bytes: hand decode of both sensors,
        its min/max collector (collect), ((float)raw - offset) * scale, the float tilt
        heading (desktop/benchmarks/floatpath.py).
Both run the same number of samples from the same recorded session (bench.py records it on
CPython with host_sim, so the simulator is not in this process); the replay bus's own cost is
measured and subtracted. Median over interleaved runs; ratios are the headline.
"""
import sys

from desktop.benchmarks import common, floatpath

SMOKE = common.smoke()
N = 100 if SMOKE else 400
RUNS = 3 if SMOKE else 25
PERIOD_US = 5000


def load(path, mpu_bytes=6):
    """(mag bytes, MPU6050 bytes) of a recorded session (bench.py write_session): 6 bytes of
    the magnetometer, then `mpu_bytes` of the MPU6050 (14: its burst with the gyroscope)."""
    with open(path, "rb") as f:
        data = f.read()
    n = len(data) // (6 + mpu_bytes)
    return data[:6 * n], data[6 * n:(6 + mpu_bytes) * n]


def make_app(bus, fast, learn=True):
    from firmware.app import CompassApp
    from firmware.mpu6050 import MPU6050
    from firmware.qmc5883l import QMC5883L
    clock = common.Clock()
    app = CompassApp(bus, mag=QMC5883L(bus, odr=200), accel=MPU6050(bus), ticks_us=clock.ticks,
                     store=None, fast=fast, learn=learn)
    return app, clock


def _never():
    return False


def calibrate(app, clock, steps):
    """Two laps of the session (solves run, a calibration is accepted); then no more solves
    start, so the timed steps are the per-sample path (the collector still offered every
    sample), not the background solver's slices (make bench times those separately)."""
    for _ in range(2 * steps):
        clock.now += PERIOD_US
        app.step()
    while app.collector.job is not None:
        clock.now += PERIOD_US
        app.step()
    app.collector.due = _never
    return app.calibration.model


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    mag, acc = load(args[0])
    steps = len(mag) // 6
    bus = common.replay_board(mag, acc)  # the float path's (and the bare transfers')
    apps = {}
    for name, fast in (("ours_fast", None), ("ours_plain", False)):
        b = common.replay_board(mag, acc)  # a bus of its own: a driver's set-up writes to it
        app, clock = make_app(b, fast)
        model = calibrate(app, clock, steps)
        apps[name] = (app, clock, model, b)
    for name, fast, of in (("core_fast", None, "ours_fast"), ("core_plain", False, "ours_plain")):
        b = common.replay_board(mag, acc)
        app, clock = make_app(b, fast, learn=False)  # no session: the calibrated board's step
        app.use_calibration(apps[of][0].calibration, save=False)
        apps[name] = (app, clock, app.calibration.model, b)
    from firmware import compass, i2cdevice
    from firmware.calibrate import samples

    def stepper(name):
        app, clock, _, b = apps[name]
        kern = compass.KERNELS if app.fast else False

        def select():  # the set this app chose (module-wide)
            compass.use_kernels(kern)
            samples.use_kernels(kern)
            i2cdevice.use_kernels(kern)
        return common.app_runner(app, clock, b, PERIOD_US, select)

    st = bytearray(1)
    d6 = bytearray(6)
    fraw = [0, 0, 0]
    fm = [0.0, 0.0, 0.0]
    fa = [0.0, 0.0, 0.0]
    mm = floatpath.MinMaxCollector()
    fcal = floatpath.FloatCal()

    def flt(n):
        bus.rewind()
        for _ in range(n):
            if floatpath.read_mag(bus, st, d6, fraw):
                floatpath.read_accel_g(bus, d6, fa)
                mm.collect(fraw[0], fraw[1], fraw[2])
                floatpath.mag_apply_cal(fcal, fraw, fm)
                floatpath.compute_heading(fa[0], fa[1], fa[2], fm[0], -fm[1], -fm[2], 0.0)

    def bare(n):
        bus.rewind()
        for _ in range(n):
            bus.readfrom_mem_into(0x0D, 0x06, st)
            bus.readfrom_mem_into(0x0D, 0x00, d6)
            bus.readfrom_mem_into(0x68, 0x3B, d6)

    fns = (("bus", bare), ("float", flt), ("ours_fast", stepper("ours_fast")),
           ("ours_plain", stepper("ours_plain")), ("core_fast", stepper("core_fast")),
           ("core_plain", stepper("core_plain")))
    t = common.interleaved_medians(fns, N, RUNS)
    cpu = {name: t[name] - t["bus"] for name in ("float", "ours_fast", "ours_plain",
                                                  "core_fast", "core_plain")}
    res = {"interpreter": common.interpreter(), "n_per_run": N, "runs": RUNS,
           "us_per_sample": t, "cpu_us": cpu,
           "fast_available": apps["ours_fast"][0].fast,
           "ratio_fast": cpu["ours_fast"] / cpu["float"],
           "ratio_plain": cpu["ours_plain"] / cpu["float"],
           "ratio_core_fast": cpu["core_fast"] / cpu["float"],
           "ratio_core_plain": cpu["core_plain"] / cpu["float"],
           "models": [apps[k][2] for k in ("ours_fast", "ours_plain")]}
    if common.IS_MP:
        alloc = {}
        for name, fn in fns:
            a, m = common.alloc_per_call(fn, N)
            alloc[name] = {"mem_alloc": a, "mem_total": m}
        res["bytes_per_sample"] = alloc
    common.emit(res)


if __name__ == "__main__":
    main()
