# A busio.I2C look-alike over any machine.I2C-shaped bus (host_sim's SimI2C, or a replay bus),
# so that firmware.circuitpython.busio_i2c runs on CPython and MicroPython as it would on CircuitPython.
# Runs on both interpreters (the parity scenarios import it).
#
# The semantics follow CircuitPython's busio.I2C documentation:
# - try_lock() returns True when it took the lock, False when the lock is held (by anyone,
#   the caller included); unlock() releases it.
# - every transfer and scan() without the lock raises RuntimeError ("Function requires lock").
# - writeto(address, buffer, *, start=0, end=None), readfrom_into(address, buffer, *, start=0,
#   end=None), writeto_then_readfrom(address, out_buffer, in_buffer, *, out_start=0,
#   out_end=None, in_start=0, in_end=None): buffer[start:end] goes out / comes in.
#   writeto_then_readfrom is one transaction with a repeated START.
# - a missing ACK raises OSError (errno 19 here, as the simulated bus raises it).
# - after deinit() every method raises ValueError ("Object has been deinitialized").
#
# Another task holding the lock: hold(polls) makes the next `polls` try_lock() calls fail (as if
# another user of the bus held it and released it after that many attempts); hold(-1) holds it
# for ever, until release().
#
# Mapping onto the machine.I2C-shaped bus, with the same transactions and the same time on
# the wire (host_sim.bus charges the same bytes and START/STOP conditions): a one-byte write
# then read is readfrom_mem_into(addr, out[0], in); a write is writeto_mem(addr, out[0],
# out[1:]); a bare read is readfrom_into. Reads with the default in_start/in_end and a one-byte
# out slice allocate nothing here.


class FakeBusioI2C:
    def __init__(self, bus):
        self.bus = bus
        self.locked = False          # held by the caller of try_lock()
        self.other = 0               # try_lock() polls still refused (another task); -1: for ever
        self.try_locks = 0           # try_lock() calls
        self.refused = 0             # of them refused
        self.deinited = False

    # --- the other task ---------------------------------------------------------------
    def hold(self, polls):
        self.other = polls

    def release(self):
        self.other = 0

    # --- locking ----------------------------------------------------------------------
    def _check(self, need_lock=True):
        if self.deinited:
            raise ValueError("Object has been deinitialized and can no longer be used. "
                             "Create a new object.")
        if need_lock and not self.locked:
            raise RuntimeError("Function requires lock")

    def try_lock(self):
        self._check(False)
        self.try_locks += 1
        if self.locked or self.other:
            if self.other > 0:
                self.other -= 1
            self.refused += 1
            return False
        self.locked = True
        return True

    def unlock(self):
        self._check(False)
        self.locked = False

    def deinit(self):
        self.locked = False
        self.deinited = True

    # --- transfers --------------------------------------------------------------------
    def scan(self):
        self._check()
        return list(self.bus.scan())

    def writeto(self, address, buffer, *, start=0, end=None):
        self._check()
        mv = memoryview(buffer)[start:len(buffer) if end is None else end]
        if len(mv) == 0:
            raise ValueError("writeto: empty buffer")
        self.bus.writeto_mem(address, mv[0], mv[1:])

    def readfrom_into(self, address, buffer, *, start=0, end=None):
        self._check()
        if start == 0 and end is None:
            self.bus.readfrom_into(address, buffer)
        else:
            self.bus.readfrom_into(address, memoryview(buffer)[start:end])

    def writeto_then_readfrom(self, address, out_buffer, in_buffer, *, out_start=0,
                              out_end=None, in_start=0, in_end=None):
        self._check()
        if out_start == 0 and out_end is None and len(out_buffer) == 1:
            reg = out_buffer[0]
        else:
            out = memoryview(out_buffer)[out_start:len(out_buffer) if out_end is None else out_end]
            if len(out) != 1:
                raise ValueError("this fake sends one register byte, got %d" % len(out))
            reg = out[0]
        if in_start == 0 and in_end is None:
            self.bus.readfrom_mem_into(address, reg, in_buffer)
        else:
            self.bus.readfrom_mem_into(address, reg, memoryview(in_buffer)[in_start:in_end])
