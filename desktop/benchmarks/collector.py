"""Calibrator.add per raw sample, empty buffer against full buffer.

One simulated 200 Hz figure-8 stream (QMC5883L, hard and rotated soft iron) goes through a
Calibrator(model=10, capacity=300 (100 with --smoke), separation=900) - the separation of
tests/scenarios/calibrator_bench.py, small enough for the buffer to fill and start replacing.
  empty   the first `capacity` raw samples of the session (the buffer fills from 0)
  full    every later raw sample offered while the buffer holds its capacity
Times: chunks of CHUNK consecutive adds with the collector running as it would in the app
(no gc.collect() forced between chunks: right after one, on a fragmented heap, the call
frames that SampleBuffer.offer takes from the heap - it is larger than the 11 words
MicroPython keeps on the C stack - are found only after a long scan, several times the
steady cost); per raw sample = summed chunk time / samples, so kept and replaced samples
(which update the exact moment sums, long ints) are billed where they happen. Per path
(rejected / kept / replaced) each add is also timed alone. Bytes per raw sample:
micropython.mem_total delta (every allocation, freed or not: those frames) and gc.mem_alloc
delta over chunks without a collection (what stays: the kept samples' garbage).
"""
import gc
import sys
from array import array

from desktop.benchmarks import common
from desktop.benchmarks.common import IS_MP

from firmware.calibrate.calibrator import Calibrator

SMOKE = common.smoke()
N = 1500 if SMOKE else 6000
DT_US = 20000 if SMOKE else 5000   # one 30 s figure-8 either way
CHUNK = 25
CAPACITY = 100 if SMOKE else 300
EMPTY = CAPACITY
SEPARATION = 900


def make():
    return Calibrator(model=10, capacity=CAPACITY, separation=SEPARATION,
                      counts_per_gauss=common.QMC_CPG)


def phases(raw):
    """Chunked timing: {phase: [us, samples, bytes]} plus the held count at the end."""
    cal = make()
    acc = {"empty": [0, 0, 0, 0, 0], "full": [0, 0, 0, 0, 0]}
    n = len(raw) // 3
    i = 0
    while i + CHUNK <= n:
        if i + CHUNK <= EMPTY:
            ph = "empty"
        elif cal.count == CAPACITY:
            ph = "full"
        else:
            ph = None
        m0 = common.mem_total()
        n0 = common.mem_alloc()
        t0 = common.clock()
        for j in range(3 * i, 3 * (i + CHUNK), 3):
            cal.add(raw[j], raw[j + 1], raw[j + 2])
        dt = common.since_us(t0)
        n1 = common.mem_alloc()
        m1 = common.mem_total()
        if ph is not None:
            a = acc[ph]
            a[0] += dt
            a[1] += CHUNK
            if IS_MP:
                a[2] += m1 - m0
                if n1 >= n0:  # no collection ran inside the chunk
                    a[3] += n1 - n0
                    a[4] += CHUNK
        i += CHUNK
    return acc, cal.count


def paths(raw):
    """Each add timed alone: {path_phase: [us total, count]}."""
    cal = make()
    out = {}
    for k in range(len(raw) // 3):
        n0 = cal.count
        full = n0 == CAPACITY
        j = 3 * k
        t0 = common.clock()
        kept = cal.add(raw[j], raw[j + 1], raw[j + 2])
        dt = common.since_us(t0)
        p = "rejected" if not kept else ("kept" if cal.count > n0 else "replaced")
        ph = "empty" if k < EMPTY else ("full" if full else "filling")
        key = p + "_" + ph
        a = out.get(key)
        if a is None:
            a = out[key] = [0, 0]
        a[0] += dt
        a[1] += 1
    return out


def main():
    mag, _ = common.session(N, dt_us=DT_US, accel=False)
    if sys.byteorder == "little":
        raw = array("h", bytes(mag))  # int16 x, y, z per sample, LSB first: compact
    else:
        raw = array("h", [common.le16(mag, 2 * i) for i in range(3 * N)])
    del mag
    gc.collect()
    phases(raw[:3 * EMPTY])  # warm-up
    acc, held = phases(raw)
    res = {"interpreter": common.interpreter(), "samples": N, "held_at_end": held,
           "capacity": CAPACITY, "separation": SEPARATION}
    per = {}
    for ph, a in acc.items():
        per[ph] = {"us_per_raw": a[0] / a[1] if a[1] else None, "raw_samples": a[1],
                   "mem_total_per_raw": a[2] / a[1] if (a[1] and IS_MP) else None,
                   "mem_alloc_per_raw": a[3] / a[4] if (a[4] and IS_MP) else None}
    res["phases"] = per
    e = per["empty"]["us_per_raw"]
    f = per["full"]["us_per_raw"]
    res["ratio_full_empty"] = f / e if (e and f) else None
    pt = paths(raw)
    res["paths_us"] = {k: [v[0] / v[1], v[1]] for k, v in pt.items()}
    common.emit(res)


if __name__ == "__main__":
    main()
