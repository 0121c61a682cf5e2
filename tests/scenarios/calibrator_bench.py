# Timing figures on the interpreter that runs it (meant for the MicroPython unix port):
#  - solve() time per model on a full 300-sample buffer from the simulated QMC5883L;
#  - the time-sliced solve: number of steps and the longest step (model 10);
#  - add() cost per raw sample with the buffer (nearly) empty and full, and per path
#    (rejected / kept / replaced), over a 200 Hz figure-8 stream.
# Prints one JSON object (microseconds). Not a parity scenario: times differ by design.
import gc
import json
import sys
import time

sys.path.append("tests/scenarios")
from calibrator_parity import CPG, sim_raw  # noqa: E402

from firmware.calibrate.calibrator import Calibrator  # noqa: E402

try:
    ticks = time.ticks_us
    diff = time.ticks_diff
except AttributeError:  # CPython
    def ticks():
        return time.perf_counter_ns() // 1000

    def diff(a, b):
        return a - b

N = 6000
raw = sim_raw(N)
out = {}
gc.collect()  # the simulator's garbage would otherwise bill its collection to the first adds

# add(): per path, and empty (first 300 raw samples) vs full (buffer at capacity)
cal = Calibrator(model=10, capacity=300, separation=900, counts_per_gauss=CPG)
paths = {"rejected": [0, 0], "kept": [0, 0], "replaced": [0, 0]}
phase = {"empty": [0, 0], "full": [0, 0]}
rej = {"empty": [0, 0], "full": [0, 0]}
for i in range(N):
    x = raw[3 * i]
    y = raw[3 * i + 1]
    z = raw[3 * i + 2]
    n0 = cal.count
    t0 = ticks()
    k = cal.add(x, y, z)
    dt = diff(ticks(), t0)
    p = "rejected" if not k else ("kept" if cal.count > n0 else "replaced")
    paths[p][0] += dt
    paths[p][1] += 1
    if i < 300:
        ph = "empty"
    elif n0 == cal.capacity:
        ph = "full"
    else:
        ph = None
    if ph:
        phase[ph][0] += dt
        phase[ph][1] += 1
        if not k:
            rej[ph][0] += dt
            rej[ph][1] += 1
for name, v in paths.items():
    out["add_%s_us" % name] = [v[0] // v[1] if v[1] else 0, v[1]]
for name, v in phase.items():
    out["add_per_raw_%s_us" % name] = [v[0] // v[1] if v[1] else 0, v[1]]
for name, v in rej.items():
    out["add_rejected_%s_us" % name] = [v[0] // v[1] if v[1] else 0, v[1]]
out["held"] = cal.count

for m in ("minmax", 4, 7, 10):
    best = None
    for rep in range(3):
        t0 = ticks()
        c = cal.solve(model=m, accept=False)
        dt = diff(ticks(), t0)
        best = dt if best is None or dt < best else best
    out["solve_%s_us" % m] = best
    out["fit_error_%s" % m] = c.fit_error

steps = 0
longest = 0
job = cal.solve_steps(model=10, accept=False)
while True:
    t0 = ticks()
    try:
        next(job)
    except StopIteration:
        break
    dt = diff(ticks(), t0)
    longest = dt if dt > longest else longest
    steps += 1
out["sliced_10_steps"] = steps
out["sliced_10_longest_step_us"] = longest
print(json.dumps(out))
