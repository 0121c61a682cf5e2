"""The bus plumbing every chip driver shares: register helpers, error mapping, bounded waits.

    class MyChip(Device):
        def read_into(self, buf):
            with self.guard:                 # OSError from the bus -> BusError(address, register)
                self.wait(_STATUS, _DRDY)
                self._read_into(_DATA, self._buf)

Device(i2c, address, period_us, delay_us=None, timeout_us=None)
  i2c         machine.I2C / SoftI2C, or anything with readfrom_mem_into / writeto_mem / scan
              (the simulator's bus, firmware.busio_i2c's adapter for CircuitPython).
  period_us   the chip's output data period: sizes the default data-ready bound.
  delay_us    None on a board (time.sleep_us, waits measured with time.ticks_us); the
              simulator passes its bus.sleep_us, and the waited time is then the sum of the
              delays asked for (simulated time moves only when delay_us is called).
  timeout_us  the data-ready bound; default two periods + 10 ms.

wait_ready(reg, mask) polls a status register until a bit of mask is set, within the bound,
else DataReadyTimeout(address, waited_us). Public driver methods run their bus transfers
inside `with self.guard:`, which turns a port's OSError (errno 19 ENODEV, 5 EIO, 110/116
ETIMEDOUT) into BusError naming address, register and errno. Why a `with` block and not
try/except: a bytecode frame with `except OSError as e` exceeds the 11 words MicroPython keeps
on the C stack (py/objfun.c VM_MAX_STATE_ON_STACK) and would come from the heap on every
sample; the `with` frame stays on the stack, so a read allocates nothing
(tests/scenarios/drivers_alloc.py).

option_code(chip, name, value, table): the register code of a keyword option.
int16x3_into(d, buf, msb): three int16, LSB first (QMC5883L, QMC5883P data blocks) or MSB
first (MPU6050), sign-extended by hand.
"""
from firmware.compat import const, sleep_us, ticks_diff, ticks_us
from firmware.errors import BusError, DataReadyTimeout, SensorNotFound

_MIN_POLL_US = const(250)       # no faster status polling than this (an I2C status read ~100 us)
_MAX_TIMEOUT_US = const(1 << 29)  # keeps every wait computation a small int on 32-bit ports

# errno values ports raise from machine.I2C (116 is ETIMEDOUT in the ESP-IDF's newlib)
_ERRNO_NAMES = {5: "EIO", 19: "ENODEV: no ACK", 110: "ETIMEDOUT", 116: "ETIMEDOUT"}


def _errno(e):
    n = getattr(e, "errno", None)
    if n is None and e.args:  # CPython: OSError(19).errno is None, args[0] holds it
        n = e.args[0]
    return n if type(n) is int else None


def bus_error(e, address, register):
    """The BusError for OSError `e` raised by a transaction with `address`/`register`."""
    n = _errno(e)
    where = "I2C error at address 0x%02X" % address if address is not None else "I2C scan error"
    if register is not None:
        where += ", register 0x%02X" % register
    return BusError("%s: errno %s (%s)" % (where, n, _ERRNO_NAMES.get(n, e)),
                    address=address, register=register, errno=n)


def option_code(chip, name, value, table):
    """The register code of a keyword option: its index in `table`, or ValueError naming it."""
    if value not in table:
        raise ValueError("%s %s=%s: expected one of %s"
                         % (chip, name, value, ", ".join(str(v) for v in table)))
    return table.index(value)


def int16x3_into(d, buf, msb):
    """buf[0..2] = the three int16 of d[0..5], LSB first (msb=0: QMC5883L, QMC5883P data
    blocks) or MSB first (msb=1: MPU6050), sign-extended by hand: struct.unpack would
    allocate a tuple. Written out per axis: a loop costs a third more on the per-sample path."""
    h = 1 - msb  # offset of the high byte in each pair
    v = d[h] << 8 | d[msb]
    buf[0] = v - 0x10000 if v & 0x8000 else v
    v = d[2 + h] << 8 | d[2 + msb]
    buf[1] = v - 0x10000 if v & 0x8000 else v
    v = d[4 + h] << 8 | d[4 + msb]
    buf[2] = v - 0x10000 if v & 0x8000 else v


