# MicroPython only: a driver read through firmware.circuitpython.busio_i2c.BusioI2C allocates nothing,
# frames included.
#
# As in drivers_alloc.py the chips are register images (ReplayBusio below allocates nothing),
# since the simulator allocates when it computes a sample. Per chip, N reads, each measured three
# ways:
#   mem_total    micropython.mem_total() after minus before, over N reads: every byte taken
#                from the heap, a frame freed at return included (0 is the goal)
#   heap_lock    the same reads under micropython.heap_lock(): any allocation raises
#                MemoryError (frames that fall back to the C stack would pass this one)
# and two lock situations: "free" (try_lock succeeds at once) and "busy" (another task holds
# the lock for 2 polls per read: the bounded wait runs, time counted or real).
import gc
import json
import micropython

from firmware.circuitpython.busio_i2c import BusioI2C
from firmware.hmc5883l import HMC5883L
from firmware.mpu6050 import MPU6050
from firmware.qmc5883l import QMC5883L
from firmware.qmc5883p import QMC5883P

N = 200


class ReplayBusio:
    """busio.I2C's methods over register images, lean: CircuitPython's busio is C code (no
    frames), so this stand-in keeps its own frames within MicroPython's 11 words to let the
    adapter's be measured (tests/busio_fake.py's full signatures, with their keyword
    arguments, make frames that come from the heap). Its bare transfer is measured first."""

    def __init__(self):
        self.images = {}
        self.locked = False
        self.other = 0          # try_lock() polls still refused (another task holds the lock)
        self.refused = 0

    def attach(self, addr, image):
        self.images[addr] = image

    def hold(self, polls):
        self.other = polls

    def sleep_us(self, us):
        pass

    def try_lock(self):
        if self.locked or self.other:
            self.other -= 1
            self.refused += 1
            return False
        self.locked = True
        return True

    def unlock(self):
        self.locked = False

    def scan(self):
        if not self.locked:
            raise RuntimeError("Function requires lock")
        return sorted(self.images)

    def writeto_then_readfrom(self, addr, out_buffer, in_buffer):
        if not self.locked:
            raise RuntimeError("Function requires lock")
        _copy_out(self.images[addr], out_buffer[0], in_buffer)

    def writeto(self, addr, buffer, end=None):
        if not self.locked:
            raise RuntimeError("Function requires lock")
        _copy_in(self.images[addr], buffer, len(buffer) if end is None else end)


def _copy_out(img, reg, buf):
    for i in range(len(buf)):
        buf[i] = img[reg + i]


def _copy_in(img, buf, end):
    for i in range(1, end):
        img[buf[0] + i - 1] = buf[i]


def image(pairs):
    img = bytearray(256)
    for reg, value in pairs:
        img[reg] = value
    return img


def make_bus():
    bus = ReplayBusio()
    bus.attach(0x0D, image([(0x0D, 0xFF), (0x06, 0x01), (0, 0x34), (1, 0x12), (4, 0xFF),
                            (5, 0xFF)]))
    bus.attach(0x1E, image([(0x0A, 0x48), (0x0B, 0x34), (0x0C, 0x33), (0x09, 0x01),
                            (3, 0x01)]))
    bus.attach(0x2C, image([(0x00, 0x80), (0x09, 0x01), (1, 0x00), (2, 0x80)]))
    bus.attach(0x68, image([(0x75, 0x68), (0x3B, 0x40), (0x3C, 0x00)]))
    return bus


def reads(read, buf, fake, busy):
    for _ in range(N):
        if busy:
            fake.hold(2)
        read(buf)


def measure(name, read, buf, fake, busy):
    gc.collect()
    t0 = micropython.mem_total()
    reads(read, buf, fake, busy)
    total = micropython.mem_total() - t0
    locked = 0
    micropython.heap_lock()
    try:
        for _ in range(N):
            if busy:
                fake.hold(2)
            read(buf)
            locked += 1
    finally:
        micropython.heap_unlock()
    print(json.dumps({"chip": name, "lock": "busy" if busy else "free", "reads": N,
                      "mem_total_bytes": total, "bytes_per_read": total // N,
                      "heap_locked_reads": locked, "refused_polls": fake.refused,
                      "locked_after": fake.locked, "last": [buf[0], buf[1], buf[2]]}))


# the instrument: the stand-in's bare transfer (lock, write-then-read, unlock)
def bare(bus, reg, data):
    gc.collect()
    t0 = micropython.mem_total()
    for _ in range(N):
        bus.try_lock()
        bus.writeto_then_readfrom(0x0D, reg, data)
        bus.unlock()
    return micropython.mem_total() - t0


print(json.dumps({"instrument_bytes": bare(make_bus(), bytearray(1), bytearray(6))}))

for clock in ("counted", "board"):
    for busy in (False, True):
        fake = make_bus()
        if clock == "counted":
            i2c = BusioI2C(fake, delay_us=fake.sleep_us)
            q = QMC5883L(i2c, delay_us=fake.sleep_us)
            h = HMC5883L(i2c, delay_us=fake.sleep_us)
            p = QMC5883P(i2c, delay_us=fake.sleep_us)
        else:  # time.sleep_us and time.ticks_us, for real
            i2c = BusioI2C(fake)
            q = QMC5883L(i2c, odr=200)
            h = HMC5883L(i2c, rate=75)
            p = QMC5883P(i2c, odr=200)
        m = MPU6050(i2c)
        print(json.dumps({"clock": clock}))
        measure("qmc5883l", q.read_into, [0, 0, 0], fake, busy)
        measure("hmc5883l", h.read_into, [0, 0, 0], fake, busy)
        measure("qmc5883p", p.read_into, [0, 0, 0], fake, busy)
        measure("mpu6050", m.read_accel_into, [0, 0, 0], fake, busy)
