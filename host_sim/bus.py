"""Simulated I2C bus with the machine.I2C method set, bus timing and fault injection.

    from host_sim.clock import SimClock
    from host_sim.bus import SimI2C
    i2c = SimI2C(SimClock())
    i2c.attach(0x0D, chip)                 # any RegisterDevice (below)
    i2c.readfrom_mem(0x0D, 0x0D, 1)        # -> b'\\xff'
    i2c.inject_nack(after=0)               # the next transaction raises OSError(19)

Timing: every transaction advances the clock by its time on the wire, 9 bits per byte
(8 data + ACK) including the address bytes, plus one bit time each for START, repeated
START and STOP, at `freq`. The sub-microsecond remainder is carried, so long runs do not
drift. `sleep_us(us)` advances the same clock: the host board hands it to drivers as their
delay function.

Faults: a transaction is one call of readfrom_mem/readfrom_mem_into/writeto_mem/readfrom/
readfrom_into/writeto/writevto; `.transactions` counts them (faulted ones included).
`scan()` is not a counted transaction and is never faulted (it only probes addresses).
- inject_nack(after=N, count=1, errno=19): transactions N..N+count-1 from now (0 = the next
  one) raise OSError(errno) without reaching the device (an address NACK).
- inject_eio(after=N, count=K): the same with OSError(5) (EIO), a burst of K.
- kill(addr): the device stops answering (OSError(19), absent from scan) until revive(addr).
- stuck_high(addr, on=True): the device's data line reads all ones (SDA held high by a
  browned-out slave or a broken pull-down): transactions succeed, every byte read is 0xFF.
An address with no device, or whose gate is closed, raises OSError(19) (ENODEV), as
MicroPython's machine.I2C does on an address NACK. The errors carry the number in both
e.errno and e.args[0] on both interpreters.

Device protocol (how chip models plug in): a device is any object with
    begin(now_us)     called at the start of each transaction addressed to it (lazy catch-up:
                      the chip computes what happened since its last access);
    write(data)       a write transaction's payload: data[0] sets the register pointer, the
                      following bytes are written from there with the chip's own auto-increment;
    read(n) -> bytes  n bytes from the pointer, with the chip's own auto-increment;
    select(reg), store(buf), read_into(buf)
                      the same three steps without building byte strings (8-bit register
                      addresses): set the pointer, write buf from it, fill buf from it.
A combined read (readfrom_mem) is "set the pointer" then "read" in one transaction.
RegisterDevice implements all of them from three per-chip hooks: read_reg(reg),
write_reg(reg, value) and next_pointer(reg); chip models subclass it.

Allocation: with addrsize=8 and no trace, readfrom_mem_into, writeto_mem and readfrom_into
allocate nothing themselves, so a driver's per-sample path can run under
micropython.heap_lock() on the simulated bus. A chip does allocate when it computes a new
sample (floats); call settle() just before heap_lock() so that the samples due by now are
computed, and keep the locked section shorter than the chip's sample period.
"""

_ENODEV = 19
_EIO = 5
_ERRNO_NAMES = {_ENODEV: "ENODEV", _EIO: "EIO", 110: "ETIMEDOUT"}
_SCAN_FIRST = 0x08  # machine.I2C.scan() probes 0x08..0x77 (the non-reserved 7-bit range)
_SCAN_LAST = 0x77


def _oserror(errno):
    # Two arguments so that CPython fills .errno too (MicroPython does with one); args[0] and
    # .errno are the number on both interpreters, as with a real machine.I2C NACK.
    return OSError(errno, _ERRNO_NAMES.get(errno, "I2C error"))


class RegisterDevice:
    """Base class for an 8-bit-register I2C chip model (see the module docstring)."""

    def __init__(self):
        self.pointer = 0
        self.now_us = 0

    def begin(self, now_us):
        self.now_us = now_us
        self.update(now_us)

    def update(self, now_us):
        """Bring the chip's lazily computed state up to `now_us` (override)."""

    def select(self, reg):
        self.pointer = reg & 0xFF

    def store(self, buf, start=0):
        for i in range(start, len(buf)):
            self.write_reg(self.pointer, buf[i] & 0xFF)
            self.pointer = self.next_pointer(self.pointer)

    def read_into(self, buf):
        for i in range(len(buf)):
            buf[i] = self.read_reg(self.pointer) & 0xFF
            self.pointer = self.next_pointer(self.pointer)

    def write(self, data):
        if len(data):
            self.select(data[0])
            self.store(data, 1)

    def read(self, n):
        out = bytearray(n)
        self.read_into(out)
        return bytes(out)

    def next_pointer(self, reg):
        return (reg + 1) & 0xFF

    def read_reg(self, reg):
        return 0

    def write_reg(self, reg, value):
        pass


