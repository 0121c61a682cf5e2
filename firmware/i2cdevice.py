"""The bus plumbing every chip driver shares: register helpers, error mapping, bounded waits."""
#     class MyChip(Device):
#         def read_into(self, buf):
#             with self.guard:                 # OSError from the bus -> BusError(address, register)
#                 self.wait(_STATUS, _DRDY)
#                 self._read_into(_DATA, self._buf)
#
# Device(i2c, address, period_us, delay_us=None, timeout_us=None); Magnetometer(Device): the
# scaffolding the magnetometer drivers share (see the class). The arguments, why the guard is a
# `with` block, and the unguarded calls the app uses: docs/design.md (module notes, i2cdevice).
from firmware.compat import const, pick, room, ticks_diff, ticks_us
from firmware.errors import BusError, DataReadyTimeout, SensorNotFound

DEFAULT_PERIOD_US = const(20000)  # a driver without .period_us: its users assume 50 Hz
_OURS = (BusError, DataReadyTimeout, SensorNotFound)  # already say what happened (a module
#                                                      constant: a literal tuple is built per use)


def bus_error(e, address, register):
    """The BusError for OSError `e` raised by a transaction with `address`/`register`
    (firmware/devinit.py writes it)."""
    from firmware.devinit import bus_error
    return bus_error(e, address, register)


def option_code(chip, name, value, table):
    """The register code of a keyword option: its index in `table`, or ValueError naming it."""
    from firmware.devinit import option_code
    return option_code(chip, name, value, table)


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


decode = int16x3_into  # the drivers' per-sample decode: it or its fast mirror (use_kernels)


def use_kernels(kn=None):
    """The drivers' decode from the kernel set `kn`: None picks firmware.fast where the
    native emitter exists, False the plain function."""
    global decode
    decode = pick(kn, "int16x3_into", int16x3_into)


class BusGuard:
    """`with dev.guard:` maps a bus OSError to BusError(dev.address, dev.register)."""

    def __init__(self, dev):
        self._dev = dev

    def __enter__(self):
        return None

    def __exit__(self, kind, value, tb):
        if value is None:
            return False
        e = self.mapped(value)
        if e is not value:
            raise e
        return False

    def mapped(self, value):
        """The error to report for `value`: a BusError naming the device's address and register
        for a port's OSError; anything else (already one of ours, or no OSError) unchanged."""
        if value is None or not isinstance(value, OSError) or isinstance(value, _OURS):
            return value
        d = self._dev
        return bus_error(value, d.address, d.register)


class Device:
    """One chip at one address: one scratch buffer, error mapping, bounded data-ready wait."""

    def __init__(self, i2c, address, period_us, delay_us=None, timeout_us=None):
        self._i2c = i2c
        self.address = address
        self.register = None            # the register of the transfer under way (for errors)
        self._buf = bytearray(6)        # the one scratch buffer: data block, status, config byte
        self._b1 = memoryview(self._buf)[0:1]
        self.guard = BusGuard(self)
        from firmware.devinit import set_timing
        set_timing(self, period_us, delay_us, timeout_us)

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

    def _probe(self, reg, n, name):
        # the ID read: no answer means no chip here (SensorNotFound), not a failed transfer
        from firmware.devinit import probe
        return probe(self, reg, n, name)

    def wait_ready(self, reg, mask):
        """Poll status register `reg` until a bit of `mask` is set; return the status byte."""
        with self.guard:
            return self.wait(reg, mask)

    def wait(self, reg, mask):
        """wait_ready() for callers already inside `with self.guard:`. The first poll is the
        usual answer (a driver reads at or below the output rate): it costs one transfer and
        no clock reading; the bounded wait starts only when it says "not ready"."""
        self.register = reg
        self._i2c.readfrom_mem_into(self.address, reg, self._b1)
        status = self._buf[0]
        if status & mask:
            return status
        return self._poll(reg, mask)

    def _poll(self, reg, mask):
        # The bound counts from the first "not ready": the poll before it is one transfer
        # (~100 us at 400 kHz) more than timeout_us at the most.
        t0 = ticks_us() if self._measured else 0
        waited = 0
        while True:
            if self._measured:
                waited = ticks_diff(ticks_us(), t0)
            if waited >= self.timeout_us:  # the status was read once more after the bound
                self._timed_out(reg, self._buf[0], waited)
            self._delay(self._poll_us)
            if not self._measured:
                waited += self._poll_us
            status = self._read_u8(reg)
            if status & mask:
                return status

    def _timed_out(self, reg, status, waited):
        from firmware.devinit import timed_out
        timed_out(self, reg, status, waited)


