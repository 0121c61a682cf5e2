"""Heap in use by the firmware (MicroPython; CPython prints nothing useful).

    micropython -m desktop.benchmarks.memory SESSION.bin [--smoke]

SESSION.bin: a recorded session (mag bytes then accel bytes, 6 per sample each; bench.py
writes it with host_sim on CPython, so host_sim is never imported here and its memory does
not count). Steps, each after gc.collect() (gc.mem_alloc = live heap):
  base       the interpreter, this script and the session bytes
  heading_only  + what a calibrated board imports to show a heading (the app, the store,
             the record, the compass, the QMC5883L and MPU6050 drivers; the fast path where
             the port has the native emitter)
  imported   + the calibration machinery and the other drivers (the full app)
  app        + CompassApp over ReplayBus (drivers, Calibrator with its preallocated
             300-sample buffer and hash, Compass), before the first sample
  peak       the largest live heap seen while solves run in the first lap of the session
             (gc.collect() after every step that ran a solver slice)
  running    after a second lap: the calibration session has ended once its fit was
             saved and the replay brought no new direction (firmware/calibrate/session.py), and its
             machinery has left; "session_ended" says whether it had
  fast       + firmware.fast (the viper kernels and their tables)
Also: bytes allocated per sample in the steady state (micropython.mem_total over 1000 steps
once the session is calibrated), whether the run
was complete (a 10-element calibration accepted, then 1000 headings), and the moment sums
that are small ints on a 64-bit port but long ints (heap objects) on a 32-bit board.
With --min the script only runs the session (the smallest-heap search runs it with
-X heapsize=N and looks at the exit status and "complete"). With --romfs IMAGE the firmware
is imported from a ROMFS image (`mpremote romfs build` of the .mpy files) mounted at /rom,
so its bytecode runs in place, as from a board's flash (ROMFS, or modules frozen with
manifest.py); the image's bytes are read before the base figure, so they do not count.
"""
import gc
import sys

from desktop.benchmarks import common

SMOKE = common.smoke()
PERIOD_US = 5000


def mem_total():
    import micropython
    f = getattr(micropython, "mem_total", None)
    return f() if f is not None else None


def live():
    gc.collect()
    gc.collect()
    return gc.mem_alloc()


def load(path):
    with open(path, "rb") as f:
        data = f.read()
    n = len(data) // 12
    return data[:6 * n], data[6 * n:12 * n]


def machinery(app):
    """What the calibration session holds (read while it runs: it leaves when it is done)."""
    cal = app.calibrator
    out = {"held": cal.count, "capacity": cal.capacity}
    mid = 0
    big = 0
    for v in cal.moments.s:
        a = v if v >= 0 else -v
        if a >= (1 << 62):
            big += 1
        elif a >= (1 << 30):
            mid += 1
    out["moment_sums"] = {"long_on_32bit_only": mid, "long_on_both": big,
                          "total": len(cal.moments.s)}
    # preallocated arrays: the same bytes on every port (the rest is object words)
    buf = cal.buffer
    arrays = [buf.data, buf.evicted, buf._cells, buf._table, buf.region_counts, app.raw,
              app.body, app.gravity, app._cor, app._acc]
    out["array_bytes"] = sum(len(bytes(a)) for a in arrays)
    return out


def mount_romfs(path):
    """The ROMFS image at `path` mounted at /rom, first on the path (bytecode in place, as
    frozen); its bytes."""
    import vfs
    with open(path, "rb") as f:
        rom = f.read()
    vfs.mount(vfs.VfsRom(rom), "/rom")
    sys.path.insert(0, "/rom")
    return rom


def firmware_bytes(m):
    """The heap each stage adds, from the live heap `m` at each (main())."""
    base = m["base"]
    peak = m["peak_solving"]
    return {"heading_only": m["heading_only"] - base,
            "imports": m["imported"] - base, "app_start": m["app"] - base,
            "app_running": m["running"] - base,
            "peak_solving": (peak - base) if peak is not None else None,
            "fast_module": m["fast"] - m["after"]}


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if not common.IS_MP:
        common.emit({"interpreter": common.interpreter(), "skipped": "needs gc.mem_alloc"})
        return
    mag, acc = load(args[0])
    steps = len(mag) // 6
    rom = mount_romfs(args[1]) if "--romfs" in sys.argv else None
    res = {"interpreter": common.interpreter(), "session_samples": steps}
    m = {"base": live()}
    import firmware.app  # noqa: F401
    import firmware.store  # noqa: F401
    import firmware.mpu6050  # noqa: F401
    import firmware.qmc5883l  # noqa: F401
    m["heading_only"] = live()
    import firmware.calibrate.calibrator  # noqa: F401
    import firmware.hmc5883l  # noqa: F401
    import firmware.qmc5883p  # noqa: F401
    m["imported"] = live()
    from firmware.app import CompassApp
    from firmware.mpu6050 import MPU6050
    from firmware.qmc5883l import QMC5883L
    bus = common.replay_board(mag, acc)
    clock = common.Clock()
    app = CompassApp(bus, mag=QMC5883L(bus, odr=200), accel=MPU6050(bus),
                     ticks_us=clock.ticks, store=None)
    m["app"] = live()
    peak = 0
    solving = 0
    seen = {}
    for _ in range(steps):  # first lap: the buffer fills and solves run
        clock.now += PERIOD_US
        s0 = app.slices
        app.step()
        if app.slices != s0:
            solving += 1
            a = live()
            peak = a if a > peak else peak
            if app.collector is not None:
                seen = machinery(app)
    for _ in range(steps):
        clock.now += PERIOD_US
        app.step()
    ok = 0
    t = mem_total()
    for _ in range(1000):  # steady state: calibrated
        clock.now += PERIOD_US
        if app.step():
            ok += 1
    per_sample = (mem_total() - t) // 1000 if t is not None else None
    res["complete"] = app.calibration.model == 10 and ok == 1000
    res["steady_bytes_per_sample"] = per_sample
    res["session_ended"] = app.collector is None
    res["fast"] = app.fast
    if "--min" in sys.argv:
        common.emit(res)
        return
    m["peak_solving"] = peak if solving else None
    m["running"] = live()
    m["after"] = m["running"]
    try:
        import firmware.fast  # noqa: F401
    except (ImportError, SyntaxError, ValueError):  # no native emitter on this port
        pass
    m["fast"] = live()
    res["heap_bytes"] = m
    res["firmware_bytes"] = firmware_bytes(m)
    res.update(seen)
    res["frozen_or_mpy"] = ("romfs" if rom is not None else
                            "mpy" if firmware.app.__file__.endswith(".mpy") else "py")
    common.emit(res)


if __name__ == "__main__":
    main()
