# The calibration store's record format and its slot scheme (firmware/store.py's CalStore
# describes both): encode and decode a record, CRC-32, and the load / save / erase of the three
# slot files. CalStore imports this module for each operation; a running app drops it again
# (firmware.compat.drop), so a board that is not saving holds only the small CalStore front.
#
#     from firmware.store_slots import encode_record, decode_record, crc32
#     record = encode_record(payload, "qmc5883l", range_code, seq)
#     seq, payload = decode_record(record, "qmc5883l", range_code)   # or StoreError(reason)
import struct

from firmware.errors import StoreError

try:
    from binascii import crc32 as _crc32_builtin
except ImportError:  # a port built without binascii, or without its crc32
    _crc32_builtin = None

from firmware.compat import const

REASON_MISSING = "missing"                  # no file in the slot
REASON_TRUNCATED = "truncated"              # shorter than its header says (a cut write)
REASON_BAD_LENGTH = "bad_length"            # longer than its header says
REASON_BAD_MAGIC = "bad_magic"              # not a calibration record at all
REASON_BAD_CRC = "bad_crc"                  # torn or corrupted record
REASON_UNKNOWN_VERSION = "unknown_version"  # an intact record of a format this code cannot read
REASON_OTHER_SENSOR = "other_sensor"        # intact, but made for another magnetometer
REASON_OTHER_RANGE = "other_range"          # intact, but made at another range setting
REASON_OLDER = "older"                      # load(): intact and usable, but the other is newer
REASON_VERIFY_FAILED = "verify_failed"      # save(): the record read back differs
REASON_IO_ERROR = "io_error"                # the slot cannot be read (EIO, a directory, ...)
REASON_BAD_PAYLOAD = "bad_payload"          # intact, but validate() refused the payload
REASON_NO_SLOT = "no_slot"                  # save(): no slot but the current one took it

MAGIC = b"eCAL"
_VERSION = const(1)
_HEADER_LEN = const(32)
MAX_PAYLOAD = const(4096)      # bytes; a calibration is about a hundred
_HEADER = "<4sBBH16sBBHI"      # magic, version, header len, payload len, sensor, range, 0, 0, seq
_SENSOR_LEN = const(16)
# errno of a missing file: 2 (ENOENT) on CPython and most ports, 44 on the WebAssembly port
# (Emscripten's numbering)
_ENOENT = (2, 44)

# Why load() failed when no slot is usable: the most telling reason of the slots.
_REASON_RANK = (REASON_OTHER_SENSOR, REASON_OTHER_RANGE, REASON_UNKNOWN_VERSION,
                REASON_BAD_PAYLOAD, REASON_IO_ERROR, REASON_BAD_CRC, REASON_BAD_LENGTH, REASON_TRUNCATED, REASON_BAD_MAGIC,
                REASON_MISSING)


def _make_crc_table():
    # CRC-32/IEEE, reflected polynomial 0xEDB88320, one entry per nibble (16 ints).
    t = []
    for n in range(16):
        c = n
        for _ in range(4):
            c = (c >> 1) ^ 0xEDB88320 if c & 1 else c >> 1
        t.append(c)
    return tuple(t)


_CRC_NIBBLE = _make_crc_table()


def crc32_int(data, crc=0):
    """CRC-32 (IEEE) in integers only, the same value as binascii.crc32(data, crc)."""
    crc ^= 0xFFFFFFFF
    t = _CRC_NIBBLE
    for b in data:
        crc ^= b
        crc = (crc >> 4) ^ t[crc & 15]
        crc = (crc >> 4) ^ t[crc & 15]
    return crc ^ 0xFFFFFFFF


def crc32(data):
    """CRC-32 of data: binascii's when the port has it, else crc32_int()."""
    if _crc32_builtin is not None:
        return _crc32_builtin(data) & 0xFFFFFFFF
    return crc32_int(data)


def _sensor_field(sensor):
    b = sensor.encode() if isinstance(sensor, str) else bytes(sensor)
    if not 0 < len(b) <= _SENSOR_LEN or b"\x00" in b:
        raise ValueError("sensor kind %r must be 1..%d bytes without NUL" % (sensor, _SENSOR_LEN))
    return b + bytes(_SENSOR_LEN - len(b))


def check_sensor(sensor, range_code):
    """ValueError unless `sensor` is a kind name for a record and range_code is 0..255."""
    _sensor_field(sensor)
    if not 0 <= range_code <= 255:
        raise ValueError("range code %d not in 0..255" % range_code)


