# One part installed with only the parts it requires (tests/test_packaging.py lays the tree
# at argv[1]) runs its entry point: argv[2] names the part. Prints one JSON line:
# [part, what the entry point gave, the firmware modules loaded from outside argv[1]].
import json
import sys

lib = sys.argv[1]
part = sys.argv[2]
sys.path.insert(0, lib)
sys.path.insert(1, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.store import CalStore  # noqa: E402

assert sys.modules["firmware"].__file__.startswith(lib)


def outside():
    return sorted(k for k, m in sys.modules.items() if k.startswith("firmware")
                  and not (getattr(m, "__file__", None) or lib).startswith(lib))


if part == "core":  # a stored calibration: headings
    b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
    app = W.make_app(b, store=W.stored_calibration(W.MemFs()))
    got = [sum(1 for _ in range(50) if app.step()), app.status]
elif part == "calibrate":  # an empty store: a session starts and collects
    b = W.make_sim("gy271", seed=5)
    app = W.make_app(b, store=CalStore("/", fs=W.MemFs()))
    for _ in range(200):
        app.step()
    got = [app.collector is not None, app.collector.calibrator.count if app.collector else 0,
           app.not_installed]
elif part == "calfile":  # a desktop calibration file, imported at boot
    from firmware.boot import start
    b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=6)
    good = {"format": "ecompass-calibration", "version": 1, "sensor": "qmc5883l",
            "range_code": 0, "model": 10, "offset_counts": [5400, -4200, 3600],
            "invw_q15": [27000, -2000, 1300, -2000, 29000, -1500, 1300, -1500, 28000],
            "field_counts": 6000, "field_out_counts": 5900, "fit_error_x100": 120,
            "samples": 220, "coverage_percent": 80}
    with open(lib + "/calibration.json", "w") as f:
        f.write(json.dumps(good))
    app, note = start(b.bus, lib, cal_file=lib + "/calibration.json", delay_us=b.sleep_us,
                      ticks_us=b.clock.ticks_us, mag_axes=W.MAG_AXES, accel_axes=W.ACCEL_AXES,
                      learn=False)
    got = [note.split(":")[0].split(" ")[0], app.calibration.model]
elif part == "motioncal":  # MotionCal mode streams Raw lines
    from firmware.motioncal.mode import MotionCalMode
    b = W.make_sim("gy87", seed=5)
    app = W.make_app(b, store=CalStore("/", fs=W.MemFs()), learn=False)
    out = bytearray()
    mode = MotionCalMode(app, write=out.extend, poll=lambda: b"", ticks_us=b.clock.ticks_us)
    mode.run(100)
    got = [mode.lines, out.count(b"Raw:")]
elif part == "field":  # the field model answers a location
    b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
    app = W.make_app(b, store=W.stored_calibration(W.MemFs()))
    got = [app.set_location(473977000, 85456000, 2026500)]
elif part == "gyro":  # the gyro-aided heading
    b = W.make_sim("gy87", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
    app = W.make_app(b, store=W.stored_calibration(W.MemFs()))
    app.use_gyro()
    got = [sum(1 for _ in range(100) if app.step()), app.attitude is not None]
else:
    raise SystemExit("part_alone.py: no entry point for part %r" % part)
print(json.dumps([part, got, outside()]))
