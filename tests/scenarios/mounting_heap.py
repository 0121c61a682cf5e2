# MicroPython only: what the mounting check costs in heap, and that Pairs.feed allocates
# nothing. The core modules it uses are imported first (a board in a calibration session holds
# them already); then, after gc.collect() each: firmware/calibrate/mounting.py (the session holds it),
# a Pairs with all 24 bins filled, firmware/calibrate/mountcheck.py (loaded for a check), check()'s
# transient allocations (gc.mem_alloc() right after it, nothing collected: an upper bound of
# its peak) and what stays after it. Prints one JSON object.
import gc
import json
from array import array

import micropython

from firmware import axes, calibration, compat, fixedpoint, trig  # noqa: F401 - the core's

# a board turning slowly through every direction of gravity: 24 directions, each held for a
# few steps (the first step of a new direction moves too far and is refused)
G = 16384
dirs = []
for face in range(3):
    for sgn in (1, -1):
        for s1 in (1, -1):
            for s2 in (1, -1):
                v = [0, 0, 0]
                v[face] = sgn * 13000
                v[(face + 1) % 3] = s1 * 6000
                v[(face + 2) % 3] = s2 * 5000
                n = fixedpoint.isqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                dirs.append(array("h", (v[0] * G // n, v[1] * G // n, v[2] * G // n,
                                        1000 + v[1] // 4, 1000 + v[2] // 4, 1000 + v[0] // 4)))
raw = array("h", (0, 0, 0))
acc = array("h", (0, 0, 0))
cal = calibration.Calibration(model=10, offset=(1000, 1000, 1000),
                              invw=(30000, 0, 0, 0, 30000, 0, 0, 0, 30000), field=3000,
                              field_out=2700)
mm = axes.AxisMap("x,-y,-z").m
am = axes.AxisMap("-x,y,z").m
alloc = 0
calls = 0
rep = 0
i = 0


def live():
    gc.collect()
    gc.collect()
    return gc.mem_alloc()


m0 = live()
from firmware.calibrate import mounting  # noqa: E402
m1 = live()
p = mounting.Pairs(16384, 20000)
m2 = live()
for d in dirs:
    for rep in range(4):
        for i in range(3):
            acc[i] = d[i] + rep
            raw[i] = d[3 + i] + rep
        micropython.heap_lock()
        try:
            p.feed(raw, acc)
        except MemoryError:
            alloc += 1
        micropython.heap_unlock()
        calls += 1
m3 = live()
from firmware.calibrate import mountcheck  # noqa: E402
m4 = live()
v = mountcheck.check(p, cal, mm, am)
m5 = gc.mem_alloc()
m6 = live()
print(json.dumps({"module": m1 - m0, "pairs": m2 - m1, "bins": p.count, "feed_calls": calls,
                  "feed_allocated": alloc, "after_feeding": m3 - m2,
                  "check_module": m4 - m3, "check_transient": m5 - m4,
                  "after_check": m6 - m4, "verdict": v[0]}))
