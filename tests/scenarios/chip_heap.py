# The live heap of a calibrated board per chip (tests/test_budgets.py, x86-32 from .mpy
# files): the simulated board of argv[1] (app_world.ALL_SETUPS) built first, then the firmware
# booted as boards/main.py boots it (firmware/boot.py start) over the store in argv[2], 500
# headings; the heap held after boot and after them, minus the heap before the first firmware
# import (the simulator's included there). The names the boot interns go to MicroPython's name
# pool, which grows in blocks of ~9 KB wherever the simulator's own names left it: the pool's
# counts are printed before and after (micropython.qstr_info, one line each) for the test to
# take the pool's growth out. Then one JSON object.
import gc
import json
import sys

sys.path.append("tests/scenarios")
from app_world import ALL_SETUPS, axes  # noqa: E402

from host_sim import motion  # noqa: E402
from host_sim.boards import make_board  # noqa: E402
from host_sim.world import World  # noqa: E402


def live():
    gc.collect()
    gc.collect()
    return gc.mem_alloc()


setup = sys.argv[1]
chip, accel = ALL_SETUPS[setup]
b = make_board(chip, world=World(field_ut=50.0, inclination_deg=60.0,
                                 motion=motion.still(30.0, 10.0, -5.0)), seed=3, accel=accel)
for _ in range(3):
    b.clock.advance(20000)
    b.bus.scan()
mag_axes, accel_axes = axes(b)
import micropython  # noqa: E402
base = live()
micropython.qstr_info()
from firmware.boot import start  # noqa: E402
from firmware.compat import drop  # noqa: E402
app = start(b.bus, sys.argv[2], delay_us=b.sleep_us, ticks_us=b.clock.ticks_us,
            mag_axes=mag_axes, accel_axes=accel_axes)[0]
drop("boot")
boot = live() - base
ok = 0
for _ in range(500):
    ok += 1 if app.step() else 0
after = live() - base
micropython.qstr_info()
print(json.dumps({"setup": setup, "kind": app.mag.KIND, "model": app.calibration.model,
                  "load_reason": app.load_reason, "ok": ok, "status": app.status,
                  "boot": boot, "after": after,
                  "modules": sorted(n[9:] for n in sys.modules if n.startswith("firmware."))}))
