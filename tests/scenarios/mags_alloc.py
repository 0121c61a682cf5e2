# MicroPython only: the LIS3MDL, LIS2MDL and MMC5603 drivers' per-sample path allocates nothing.
#
# The drivers run over ReplayBus, a machine.I2C stand-in over preallocated register images that
# allocates nothing itself (the simulator allocates on every transaction, see
# tests/scenarios/drivers_alloc.py). Per chip, over N reads (status polls that say "not ready"
# included):
#   heap_locked_reads  reads done under micropython.heap_lock(): an allocation that cannot fall
#                      back raises MemoryError.
#   mem_total_bytes    micropython.mem_total() after minus before: every byte allocated, freed or
#                      not, a call frame taken from the heap included (py/objfun.c, frames over
#                      11 words), which heap_lock does not see (such a frame falls back to the C
#                      stack). The control (an oversized function) shows the instrument sees one.
import json
import micropython

from firmware.lis2mdl import LIS2MDL
from firmware.lis3mdl import LIS3MDL
from firmware.mmc5603 import MMC5603

N = 200
mt = micropython.mem_total


class ReplayBus:
    def __init__(self):
        self.images = {}
        self.status = {}
        self.mask = {}
        self.not_ready = 0      # status polls still to answer "not ready"

    def attach(self, addr, image, status_reg, mask=0xFF):
        self.images[addr] = image
        self.status[addr] = status_reg
        self.mask[addr] = mask  # 0x7F: bit 7 of the sub-address is the ST chips' SUB(7)

    def scan(self):
        return sorted(self.images)

    def sleep_us(self, us):
        pass

    def readfrom_mem_into(self, addr, reg, buf):
        reg &= self.mask[addr]
        if self.not_ready and reg == self.status[addr]:
            self.not_ready -= 1
            buf[0] = 0
            return
        _copy_out(self.images[addr], reg, buf)

    def writeto_mem(self, addr, reg, buf):
        _copy_in(self.images[addr], reg & self.mask[addr], buf)


# the copies in functions of their own: small frames (see measure() below)
def _copy_out(img, reg, buf):
    for i in range(len(buf)):
        buf[i] = img[reg + i]


def _copy_in(img, reg, buf):
    for i in range(len(buf)):
        img[reg + i] = buf[i]


def st_image(who_reg, who, status, data, raw):
    img = bytearray(256)
    img[who_reg] = who
    img[status] = 0x08                      # ZYXDA
    for i in range(3):
        img[data + 2 * i] = raw[i] & 0xFF
        img[data + 2 * i + 1] = (raw[i] >> 8) & 0xFF
    return img


def mmc_image(codes):
    img = bytearray(256)
    img[0x39] = 0x10
    img[0x18] = 0x40                        # Meas_m_done
    for i in range(3):
        img[2 * i] = codes[i] >> 12
        img[2 * i + 1] = (codes[i] >> 4) & 0xFF
        img[6 + i] = (codes[i] & 0x0F) << 4
    return img


def oversized(a):
    b = a + 1
    c = b + 1
    d = c + 1
    e = d + 1
    f = e + 1
    g = f + 1
    h = g + 1
    i = h + 1
    j = i + 1
    k = j + 1
    return a + b + c + d + e + f + g + h + i + j + k


def measure(name, bus, read, buf, polls):
    read(buf)                                # first call: anything lazily made
    t0 = mt()
    for _ in range(N):
        bus.not_ready = polls
        read(buf)
    total = mt() - t0
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
                      "heap_locked_reads": locked, "mem_total_bytes": total,
                      "last": [buf[0], buf[1], buf[2]]}))


t0 = mt()
oversized(1)
print(json.dumps({"control_bytes": mt() - t0}))

from array import array

for delay in ("counted", "board"):
    bus = ReplayBus()
    bus.attach(0x1C, st_image(0x0F, 0x3D, 0x27, 0x28, (-32767, 32766, -1)), 0x27, 0x7F)
    bus.attach(0x1E, st_image(0x4F, 0x40, 0x67, 0x68, (-10922, 10922, -1)), 0x67, 0x7F)
    bus.attach(0x30, mmc_image((0x80123, 0x7FEDC, 0x80000)), 0x18)
    # "board": the drivers' own delay (time.sleep_us, time.ticks_us), sleeping for real; the
    # fastest rates and one "not ready" poll per read keep that short
    if delay == "counted":
        chips = (LIS3MDL(bus, delay_us=bus.sleep_us), LIS2MDL(bus, delay_us=bus.sleep_us),
                 MMC5603(bus, delay_us=bus.sleep_us))
        polls = 3
    else:
        chips = (LIS3MDL(bus, odr=80), LIS2MDL(bus, odr=100), MMC5603(bus, bw=3))
        polls = 1
    print(json.dumps({"delay": delay}))
    for d in chips:
        measure(d.KIND, bus, d.read_into, [0, 0, 0], polls)
        measure(d.KIND + "/array-h", bus, d.read_into, array("h", [0, 0, 0]), polls)
