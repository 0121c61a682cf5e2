"""The firmware's exceptions, in one place."""
# Policy: bad data is never returned as good data. Hardware errors subclass OSError, as
# MicroPython's own bus errors do, so ``except OSError`` still catches everything from the bus.
# What raises each class, what it carries and what the caller should do: docs/api.md (errors).
class SensorNotFound(OSError):
    def __init__(self, msg, address=None, tried=(), found=()):
        super().__init__(msg)
        self.errno = None  # not a bus errno (MicroPython would otherwise return the message)
        self.address = address
        self.tried = tuple(tried)
        self.found = tuple(found)


class BusError(OSError):
    def __init__(self, msg, address=None, register=None, errno=None):
        super().__init__(msg)
        self.address = address
        self.register = register
        self.errno = errno


class DataReadyTimeout(OSError):
    def __init__(self, msg, address=None, waited_us=0):
        super().__init__(msg)
        self.errno = None  # not a bus errno (MicroPython would otherwise return the message)
        self.address = address
        self.waited_us = waited_us


class SensorOverflow(ValueError):
    def __init__(self, msg, address=None, raw=None):
        super().__init__(msg)
        self.address = address
        self.raw = raw


class Refusal(Exception):
    """Base of the refusals that carry a named .reason and a human-readable .detail."""

    def __init__(self, reason, detail=""):
        super().__init__(reason, detail)
        self.reason = reason
        self.detail = detail

    def __str__(self):
        return "%s: %s" % (self.reason, self.detail) if self.detail else self.reason


class CalibrationRejected(Refusal):
    pass


class StoreError(Refusal):
    pass
