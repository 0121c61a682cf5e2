# CPython and MicroPython must print the same: set_location (declination, status, bad input),
# a quick calibration in the simulator (offset, heading afterwards), the accuracy level and
# the status line. Run by tests/test_quickcal.py through tests/mp.parity.
import json
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.app import status_line  # noqa: E402
from firmware.errors import CalibrationRejected  # noqa: E402

ZURICH = (473977000, 85000000)
b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
app = W.make_app(b, learn=False)
out = {"before": status_line(app), "accuracy_before": app.accuracy}
for args in ((47.4, 85000000), (900000001, 0), (0, 0, 2026)):
    try:
        app.set_location(*args)
    except (TypeError, ValueError) as e:
        out.setdefault("errors", []).append(type(e).__name__)
try:
    app.quick_calibrate(9000)
except CalibrationRejected as e:
    out["no_location"] = e.reason
out["outside"] = app.set_location(ZURICH[0], ZURICH[1], 2031000)
out["status"] = app.set_location(ZURICH[0], ZURICH[1], 2026500)
out["decl"] = app.compass.declination_kang
W.run_until(app, b, 0.3)
cal = app.quick_calibrate(3400)
out["offset"] = list(cal.offset)
out["field"] = cal.field
ok = sum(1 for _ in range(50) if app.step())
out["heading"] = app.heading_kang
out["ok"] = ok
out["accuracy"] = app.accuracy
out["line"] = status_line(app)
print(json.dumps([[k, out[k]] for k in sorted(out)]))  # a fixed order on both
