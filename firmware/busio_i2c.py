"""machine.I2C's transfers on CircuitPython's busio.I2C, so the drivers run unchanged there.

    import board, busio
    from firmware.busio_i2c import BusioI2C
    from firmware.detect import detect
    i2c = BusioI2C(busio.I2C(board.GP5, board.GP4, frequency=400000))
    mag = detect(i2c)                      # the same drivers, waits and errors as on MicroPython

BusioI2C(i2c, lock_timeout_us=50000, delay_us=None) offers what the drivers use of
machine.I2C: readfrom_mem_into(addr, reg, buf), writeto_mem(addr, reg, buf) and scan().
busio.I2C is shared between tasks: each transfer takes the bus with try_lock(), polled every
_POLL_US within lock_timeout_us, and always unlocks, also when the transfer raises. A lock
that cannot be had raises OSError(110) (ETIMEDOUT), which the drivers' bus guard
(firmware/i2cdevice.py) names as a BusError with the address and register, like a NACK;
busio's own OSError for a NACK passes through the same way. A register read is one
writeto_then_readfrom (a repeated start, as readfrom_mem_into does on MicroPython) through a
one-byte buffer made once: nothing is allocated per read. delay_us: the wait between lock
attempts (default firmware.compat.sleep_us).
Tested against a busio-shaped fake of the simulated bus (tests/busio_fake.py) on CPython and
the MicroPython tiers; no CircuitPython interpreter runs here (docs/design.md).
"""
from firmware.compat import const, sleep_us

_ETIMEDOUT = const(110)
_LOCK_TIMEOUT_US = const(50000)   # 50 ms: a few transfers of another task at 100 kHz
_POLL_US = const(100)


class _Held:
    """`with` block that unlocks the bus however the transfer ends (a `with` frame stays on
    MicroPython's C stack where try/finally around the call would not: no allocation)."""

    def __init__(self, i2c):
        self._i2c = i2c

    def __enter__(self):
        return None

    def __exit__(self, kind, value, tb):
        self._i2c.unlock()
        return False


class BusioI2C:
    """See the module docstring."""

    def __init__(self, i2c, lock_timeout_us=_LOCK_TIMEOUT_US, delay_us=None):
        if type(lock_timeout_us) is not int or lock_timeout_us < 0:
            raise ValueError("lock_timeout_us=%r: expected an int >= 0 (microseconds)"
                             % (lock_timeout_us,))
        self._i2c = i2c
        self.lock_timeout_us = lock_timeout_us
        self._delay = delay_us if delay_us is not None else sleep_us
        self._reg = bytearray(1)
        self._held = _Held(i2c)
        self._addr = 0
        self._into = None
        self.lock_waits = 0   # transfers that had to wait for the lock

    def _lock(self):
        if self._i2c.try_lock():
            return
        self.lock_waits += 1
        waited = 0
        while not self._i2c.try_lock():
            if waited >= self.lock_timeout_us:
                raise OSError(_ETIMEDOUT)
            self._delay(_POLL_US)
            waited += _POLL_US

    def readfrom_mem_into(self, addr, reg, buf):
        self._reg[0] = reg
        self._addr = addr
        self._into = buf
        self._locked_read()

    def _locked_read(self):
        # its own frame: with readfrom_mem_into's three arguments the `with` would not fit
        self._lock()
        with self._held:
            self._read()

    def _read(self):
        self._i2c.writeto_then_readfrom(self._addr, self._reg, self._into)

    def writeto_mem(self, addr, reg, buf):
        # configuration writes only (not per sample): one buffer of register + data
        data = bytearray(1 + len(buf))
        data[0] = reg
        data[1:] = buf
        self._lock()
        with self._held:
            self._i2c.writeto(addr, data)

    def scan(self):
        self._lock()
        with self._held:
            return list(self._i2c.scan())
