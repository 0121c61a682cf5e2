"""In the qemu Cortex-M guest (tools/run-qemu-mps2.sh with QEMU_ICOUNT=0): instruction counts of
the app's step and of one complete 10-element solve. With `-icount shift=0` the guest's clock
advances 1 ns per instruction executed, so time.ticks_us() differences are thousands of
instructions, the same on every run (bench.py turns them into RP2040 estimates and says
what it assumes).

    QEMU_ICOUNT=0 tools/run-qemu-mps2.sh . desktop/benchmarks/boardtime.py

Reads build/boardtime/session.bin (mag bytes then accel bytes, 6 per sample) and
build/boardtime/cal.bin (a calibration record's payload for that session), which bench.py
writes on CPython (the guest runs no simulator). Prints one JSON object:
  step_kinstr     {"fast": .., "plain": ..}: a calibrated board's step (its session ended),
                  mean over STEPS steps, thousands of instructions
  bus_kinstr      the replay bus's own part of a step (the four transfers a step makes:
                  status, data, accelerometer, configuration read-back), to subtract: a
                  board's machine.I2C is C code and its wire time bench.py adds
  collect_kinstr  the same with a collector fed every sample (learn=True), fast and plain
  solve_kinstr    one complete 10-element solve on a full buffer: total, slices, worst
                  slice, and the slices list
  yardstick_kinstr  the reference loops of yardstick.py whose RP2040 times are published:
                  int_add per 1000 iterations, pi_1000 per run - bench.py divides the
                  published cycles by these counts: the board's cycles per counted
                  instruction, measured, not assumed
"""
import gc
import json

from time import ticks_diff, ticks_us

from desktop.benchmarks import common

DIR = "build/boardtime/"
STEPS = 200
PERIOD_US = 5000


def kinstr(t0):
    return ticks_diff(ticks_us(), t0)


def load():
    import os
    n = os.stat(DIR + "session.bin")[6] // 12
    with open(DIR + "session.bin", "rb") as f:
        mag = f.read(6 * n)
        acc = f.read(6 * n)
    with open(DIR + "cal.bin", "rb") as f:
        cal = f.read()
    return mag, acc, cal


def app_steps(mag, acc, cal, fast, learn):
    from firmware.app import CompassApp
    from firmware.calibration import Calibration
    from firmware.mpu6050 import MPU6050
    from firmware.qmc5883l import QMC5883L
    bus = common.replay_board(mag, acc)
    clock = common.Clock()
    app = CompassApp(bus, mag=QMC5883L(bus, odr=200), accel=MPU6050(bus), ticks_us=clock.ticks,
                     store=None, fast=fast, learn=False)
    app.use_calibration(Calibration.from_bytes(cal), save=False)
    if learn:
        app.calibrate()
        app.collector.due = _never  # the per-sample path: no solve starts while timed
    for _ in range(STEPS):  # warm: the dip is learned, the buffer takes its first samples
        clock.now += PERIOD_US
        app.step()
    gc.collect()
    t0 = ticks_us()
    for _ in range(STEPS):
        clock.now += PERIOD_US
        app.step()
    return kinstr(t0) / STEPS


def bus_cost(mag, acc):
    bus = common.replay_board(mag, acc)
    b1 = bytearray(1)
    b6 = bytearray(6)
    b2 = bytearray(2)
    gc.collect()
    t0 = ticks_us()
    for _ in range(STEPS):
        bus.readfrom_mem_into(0x0D, 0x06, b1)
        bus.readfrom_mem_into(0x0D, 0x00, b6)
        bus.readfrom_mem_into(0x68, 0x3B, b6)
        bus.readfrom_mem_into(0x0D, 0x09, b2)
    return kinstr(t0) / STEPS


def _never():
    return False


def solve(mag):
    from firmware.calibrate.calibrator import Calibrator
    c = Calibrator(model=10, capacity=300, counts_per_gauss=common.QMC_CPG)
    v = [0, 0, 0]
    from firmware.i2cdevice import int16x3_into
    b = bytearray(6)
    for i in range(len(mag) // 6):
        for k in range(6):
            b[k] = mag[6 * i + k]
        int16x3_into(b, v, 0)
        c.add(v[0], v[1], v[2])
    gc.collect()
    job = c.solve_steps(10, accept=False)
    slices = []
    t0 = ticks_us()
    while True:
        t = ticks_us()
        try:
            next(job)
        except StopIteration:
            break
        slices.append(ticks_diff(ticks_us(), t))
    return {"total": kinstr(t0), "slices": len(slices), "worst": max(slices),
            "held": c.count, "per_slice": slices}


def main():
    from desktop.benchmarks import yardstick
    gc.collect()
    t0 = ticks_us()
    yardstick.add_loop([1000, 12345678, 56781234])
    add = kinstr(t0)
    gc.collect()
    t0 = ticks_us()
    yardstick.pi_digits(1000)
    pi = kinstr(t0)
    mag, acc, cal = load()
    out = {"yardstick_kinstr": {"int_add_per_1000": add, "pi_1000": pi}, "step_kinstr": {},
           "collect_kinstr": {}}
    for name, fast in (("fast", None), ("plain", False)):
        out["step_kinstr"][name] = app_steps(mag, acc, cal, fast, False)
        out["collect_kinstr"][name] = app_steps(mag, acc, cal, fast, True)
    out["bus_kinstr"] = bus_cost(mag, acc)
    out["solve_kinstr"] = solve(mag)
    print(json.dumps(out))


main()