def encode_record(payload, sensor, range_code, seq):
    """The record bytes for payload (bytes) made with sensor kind / range code, number seq."""
    if len(payload) > MAX_PAYLOAD:
        raise ValueError("payload of %d bytes exceeds %d" % (len(payload), MAX_PAYLOAD))
    if not 0 <= range_code <= 255:
        raise ValueError("range code %d not in 0..255" % range_code)
    head = struct.pack(_HEADER, MAGIC, _VERSION, _HEADER_LEN, len(payload), _sensor_field(sensor),
                       range_code, 0, 0, seq & 0xFFFFFFFF)
    body = head + bytes(payload)
    return body + struct.pack("<I", crc32(body))


def decode_record(data, sensor, range_code):
    """(seq, payload) of a record, or StoreError(reason) naming what is wrong with it.

    Checks run from framing to meaning, so a torn write is reported as such (truncated,
    bad_crc) and only an intact record can be refused as another version, sensor or range.
    """
    n = len(data)
    if bytes(data[:4]) != MAGIC[:n if n < 4 else 4]:
        raise StoreError(REASON_BAD_MAGIC, "starts %s, not %s" % (bytes(data[:4]), MAGIC))
    if n < 8:
        raise StoreError(REASON_TRUNCATED, "%d bytes, header needs 8" % n)
    hlen = data[5]
    plen = data[6] | (data[7] << 8)
    total = hlen + plen + 4
    if n < total:
        raise StoreError(REASON_TRUNCATED, "%d bytes of %d" % (n, total))
    if n > total:
        raise StoreError(REASON_BAD_LENGTH, "%d bytes, header says %d" % (n, total))
    want = struct.unpack("<I", bytes(data[total - 4:total]))[0]
    got = crc32(bytes(data[:total - 4]))
    if got != want:
        raise StoreError(REASON_BAD_CRC, "crc 0x%08x, stored 0x%08x" % (got, want))
    if data[4] != _VERSION or hlen != _HEADER_LEN:
        raise StoreError(REASON_UNKNOWN_VERSION, "format %d (header %d bytes), this code reads %d"
                         % (data[4], hlen, _VERSION))
    _, _, _, _, kind, rng, r1, r2, seq = struct.unpack(_HEADER, bytes(data[:_HEADER_LEN]))
    if r1 or r2:
        raise StoreError(REASON_UNKNOWN_VERSION, "reserved bytes set: %d %d" % (r1, r2))
    if kind != _sensor_field(sensor):
        raise StoreError(REASON_OTHER_SENSOR, "made for %s, this sensor is %s"
                         % (kind.rstrip(b"\x00"), sensor))
    if rng != range_code:
        raise StoreError(REASON_OTHER_RANGE, "made at range code %d, sensor at %d"
                         % (rng, range_code))
    return seq, bytes(data[_HEADER_LEN:_HEADER_LEN + plen])


def _newer(a, b):
    # Sequence numbers compare modulo 2**32 (RFC 1982 style), so wrap-around is harmless.
    d = (a - b) & 0xFFFFFFFF
    return 0 < d < 0x80000000


_SPARE = const(2)  # index of the spare slot in CalStore.paths


def _read(st, path):
    try:
        f = st.fs.open(path, "rb")
    except OSError as e:
        if e.args and e.args[0] in _ENOENT:
            return None
        raise
    try:
        # The header's first 8 bytes say how long the record is: read that much and one byte
        # more (a longer file is bad_length), never more than one byte past the largest
        # record. A fixed read of the largest would ask for 4 KB in one piece, which a
        # board's fragmented heap at boot may not have for a record of about a hundred bytes.
        head = f.read(8)
        if len(head) < 8 or head[:4] != MAGIC:
            return head  # decode_record says what is wrong from these alone
        total = head[5] + (head[6] | (head[7] << 8)) + 4
        cap = _HEADER_LEN + MAX_PAYLOAD + 5
        return head + f.read((total + 1 if total + 1 < cap else cap) - 8)
    finally:
        f.close()

def _inspect(st, path):
    # -> (seq or None, payload or None, reason or None, intact seq or None)
    try:
        data = _read(st, path)
    except OSError:
        return None, None, REASON_IO_ERROR, None
    if data is None:
        return None, None, REASON_MISSING, None
    try:
        seq, payload = decode_record(data, st.sensor, st.range_code)
    except StoreError as e:
        intact = None
        if (e.reason in (REASON_OTHER_SENSOR, REASON_OTHER_RANGE, REASON_UNKNOWN_VERSION)
                and data[5] >= _HEADER_LEN):
            intact = struct.unpack("<I", bytes(data[28:32]))[0]
        return None, None, e.reason, intact
    if st.validate is not None:
        try:
            st.validate(payload)
        except ValueError:
            return None, None, REASON_BAD_PAYLOAD, seq
    return seq, payload, None, seq

