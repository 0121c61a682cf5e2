# The drivers and the app through firmware.busio_i2c.BusioI2C over a busio-shaped fake of the
# simulated bus (tests/busio_fake.py), against the same simulated board driven directly:
# the same samples and headings; a NACK and a held lock become BusError naming the address
# and register (errno 19, 110); the lock is released after every failure. Prints JSON lines
# of integers and strings; on MicroPython also the bytes one read allocates (mem_total).
import json
import sys

sys.path.append("tests")
sys.path.append("tests/scenarios")
from busio_fake import BusioFake  # noqa: E402
import app_world as W  # noqa: E402

from firmware.busio_i2c import BusioI2C  # noqa: E402
from firmware.detect import detect, detect_accel  # noqa: E402
from firmware.errors import BusError  # noqa: E402


def board(seed=4):
    return W.make_sim("gy271", m=W.motion.figure8(), seed=seed)


def samples(i2c, b, n=40):
    mag = detect(i2c, delay_us=b.sleep_us)
    acc = detect_accel(i2c)
    out = []
    buf = [0, 0, 0]
    for _ in range(n):
        mag.read_into(buf)
        a = acc.read_accel()
        out.append([buf[0], buf[1], buf[2], a[0], a[1], a[2]])
    return mag.KIND, out


b1 = board()
b2 = board()
fake = BusioFake(b2.bus)
k1, direct = samples(b1.bus, b1)
k2, adapted = samples(BusioI2C(fake, delay_us=b2.sleep_us), b2)
print(json.dumps(["samples", k1 == k2, direct == adapted, len(adapted), adapted[-1]]))

# errors: a NACK, then a lock another task keeps
mag = detect(BusioI2C(fake, delay_us=b2.sleep_us), delay_us=b2.sleep_us)
b2.bus.inject_nack(count=1)
try:
    mag.read()
    print(json.dumps(["nack", "no error"]))
except BusError as e:
    print(json.dumps(["nack", e.address, e.register, e.errno, fake.locked]))
fake.held_by_other = 1000
try:
    mag.read()
    print(json.dumps(["lock", "no error"]))
except BusError as e:
    print(json.dumps(["lock", e.address, e.register, e.errno, fake.locked]))
fake.held_by_other = 3  # a short wait, then the transfer goes through
mag.read()
print(json.dumps(["short_wait", fake.locked, mag._i2c.lock_waits]))

# the app through the adapter gives the headings it gives directly
a1 = W.make_app(board(5))
b4 = board(5)
bus4 = BusioI2C(BusioFake(b4.bus), delay_us=b4.sleep_us)
from firmware.app import CompassApp  # noqa: E402
a2 = CompassApp(bus4, mag_axes=W.MAG_AXES, accel_axes=W.ACCEL_AXES,
                declination_cdeg=W.DECLINATION_CDEG, delay_us=b4.sleep_us,
                ticks_us=b4.clock.ticks_us)
same = 0
for _ in range(500):
    a1.step()
    a2.step()
    same += a1.heading_kang == a2.heading_kang
print(json.dumps(["app", same, a2.status, a2.calibration.model == a1.calibration.model]))

try:
    import micropython
    mt = micropython.mem_total
except (ImportError, AttributeError):
    mt = None
if mt is not None:
    class Quiet:  # a busio stand-in that allocates nothing itself: what the adapter costs
        def try_lock(self):
            return True

        def unlock(self):
            pass

        def writeto_then_readfrom(self, addr, out_buf, in_buf):
            pass
    buf = bytearray(6)
    ad = BusioI2C(Quiet())
    ad.readfrom_mem_into(0x0D, 0x00, buf)
    t = mt()
    for _ in range(100):
        ad.readfrom_mem_into(0x0D, 0x00, buf)
    print(json.dumps(["alloc_per_read_x100", mt() - t]))
