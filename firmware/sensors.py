"""Find the compass chip on a bus, and the bus plumbing every driver shares.

    from machine import I2C, Pin
    from firmware import sensors
    mag = sensors.detect(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000))  # QMC5883L or HMC5883L

detect(i2c, **options) probes 0x0D (QMC5883L), 0x1E (HMC5883L) and 0x2C (QMC5883P) and checks
their ID registers. When none of them answers but an MPU6050 does (0x68/0x69), it wakes it and
opens its I2C bypass, then probes again: a GY-87/GY-86 board keeps its HMC5883L on the MPU6050's
auxiliary bus, invisible until then. It returns the configured driver; `options` go to the
driver that accepts them (QMC5883L: range, odr, osr; HMC5883L: gain, rate, averaging; QMC5883P:
range, odr, osr, dsr; all: delay_us, timeout_us). A value the chip found does not support raises
ValueError (osr is 512..64 on the QMC5883L, 8..1 on the QMC5883P). An empty bus or wrong IDs
raise SensorNotFound naming every address tried and what the scan found.

detect_accel(i2c) returns an MPU6050 driver, or None when none answers (a DS3231 RTC also sits
at 0x68: a wrong WHO_AM_I there is "no accelerometer", not an error).

Device is the base of the drivers: bus errors become BusError(address, register, errno), and
wait_ready() is the bounded data-ready wait. How the wait is bounded:
- delay_us=None (a board): the wait sleeps with time.sleep_us and measures with time.ticks_us.
- delay_us given (the simulator passes bus.sleep_us; CPython has no ticks_us): the waited time
  is the sum of the delays asked for. Measuring wall time there would be wrong: simulated time
  moves only when delay_us is called, so the MicroPython unix port would spin against the
  simulator until real microseconds passed.
Either way DataReadyTimeout(address, waited_us) is raised once waited_us >= timeout_us.
"""
try:
    from micropython import const
except ImportError:  # CPython
    def const(x):
        return x

try:
    from time import ticks_diff, ticks_us
except ImportError:  # CPython: only ever runs against the simulator
    ticks_us = None
    ticks_diff = None
try:
    from time import sleep_us
except ImportError:
    sleep_us = None

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound
from firmware.fixedpoint import micropython

_QMC5883L_ADDR = const(0x0D)
_HMC5883L_ADDR = const(0x1E)
_QMC5883P_ADDR = const(0x2C)
_MPU6050_ADDR = const(0x68)
_MPU6050_ADDR_AD0 = const(0x69)
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


@micropython.native
def le16x3_into(d, buf):
    """buf[0..2] = the three int16, LSB first, of d[0..5] (QMC5883L and QMC5883P data blocks),
    sign-extended by hand: struct.unpack would allocate a tuple."""
    v = d[1] << 8 | d[0]
    buf[0] = v - 0x10000 if v & 0x8000 else v
    v = d[3] << 8 | d[2]
    buf[1] = v - 0x10000 if v & 0x8000 else v
    v = d[5] << 8 | d[4]
    buf[2] = v - 0x10000 if v & 0x8000 else v


def _no_delay(us):
    pass


class Device:
    """One chip at one address: one scratch buffer, error mapping, bounded data-ready wait."""

    def __init__(self, i2c, address, period_us, delay_us=None, timeout_us=None):
        self._i2c = i2c
        self.address = address
        self._buf = bytearray(6)        # the one scratch buffer: data block, status, config byte
        self._b1 = memoryview(self._buf)[0:1]
        self._set_timing(period_us, delay_us, timeout_us)

    def _set_timing(self, period_us, delay_us, timeout_us):
        # period_us: the chip's output data period. Default bound: two periods (the first set
        # after a configuration write takes up to two, HMC5883L) plus 10 ms of bus latency.
        if delay_us is None:
            self._delay = sleep_us if sleep_us is not None else _no_delay
            self._measured = ticks_us is not None
        else:
            self._delay = delay_us
            self._measured = False
        if timeout_us is None:
            timeout_us = 2 * period_us + 10000
        if not 0 < timeout_us <= _MAX_TIMEOUT_US:
            raise ValueError("timeout_us=%s: expected 1..%d" % (timeout_us, _MAX_TIMEOUT_US))
        self.timeout_us = timeout_us
        self._period_us = period_us
        self.period_us = period_us  # the output data period: the app sizes its work by it
        self._poll_us = max(period_us >> 4, _MIN_POLL_US)  # latency <= 1/16 of a period

    # -- bus access: every OSError becomes BusError naming address and register
    @micropython.native
    def _read_into(self, reg, buf):
        # Native code: a bytecode function with try/except exceeds the 11 words MicroPython
        # keeps on the C stack, so its frame would come from the heap on every transfer
        # (~190 bytes, freed at return, but able to start a GC); a native frame lives on the
        # C stack (tests/scenarios/drivers_alloc.py measures 0 bytes).
        try:
            self._i2c.readfrom_mem_into(self.address, reg, buf)
        except OSError as e:
            raise bus_error(e, self.address, reg)

    def _read_u8(self, reg):
        self._read_into(reg, self._b1)
        return self._buf[0]

    @micropython.native
    def _write_u8(self, reg, value):
        self._buf[0] = value
        try:
            self._i2c.writeto_mem(self.address, reg, self._b1)
        except OSError as e:
            raise bus_error(e, self.address, reg)

    def _probe_u8(self, reg, name):
        # The ID read: no answer means no chip here (SensorNotFound), not a failed transfer.
        try:
            return self._read_u8(reg)
        except BusError as e:
            raise SensorNotFound("no %s at 0x%02X: reading ID register 0x%02X failed (errno %s)"
                                 % (name, self.address, reg, e.errno), address=self.address)

    @micropython.native  # per-sample path: C-stack frame, fewer VM dispatches
    def wait_ready(self, reg, mask):
        """Poll status register `reg` until a bit of `mask` is set; return the status byte."""
        # Few locals and the raise in its own method: a frame above 11 words would make
        # MicroPython take its state from the heap on every call (freed again at return).
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

