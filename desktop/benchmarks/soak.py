"""The fault campaign in the bench (docs/faults.md; make soak runs the long one): BENCH_SESSIONS
sessions of BENCH_SECONDS simulated seconds, seed 1, every fault class, and one fault-free
session in ten beside them (false alarms); then the same with the gyro-aided heading
("gyro_campaign", soak --gyro). The figures are counts, not times, so they are the
same on every machine; elapsed_s is this machine's wall clock. CPython only (the simulator
with floats)."""
import time

from desktop import soak

BENCH_SESSIONS = 120    # ~200,000 steps and ~400 faults, ~35 per class: bench-friendly (~30 s)
BENCH_SECONDS = 60
SMOKE_SESSIONS = 4
SMOKE_SECONDS = 10


def figures(sessions=BENCH_SESSIONS, seconds=BENCH_SECONDS, seed=1, gyro=False):
    t0 = time.time()
    st = soak.campaign(sessions, seconds, seed, gyro=gyro)
    st["elapsed_s"] = round(time.time() - t0, 1)
    st["report"] = soak.report(st)
    return st


def main():
    # the campaign, and the same campaign with the gyro-aided heading (soak --gyro)
    from desktop.benchmarks import common
    n, s = (SMOKE_SESSIONS, SMOKE_SECONDS) if common.smoke() else (BENCH_SESSIONS, BENCH_SECONDS)
    st = figures(n, s)
    st["gyro_campaign"] = figures(n, s, gyro=True)
    common.emit(st)


if __name__ == "__main__":
    main()
