# Cost of SampleBuffer.offer() per path and with an empty vs a full buffer: hash cells looked up
# and table entries read per offer (deterministic), and on MicroPython the time per offer with
# the heap locked (so no garbage collection can land in a timed loop). One JSON line per case:
# [name, offers, cells, probes, elapsed_us]  (elapsed_us is 0 on CPython).
import json

from firmware.fixedpoint import isqrt
from firmware.calibrate.samples import SampleBuffer, separation_for

try:
    import micropython
    from time import ticks_diff, ticks_us
except ImportError:  # CPython: counts only
    micropython = None

    def ticks_us():
        return 0

    def ticks_diff(a, b):
        return 0

import sys  # noqa: E402
sys.path.append("tests/scenarios")  # smallrand, also when the script arrives on stdin (qemu)
from smallrand import SmallRand  # noqa: E402

seed = 7
_R = SmallRand(seed)


def rnd():
    global seed
    seed = _R.u30()
    return ((seed >> 8) & 0x7FFF) - 16384


def on_sphere(v, R, c):
    q = isqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] * R // q + c, v[1] * R // q, v[2] * R // q)


def sphere(n, R, c):
    pts = []
    while len(pts) < n:
        v = (rnd(), rnd(), rnd())
        n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        if (1 << 20) < n2 < (1 << 28):
            pts.append(on_sphere(v, R, c))
    return pts


def smooth(n, R):
    # a slow wander over the sphere: each step moves about 1/60 of the radius
    v = [R, 0, 0]
    pts = []
    for _ in range(n):
        for k in range(3):
            v[k] += ((rnd() >> 7) * R) >> 13
        p = on_sphere(v, R, 0)
        v = [p[0], p[1], p[2]]
        pts.append(p)
    return pts


res = [0, 0, 0]


def run(buf, pts, reps):
    cells = 0
    probes = 0
    t = ticks_us()
    for _ in range(reps):
        for p in pts:
            buf.offer(p[0], p[1], p[2])
            cells += buf.last_cells
            probes += buf.last_probes
    res[0] = ticks_diff(ticks_us(), t)
    res[1] = cells
    res[2] = probes
    return 0


def case(name, buf, pts, reps=1):
    if micropython:
        micropython.heap_lock()
    try:
        run(buf, pts, reps)
    finally:
        if micropython:
            micropython.heap_unlock()
    print(json.dumps([name, len(pts) * reps, res[1], res[2], res[0]]))


R = 6000
s = separation_for(R, 225)
buf = SampleBuffer(capacity=300, separation=s)
case("random_filling", buf, sphere(200, R, 0))
for i in range(6):
    run(buf, sphere(1500, R, 0 if i < 3 else 3000), 1)
j = 3 * buf.slot_by_age(buf.count - 1)
case("reject_newest", buf, [(buf.data[j] + 1, buf.data[j + 1], buf.data[j + 2])], 2000)
j = 3 * buf.slot_by_age(0)
case("reject_own_cell", buf, [(buf.data[j], buf.data[j + 1], buf.data[j + 2])], 2000)
case("random_full", buf, sphere(2000, R, -3000))
case("smooth_stream", SampleBuffer(capacity=300, separation=s), smooth(3000, R))
t = ticks_us()
for i in range(10):
    buf.coverage(0, 0, 0)
print(json.dumps(["coverage_300", 10, buf.count, 0, ticks_diff(ticks_us(), t)]))
