# MicroPython only: proves that Calibration.correct() allocates nothing (heap_lock) for inputs
# across the int16 range, including saturating ones, with a real solved calibration and with
# the identity; and that Calibrator.add() allocates nothing on its common path (a rejected
# sample, buffer full). Prints one JSON object of booleans and counts.
import json
from array import array

import micropython

from firmware.calibration import UNCALIBRATED, Calibration
from firmware.calibrate.calibrator import Calibrator

cal = Calibration(model=10, offset=(14398, -9596, 4803),
                  invw=(25173, -1154, 768, -1154, 30077, -1237, 768, -1237, 27945),
                  field=6013, field_out=5110, fit_error=41, samples=218, coverage=97)
out = array("h", bytearray(6))
raw = array("h", bytearray(6))
results = {"correct_calls": 0, "correct_allocated": 0, "add_calls": 0, "add_allocated": 0}


def locked_correct(c):
    micropython.heap_lock()
    try:
        c.correct(raw, out)
    except MemoryError:
        micropython.heap_unlock()
        return True
    micropython.heap_unlock()
    return False


for c in (cal, UNCALIBRATED):
    for x in (-32768, -20000, -1, 0, 1, 12345, 32767):
        for y in (-32768, -7, 0, 30000, 32767):
            for z in (-32768, 0, 4803, 32767):
                raw[0] = x
                raw[1] = y
                raw[2] = z
                results["correct_calls"] += 1
                if locked_correct(c):
                    results["correct_allocated"] += 1

# fill a Calibrator, then offer samples it must reject (the common path at 50-200 Hz)
cb = Calibrator(model=10, capacity=40, separation=2000)
k = 0
while cb.count < cb.capacity:
    cb.add((k * 7919) % 60000 - 30000, (k * 104729) % 60000 - 30000, (k * 1299709) % 60000 - 30000)
    k += 1
held = cb.buffer.data
for i in range(cb.count):
    x = held[3 * i] + 3
    y = held[3 * i + 1] - 2
    z = held[3 * i + 2] + 1
    micropython.heap_lock()
    try:
        kept = cb.add(x, y, z)
        alloc = False
    except MemoryError:
        alloc = True
        kept = None
    micropython.heap_unlock()
    results["add_calls"] += 1
    if alloc or kept:
        results["add_allocated"] += 1
results["buffer_full"] = cb.count == cb.capacity

# heap_lock misses a call frame moved to the heap (it falls back to the C stack when locked);
# mem_total counts every byte allocated, frames included: correct() must add none.
def correct_bytes(n):
    raw[0] = 20000
    i = 0
    t0 = micropython.mem_total()
    while i < n:
        cal.correct(raw, out)
        i += 1
    return micropython.mem_total() - t0


correct_bytes(10)
results["correct_mem_total_bytes_per_1000"] = correct_bytes(1000)
print(json.dumps(results))
