"""MicroPython only: the live heap of what a board is doing, profile by profile, booted the way
boards/main.py boots (detect, the store, the calibration file check, the app).

    micropython -m desktop.benchmarks.profiles SESSION.bin STOREDIR PROFILE [--romfs IMG]

SESSION.bin: a recorded session (bench.py writes it; mag bytes then accel bytes, 6 per sample),
replayed by an allocation-free bus, so host_sim's simulator is never imported here. STOREDIR:
the board's filesystem directory for the calibration store. Every figure is after
gc.collect(), minus the heap before the first firmware import (the interpreter, this script
and the session bytes). PROFILE:
  program    the calibration program alone (firmware/calibrate/program.py, as boards/main.py
             runs it on a board without a calibration): "peak_solving", the largest live heap
             after a step that ran a solve, "peak_modules" the firmware modules loaded then,
             "saved" when it is done, "model"; leaves the record in STOREDIR.
  calibrate  a board with an empty store: it collects, solves, accepts and saves a 10-element
             calibration in a session beside the heading line ("saved": the live heap then,
             the session still running; "peak_solving": the largest live heap after a step
             that ran solver slices, "peak_modules": the firmware modules loaded then); then the
             board is put down (it jitters about directions the buffer holds) until the
             session ends ("ended"), then 1000 headings ("after"), and the firmware modules
             still loaded; leaves the record in STOREDIR.
  heading    a board whose store holds that calibration: boot, then 1000 headings. Reports
             the live heap after them ("after") and the modules loaded.
  gyro       the same with the gyro-aided heading (app.use_gyro() after boot); its SESSION
             holds the MPU6050's 14-byte bursts (accelerometer, temperature, gyroscope).
Both then run 1000 more headings and report the bytes allocated per sample over those
(micropython.mem_total): the steady state, once the dip a new fit measures has been saved.
The names interned so far (micropython.qstr_info(): never freed) are printed on a line of their
own before the JSON. With --romfs IMAGE the firmware is imported from a ROMFS image mounted at /rom (bytecode in
place, as frozen). With --min only "complete" is printed (the smallest-heap search runs this
with -X heapsize=N and looks at it).
"""
import gc
import sys

from desktop.benchmarks import common

PERIOD_US = 5000
HEADINGS = 1000


def live():
    gc.collect()
    gc.collect()
    return gc.mem_alloc()


def firmware_modules():
    return sorted(n[9:] for n in sys.modules if n.startswith("firmware."))


def boot(bus, store_dir, clock):
    # boards/main.py's sequence, with the replay bus and the benchmark's clock
    from firmware.boot import start
    from firmware.compat import drop
    app = start(bus, store_dir, mag_options={"odr": 200}, ticks_us=clock.ticks)[0]
    drop("boot")
    return app


def steps(app, clock, n):
    ok = 0
    for _ in range(n):
        clock.now += PERIOD_US
        if app.step():
            ok += 1
    return ok


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if not common.IS_MP:
        common.emit({"interpreter": common.interpreter(), "skipped": "needs gc.mem_alloc"})
        return
    import os
    store_dir, profile = args[1], args[2]
    rec = 14 if profile == "gyro" else 6  # the MPU6050's bytes per sample
    n = os.stat(args[0])[6] // (6 + rec)
    with open(args[0], "rb") as f:  # the two halves, each read once (no copy of the whole)
        mag = f.read(6 * n)
        acc = f.read(rec * n)
    if "--romfs" in sys.argv:
        import vfs
        with open(args[3], "rb") as f:
            rom = f.read()
        vfs.mount(vfs.VfsRom(rom), "/rom")
        sys.path.insert(0, "/rom")
    bus = common.replay_board(mag, acc)
    clock = common.Clock()
    base = live()
    res = {"interpreter": common.interpreter(), "profile": profile}
    if profile == "program":
        return program(bus, store_dir, clock, base, res, n)
    app = boot(bus, store_dir, clock)
    res["boot"] = live() - base
    if profile == "gyro":
        app.use_gyro()
        res["gyro_attached"] = live() - base
    if profile == "calibrate":
        peak = 0
        peak_at = None
        track = "--min" not in sys.argv
        for _ in range(3 * n):
            clock.now += PERIOD_US
            app.step()
            if track and app.solving:  # the live heap while a solve runs (slow: collects)
                a = live() - base
                if a > peak:  # and what the board held then
                    peak = a
                    peak_at = firmware_modules()
            if app.calibration.model == 10 and app.stored and not app.solving:
                break
        res["peak_solving"] = peak
        res["peak_modules"] = peak_at
        res["saved"] = live() - base
        res["model"] = app.calibration.model
        # the board put down: it jitters about the directions of the first 50 samples, which
        # the buffer holds already, so the session ends (firmware/calibrate/session.py)
        k = 0
        while app.collector is not None and k < 12000:  # 60 s at the most
            if k % 50 == 0:
                bus.rewind()
            clock.now += PERIOD_US
            app.step()
            k += 1
        res["ended"] = live() - base if app.collector is None else None
        res["ended_after_s"] = k * PERIOD_US // 1000000
    ok = steps(app, clock, HEADINGS)
    res["after"] = live() - base
    total = getattr(common.micropython, "mem_total", None)  # not on the WebAssembly port
    t = total() if total else 0  # the steady state: 1000 more (the first may save the dip)
    ok += steps(app, clock, HEADINGS)
    per_sample = (total() - t) // HEADINGS if total else None
    res["complete"] = app.calibration.model == 10 and ok == 2 * HEADINGS
    res["bytes_per_sample"] = per_sample
    res["status"] = app.status
    if profile == "gyro":
        res["gyro_source"] = app.attitude.source
    if "--min" in sys.argv:
        common.emit({"complete": res["complete"]})
        return
    res["modules"] = firmware_modules()
    qstr_info = getattr(common.micropython, "qstr_info", None)
    if qstr_info is not None:
        qstr_info()  # one line on stdout: the pool of interned names (bench.py reads it)
    common.emit(res)


def program(bus, store_dir, clock, base, res, n):
    from firmware import compat
    compat.FAST = False  # as boards/main.py runs it: the plain kernels
    from firmware.calibrate.program import Program
    p = Program(bus, store_dir, mag_options={"odr": 200}, ticks_us_=clock.ticks,
                report=lambda s: None)
    res["constructed"] = live() - base
    c = p.collector
    peak = 0
    peak_at = None
    track = "--min" not in sys.argv
    for _ in range(3 * n):
        if p.done() or p.short >= 3:
            break
        clock.now += PERIOD_US
        k = c.solves
        p.step()
        if track and c.solves != k:  # a solve ran in this step: what it held at its end
            a = live() - base
            if a > peak:
                peak = a
                peak_at = firmware_modules()
    res["complete"] = p.done()
    res["model"] = p.saved.model if p.saved is not None else None
    if "--min" in sys.argv:
        common.emit({"complete": res["complete"]})
        return
    res["peak_solving"] = peak
    res["peak_modules"] = peak_at
    res["saved"] = live() - base
    res["solves"] = c.solves
    common.emit(res)


if __name__ == "__main__":
    main()
