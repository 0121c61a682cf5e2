"""Power-safe storage of the calibration on the board's filesystem.

    store = CalStore(sensor=mag.KIND, range_code=mag.range_code)
    store.save(cal.to_bytes())                    # returns the record's sequence number
    cal = Calibration.from_bytes(store.load())    # or StoreError with .reason
"""
# The payload is Calibration.to_bytes()'s; this module owns the record around it and the
# slots. The record's layout, the power-safety argument and faulty slots: docs/design.md
# (module notes, store). The format and slot code are firmware/store_slots.py, loaded for each
# operation: this module is the small front a board keeps.
import os


class _OsFs:
    """The default filesystem: builtin open and os.remove (MicroPython and CPython)."""

    @staticmethod
    def open(path, mode):
        return open(path, mode)

    @staticmethod
    def remove(path):
        os.remove(path)


class CalStore:
    """Power-safe, CRC-protected calibration record in `directory` (see the module doc)."""
    # fs: object with open(path, mode) -> file (read/write/close) and remove(path); default the
    # real filesystem. validate: None, or a function of the payload that raises ValueError
    # when the payload means nothing valid (the app sets Calibration.from_bytes). After load():
    # .seq and .path of the record returned, .last_skipped the list of (path, reason) for the
    # slot(s) not used (the spare only when it holds something). .prefix: the path of the
    # slot files without their '_a.cal' ending (firmware.calibrate.history names its files after it,
    # and firmware.mountnote the mounting check's verdict).

    def __init__(self, directory="/", name="ecompass", sensor="qmc5883l", range_code=0, fs=None,
                 validate=None):
        from firmware.store_slots import check_sensor
        check_sensor(sensor, range_code)
        self.sensor = sensor
        self.range_code = range_code
        self.fs = fs if fs is not None else _OsFs
        self.validate = validate
        if directory in ("", "/"):
            prefix = directory
        else:
            prefix = directory.rstrip("/") + "/"
        self.prefix = prefix + name
        self.paths = (self.prefix + "_a.cal", self.prefix + "_b.cal", self.prefix + "_c.cal")
        self.seq = None
        self.path = None
        self.last_skipped = []
        self._write_failed = [False, False, False]
        self._written = None  # the sequence number of this object's last save

    def load(self):
        """The newest usable payload (bytes); StoreError(reason) if no slot has one."""
        from firmware.store_slots import load
        return load(self)

    def save(self, payload):
        """Store payload as the newest record, power-safely; returns its sequence number."""
        # Raises ValueError for an oversized payload, OSError from the filesystem (full, read
        # only, EIO while writing), StoreError('verify_failed') if the record read back is not
        # the one written. A slot that cannot be opened is passed over for the next one; when
        # none opens, the last OSError is raised (StoreError('no_slot') if there was none to
        # try: no slot but the current record's).
        from firmware.store_slots import save
        return save(self, payload)

    def erase(self):
        """Remove every slot, the current record's last, so a cut in between leaves it."""
        from firmware.store_slots import erase
        erase(self)
