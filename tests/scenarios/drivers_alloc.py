# MicroPython only: proves the per-sample driver path allocates nothing.
#
# Why not through host_sim: the simulator is Python code that allocates on every transaction
# (it computes samples lazily, builds bytes), so a heap lock around a read through it would
# measure the simulator, not the driver. The real driver classes run here over ReplayBus, a
# machine.I2C stand-in over preallocated register images that allocates nothing itself. The
# locked region holds both, so an allocation by either raises MemoryError: nothing is assumed.
#
# Three measures per chip, each over N reads (status polls that say "not ready" included):
#   heap_lock     micropython.heap_lock() around the reads: any allocation raises MemoryError.
#   net_bytes     gc off, gc.mem_alloc() after minus before: garbage left behind.
#   frame_bytes   gc off, the peak of gc.mem_alloc() seen inside each bus transfer. MicroPython
#                 takes a function's frame from the heap (freed at return) when it exceeds 11
#                 words, and falls back to the C stack only when the heap is locked; such a
#                 transient allocation passes the heap_lock test but can still start a GC on a
#                 board. The driver frames are live at every transfer, so a nonzero peak there
#                 shows it (the try/except transfer helpers are @micropython.native for this
#                 reason). ReplayBus's own frames are calibrated to 0 first (printed).
import gc
import json
import micropython
from array import array

from firmware.ak09916 import AK09916
from firmware.ak8963 import AK8963
from firmware.hmc5883l import HMC5883L
from firmware.icm20948 import ICM20948
from firmware.mpu6050 import MPU6050
from firmware.mpu9250 import MPU9250
from firmware.qmc5883l import QMC5883L
from firmware.qmc5883p import QMC5883P

N = 200


class ReplayBus:
    def __init__(self):
        self.images = {}
        self.status_reg = {}
        self.not_ready = 0      # status polls still to answer "not ready"
        self.measure = False
        self.base = 0
        self.peak = 0
        self.slept = 0

    def attach(self, addr, image, status_reg):
        self.images[addr] = image
        self.status_reg[addr] = status_reg

    def scan(self):
        return sorted(self.images)

    def sleep_us(self, us):
        self.slept += us

    def _probe(self):
        if self.measure:
            m = gc.mem_alloc() - self.base
            if m > self.peak:
                self.peak = m

    def readfrom_mem_into(self, addr, reg, buf):
        self._probe()
        if self.not_ready and reg == self.status_reg[addr]:
            self.not_ready -= 1
            buf[0] = 0
            return
        _copy_out(self.images[addr], reg, buf)

    def writeto_mem(self, addr, reg, buf):
        _copy_in(self.images[addr], reg, buf)


def _copy_out(img, reg, buf):
    for i in range(len(buf)):
        buf[i] = img[reg + i]


def _copy_in(img, reg, buf):
    for i in range(len(buf)):
        img[reg + i] = buf[i]


def measure(name, bus, read, buf, polls):
    # calibration: the instrument alone (a bare transfer) must show 0
    gc.collect()
    gc.disable()
    bus.base = gc.mem_alloc()
    bus.peak = 0
    bus.measure = True
    bus.readfrom_mem_into(0x0D if 0x0D in bus.images else next(iter(bus.images)), 0, buf)
    calib = bus.peak
    bus.peak = 0
    for _ in range(N):
        bus.not_ready = polls
        read(buf)
    frame = bus.peak
    net = gc.mem_alloc() - bus.base
    bus.measure = False
    gc.enable()
    locked = 0
    micropython.heap_lock()
    try:
        for _ in range(N):
            bus.not_ready = polls
            read(buf)
            locked += 1
    finally:
        micropython.heap_unlock()
    print(json.dumps({"chip": name, "reads": N, "polls_per_read": polls,
                      "heap_locked_reads": locked,
                      "net_bytes": net, "frame_bytes": frame, "instrument_bytes": calib,
                      "last": [buf[0], buf[1], buf[2]]}))


def qmc_image(raw):
    img = bytearray(256)
    img[0x0D] = 0xFF
    for i in range(3):
        img[2 * i] = raw[i] & 0xFF
        img[2 * i + 1] = (raw[i] >> 8) & 0xFF
    img[0x06] = 0x01  # DRDY
    return img


def hmc_image(raw):
    img = bytearray(256)
    img[0x0A:0x0D] = b"H43"
    for i, v in enumerate((raw[0], raw[2], raw[1])):  # X, Z, Y
        img[3 + 2 * i] = (v >> 8) & 0xFF
        img[4 + 2 * i] = v & 0xFF
    img[0x09] = 0x01  # RDY
    return img


def qmcp_image(raw):
    img = bytearray(256)
    img[0x00] = 0x80
    for i in range(3):
        img[1 + 2 * i] = raw[i] & 0xFF
        img[2 + 2 * i] = (raw[i] >> 8) & 0xFF
    img[0x09] = 0x01  # DRDY
    return img


