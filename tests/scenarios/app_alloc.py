# MicroPython only: what one CompassApp.step() allocates, and the worst stall of a 10-element
# solve, on the unix port. Prints one JSON object.
#
# Why a replay bus: the simulator allocates on every new sample (it computes floats), so a
# measure around step() on it would count the simulator. Here a 40 s figure-8 session is
# first recorded from host_sim (QMC5883L GY-271 + MPU6050, strong hard and soft iron); then
# the real drivers and the real app run over ReplayBus, a machine.I2C stand-in that serves
# the recorded samples from preallocated register images and allocates nothing itself
# (calibrated to 0 bytes below). Its clock moves 20 ms per magnetometer sample (50 Hz).
#
# Measures, each over N steps once the app has converged (a calibration in force, the
# buffer spread over the sphere, the recorded session replayed until a whole pass keeps no
# sample), in a window that starts just after a solve and holds none:
#   mem_total_bytes_per_step  micropython.mem_total() delta / N: every byte allocated, call
#                             frames that MicroPython puts on the heap included;
#   app_path_bytes_per_step   the same with Calibrator.add stubbed out: drivers, correct,
#                             axes, heading and the app's own bookkeeping;
#   calibrator_add_bytes_per_call  Calibrator.add alone, on the last sample read (rejected);
#   gc_net_bytes              gc off, gc.mem_alloc() after minus before (garbage left);
#   heap_locked_steps         steps that ran under heap_lock() (any allocation that cannot
#                             fall back raises MemoryError and ends the count);
#   solve_*                   a 10-element solve started by hand: steps, bytes (long-int
#                             arithmetic allocates by design), the app's worst slice
#                             (worst_stall_us) and, for scale, the same solve in one call.
import gc
import json
import time

import micropython

from firmware.app import CompassApp

N = 1000
PERIOD_US = 20000
mt = micropython.mem_total


def record(seconds):
    from host_sim import motion
    from host_sim.boards import make_board
    from host_sim.world import World
    w = World(hard_iron_ut=(40, -30, 25), motion=motion.figure8(),
              soft_iron=((1.15, 0.08, -0.05), (0.08, 0.9, 0.06), (-0.05, 0.06, 1.05)))
    b = make_board("gy271", world=w, accel=True, seed=3)
    app = CompassApp(b.bus, delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)
    mags = []
    accs = []
    while b.clock.now_us < seconds * 1000000:
        if app.step():
            mags.extend(app.raw)
            accs.extend(app._acc)
    return bytearray(_pack_le(mags)), bytearray(_pack_be(accs))


def _pack_le(vals):  # QMC5883L: int16 LSB first
    out = []
    for v in vals:
        out += [v & 0xFF, (v >> 8) & 0xFF]
    return out


def _pack_be(vals):  # MPU6050: int16 MSB first
    out = []
    for v in vals:
        out += [(v >> 8) & 0xFF, v & 0xFF]
    return out


class ReplayBus:
    """machine.I2C over register images; a magnetometer data read loads the next sample."""

    def __init__(self, mag_table, acc_table):
        self.qmc = bytearray(256)
        self.qmc[0x0D] = 0xFF          # chip ID
        self.qmc[0x06] = 0x01          # DRDY always set: one sample per read
        self.mpu = bytearray(256)
        self.mpu[0x75] = 0x68          # WHO_AM_I
        self.mag_table = mag_table
        self.acc_table = acc_table
        self.n = len(mag_table) // 6
        self.i = 0
        self.now = 0

    def scan(self):
        return [0x0D, 0x68]

    def sleep_us(self, us):
        self.now += us

    def ticks_us(self):
        return self.now

    def _next(self):
        j = 6 * self.i
        _copy(self.mag_table, j, self.qmc, 0)
        _copy(self.acc_table, j, self.mpu, 0x3B)
        self.i += 1
        if self.i == self.n:
            self.i = 0
        self.now += PERIOD_US

    def readfrom_mem_into(self, addr, reg, buf):
        img = self.qmc if addr == 0x0D else self.mpu
        if addr == 0x0D and reg == 0x00:
            self._next()
        _copy(img, reg, buf, 0)

    def writeto_mem(self, addr, reg, buf):
        _copy(buf, 0, self.qmc if addr == 0x0D else self.mpu, reg)


