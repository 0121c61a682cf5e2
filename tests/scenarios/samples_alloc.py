# MicroPython only: proves that SampleBuffer.offer() allocates nothing on each of its paths
# (reject by the newest sample, reject by a neighbour cell, reject by a taken cell, keep,
# replace with backward-shift deletion) and that coverage() allocates nothing either.
# Prints one JSON line: for each path, the heap_lock verdict and the bytes gc.mem_alloc() saw.
import gc
import json

import micropython

from firmware.calibrate.samples import KEPT, REJECTED, REPLACED, SampleBuffer

S = 100
buf = SampleBuffer(capacity=8, separation=S)


# Calls go through fixed-arity wrappers: forwarding *args would itself allocate a tuple.
def locked(fn, a, b, c):
    # Returns (result, allocated): allocated is True when heap_lock caught an allocation.
    micropython.heap_lock()
    try:
        r = fn(a, b, c)
    except MemoryError:
        micropython.heap_unlock()
        return None, True
    micropython.heap_unlock()
    return r, False


def counted(fn, a, b, c):
    gc.collect()
    gc.disable()
    before = gc.mem_alloc()
    r = fn(a, b, c)
    used = gc.mem_alloc() - before
    gc.enable()
    return r, used


out = {}
buf.offer(1000, 1000, 1000)       # A (oldest)
buf.offer(-5000, 2000, 300)       # B (newest)
cases = [
    ("reject_newest", (-5010, 2005, 299), REJECTED),     # within S of B: the first test
    ("reject_neighbour", (1000 + 60, 1000, 1000 - 30), REJECTED),  # near A, other cell
    ("reject_taken_cell", (1099, 1099, 1099), REJECTED),  # A's cell, 171 counts from A
    ("keep", (20000, -20000, 7000), KEPT),
]
for name, (x, y, z), want in cases:
    r, alloc = locked(buf.offer, x, y, z)
    out[name] = [r == want, alloc, buf.last_cells]
    if name != "keep":  # offered again: rejected the same way, bytes counted by the gc
        r2, used = counted(buf.offer, x, y, z)
        out[name].append(used if r2 == want else -1)
# fill up, then a keep on a full buffer replaces the oldest (exercises _unlink)
i = 0
while buf.count < buf.capacity:
    buf.offer(-30000 + 1000 * i, 30000 - 700 * i, 500 * i)
    i += 1
r, alloc = locked(buf.offer, 123, -4567, 8910)
out["replace"] = [r == REPLACED, alloc]
r, used = counted(buf.offer, 5123, -4567, 8910)
out["replace"].append(used if r == REPLACED else -1)
r, alloc = locked(buf.coverage, 0, 0, 0)
out["coverage"] = [0 <= r <= 100, alloc]
# many offers under one lock: a random walk, every path taken many times
x, y, z = 0, 0, 0
import sys  # noqa: E402
sys.path.append("tests/scenarios")  # smallrand, also when the script arrives on stdin (qemu)
from smallrand import SmallRand  # noqa: E402

seed = 1
_R = SmallRand(seed)


def walk(n, _b, _c):
    global x, y, z, seed
    kept = 0
    for _ in range(n):
        seed = _R.u30()
        x += ((seed >> 8) & 255) - 127
        y += ((seed >> 16) & 255) - 127
        z += ((seed >> 4) & 255) - 127
        x = -20000 if x < -20000 else 20000 if x > 20000 else x
        y = -20000 if y < -20000 else 20000 if y > 20000 else y
        z = -20000 if z < -20000 else 20000 if z > 20000 else z
        if buf.offer(x, y, z) != REJECTED:
            kept += 1
    return kept


r, alloc = locked(walk, 2000, 0, 0)
out["walk_2000"] = [r is not None and r > 8, alloc]


def allocates(a, b, c):
    return [a, b, c]


r, alloc = locked(allocates, 1, 2, 3)
out["control_list"] = [r is None, alloc]   # the harness must see this allocation
print(json.dumps(out))
