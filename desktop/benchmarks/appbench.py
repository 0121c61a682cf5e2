"""The app's loop while solves run in the background.

firmware.app.CompassApp runs over ReplayBus (the drivers read a recorded 200 Hz figure-8
session of a GY-271 + GY-521 with hard and rotated soft iron; the bus allocates nothing and
costs ~1 us per transfer, subtracted nowhere: it is part of every step alike). The app's
clock moves 5 ms per step (200 Hz); every step is also timed on the wall clock. Reported:
the app's own .worst_stall_us (its longest solver slice), and from the step times: the
median step without a slice, the median and the longest step with one.
"""
import gc

from desktop.benchmarks import common

from firmware.app import CompassApp
from firmware.mpu6050 import MPU6050
from firmware.qmc5883l import QMC5883L

SMOKE = common.smoke()
N = 1500 if SMOKE else 6000
DT_US = 20000 if SMOKE else 5000   # one 30 s figure-8
LAPS = 2                           # the session is replayed twice
PERIOD_US = 5000


def make_app(bus, clock):
    return CompassApp(bus, mag=QMC5883L(bus, odr=200), accel=MPU6050(bus),
                      ticks_us=clock.ticks, store=None)


def main():
    mag, acc = common.session(N, dt_us=DT_US)
    bus = common.replay_board(mag, acc)
    clock = common.Clock()
    app = make_app(bus, clock)
    gc.collect()
    plain = []
    sliced = []
    for _ in range(LAPS * N):
        clock.now += PERIOD_US
        s0 = app.slices
        t0 = common.clock()
        app.step()
        dt = common.since_us(t0)
        (sliced if app.slices != s0 else plain).append(dt)
    p = app.progress()
    res = {"interpreter": common.interpreter(), "steps": LAPS * N,
           "worst_stall_us": app.worst_stall_us, "slices": app.slices, "solves": app.solves,
           "accepted": app.accepted, "refused": app.refused, "last_reason": app.last_reason,
           "model": p["model"], "fit_error_x100": p["fit_error"], "held": p["samples"],
           "step_us": {"median_without_slice": common.median(plain),
                       "max_without_slice": max(plain) if plain else None,
                       "median_with_slice": common.median(sliced),
                       "max_with_slice": max(sliced) if sliced else None},
           "status_counts": app.errors}
    common.emit(res)


if __name__ == "__main__":
    main()
