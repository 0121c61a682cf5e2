"""machine.I2C's register transfers over CircuitPython's busio.I2C, so the drivers run there.

    import board, busio
    from firmware.circuitpython.busio_i2c import BusioI2C
    mag = detect(BusioI2C(busio.I2C(board.SCL, board.SDA, frequency=400000)))
"""
# BusioI2C(i2c, lock_timeout_us=50000, delay_us=None): readfrom_mem_into, writeto_mem and scan
# as busio's writeto_then_readfrom, writeto and scan, under busio's bus lock. The arguments,
# the locking and why a read allocates nothing: docs/design.md (module notes, busio_i2c and
# CircuitPython).
from firmware.compat import const, ticks_diff, ticks_us, wait_clock

_ETIMEDOUT = const(110)
_LOCK_POLL_US = const(100)          # one try_lock() poll every 100 us (a byte at 100 kHz is 90 us)
_MAX_TIMEOUT_US = const(1 << 29)    # keeps the wait computations small ints on 32-bit ports
_OUT_MAX = const(8)                 # register byte + up to 7 data bytes without allocating


class _Held:
    """`with adapter._held:` holds the bus lock for one transfer (see docs/design.md, module notes)."""

    def __init__(self, adapter):
        self._adapter = adapter

    def __enter__(self):
        self._adapter.lock()
        return None

    def __exit__(self, kind, value, tb):
        self._adapter.bus.unlock()
        return False


class BusioI2C:
    """machine.I2C's readfrom_mem_into / writeto_mem / scan over a busio.I2C."""

    def __init__(self, i2c, lock_timeout_us=50000, delay_us=None):
        if type(lock_timeout_us) is not int or not 0 < lock_timeout_us <= _MAX_TIMEOUT_US:
            raise ValueError("lock_timeout_us=%r: expected an int of 1..%d microseconds"
                             % (lock_timeout_us, _MAX_TIMEOUT_US))
        self.bus = i2c
        self.lock_timeout_us = lock_timeout_us
        self._delay, self._measured = wait_clock(delay_us)
        self._out = bytearray(_OUT_MAX)
        self._reg = memoryview(self._out)[0:1]
        self._write_then_read = i2c.writeto_then_readfrom
        self._addr = 0
        self._in = None
        self._held = _Held(self)

    def lock(self):
        """Take the bus lock within lock_timeout_us, else OSError(110); unlock() releases it."""
        if self.bus.try_lock():
            return
        t0 = ticks_us() if self._measured else 0
        waited = 0
        while waited < self.lock_timeout_us:
            self._delay(_LOCK_POLL_US)
            if self._measured:
                waited = ticks_diff(ticks_us(), t0)
            else:
                waited += _LOCK_POLL_US
            if self.bus.try_lock():
                return
        raise OSError(_ETIMEDOUT, "I2C bus lock not free after %d us" % waited)

    def readfrom_mem_into(self, addr, reg, buf):
        self._out[0] = reg
        self._addr = addr
        self._in = buf
        self._read()

    def _read(self):
        # The transfer's arguments come from the instance and the bound method is made once:
        # with the `with` block's slots, this frame is then 9 words + the exception-stack
        # entry, within the 11 MicroPython keeps on the C stack (see firmware/i2cdevice.py).
        with self._held:
            self._write_then_read(self._addr, self._reg, self._in)

    def writeto_mem(self, addr, reg, buf):
        n = self._stage(reg, buf)
        with self._held:
            if n:
                self.bus.writeto(addr, self._out, end=n)
            else:
                self.bus.writeto(addr, bytes((reg,)) + bytes(buf))

    def _stage(self, reg, buf):
        # reg and buf into the preallocated buffer: its used length, or 0 when it is too short
        n = len(buf)
        if n >= _OUT_MAX:
            return 0
        out = self._out
        out[0] = reg
        for i in range(n):
            out[i + 1] = buf[i]
        return n + 1

    def scan(self):
        with self._held:
            return list(self.bus.scan())