def _copy(src, i, dst, j):
    n = 6 if len(dst) > 6 and len(src) > 6 else (len(src) if len(src) < len(dst) else len(dst))
    k = 0
    while k < n:
        dst[j + k] = src[i + k]
        k += 1


mag_t, acc_t = record(40)
gc.collect()
bus = ReplayBus(mag_t, acc_t)
# learn=True: the collector stays and is offered every sample (the heaviest steady state)
app = CompassApp(bus, delay_us=bus.sleep_us, ticks_us=bus.ticks_us, learn=True)

# converge: replay until a whole pass keeps nothing
passes = 0
while passes < 20:
    kept = 0
    buf_ = app.calibrator.buffer
    for _ in range(bus.n):
        slot = buf_.next_slot  # moves with every kept sample
        app.step()
        kept += buf_.next_slot != slot
    passes += 1
    if passes >= 3 and kept == 0:
        break
res = {"recorded_samples": bus.n, "passes": passes, "accepted": app.accepted,
       "model": app.calibration.model, "held": app.calibrator.count}

# the instrument: a bare bus transfer allocates nothing
buf = bytearray(6)
t = mt()
bus.readfrom_mem_into(0x68, 0x3B, buf)
res["instrument_bytes"] = mt() - t


def window(measure):
    # N steps with no solve slice among them: start right after a solve has ended (the next
    # one, the 60 s idle solve, is 3000 steps away), and check that none ran
    s0 = app.slices
    while app.slices == s0 or app.solving:
        app.step()
    s0 = app.slices
    d = measure()
    return d if app.slices == s0 and not app.solving else None


def by_mem_total():
    t = mt()
    for _ in range(N):
        app.step()
    return mt() - t


def by_gc():
    gc.collect()
    gc.disable()
    a0 = gc.mem_alloc()
    for _ in range(N):
        app.step()
    d = gc.mem_alloc() - a0
    gc.enable()
    return d


def by_heap_lock():
    locked = 0
    micropython.heap_lock()
    try:
        for _ in range(N):
            app.step()
            locked += 1
    except MemoryError:
        pass
    micropython.heap_unlock()
    return locked


def no_add(x, y, z):
    return False


res["steps"] = N
d = window(by_mem_total)
res["mem_total_bytes_per_step"] = None if d is None else d // N
res["gc_net_bytes"] = window(by_gc)
res["heap_locked_steps"] = window(by_heap_lock)
# the same with Calibrator.add stubbed out: the app's own path (drivers, correct, axes,
# heading, bookkeeping) without the sample buffer
real_add = app.calibrator.add
app.calibrator.add = no_add
d = window(by_mem_total)
res["app_path_bytes_per_step"] = None if d is None else d // N
app.calibrator.add = real_add
r = app.raw
t = mt()
for _ in range(N):
    real_add(r[0], r[1], r[2])
res["calibrator_add_bytes_per_call"] = (mt() - t) // N
res["status"] = app.status
res["errors"] = app.errors

# with a 10-element solve running (one started by hand; the buffer holds the converged set)
gc.collect()
app.learning.session.worst_stall_us = 0  # (the session times its solve slices)
app.collector.next_model = 10
steps = 0
worst_bytes = 0
total = 0
while True:
    t = mt()
    app.step()
    d = mt() - t
    steps += 1
    total += d
    worst_bytes = d if d > worst_bytes else worst_bytes
    if not app.solving:
        break
res["solve_steps"] = steps
res["solve_bytes_total"] = total
res["solve_bytes_worst_step"] = worst_bytes
res["solve_worst_stall_us"] = app.worst_stall_us
res["solve_outcome"] = app.last_reason
t0 = time.ticks_us()
try:
    app.calibrator.solve(model=10, accept=False)
except Exception:
    pass
res["solve_one_call_us"] = time.ticks_diff(time.ticks_us(), t0)
print(json.dumps(res))
