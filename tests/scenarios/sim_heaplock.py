# The simulated bus allocates nothing in a driver's per-sample calls (readfrom_mem_into,
# writeto_mem, readfrom_into with 8-bit register addresses) once settle() has let the chips
# compute the samples due: on MicroPython the calls run under heap_lock (any allocation
# raises MemoryError); CPython runs the same calls unlocked. Prints JSON ints.
import json

try:
    from micropython import heap_lock, heap_unlock
except ImportError:
    def heap_lock():
        pass

    def heap_unlock():
        pass

from host_sim.boards import make_board


def locked(f):
    """1 if f() allocated (MemoryError under heap_lock), else 0."""
    heap_lock()
    try:
        f()
    except MemoryError:
        heap_unlock()
        return 1
    heap_unlock()
    return 0


def per_sample(i2c, addr, reg, buf, cfg_reg, cfgbuf, status):
    i2c.readfrom_mem_into(addr, reg, buf)
    i2c.writeto_mem(addr, cfg_reg, cfgbuf)
    i2c.readfrom_into(addr, status)


out = []
for chip, addr, reg, cfg_reg, cfg in (("gy271", 0x0D, 0x00, 0x09, 0x0D),
                                      ("hmc5883l", 0x1E, 0x03, 0x02, 0x01),
                                      ("qmc5883p", 0x2C, 0x01, 0x0A, 0x0D)):
    b = make_board(chip, seed=3)
    cfgbuf = bytearray([cfg])
    buf = bytearray(6)
    status = bytearray(1)
    b.bus.writeto_mem(addr, cfg_reg, cfgbuf)
    b.sleep_us(7000)
    b.bus.settle()
    err = locked(lambda: per_sample(b.bus, addr, reg, buf, cfg_reg, cfgbuf, status))
    out.append([err] + list(buf))

b = make_board("gy87", seed=3)
b.bus.writeto_mem(0x68, 0x6B, b"\x00")
b.bus.writeto_mem(0x68, 0x19, b"\x63")   # 8 kHz / 100 = 80 Hz: a sample every 12.5 ms
abuf = bytearray(6)
b.sleep_us(13000)
b.bus.settle()
err = locked(lambda: b.bus.readfrom_mem_into(0x68, 0x3B, abuf))
out.append([err] + list(abuf))
print(json.dumps(out))
