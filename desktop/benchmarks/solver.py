"""Solve time per model on a full buffer, and the time-sliced solve.

The buffer: Calibrator(model=10, capacity=300, separation=900) filled by a simulated 200 Hz
figure-8 (as collector.py), so it holds its capacity. Each model is solved with
accept=False RUNS times (gc.collect() first, the collector ON: the exact solve allocates
long ints and a board collects as it goes); the median is reported. The sliced solve
(solve_steps) is timed step by step, with its finest slices (group=1: at most
solve.SLICE_OPS long-int operations each) and with the Calibrator's default group (what the
app's one next() per step runs); the per-step medians over RUNS repetitions and their
maximum (the longest stall it adds to one step) are reported.
"""
import gc

from desktop.benchmarks import common

from firmware.calibrate.calibrator import Calibrator

SMOKE = common.smoke()
RUNS = 1 if SMOKE else 5
CAPACITY = 300


def full_calibrator():
    if SMOKE:
        mag, _ = common.session(3000, dt_us=10000, accel=False)
    else:
        mag, _ = common.session(6000, dt_us=5000, accel=False)
    cal = Calibrator(model=10, capacity=CAPACITY, separation=900,
                     counts_per_gauss=common.QMC_CPG)
    for x, y, z in common.raw_triples(mag):
        cal.add(x, y, z)
    return cal


def time_solve(cal, model):
    per = []
    c = None
    for _ in range(RUNS):
        gc.collect()
        t0 = common.clock()
        c = cal.solve(model=model, accept=False)
        per.append(common.since_us(t0))
    return common.median(per), c


def sliced(cal, model, group=1):
    runs = []
    for _ in range(RUNS):
        steps = []
        gc.collect()
        job = cal.solve_steps(model=model, accept=False, group=group)
        while True:
            t0 = common.clock()
            try:
                next(job)
            except StopIteration:
                steps.append(common.since_us(t0))
                break
            steps.append(common.since_us(t0))
        runs.append(steps)
    med = [common.median([r[i] for r in runs]) for i in range(len(runs[0]))]
    return med


def main():
    cal = full_calibrator()
    res = {"interpreter": common.interpreter(), "held": cal.count, "capacity": CAPACITY,
           "runs": RUNS, "solve_us": {}, "fit_error_x100": {}}
    for m in ("minmax", 4, 7, 10):
        t, c = time_solve(cal, m)
        res["solve_us"][str(m)] = t
        res["fit_error_x100"][str(m)] = c.fit_error
    steps = sliced(cal, 10)
    res["sliced_10"] = {"steps": len(steps), "longest_us": max(steps), "total_us": sum(steps),
                        "per_step_us": steps, "group": 1}
    g = cal.slice_group
    steps = sliced(cal, 10, g)
    res["sliced_10_app"] = {"steps": len(steps), "longest_us": max(steps),
                            "total_us": sum(steps), "group": g}
    common.emit(res)


if __name__ == "__main__":
    main()