def mpu_image(raw, who=0x68):
    img = bytearray(256)
    img[0x75] = who
    for i in range(3):
        img[0x3B + 2 * i] = (raw[i] >> 8) & 0xFF
        img[0x3C + 2 * i] = raw[i] & 0xFF
    return img


def ak_image(raw, wia, st1, data, st2):
    # an AKM compass: its ID, ST1 with DRDY, the data LSB first, ST2 (AK8963: BITM, 16-bit),
    # the AK8963's fuse ROM values
    img = bytearray(256)
    img[0:len(wia)] = wia
    img[st1] = 0x01
    for i in range(3):
        img[data + 2 * i] = raw[i] & 0xFF
        img[data + 2 * i + 1] = (raw[i] >> 8) & 0xFF
    img[st2] = 0x10 if st2 == 0x09 else 0x00
    img[0x10:0x13] = b"\xb0\xb2\xa6" if st2 == 0x09 else img[0x10:0x13]
    return img


def icm_image(raw):
    img = bytearray(256)
    img[0x00] = 0xEA
    for i in range(3):
        img[0x2D + 2 * i] = (raw[i] >> 8) & 0xFF
        img[0x2E + 2 * i] = raw[i] & 0xFF
    return img


for delay in ("counted", "board"):
    bus = ReplayBus()
    bus.attach(0x0D, qmc_image((-32768, 32767, -1)), 0x06)
    bus.attach(0x1E, hmc_image((-2048, 2047, -1)), 0x09)
    bus.attach(0x68, mpu_image((-32768, 16384, -1)), 0xFF)
    bus.attach(0x2C, qmcp_image((-32768, 32767, -1)), 0x09)
    bus.attach(0x0C, ak_image((-32760, 32760, -1), b"\x48", 0x02, 0x03, 0x09), 0x02)
    bus.attach(0x0E, ak_image((-32752, 32752, -1), b"\x48\x09", 0x10, 0x11, 0x18), 0x10)
    bus.attach(0x69, icm_image((-32768, 16384, -1)), 0xFF)
    bus.attach(0x6A, mpu_image((-32768, 16384, -1), 0x71), 0xFF)
    # "board": the driver's own delay, time.sleep_us and time.ticks_us, sleeping for real; the
    # fastest rates and one "not ready" poll per read keep that short.
    if delay == "counted":
        q = QMC5883L(bus, delay_us=bus.sleep_us)
        h = HMC5883L(bus, delay_us=bus.sleep_us)
        p = QMC5883P(bus, delay_us=bus.sleep_us)
        k = AK8963(bus, delay_us=bus.sleep_us)
        k9 = AK09916(bus, address=0x0E, delay_us=bus.sleep_us)
        polls = 3
    else:
        q = QMC5883L(bus, odr=200)
        h = HMC5883L(bus, rate=75)
        p = QMC5883P(bus, odr=200)
        k = AK8963(bus)
        k9 = AK09916(bus, address=0x0E)
        polls = 1
    m = MPU6050(bus)
    print(json.dumps({"delay": delay}))
    measure("qmc5883l", bus, q.read_into, [0, 0, 0], polls)
    measure("qmc5883l/array-h", bus, q.read_into, array("h", [0, 0, 0]), polls)
    measure("hmc5883l", bus, h.read_into, array("i", [0, 0, 0]), polls)
    measure("qmc5883p", bus, p.read_into, [0, 0, 0], polls)
    measure("mpu6050", bus, m.read_accel_into, [0, 0, 0], 0)
    g = MPU6050(bus)
    g.gyro_into = array("h", [0, 0, 0])  # use_gyro(): the 14-byte burst with the gyroscope
    measure("mpu6050/gyro", bus, g.read_accel_into, [0, 0, 0], 0)
    measure("ak8963", bus, k.read_into, array("h", [0, 0, 0]), polls)
    measure("ak09916", bus, k9.read_into, [0, 0, 0], polls)
    measure("mpu9250", bus, MPU9250(bus, address=0x6A).read_accel_into, [0, 0, 0], 0)
    c = ICM20948(bus, address=0x69)
    measure("icm20948", bus, c.read_accel_into, [0, 0, 0], 0)
    c.gyro_into = array("h", [0, 0, 0])
    measure("icm20948/gyro", bus, c.read_accel_into, [0, 0, 0], 0)

# The board path of the bounded wait (time.sleep_us + time.ticks_us, delay_us=None): a chip
# whose status never says ready must time out after timeout_us of real time.
import time
from firmware.errors import DataReadyTimeout

bus = ReplayBus()
bus.attach(0x0D, qmc_image((0, 0, 0)), 0x06)
q = QMC5883L(bus, timeout_us=10000)
bus.not_ready = 1 << 30
t0 = time.ticks_us()
try:
    q.read()
    waited = -1
except DataReadyTimeout as e:
    waited = e.waited_us
print(json.dumps({"board_timeout_us": 10000, "waited_us": waited,
                  "elapsed_us": time.ticks_diff(time.ticks_us(), t0)}))
