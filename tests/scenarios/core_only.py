# A board with only the core part installed (package-core.json): the firmware package at
# argv[1] holds nothing else. Boots from a stored calibration (100 steps), then from an
# empty store with a calibration file waiting. Prints two JSON lines:
# [steps with a heading, status, app.not_installed(, status line, boot note)].
import json
import sys

lib = sys.argv[1]
sys.path.insert(0, lib)
sys.path.insert(1, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.app import status_line  # noqa: E402
from firmware.boot import start  # noqa: E402

assert sys.modules["firmware"].__file__.startswith(lib)
b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
fs = W.MemFs()
app = W.make_app(b, store=W.stored_calibration(fs))
ok = sum(1 for _ in range(100) if app.step())
print(json.dumps([ok, app.status, app.not_installed]))

b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=6)
with open(lib + "/calibration.json", "w") as f:
    f.write("{}")
app, note = start(b.bus, lib, delay_us=b.sleep_us, ticks_us=b.clock.ticks_us,
                  mag_axes=W.MAG_AXES, accel_axes=W.ACCEL_AXES)
ok = sum(1 for _ in range(100) if app.step())
print(json.dumps([ok, app.status, app.not_installed, status_line(app), note]))
