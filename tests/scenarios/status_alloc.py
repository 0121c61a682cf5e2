# MicroPython only: the bytes one status line costs, as boards/main.py writes it
# (firmware.app.status_view), in each state the line tells apart, and once as a str
# (status_line). Prints one JSON object: {"view": {state: B}, "line_calibrated": B,
# "lines": {state: the line}} - micropython.mem_total per call over 50 calls (the simulator
# is not running meanwhile: only the line is counted). tests/test_status_line.py holds every
# view at 64 bytes or less (the memoryview itself is 16 of them on a 32-bit port).
#
# States: a GY-271 + GY-521 collecting through a figure-8 and solving; a stored calibration
# (the hand-made record is off this world's field: interference); what the heap could not
# hold (no_memory), the app that did not fit, a jump, a location with and without a date;
# the GY-87 with use_gyro() on the field, held through a magnet and held too long.
import json
import sys

import micropython

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from host_sim import motion  # noqa: E402
from desktop.benchmarks import gyroworld as G  # noqa: E402

from firmware import compat  # noqa: E402
from firmware.app import status_line, status_view  # noqa: E402
from firmware.store import CalStore  # noqa: E402

N = 50
ZURICH = (473977000, 85456000)
YEAR_E3 = 2026500
out = {"view": {}, "lines": {}}


def per_call(fn, app):
    fn(app)  # the module imported, its buffer made
    t = micropython.mem_total()
    for _ in range(N):
        fn(app)
    return (micropython.mem_total() - t) // N


def measure(state, app):
    out["view"][state] = per_call(status_view, app)
    out["lines"][state] = status_line(app)


b = W.make_sim("gy271", m=motion.figure8(), seed=3)
app = W.make_app(b)
W.run_until(app, b, 3.0)
measure("collecting", app)
while app.collector.job is None and b.clock.now_us < 20000000:
    app.step()
measure("solving", app)

fs = W.MemFs()
W.stored_calibration(fs)
b2 = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
app2 = W.make_app(b2, store=CalStore("/", fs=fs))
W.run_until(app2, b2, 2.0)
measure("calibrated", app2)
out["line_calibrated"] = per_call(status_line, app2)
for what in ("load", "calibrate"):
    app2.no_memory = what
    measure("no_memory_" + what, app2)
app2.no_memory = None
app2._args = ()  # as when the app itself did not fit (CompassApp's constructor)
measure("app_did_not_fit", app2)
app2._args = None
class Jump:  # a session holding a pending fit whose field jumped (firmware/calibrate/session.py)
    pending = None
    change = ("field", 6900, 5400, 6600)
    history_errors = 0
    history_reason = None


app2.learning.session = Jump()
measure("jump", app2)
app2.learning.session = None
app2.set_location(ZURICH[0], ZURICH[1], YEAR_E3)
W.run_until(app2, b2, 2.5)
measure("location", app2)
app2.set_location(ZURICH[0], ZURICH[1])
W.run_until(app2, b2, 3.0)
measure("location_no_date", app2)

b3 = G.board(motion.still(yaw=40), gyro={"gyro_bias_dps": (0.5, -0.4, 0.6)})
b3.world.add_magnet((8.0, 4.0, 0.0), 10, 30, ramp_s=0.3, frame="world")
app3 = G.app(b3, max_uncertainty_cdeg=150)
G.run(app3, b3, 3)
measure("gyro_on_field", app3)
G.run(app3, b3, 12)
measure("gyro_held", app3)
G.run(app3, b3, 27)
measure("gyro_held_too_long", app3)

print(json.dumps(out))
