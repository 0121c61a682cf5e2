"""A busio.I2C look-alike over host_sim's simulated bus, faithful to what CircuitPython's
busio does that matters here: transfers without the lock raise RuntimeError, try_lock() is
False while another task holds the bus, writeto_then_readfrom is a register write then a
read with a repeated start, a NACK raises OSError. Runs on CPython and MicroPython."""


class BusioFake:
    def __init__(self, sim):
        self.sim = sim              # a host_sim SimI2C (machine.I2C-shaped)
        self.locked = False
        self.held_by_other = 0      # try_lock() calls that another task still wins
        self.transfers = 0

    def try_lock(self):
        if self.held_by_other:
            self.held_by_other -= 1
            return False
        if self.locked:
            return False
        self.locked = True
        return True

    def unlock(self):
        if not self.locked:
            raise RuntimeError("unlock() without the lock")
        self.locked = False

    def _check(self):
        if not self.locked:
            raise RuntimeError("Function requires lock")
        self.transfers += 1

    def scan(self):
        self._check()
        return self.sim.scan()

    def writeto(self, addr, buf):
        self._check()
        self.sim.writeto_mem(addr, buf[0], bytes(buf[1:]))

    def writeto_then_readfrom(self, addr, out_buf, in_buf):
        self._check()
        self.sim.readfrom_mem_into(addr, out_buf[0], in_buf)

    def deinit(self):
        self.locked = False
