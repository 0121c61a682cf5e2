"""Power-safe storage of the calibration on the board's filesystem.

    store = CalStore(sensor=mag.KIND, range_code=mag.range_code)
    store.save(cal.to_bytes())                    # returns the record's sequence number
    cal = Calibration.from_bytes(store.load())    # or StoreError with .reason
"""
# The payload (model, V, InvW, B, fit error) is opaque here: Calibration.to_bytes() owns it.
# This module owns the record around it (little-endian):
#
#     offset size
#      0     4   magic b'eCAL'
#      4     1   format version (1)
#      5     1   header length (32 in version 1)
#      6     2   payload length
#      8    16   sensor kind, ASCII, NUL-padded ('qmc5883l', 'hmc5883l', ...)
#     24     1   range code of the sensor (the driver's .range_code)
#     25     3   reserved, 0
#     28     4   sequence number (newest wins)
#     32     n   payload
#     32+n   4   CRC-32 (IEEE, as binascii.crc32 / zlib.crc32) of every byte before it
#
# Bytes 0-7, the sequence number at 28-31 (when the header has 32 bytes or more) and the CRC
# trailer are the same in every version, so a record of a newer version is still recognised
# intact and refused as 'unknown_version', not as garbage, and save() numbers past it.
#
# Power safety: two slot files, <name>_a.cal and <name>_b.cal, and a spare, <name>_c.cal.
# save() writes the whole new record, with a higher sequence number, into a slot that does NOT
# hold the record load() would return now (the other of a and b; the spare only when that one
# cannot be read or written), then reads it back. Whatever a power cut leaves in that slot (nothing, a
# prefix, a torn tail of zeros or garbage, the old bytes), its CRC fails or its sequence number
# is older, so load() returns the previous calibration; once the record is complete, load()
# returns the new one. The scheme relies only on (1) a write to one file never altering
# another file's committed bytes, and (2) CRC-32 catching a torn record (it detects every error
# burst up to 32 bits, and any other corruption with probability 1 - 2**-32). It does not rely
# on rename being atomic (true on LittleFS, not on FAT), nor on a write being atomic (true of
# neither: LittleFS commits a file at close/sync, FAT writes in place).
#
# Faulty slots. A slot that cannot be read (EIO, a directory where the file should be) is
# skipped like a torn one (reason io_error): load() returns the newest valid record of the
# others, and save() writes to a healthy slot - the spare stands in for a or b, so a record
# is still never written over the current one. A slot whose write or read-back failed is tried
# last by later saves of the same session. `validate` (set by the app to
# Calibration.from_bytes) judges what an intact payload means: a record it refuses with
# ValueError is skipped as bad_payload, so a record with an impossible field or of an unknown
# payload version never hides an intact older one. save() numbers past every unreadable slot
# too (one more per such slot: records are numbered one past the newest visible one), so a
# slot that becomes readable again cannot win with an older record - unless every slot was
# unreadable when the store object was made, the one case where no number is known.
#
# Refusals carry a reason (StoreError.reason), one of the REASON_* names of firmware/store_slots.py
# (which holds the format and the slot code; this module is the small front a board keeps).


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
