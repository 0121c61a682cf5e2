# MicroPython only: the bytes one status line costs, as boards/main.py writes it
# (firmware.app.status_view) and as a str (status_line), on a simulated GY-271 + GY-521
# collecting through a figure-8 and then calibrated (a stored record). Prints one JSON object:
# {"view_collecting": B, "view_calibrated": B, "line_calibrated": B} - micropython.mem_total
# per call over 50 calls (the simulator is not running meanwhile: only the line is counted).
import json
import sys

import micropython

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from host_sim import motion  # noqa: E402

from firmware.app import status_line, status_view  # noqa: E402
from firmware.store import CalStore  # noqa: E402

N = 50


def per_call(fn, app):
    fn(app)  # the module imported, its buffer made
    t = micropython.mem_total()
    for _ in range(N):
        fn(app)
    return (micropython.mem_total() - t) // N


out = {}
b = W.make_sim("gy271", m=motion.figure8(), seed=3)
app = W.make_app(b)
W.run_until(app, b, 3.0)
out["view_collecting"] = per_call(status_view, app)
fs = W.MemFs()
W.stored_calibration(fs)
b2 = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
app2 = W.make_app(b2, store=CalStore("/", fs=fs))
W.run_until(app2, b2, 2.0)
out["calibrated_line"] = status_line(app2)
out["view_calibrated"] = per_call(status_view, app2)
out["line_calibrated"] = per_call(status_line, app2)
print(json.dumps(out))
