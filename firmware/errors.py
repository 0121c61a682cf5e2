"""The firmware's exceptions, in one place."""
# Policy: bad data is never returned as good data. Each class says what raised it, what it
# carries, and what the caller should do. Hardware errors subclass OSError, as MicroPython's own
# bus errors do, so ``except OSError`` still catches everything from the bus.
#
# SensorNotFound(OSError)   detect() or a driver's probe found no chip, or the wrong chip ID.
#                           Carries ``.address`` (int or None), ``.tried`` (addresses probed) and
#                           ``.found`` (addresses that answered a scan). Caller: check wiring,
#                           power and the address; nothing can be read.
# BusError(OSError)         an I2C transaction failed (NACK, EIO, timeout on the bus).
#                           Carries ``.address``, ``.register`` and ``.errno`` (19 ENODEV or
#                           5 EIO, as the port reports). Caller: retry later; keep the last good
#                           heading meanwhile.
# DataReadyTimeout(OSError) the chip's data-ready bit did not set within the driver's bounded
#                           wait. Carries ``.address`` and ``.waited_us``. Caller: retry; if it
#                           persists, re-initialise the driver (the chip may be in standby).
# SensorOverflow(ValueError) the chip flagged the sample as out of range (QMC5883L OVL, HMC5883L
#                           -4096). Carries ``.address`` and ``.raw`` (the raw axis values).
#                           Caller: drop the sample (a magnet is too close or the range too small).
# CalibrationRejected(Exception) a new calibration failed an acceptance check. Carries
#                           ``.reason`` (one of the REASON_* names in firmware.calibrate.acceptance) and
#                           ``.detail`` (a human-readable string with the numbers). Caller: keep
#                           the current calibration; show the reason to the user.
# StoreError(Exception)     a stored calibration record cannot be used. Carries ``.reason``, one
#                           of firmware.store's: missing, truncated, bad_length, bad_magic,
#                           bad_crc, unknown_version, other_sensor, other_range, io_error (the
#                           slot cannot be read), bad_payload (intact, but its payload means
#                           nothing valid), verify_failed (a save read back different bytes),
#                           no_slot (a save found no slot but the current record's). Caller: keep running uncalibrated
#                           or with the other slot; never use the record.


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