class MagnetometerModel(RegisterDevice):
    """A RegisterDevice with the data-register fault hooks the magnetometer models share
    (their docstrings say what each chip then shows): freeze() keeps the output registers as
    they are, constant(x, y, z) makes every conversion read that sample; sticky=True survives
    a reset. The model reads .fault, .fault_value and .sticky when it converts. Each model
    also has counts_per_gauss() (its output's scale now), period_us() (its output period now;
    the MMC5603, commanded per measurement, has meas_us()), and glitch_range() (a glitch write
    to its range or gain setting) or, for a chip with one range, FIXED_RANGE: why not."""
    fault = None
    fault_value = (0, 0, 0)
    sticky = False

    def freeze(self, sticky=False):
        self.fault = "freeze"
        self.sticky = sticky

    def constant(self, x=0, y=0, z=0, sticky=False):
        self.fault = "constant"
        self.fault_value = (int(x), int(y), int(z))
        self.sticky = sticky

    def clear_fault(self):
        self.fault = None
        self.sticky = False


class RegisterFile(RegisterDevice):
    """A passive chip: fixed register contents, writes stored (e.g. a BMP180 on the GY-87)."""

    def __init__(self, regs=None):
        RegisterDevice.__init__(self)
        self.regs = bytearray(256)
        if regs:
            for r in regs:
                self.regs[r] = regs[r]

    def read_reg(self, reg):
        return self.regs[reg]

    def write_reg(self, reg, value):
        self.regs[reg] = value


