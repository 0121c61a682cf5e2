# A deterministic offer sequence (integer LCG, points on a shifted sphere, wrap-around of a small
# buffer), then coverage, region() on a grid and set_separation(). Prints integers only (JSON),
# so CPython and MicroPython must agree bit for bit (lists, not dicts: key order differs).
import json

from firmware.fixedpoint import isqrt
from firmware.calibrate.samples import REPLACED, SampleBuffer, region, separation_for

import sys  # noqa: E402
sys.path.append("tests/scenarios")  # smallrand, also when the script arrives on stdin (qemu)
from smallrand import SmallRand  # noqa: E402

seed = 12345
_R = SmallRand(seed)


def rnd(bits):
    global seed
    seed = _R.u30()
    return (seed >> 8) & ((1 << bits) - 1)


R = 6000
V = (1500, -2500, 700)
buf = SampleBuffer(capacity=64, separation=separation_for(R, 120))
results = [0, 0, 0]
cells = 0
probes = 0
evicted_sum = [0, 0, 0]
first = []
for i in range(3000):
    while True:
        v = [rnd(15) - 16384, rnd(15) - 16384, rnd(15) - 16384]
        n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        if (1 << 20) < n2 < (1 << 28):
            break
    n = isqrt(n2)
    x, y, z = [v[k] * R // n + V[k] for k in range(3)]
    r = buf.offer(x, y, z)
    results[r] += 1
    cells += buf.last_cells
    probes += buf.last_probes
    if r == REPLACED:
        for k in range(3):
            evicted_sum[k] += buf.evicted[k]
    if i < 40:
        first.append(r)
print(json.dumps(["offers", results, first, cells, probes, evicted_sum, buf.count, buf.next_slot]))
print(json.dumps(["held", list(buf.data), [buf.slot_by_age(k) for k in range(buf.count)]]))
cov_v = buf.coverage(V[0], V[1], V[2])
gaps_v = buf.gaps_x100
regions_v = list(buf.region_counts)
cov_0 = buf.coverage(0, 0, 0)
print(json.dumps(["coverage", cov_v, gaps_v, regions_v, cov_0, buf.gaps_x100]))
grid = []
for a in range(-3, 4):
    for b in range(-3, 4):
        for c in range(-3, 4):
            grid.append(region(a * 9001, b * 7919 - c, c * 10007 + a))
grid.append(region(0, 0, 0))
grid.append(region(-65535, 65535, -65535))
grid.append(region(1, 0, 0))
print(json.dumps(["grid", grid]))
dropped = buf.set_separation(buf.separation * 2)
print(json.dumps(["resep", dropped, buf.count, list(buf.data)[:3 * buf.count]]))
