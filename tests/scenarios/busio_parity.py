# Parity: the drivers and the app through firmware.circuitpython.busio_i2c over a busio.I2C look-alike
# (tests/busio_fake.py) of the simulated bus, against the same simulation read directly. Run on
# CPython and the MicroPython tiers (the WebAssembly one has no native emitter, as
# CircuitPython has none): every line is ints, bools and strings.
#   drivers     per board: detect() + 20 reads of the magnetometer (and the MPU6050) through
#               the adapter and directly; equal samples and equal simulated time
#   app         500 steps of CompassApp on twin simulations (a NACK burst at step 200 on
#               both): equal headings, statuses and calibrations
#   lock_wait   the lock held by another task for 7 polls: lock() waits 7 x 100 us; a read
#               then succeeds
#   lock_held   the lock never free: BusError with errno 110 after the bound (simulated us)
#   nack        a NACK: BusError naming address and register; the lock is released
#   no_lock     busio refuses a transfer without the lock (RuntimeError)
import json
import sys

sys.path.append("tests/scenarios")
from app_world import ACCEL_AXES, DECLINATION_CDEG, MAG_AXES, make_sim  # noqa: E402

from host_sim.boards import make_board  # noqa: E402
from firmware.app import CompassApp  # noqa: E402
from firmware.circuitpython.busio_i2c import BusioI2C  # noqa: E402
from firmware.detect import detect, detect_accel  # noqa: E402
from firmware.errors import BusError  # noqa: E402
from tests.busio_fake import FakeBusioI2C  # noqa: E402

READS = 20
STEPS = 500


def wrap(b, **kw):
    fake = FakeBusioI2C(b.bus)
    return fake, BusioI2C(fake, delay_us=b.sleep_us, **kw)


def samples(bus, b):
    mag = detect(bus, delay_us=b.sleep_us)
    acc = detect_accel(bus)
    out = []
    for _ in range(READS):
        out.append(list(mag.read()))
        if acc is not None:
            out.append(list(acc.read_accel()))
    return mag.KIND, out


def checksum(rows):
    s = 0
    for r in rows:
        for v in r:
            s = (s * 31 + v) & 0x3FFFFFFF
    return s


for chip, accel in (("qmc5883l", True), ("hmc5883l", True), ("qmc5883p", None),
                    ("gy87", None), ("gy87-qmc", None)):
    direct = make_board(chip, seed=7, accel=accel)
    via = make_board(chip, seed=7, accel=accel)
    fake, adapter = wrap(via)
    kind, a = samples(direct.bus, direct)
    kind2, c = samples(adapter, via)
    print(json.dumps(["drivers", chip, kind, kind2, len(a), a == c, checksum(c),
                      direct.clock.now_us, via.clock.now_us, fake.try_locks, fake.refused,
                      fake.locked]))


def app_run(b, bus):
    app = CompassApp(bus, mag_axes=MAG_AXES, accel_axes=ACCEL_AXES,
                     declination_cdeg=DECLINATION_CDEG, delay_us=b.sleep_us,
                     ticks_us=b.clock.ticks_us)
    hs = []
    for i in range(STEPS):
        if i == 200:
            b.bus.inject_nack(after=0, count=3)
        app.step()
        hs.append([app.heading_kang, app.status])
    return app, hs


d = make_sim("gy271", seed=5)
app_d, hs_d = app_run(d, d.bus)
v = make_sim("gy271", seed=5)
fake, adapter = wrap(v)
app_v, hs_v = app_run(v, adapter)
same = 0
for i in range(STEPS):
    if hs_d[i] == hs_v[i]:
        same += 1
statuses = sorted(set(h[1] for h in hs_v))
print(json.dumps(["app", STEPS, same, checksum([[h[0]] for h in hs_v]), statuses,
                  app_d.accepted, app_v.accepted, sorted(app_v.errors.items()),
                  d.clock.now_us, v.clock.now_us, fake.locked]))

b = make_board("qmc5883l", seed=7)
fake, adapter = wrap(b)
mag = detect(adapter, delay_us=b.sleep_us)
buf = [0, 0, 0]
fake.hold(7)
t0 = b.clock.now_us
adapter.lock()
lock_us = b.clock.now_us - t0
adapter.bus.unlock()
fake.hold(7)
mag.read_into(buf)
print(json.dumps(["lock_wait", 7, fake.refused, lock_us, buf != [0, 0, 0], fake.locked]))

b = make_board("qmc5883l", seed=7)
fake, adapter = wrap(b, lock_timeout_us=2000)
mag = detect(adapter, delay_us=b.sleep_us)
fake.hold(-1)
t0 = b.clock.now_us
try:
    mag.read_into(buf)
    err = None
except BusError as e:
    err = [e.errno, e.address, e.register]
waited = b.clock.now_us - t0
fake.release()
print(json.dumps(["lock_held", 2000, err, waited, fake.locked, fake.try_lock()]))
fake.unlock()

b.bus.inject_nack(after=0, count=1)
try:
    mag.read_into(buf)
    err = None
except BusError as e:
    err = [e.errno, e.address, e.register]
print(json.dumps(["nack", err, fake.locked, fake.try_lock()]))
fake.unlock()

try:
    fake.writeto_then_readfrom(0x0D, b"\x0d", bytearray(1))
    refused = False
except RuntimeError:
    refused = True
print(json.dumps(["no_lock", refused]))