class BusGuard:
    """`with dev.guard:` maps a bus OSError to BusError(dev.address, dev.register)."""

    def __init__(self, dev):
        self._dev = dev

    def __enter__(self):
        return None

    def __exit__(self, kind, value, tb):
        if value is None or not isinstance(value, OSError):
            return False
        if isinstance(value, (BusError, DataReadyTimeout, SensorNotFound)):
            return False  # already says what happened
        d = self._dev
        raise bus_error(value, d.address, d.register)


class Device:
    """One chip at one address: one scratch buffer, error mapping, bounded data-ready wait."""

    def __init__(self, i2c, address, period_us, delay_us=None, timeout_us=None):
        self._i2c = i2c
        self.address = address
        self.register = None            # the register of the transfer under way (for errors)
        self._buf = bytearray(6)        # the one scratch buffer: data block, status, config byte
        self._b1 = memoryview(self._buf)[0:1]
        self._b2 = memoryview(self._buf)[0:2]   # config_ok() read-backs of 2 or 3 registers
        self._b3 = memoryview(self._buf)[0:3]
        self.guard = BusGuard(self)
        self._set_timing(period_us, delay_us, timeout_us)

    def _set_timing(self, period_us, delay_us, timeout_us):
        # Default bound: two periods (the first set after a configuration write takes up to
        # two, HMC5883L datasheet) plus 10 ms of bus latency.
        if delay_us is None:
            self._delay = sleep_us
            self._measured = ticks_us is not None
        else:
            self._delay = delay_us
            self._measured = False
        if timeout_us is None:
            timeout_us = 2 * period_us + 10000
        if type(timeout_us) is not int or not 0 < timeout_us <= _MAX_TIMEOUT_US:
            raise ValueError("timeout_us=%r: expected an int of 1..%d microseconds"
                             % (timeout_us, _MAX_TIMEOUT_US))
        self.timeout_us = timeout_us
        self.period_us = period_us  # the output data period: the app sizes its work by it
        self._poll_us = max(period_us >> 4, _MIN_POLL_US)  # latency <= 1/16 of a period

    # -- transfers: raw port errors; callers sit inside `with self.guard:`
    def _read_into(self, reg, buf):
        self.register = reg
        self._i2c.readfrom_mem_into(self.address, reg, buf)

    def _read_u8(self, reg):
        self._read_into(reg, self._b1)
        return self._buf[0]

    def _write_u8(self, reg, value):
        self.register = reg
        self._buf[0] = value
        self._i2c.writeto_mem(self.address, reg, self._b1)

    def _probe_u8(self, reg, name):
        # The ID read: no answer means no chip here (SensorNotFound), not a failed transfer.
        try:
            with self.guard:
                return self._read_u8(reg)
        except BusError as e:
            raise SensorNotFound("no %s at 0x%02X: reading ID register 0x%02X failed (errno %s)"
                                 % (name, self.address, reg, e.errno), address=self.address)

    def wait_ready(self, reg, mask):
        """Poll status register `reg` until a bit of `mask` is set; return the status byte."""
        with self.guard:
            return self.wait(reg, mask)

    def wait(self, reg, mask):
        """wait_ready() for callers already inside `with self.guard:`."""
        t0 = ticks_us() if self._measured else 0
        waited = 0
        while True:
            status = self._read_u8(reg)
            if status & mask:
                return status
            if self._measured:
                waited = ticks_diff(ticks_us(), t0)
            if waited >= self.timeout_us:  # the status was read once more after the bound
                self._timed_out(reg, status, waited)
            self._delay(self._poll_us)
            if not self._measured:
                waited += self._poll_us

    def _timed_out(self, reg, status, waited):
        raise DataReadyTimeout(
            "no data ready from 0x%02X after %d us: status register 0x%02X = 0x%02X "
            "(chip in standby, or not converting?)" % (self.address, waited, reg, status),
            address=self.address, waited_us=waited)
