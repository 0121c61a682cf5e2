# What the chip drivers need only to start a chip and to explain a failure, imported for that
# and dropped again (firmware.compat.drop) by the app once it is running: option codes, the ID
# probe, the timing checks, a magnetometer's construction and configuration read-back, and the
# messages of BusError, DataReadyTimeout, SensorNotFound and SensorOverflow (firmware/errors.py
# says what each carries). firmware/i2cdevice.py keeps what runs every sample.
from firmware.compat import const, wait_clock
from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow

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


def option_code(chip, name, value, table, unit=None):
    """The register code of a keyword option: its index in `table`, or ValueError naming it
    (and the option's unit, when it has one)."""
    if value not in table:
        raise ValueError("%s %s=%r: expected one of %s%s"
                         % (chip, name, value, ", ".join(str(v) for v in table),
                            " (%s)" % unit if unit else ""))
    return table.index(value)


def _hex(b):
    return " ".join("0x%02X" % v for v in b)


def set_timing(dev, period_us, delay_us, timeout_us):
    # Default bound: two periods (the first set after a configuration write takes up to
    # two, HMC5883L datasheet) plus 10 ms of bus latency.
    dev._delay, dev._measured = wait_clock(delay_us)
    if timeout_us is None:
        timeout_us = 2 * period_us + 10000
    if type(timeout_us) is not int or not 0 < timeout_us <= _MAX_TIMEOUT_US:
        raise ValueError("timeout_us=%r: expected an int of 1..%d microseconds"
                         % (timeout_us, _MAX_TIMEOUT_US))
    dev.timeout_us = timeout_us
    dev.period_us = period_us  # the output data period: the app sizes its work by it
    dev._poll_us = max(period_us >> 4, _MIN_POLL_US)  # latency <= 1/16 of a period


def probe(dev, reg, n, name):
    # The ID read (n bytes from reg, a view of the scratch buffer): no answer means no chip
    # here (SensorNotFound), not a failed transfer.
    view = memoryview(dev._buf)[0:n]
    try:
        with dev.guard:
            dev._read_into(reg, view)
    except BusError as e:
        raise SensorNotFound("no %s at 0x%02X: reading ID register 0x%02X failed (errno %s)"
                             % (name, dev.address, reg, e.errno), address=dev.address)
    return view


def timed_out(dev, reg, status, waited):
    raise DataReadyTimeout(
        "no data ready from 0x%02X after %d us: status register 0x%02X = 0x%02X "
        "(chip in standby, or not converting?)" % (dev.address, waited, reg, status),
        address=dev.address, waited_us=waited)


def magnetometer(dev, device_init, i2c, address, delay_us, timeout_us, values):
    """Magnetometer.__init__: option codes, timing, the ID probe, the configuration."""
    units = getattr(dev, "UNITS", ())
    codes = [option_code(dev.KIND.upper(), dev.OPTIONS[i], v, dev.TABLES[i],
                         units[i] if i < len(units) else None)
             for i, v in enumerate(values)]
    periods, counts = dev.PER_CODE
    device_init(dev, i2c, address, periods[codes[1]], delay_us, timeout_us)
    dev.chip = dev.KIND.upper()
    reg, dev._status, dev._ready, dev._data, dev._config = dev.REGISTERS
    dev._stale, dev._alarms = dev.FLAGS
    dev.range_code = codes[0]
    dev.counts_per_gauss = counts[codes[0]]
    dev.suspect = False  # the status hinted at old data on the last read (DOR, LOCK)
    dev.skipped = 0      # reads whose status said a sample set was lost (QMC5883L DOR)
    dev.expect_id(reg, dev.ID)
    dev.set_config(dev._config_of(codes))
    dev.configure()


def expect_id(dev, reg, want):
    """The ID probe: SensorNotFound unless the registers from `reg` on read `want` (bytes)."""
    got = dev._probe(reg, len(want), dev.chip)
    if got != want:
        raise SensorNotFound("no %s at 0x%02X: ID register 0x%02X reads %s, expected %s"
                             % (dev.chip, dev.address, reg, _hex(got), _hex(want)),
                             address=dev.address)


def check_config(dev):
    # the read-back after configuring: a chip that does not keep what was written is not
    # the chip named (or not a chip at all)
    if dev.config_matches():
        return
    b = dev._buf
    i = 0
    while b[i] == dev._want[i]:
        i += 1
    raise SensorNotFound("no %s at 0x%02X: register 0x%02X written 0x%02X reads back 0x%02X"
                         % (dev.chip, dev.address, dev._config + i, dev._want[i], b[i]),
                         address=dev.address)


def overflow(dev, raw, detail):
    """SensorOverflow for raw sample `raw` (a tuple, the chip's axes): `detail` says why."""
    return SensorOverflow("%s at 0x%02X: %s" % (dev.chip, dev.address, detail),
                          address=dev.address, raw=raw)

def overflow_bit(dev, bit, advice):
    # the status said an axis is beyond the range: the block is read (data lock released)
    raw = dev.held(0)
    raise overflow(dev, raw, "%s set (an axis is beyond +-%d G), raw %s; %s"
                        % (bit, dev.TABLES[0][dev.range_code], raw, advice))


def restart(health, mag, acc):
    """Each driver re-applies its own configuration (CompassApp.reinit), counted in `health`
    (firmware/health.py Health); True when both answered (the app keeps whatever did)."""
    err = None
    if acc is not None:
        try:
            acc.configure()
        except OSError as e:  # the magnetometer may still be reachable: go on
            err = e
    try:
        try:
            mag.configure()
        except OSError:
            if acc is None:
                raise
            acc.enable_bypass()  # GY-87: a reset MPU6050 hides the magnetometer again
            mag.configure()
    except OSError as e:  # SensorNotFound, BusError, DataReadyTimeout: still not back
        err = e
    if err is None:
        health.reinits += 1
    else:
        health.reinit_failures += 1
        health.last_error = err
    health.cfg_due = True  # (the runs of repeats go on: a cured chip ends them itself)
    return err is None