class SimI2C:
    """machine.I2C look-alike over simulated devices (MicroPython signatures)."""

    def __init__(self, clock=None, freq=400000):
        if clock is None:
            from host_sim.clock import SimClock
            clock = SimClock()
        if freq <= 0:
            raise ValueError("SimI2C: freq must be > 0, got %d" % freq)
        self.clock = clock
        self.freq = int(freq)
        self.transactions = 0
        self.trace = None  # set to [] to record (op, addr, reg_or_None, bytes) per transaction
        self._devices = {}
        self._gates = {}
        self._dead = {}
        self._high = {}    # addresses whose reads return 0xFF (stuck_high)
        self._faults = []  # [first_index, last_index_exclusive, errno]
        self._bit_rem = 0

    # --- wiring -----------------------------------------------------------------------
    def attach(self, addr, device, gate=None):
        """Put `device` at 7-bit `addr`. `gate()`, if given, must return True for it to answer."""
        if not 0 <= addr <= 0x7F:
            raise ValueError("SimI2C.attach: address 0x%02x is not 7-bit" % addr)
        if addr in self._devices:
            raise ValueError("SimI2C.attach: address 0x%02x already in use" % addr)
        self._devices[addr] = device
        if gate is not None:
            self._gates[addr] = gate
        return device

    def detach(self, addr):
        self._devices.pop(addr, None)
        self._gates.pop(addr, None)
        self._dead.pop(addr, None)

    def device(self, addr):
        """The model at `addr` (even if killed or gated), or None."""
        return self._devices.get(addr)

    def answers(self, addr):
        """True when a device at `addr` would ACK its address now."""
        dev = self._devices.get(addr)
        if dev is None or addr in self._dead:
            return False
        gate = self._gates.get(addr)
        return gate is None or bool(gate())

    # --- faults -----------------------------------------------------------------------
    def inject_nack(self, after=0, count=1, errno=_ENODEV):
        if after < 0 or count < 1:
            raise ValueError("inject_nack: after >= 0 and count >= 1 (got %d, %d)" % (after, count))
        first = self.transactions + after
        self._faults.append([first, first + count, errno])

    def inject_eio(self, after=0, count=1):
        self.inject_nack(after, count, _EIO)

    def clear_faults(self):
        self._faults = []

    def kill(self, addr):
        self._dead[addr] = True

    def revive(self, addr):
        self._dead.pop(addr, None)

    def stuck_high(self, addr, on=True):
        if on:
            self._high[addr] = True
        else:
            self._high.pop(addr, None)

    def _ff(self, addr, buf):
        if self._high and addr in self._high:
            for i in range(len(buf)):
                buf[i] = 0xFF

    # --- time -------------------------------------------------------------------------
    def sleep_us(self, us):
        self.clock.advance(us)

    def sleep_ms(self, ms):
        self.clock.advance(int(ms) * 1000)

    def settle(self):
        """Let every answering device catch up to now (see Allocation above)."""
        for addr in self._devices:
            if self.answers(addr):
                self._devices[addr].begin(self.clock.now_us)

    def _charge(self, wire_bytes, conditions):
        total = (9 * wire_bytes + conditions) * 1000000 + self._bit_rem
        self.clock.advance(total // self.freq)
        self._bit_rem = total % self.freq

    # --- one transaction --------------------------------------------------------------
    def _open(self, addr):
        """Count the transaction, apply faults and return the device (or raise OSError)."""
        idx = self.transactions
        self.transactions = idx + 1
        faults = self._faults
        if faults:
            hit = 0
            keep = []
            for f in faults:
                if f[0] <= idx < f[1]:
                    hit = f[2]
                if f[1] > idx + 1:
                    keep.append(f)
            self._faults = keep
            if hit:
                self._charge(1, 2)  # the address byte went out and was not ACKed
                raise _oserror(hit)
        if not self.answers(addr):
            self._charge(1, 2)
            raise _oserror(_ENODEV)
        dev = self._devices[addr]
        dev.begin(self.clock.now_us)
        return dev

    @staticmethod
    def _mem_bytes(memaddr, addrsize):
        if addrsize not in (8, 16, 24, 32):
            raise ValueError("addrsize must be 8, 16, 24 or 32, got %d" % addrsize)
        return (memaddr & ((1 << addrsize) - 1)).to_bytes(addrsize // 8, "big")

    def _log(self, op, addr, reg, data):
        if self.trace is not None:
            self.trace.append((op, addr, reg, bytes(data)))

    # --- machine.I2C methods ----------------------------------------------------------
    def scan(self):
        found = []
        for addr in range(_SCAN_FIRST, _SCAN_LAST + 1):
            self._charge(1, 2)
            if self.answers(addr):
                found.append(addr)
        return found

    def readfrom_mem(self, addr, memaddr, nbytes, *, addrsize=8):
        dev = self._open(addr)
        mem = self._mem_bytes(memaddr, addrsize)
        dev.write(mem)
        data = dev.read(nbytes)
        if self._high and addr in self._high:
            data = b"\xff" * nbytes
        self._charge(2 + len(mem) + nbytes, 3)
        self._log("rm", addr, memaddr, data)
        return data

    def readfrom_mem_into(self, addr, memaddr, buf, *, addrsize=8):
        if addrsize != 8 or self.trace is not None:
            data = self.readfrom_mem(addr, memaddr, len(buf), addrsize=addrsize)
            for i in range(len(buf)):
                buf[i] = data[i]
            return
        dev = self._open(addr)
        dev.select(memaddr)
        dev.read_into(buf)
        self._ff(addr, buf)
        self._charge(3 + len(buf), 3)

    def writeto_mem(self, addr, memaddr, buf, *, addrsize=8):
        dev = self._open(addr)
        if addrsize == 8:
            dev.select(memaddr)
            dev.store(buf)
            self._charge(2 + len(buf), 2)
        else:
            payload = self._mem_bytes(memaddr, addrsize) + bytes(buf)
            dev.write(payload)
            self._charge(1 + len(payload), 2)
        self._log("wm", addr, memaddr, buf)

    def readfrom(self, addr, nbytes, stop=True):
        dev = self._open(addr)
        data = dev.read(nbytes)
        self._charge(1 + nbytes, 2)
        self._log("r", addr, None, data)
        return data

    def readfrom_into(self, addr, buf, stop=True):
        dev = self._open(addr)
        dev.read_into(buf)
        self._charge(1 + len(buf), 2)
        self._log("r", addr, None, buf)

    def writeto(self, addr, buf, stop=True):
        dev = self._open(addr)
        payload = bytes(buf)
        dev.write(payload)
        self._charge(1 + len(payload), 2)
        self._log("w", addr, None, payload)
        return len(payload)

    def writevto(self, addr, vector, stop=True):
        payload = b"".join([bytes(v) for v in vector])
        return self.writeto(addr, payload, stop)
