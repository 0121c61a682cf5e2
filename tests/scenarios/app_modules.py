# Which firmware modules a board has loaded: after booting from a stored calibration and 100
# steps (the heading-only runtime), after it starts collecting, once that session has ended
# (the board still: no new direction), and after set_location(). Prints four JSON lines:
# [phase, modules, steps with a heading, collecting] (+ the steps run, or the location's
# status). Run by tests/test_layout.py on CPython and MicroPython. The stored calibration is
# made by hand (app_world.stored_calibration), so nothing of the calibration machinery runs
# before the check.
import json
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402


def firmware_modules():
    # firmware.fast (the viper mirrors) loads only on ports with the native emitter
    return sorted(k for k in sys.modules if k.startswith("firmware.") and k != "firmware.fast")


b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
fs = W.MemFs()
app = W.make_app(b, store=W.stored_calibration(fs))
ok = sum(1 for _ in range(100) if app.step())
print(json.dumps(["heading_only", firmware_modules(), ok, app.collector is not None]))
app.calibrate()
ok = sum(1 for _ in range(100) if app.step())
print(json.dumps(["collecting", firmware_modules(), ok, app.collector is not None]))
n = 0
ok = 0
while app.collector is not None and n < 1500:  # 30 s at 50 Hz at the most
    n += 1
    ok += app.step()
print(json.dumps(["ended", firmware_modules(), ok, app.collector is not None, n]))
status = app.set_location(473977000, 85456000, 2026500)  # Zurich, mid-2026
ok = sum(1 for _ in range(100) if app.step())
print(json.dumps(["located", firmware_modules(), ok, app.collector is not None, status]))