class Magnetometer(Device):
    # What the magnetometer drivers share: options to register codes, the ID probe,
    # configure() with its read-back, read_into() behind the data-ready bit, config_ok(),
    # read() and the overflow report. Each chip's file (qmc5883l.py, qmc5883p.py, hmc5883l.py)
    # keeps its datasheet's facts and gives them as class attributes:
    #
    #   KIND, OPTIONS  the driver's name in records and its keyword options (public)
    #   UNITS          (optional) each option's unit, named by a bad value's ValueError
    #   TABLES         per option the values offered, register code = index; the first option
    #                  is the range (its code is .range_code), the second the output rate
    #   PER_CODE       (output period in us per rate code, counts/G per range code)
    #   FLAGS          (status bit saying the data may be old, status bits for _alarm())
    #   REGISTERS      (ID register, status register, data-ready bit, first of the six data
    #                  registers, first configuration register)
    #   ID             the bytes the ID register and those after it read
    #   MIRROR         (where True only) the datasheet draws the magnetometer's axes as a
    #                  mirror image of its package's accelerometer's: MAG_AXES is a mirror too
    #
    # The chip's constructor passes its option values in the order of OPTIONS; the chip gives
    # _config_of(codes) (the bytes the configuration registers hold from the first on, which
    # config_ok() reads back in one transfer), _configure() (the datasheet's sequence, inside
    # the guard; _check_config() reads the configuration back) and, where its data block is not
    # X, Y, Z int16 LSB first, its own sample_into(buf). The six data bytes are read in one
    # transaction: a partial read leaves the chip's data lock set.

    def __init__(self, i2c, address, delay_us, timeout_us, *values):
        from firmware.devinit import magnetometer
        magnetometer(self, Device.__init__, i2c, address, delay_us, timeout_us, values)

    def expect_id(self, reg, want):
        """The ID probe: SensorNotFound unless the registers from `reg` on read `want` (bytes)."""
        from firmware.devinit import expect_id
        expect_id(self, reg, want)

    def set_config(self, want):
        """The bytes the configuration registers must hold from self._config on."""
        self._want = bytes(want)
        self._back = memoryview(self._buf)[0:len(want)]

    def configure(self):
        """This driver's configuration, written again after a chip reset (the datasheet's
        sequence in the driver's _configure())."""
        with self.guard:
            self._configure()

    def _check_config(self):
        # the read-back after configuring: SensorNotFound when the chip does not keep it
        from firmware.devinit import check_config
        check_config(self)

    def config_ok(self):
        """True when the configuration registers still hold this driver's configuration (one
        transfer): False after a brown-out or soft reset, or a glitch write."""
        with self.guard:
            return self.config_matches()

    def config_matches(self):
        """config_ok() for callers already inside a guard (the app's read guard)."""
        self.register = self._config
        self._i2c.readfrom_mem_into(self.address, self._config, self._back)
        return self._back == self._want

    def read_into(self, buf):
        """Wait for data-ready, read X, Y, Z (counts) into buf[0..2]. Allocates nothing."""
        with self.guard:
            self.sample_into(buf)

    def sample_into(self, buf):
        """read_into() for callers already inside a guard: X, Y, Z int16 LSB first."""
        status = self.wait(self._status, self._ready)
        self.register = self._data  # fetch(), written out: one call less per sample
        self._i2c.readfrom_mem_into(self.address, self._data, self._buf)
        self.suspect = status & self._stale != 0
        if status & self._alarms:
            self._alarm(status)
        decode(self._buf, buf, 0)

    def fetch(self):
        """Wait for data-ready and read the six data bytes into self._buf (inside a guard);
        the status byte."""
        status = self.wait(self._status, self._ready)
        self.register = self._data
        self._i2c.readfrom_mem_into(self.address, self._data, self._buf)
        return status

    def read(self):
        """(x, y, z) raw counts, the chip's axes."""
        v = [0, 0, 0]
        self.read_into(v)
        return (v[0], v[1], v[2])

    def held(self, msb):
        """The data block in self._buf as a tuple of three int16, LSB (msb=0) or MSB first
        (msb=1), in register order: for error reports (allocates)."""
        v = [0, 0, 0]
        int16x3_into(self._buf, v, msb)
        return tuple(v)

    def overflow(self, raw, detail):
        """SensorOverflow for raw sample `raw` (a tuple, the chip's axes): `detail` says why."""
        from firmware.devinit import overflow
        return overflow(self, raw, detail)

    def _overflow_bit(self, bit, advice):
        # the status said an axis is beyond the range: the block is read (data lock released)
        from firmware.devinit import overflow_bit
        overflow_bit(self, bit, advice)


room(Magnetometer)  # its methods' table too (firmware/compat.py room)


use_kernels()
