# MicroPython only: proves the per-sample heading path allocates nothing.
#
# bytes       micropython.mem_total() (cumulative bytes ever allocated, freed or not) before
#             and after each call: every allocation counts, including a call frame that
#             MicroPython takes from the heap and frees at return (functions whose arguments,
#             locals and stack exceed 11 words, py/objfun.c VM_MAX_STATE_ON_STACK).
# locked_loop heap_lock() around many samples: any allocation that cannot fall back raises
#             MemoryError.
# control     an oversized function: mem_total sees its frame, heap_lock does not (the frame
#             falls back to the C stack), which is why both measures are used.
import json
import micropython
from array import array

from firmware.axes import AxisMap
from firmware.compass import Compass, heading
from firmware.trig import atan2, cos, sin

mt = micropython.mem_total


def oversized(a):
    b = a + 1
    c = b + 1
    d = c + 1
    e = d + 1
    f = e + 1
    g = f + 1
    h = g + 1
    i = h + 1
    j = i + 1
    k = j + 1
    return a + b + c + d + e + f + g + h + i + j + k


raw_mag = array("h", [2400, 1700, -4600])
raw_acc = array("h", [-3100, 2200, 15800])
b = array("h", [0, 0, 0])
g = array("h", [0, 0, 0])
mag_map = AxisMap("x,-y,-z")
acc_map = AxisMap("-x,y,z")
c = Compass(field=6000, declination_kang=1000)
zero = array("h", [0, 0, 0])
out = array("i", [0] * 8)


def measure(res):
    # each entry: bytes allocated by one call (already warmed up below)
    t = mt(); mag_map.apply(raw_mag, b); res["axes.apply"] = mt() - t
    t = mt(); acc_map.apply(raw_acc, g); res["axes.apply_accel"] = mt() - t
    t = mt(); c.update(b, g); res["Compass.update"] = mt() - t
    t = mt(); c.update(b); res["Compass.update_level"] = mt() - t
    t = mt(); c.update(b, zero); res["Compass.update_no_gravity"] = mt() - t
    t = mt(); c.update(zero, g); res["Compass.update_no_field"] = mt() - t
    t = mt(); heading(b, g, 500); res["heading"] = mt() - t
    t = mt(); heading(b); res["heading_level"] = mt() - t
    t = mt(); atan2(-12345, 321); res["atan2"] = mt() - t
    t = mt(); sin(40000); res["sin"] = mt() - t
    t = mt(); cos(-40000); res["cos"] = mt() - t
    b[0] = 30; b[1] = -2; b[2] = 1
    t = mt(); c.update(b, raw_acc); res["Compass.update_tiny_field"] = mt() - t
    b[0] = -32768; b[1] = 20001; b[2] = -16385  # scaled down (the rounding right shift)
    t = mt(); c.update(b, raw_acc); res["Compass.update_big_field"] = mt() - t
    mag_map.apply(raw_mag, b)


res = {}
measure(res)
measure(res)  # second run: dictionary slots exist, only the calls are measured

t = mt()
oversized(1)
control = mt() - t


def sensor_loop():
    for i in range(200):
        raw_mag[0] = 2400 + i * 7
        raw_acc[1] = 2200 - i * 50
        mag_map.apply(raw_mag, b)
        acc_map.apply(raw_acc, g)
        out[0] = c.update(b, g)
        out[1] = heading(b, g, 500)
        out[2] = c.flags


def control_loop():
    for i in range(200):
        out[3] = oversized(i)


def under_lock(fn):
    micropython.heap_lock()
    try:
        fn()
    except MemoryError:
        return "MemoryError"
    finally:
        micropython.heap_unlock()
    return "ok"


print(json.dumps({"bytes": res, "control_frame_bytes": control,
                  "control_under_lock": under_lock(control_loop),
                  "locked_loop": under_lock(sensor_loop),
                  "last": [out[0], out[1], out[2]]}))