def _hex(addrs):
    return "[" + ", ".join("0x%02X" % a for a in addrs) + "]" if addrs else "nothing"


def _scan(i2c):
    try:
        return list(i2c.scan())
    except OSError as e:
        raise bus_error(e, None, None)


def _options_for(cls, options):
    return {k: v for k, v in options.items() if k in cls.OPTIONS}


def _mag_drivers():
    from firmware.hmc5883l import HMC5883L
    from firmware.qmc5883l import QMC5883L
    from firmware.qmc5883p import QMC5883P
    return ((_QMC5883L_ADDR, QMC5883L), (_HMC5883L_ADDR, HMC5883L), (_QMC5883P_ADDR, QMC5883P))


def _probe_mags(i2c, found, options, notes):
    for addr, cls in _mag_drivers():
        if addr not in found:
            continue
        try:
            return cls(i2c, address=addr, **_options_for(cls, options))
        except (SensorNotFound, BusError) as e:
            notes.append(str(e))
    return None


def detect(i2c, **options):
    """Return the driver of the magnetometer on `i2c` (see the module docstring)."""
    from firmware.mpu6050 import MPU6050
    known = set()
    for _, cls in _mag_drivers():
        known |= set(cls.OPTIONS)
    for k in options:
        if k not in known:
            raise TypeError("detect(): unknown option '%s' (expected one of %s)"
                            % (k, ", ".join(sorted(known))))
    notes = []
    found = _scan(i2c)
    seen = list(found)
    mag = _probe_mags(i2c, found, options, notes)
    if mag is not None:
        return mag
    for addr in (_MPU6050_ADDR, _MPU6050_ADDR_AD0):
        if addr not in found:
            continue
        try:
            mpu = MPU6050(i2c, address=addr)
            mpu.enable_bypass()
        except (SensorNotFound, BusError) as e:
            notes.append(str(e))
            continue
        behind = _scan(i2c)
        for a in behind:
            if a not in seen:
                seen.append(a)
        mag = _probe_mags(i2c, [a for a in behind if a not in found], options, notes)
        if mag is not None:
            return mag
    raise SensorNotFound(
        "no magnetometer found: tried 0x0D (QMC5883L), 0x1E (HMC5883L), 0x2C (QMC5883P) and the "
        "MPU6050 bypass at 0x68/0x69 (GY-87); the bus scan found %s%s"
        % (_hex(sorted(seen)), "; " + "; ".join(notes) if notes else ""),
        address=None, tried=(_QMC5883L_ADDR, _HMC5883L_ADDR, _QMC5883P_ADDR, _MPU6050_ADDR,
                             _MPU6050_ADDR_AD0),
        found=sorted(seen))


def detect_accel(i2c, **options):
    """Return an MPU6050 driver (woken, `options` e.g. accel_range=2), or None if none answers."""
    from firmware.mpu6050 import MPU6050
    found = _scan(i2c)
    for addr in (_MPU6050_ADDR, _MPU6050_ADDR_AD0):
        if addr in found:
            try:
                return MPU6050(i2c, address=addr, **options)
            except SensorNotFound:
                continue  # something else lives there (a DS3231 RTC uses 0x68)
    return None