def _scan(st):
    return [_inspect(st, p) for p in st.paths]

def _current(slots):
    best = -1
    for i in range(len(slots)):
        seq = slots[i][0]
        if seq is not None and (best < 0 or _newer(seq, slots[best][0])):
            best = i
    return best

def load(st):
    """CalStore.load(): the newest usable payload (bytes); StoreError(reason) if none."""
    slots = _scan(st)
    best = _current(slots)
    st.last_skipped = []
    for i in range(len(slots)):
        if i != best and not (i == _SPARE and slots[i][2] == REASON_MISSING):
            reason = slots[i][2] if slots[i][2] is not None else REASON_OLDER
            st.last_skipped.append((st.paths[i], reason))
    if best < 0:
        st.seq = None
        st.path = None
        reasons = [s[2] for s in slots]
        for r in _REASON_RANK:
            if r in reasons:
                break
        raise StoreError(r, "; ".join("%s: %s" % (p, q) for p, q in st.last_skipped))
    st.seq = slots[best][0]
    st.path = st.paths[best]
    return slots[best][1]

def _targets(st, slots, best):
    # The slots save() may write, best first: never the current record's; a slot that
    # failed (unreadable, or a write this session) last; the spare after a and b; with no
    # current record, spare an intact one (another sensor, range or version), the oldest
    # of them going first.
    order = []
    for i in range(len(slots)):
        if i == best:
            continue
        rank = 0
        if slots[i][2] == REASON_IO_ERROR or st._write_failed[i]:
            rank += 4
        if i == _SPARE:
            rank += 2
        if best < 0 and slots[i][3] is not None:
            rank += 1
        order.append((rank * 4 + i, i))  # the index breaks ties: MicroPython's sort
    order.sort(key=lambda r: r[0])         # is not stable
    for j in range(len(order) - 1):  # equal ranks of intact records: the older first
        (r1, i1), (r2, i2) = order[j], order[j + 1]
        if r1 >> 2 == r2 >> 2 and r1 & 4 and _newer(slots[i1][3], slots[i2][3]):
            order[j], order[j + 1] = order[j + 1], order[j]
    return [i for _, i in order]


def save(st, payload):
    """CalStore.save(payload) (firmware/store.py says what it returns and raises)."""
    slots = _scan(st)
    best = _current(slots)
    top = None
    unread = 0
    for s in slots:
        if s[3] is not None and (top is None or _newer(s[3], top)):
            top = s[3]
        if s[2] == REASON_IO_ERROR:
            unread += 1
    if top is None:
        top = 0
    # An unreadable slot may hold the newest record, numbered at most one past the
    # others per such slot: number past that too, so it cannot win if it comes back -
    # unless this object wrote the newest visible record, already numbered past them.
    if top != st._written:
        top += unread
    seq = (top + 1) & 0xFFFFFFFF
    record = encode_record(payload, st.sensor, st.range_code, seq)
    err = None
    for target in _targets(st, slots, best):
        path = st.paths[target]
        try:
            f = st.fs.open(path, "wb")
        except OSError as e:  # a directory in its place, a read-only file: try the next
            st._write_failed[target] = True
            err = e
            continue
        st._write_failed[target] = True  # until the record is read back intact
        try:
            f.write(record)
        finally:
            f.close()
        back = _read(st, path)
        if back is None or bytes(back) != record:
            raise StoreError(REASON_VERIFY_FAILED, "%s read back %s bytes of %d"
                             % (path, "no" if back is None else len(back), len(record)))
        st._write_failed[target] = False
        st._written = seq
        return seq
    if err is not None:
        raise err  # every spare slot refused: the filesystem's own error says why
    raise StoreError(REASON_NO_SLOT, "only the current record's slot is left")

def erase(st):
    """Remove every slot, the current record's last, so a cut in between leaves it."""
    slots = _scan(st)
    best = _current(slots)
    for i in [j for j in range(len(slots)) if j != best] + ([best] if best >= 0 else []):
        try:
            st.fs.remove(st.paths[i])
        except OSError as e:
            if not (e.args and e.args[0] in _ENOENT):
                raise
    st.seq = None
    st.path = None
