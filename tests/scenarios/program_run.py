# The calibration program (firmware/calibrate/program.py) alone on the simulated GY-271 + GY-521
# doing a figure-8 (app_world's strong iron), on CPython and MicroPython alike. argv[1]: the
# case ("clean"; "save_fails": every slot write fails; "stored": a good calibration stored,
# renew=True). Prints one JSON line: [case, saved payload as hex or None, model, fit error,
# samples, solves, done at (us), last save at (us), progress lines, mounting verdict, reason,
# save errors, the last progress line]. Case "held": the clean run, printing only whether the
# solver's code was loaded at each save (it must not be where the board did not compile it).
import json
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.calibrate.program import Program  # noqa: E402

case = sys.argv[1] if len(sys.argv) > 1 else "clean"
held = case == "held"
case = "clean" if held else case
b = W.make_sim("gy271", seed=3)
fs = W.MemFs()
if case == "stored":
    W.stored_calibration(fs)
if case == "save_fails":
    for s in "abc":
        fs.bad["/ecompass_%s.cal" % s] = "write_eio"
lines = []
p = Program(b.bus, "/", mag_axes=W.MAG_AXES, accel_axes=W.ACCEL_AXES, fs=fs,
            ticks_us_=b.clock.ticks_us, delay_us=b.sleep_us, report=lines.append,
            renew=case == "stored")
at_save = []
if held:
    _save = p._save

    def _spy(*a):
        at_save.append("firmware.calibrate.solve" in sys.modules)
        return _save(*a)
    p._save = _spy
cal = p.run(limit_s=90)
s = p.saved
if held:
    print(json.dumps(at_save))
    sys.exit(0)
print(json.dumps([case, s.to_bytes().hex() if s is not None else None,
                  cal.model if cal is not None else None,
                  cal.fit_error if cal is not None else None, p.collector.calibrator.count,
                  p.solves, b.clock.now_us, p.saved_us, len(lines),
                  p.mounting[0] if p.mounting else None, p.reason, p.save_errors, lines[-1]]))
