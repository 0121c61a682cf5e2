"""The gyro-aided heading's per-sample cost (firmware/gyro/attitude.py, CompassApp.use_gyro).

    micropython -m desktop.benchmarks.gyrobench SESSION.gyro [--smoke]

SESSION.gyro: a recorded session whose MPU6050 records are the driver's 14-byte bursts
(accelerometer, temperature, gyroscope; bench.py write_session(mpu_bytes=14)). A first app
calibrates on it (as apppath.py does), then four calibrated boards replay it without a
calibration session: core (the compass step a calibrated board runs every sample) and gyro
(the same with use_gyro()), each with the fast kernels where the port has the native emitter
and with the plain functions. Printed: microseconds per step (median over interleaved runs,
the replay bus's own cost subtracted) and the filter's share: gyro - core, and that over core
(docs/gyro.md's "per-sample cost vs the compass step"), plus Attitude.update alone and bytes per
step on MicroPython.
"""
import sys

from desktop.benchmarks import common
from desktop.benchmarks.apppath import load, make_app

SMOKE = common.smoke()
N = 100 if SMOKE else 400
RUNS = 3 if SMOKE else 21
PERIOD_US = 5000


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    mag, acc = load(args[0], 14)
    steps = len(mag) // 6
    b = common.replay_board(mag, acc)
    app, clock = make_app(b, None, True)
    while app.calibration.model != 10 and clock.now < 4 * steps * PERIOD_US:
        clock.now += PERIOD_US
        app.step()
    cal = app.calibration
    apps = {}
    for name, fast, gyro in (("core_fast", None, False), ("core_plain", False, False),
                             ("gyro_fast", None, True), ("gyro_plain", False, True)):
        bus = common.replay_board(mag, acc)
        a, clock = make_app(bus, fast, False)
        a.use_calibration(cal, save=False)
        if gyro:
            a.use_gyro()._use(20)  # the bias known (0.2 deg/s, as after the integral's
            #                        evidence): the filter's whole path, its heading the app's
        apps[name] = (a, clock, bus)
    from firmware import compass, i2cdevice
    from firmware.gyro import attitude

    def stepper(name):
        a, clock, bus = apps[name]
        kern = compass.KERNELS if a.fast else False

        def select():  # the sets this app chose (module-wide)
            compass.use_kernels(kern)
            i2cdevice.use_kernels(kern)
            attitude.use_kernels(None if a.fast else False)
        return common.app_runner(a, clock, bus, PERIOD_US, select)

    st = bytearray(1)
    d6 = bytearray(6)
    d14 = bytearray(14)
    bare_bus = common.replay_board(mag, acc)

    def bare(n):  # the replay bus's own transfers (the gyro boards read 14 bytes, not 6)
        bare_bus.rewind()
        for _ in range(n):
            bare_bus.readfrom_mem_into(0x0D, 0x06, st)
            bare_bus.readfrom_mem_into(0x0D, 0x00, d6)
            bare_bus.readfrom_mem_into(0x68, 0x3B, d14)

    upd = apps["gyro_plain"][0].attitude

    def update(n):  # the filter alone, on its last inputs (plain functions)
        attitude.use_kernels(False)
        for _ in range(n):
            upd.update(PERIOD_US, 7)

    fns = (("bus", bare), ("core_fast", stepper("core_fast")),
           ("core_plain", stepper("core_plain")), ("gyro_fast", stepper("gyro_fast")),
           ("gyro_plain", stepper("gyro_plain")), ("update_plain", update))
    t = common.interleaved_medians(fns, N, RUNS)
    cpu = {k: t[k] - t["bus"] for k in ("core_fast", "core_plain", "gyro_fast", "gyro_plain")}
    res = {"interpreter": common.interpreter(), "n_per_run": N, "runs": RUNS,
           "us_per_step": t, "cpu_us": cpu, "fast_available": apps["core_fast"][0].fast,
           "filter_fast_us": cpu["gyro_fast"] - cpu["core_fast"],
           "filter_plain_us": cpu["gyro_plain"] - cpu["core_plain"],
           "update_plain_us": t["update_plain"],
           "ratio_fast": (cpu["gyro_fast"] - cpu["core_fast"]) / cpu["core_fast"],
           "ratio_plain": (cpu["gyro_plain"] - cpu["core_plain"]) / cpu["core_plain"],
           "status": apps["gyro_plain"][0].status,
           "known": apps["gyro_plain"][0].attitude.known}
    if common.IS_MP:
        res["bytes_per_step"] = {name: common.alloc_per_call(fn, N)[1] for name, fn in fns[1:]}
    common.emit(res)


if __name__ == "__main__":
    main()
