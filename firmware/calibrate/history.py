# A short history of accepted calibrations on the board, and the check of each new one against
# it: a jump outside the spread its history shows reveals changed hardware (a magnet fixed near
# the sensor, another chip, a new mounting) before it costs a wrong heading.
#
#     from firmware.calibrate.history import History
#     h = History(store)                   # files <store.prefix>_h0.cal .. _h7.cal
#     jump = h.check(cal, current)         # None, or (parameter, value, low, high)
#     h.record(cal, FLAG_ACCEPTED, date_s) # the entry's count
#
# Imported at the first accepted fit, never on a board that only reads headings
# (tests/test_layout.py). The entries, the ring of files and the limits per parameter:
# docs/design.md (module notes, history).
import struct

from firmware.calibration import MINMAX, PAYLOAD_SIZE, Calibration
from firmware.compat import const
from firmware.errors import StoreError
from firmware.fixedpoint import isqrt
from firmware.store_slots import decode_record, encode_record

ENTRIES = const(8)          # entries in the ring
MIN_STATS = const(4)        # reference values before mean +- _K_SIGMA sigma replaces the wide limits
_K_SIGMA = const(4)        # sigmas of half-width: 4 sigma of a normal spread is 1 in 16000

FLAG_ACCEPTED = const(1)    # made current
FLAG_PENDING = const(2)     # a jump kept as evidence, not made current
FLAG_BASELINE = const(4)    # an accepted hardware change: older entries describe other hardware

NAMES = ("hard_iron_x", "hard_iron_y", "hard_iron_z", "field", "soft_iron_xx",
         "soft_iron_yy", "soft_iron_zz", "fit_error")
# Half-widths: (floor, wide), V and B in 1/1000 of the reference B, soft iron in Q15 (1/32768),
# fit error in 0.01 %. A floor keeps a history of near-identical fits from flagging noise;
# the wide limit, used before MIN_STATS entries, flags only a gross jump (a quarter of the
# field in V: a magnet of 12 uT at 50 uT; a fifth in gain).
_HALF = ((30, 250), (30, 250), (30, 250), (30, 200), (983, 6554), (983, 6554), (983, 6554),
         (200, 400))
_FIELD_PARAMS = const(4)    # NAMES[0:4] scale with B
_SOFT_FIRST = const(4)
_FIT_ERROR = const(7)

_TAIL = "<IBBH"             # date, flags, reserved, reserved
_ENTRY_SIZE = const(54)    # PAYLOAD_SIZE + 8
_READ_MAX = const(32 + 54 + 4 + 1)  # one byte more than an entry's record


def _value(cal, i):
    if i < 3:
        return cal.offset[i]
    if i == 3:
        return cal.field
    if i < _FIT_ERROR:
        return cal.invw[(i - _SOFT_FIRST) * 4]  # 0, 4, 8: the diagonal
    return cal.fit_error


def _comparable(i, new, old):
    if i < _FIELD_PARAMS:
        return (new.model == MINMAX) == (old.model == MINMAX)
    if i < _FIT_ERROR:
        return new.model in (7, 10) and old.model == new.model
    return old.model == new.model


def limits(i, values, field):
    """(low, high) of parameter NAMES[i] for a reference list of values; field: the
    reference B in counts (scales the half-widths of V and B)."""
    n = len(values)
    s = 0
    for v in values:
        s += v
    mean = (2 * s + n) // (2 * n)  # rounded
    floor, wide = _HALF[i]
    if i < _FIELD_PARAMS:
        floor = floor * field // 1000
        wide = wide * field // 1000
    if n < MIN_STATS:
        half = wide
    else:
        q = 0
        for v in values:
            q += (v - mean) * (v - mean)
        half = _K_SIGMA * isqrt(q // n)
        if half < floor:
            half = floor
    return mean - half, mean + half


def jump(cal, refs):
    """The parameter of cal furthest outside the limits its reference calibrations give, as
    (name, value, low, high), or None when every parameter is inside (or has no reference)."""
    worst = None
    excess = 0
    fs = [r.field for r in refs if _comparable(0, cal, r)]
    field = sum(fs) // len(fs) if fs else cal.field
    cross = 0  # the larger fit error where models differ, 0.01 %
    for r in refs:
        if r.model != cal.model and _comparable(0, cal, r):
            for fe in (r.fit_error, cal.fit_error):
                if fe > cross:
                    cross = fe
    for i in range(len(NAMES)):
        values = [_value(r, i) for r in refs if _comparable(i, cal, r)]
        if not values:
            continue
        lo, hi = limits(i, values, field)
        if i < _FIELD_PARAMS:
            lo -= cross * field // 10000
            hi += cross * field // 10000
        v = _value(cal, i)
        if i == _FIT_ERROR:
            lo = 0  # a fit better than its history is no hardware change
        half = (hi - lo) // 2 if (hi - lo) > 1 else 1
        out = v - hi if v > hi else (lo - v if v < lo else 0)
        if out and out * 1000 // half >= excess:
            excess = out * 1000 // half
            worst = (NAMES[i], v, lo, hi)
    return worst


class History:
    """The ring of ENTRIES entries next to `store`'s slots (see docs/design.md, module notes)."""
    # After read() or check(): .entries, a list of (count, flags, date_s, Calibration) oldest
    # first; .skipped, the number of files that hold no usable entry (missing, torn, another
    # sensor, unreadable). .own: the count of the entry this session wrote (None before).

    def __init__(self, store, entries=ENTRIES):
        self.store = store
        self.n = entries
        self.entries = []
        self.skipped = 0
        self.newest = None
        self.own = None
        self.own_flags = 0

    def path(self, count):
        return "%s_h%d.cal" % (self.store.prefix, count % self.n)

    def _entry(self, k):
        st = self.store
        try:
            f = st.fs.open(self.path(k), "rb")
        except OSError:
            return None  # missing or unreadable: no entry
        try:
            data = f.read(_READ_MAX)
        except OSError:
            return None
        finally:
            f.close()
        try:
            count, p = decode_record(data, st.sensor, st.range_code)
        except StoreError:
            return None
        if len(p) != _ENTRY_SIZE or count % self.n != k:
            return None
        date, flags, r1, r2 = struct.unpack(_TAIL, p[PAYLOAD_SIZE:])
        if r1 or r2 or not flags or flags & ~(FLAG_ACCEPTED | FLAG_PENDING | FLAG_BASELINE):
            return None
        try:
            cal = Calibration.from_bytes(p[:PAYLOAD_SIZE])
        except ValueError:
            return None
        return (count, flags, date, cal)

    def read(self):
        """Read every file of the ring; returns .entries (oldest first)."""
        got = []
        newest = None
        for k in range(self.n):
            e = self._entry(k)
            if e is None:
                continue
            got.append(e)
            if newest is None or ((e[0] - newest) & 0xFFFFFFFF) < 0x80000000:
                newest = e[0]
        self.skipped = self.n - len(got)
        # oldest first: the age below the newest, modulo 2**32 like the store's numbers
        got.sort(key=lambda e: -((newest - e[0]) & 0xFFFFFFFF))
        self.entries = got
        self.newest = newest
        return got

    def references(self):
        """The calibrations the limits come from: accepted entries since the newest baseline."""
        refs = []
        for _, flags, _, cal in self.entries:
            if flags & FLAG_BASELINE:
                refs = []
            if flags & FLAG_ACCEPTED:
                refs.append(cal)
        return refs

    def check(self, cal, current=None):
        """Read the ring and compare cal with it: None, or (parameter, value, low, high) of the
        parameter that jumped. With no reference entry the calibration in force (current)
        stands in (a board whose store predates its history)."""
        self.read()
        refs = self.references()
        if not refs and current is not None and current.model is not None:
            refs = [current]
        return jump(cal, refs)

    def record(self, cal, flags, date_s=0):
        """Write cal as an entry with `flags` (FLAG_*); returns its count. A refinement of the
        session's own entry of the same kind (accepted, or pending) replaces it. Raises
        OSError from the filesystem, StoreError('verify_failed') if it reads back different."""
        own = self.own
        if (own is not None and own == self.newest
                and (flags == FLAG_ACCEPTED and self.own_flags & FLAG_ACCEPTED
                     or flags == FLAG_PENDING and self.own_flags == FLAG_PENDING)):
            count = own
            flags = self.own_flags  # a refined baseline stays the baseline
        else:
            count = 0 if self.newest is None else (self.newest + 1) & 0xFFFFFFFF
        date_s = date_s if 0 <= date_s <= 0xFFFFFFFF else 0
        payload = cal.to_bytes() + struct.pack(_TAIL, date_s, flags, 0, 0)
        st = self.store
        rec = encode_record(payload, st.sensor, st.range_code, count)
        path = self.path(count)
        f = st.fs.open(path, "wb")
        try:
            f.write(rec)
        finally:
            f.close()
        self.newest = count
        self.own = count
        self.own_flags = flags
        f = st.fs.open(path, "rb")
        try:
            back = f.read(_READ_MAX)
        finally:
            f.close()
        if bytes(back) != rec:
            raise StoreError("verify_failed", "%s read back %d bytes of %d"
                             % (path, len(back), len(rec)))
        return count


# --- the history of a calibration's owner (a CompassApp's session, the calibration program):
# owner.store, owner.calibration (the one in force), owner._hist (None until the first use),
# owner.date_s (None, or a function giving the date in seconds), owner.history_errors and
# .history_reason (what went wrong last). Evidence only: neither raises.
def judge(owner, cal):
    """cal against the owner's history: None (in limits, or nothing to judge by) or
    (parameter, value, low, high) of the parameter that jumped."""
    try:
        if owner._hist is None:
            if owner.store is None or not hasattr(owner.store, "prefix"):
                return None
            owner._hist = History(owner.store)
        return owner._hist.check(cal, owner.calibration)
    except Exception as e:  # noqa: BLE001 - evidence only: never stop the loop for it
        failed(owner, e)
    return None


def keep(owner, cal, flags):
    """Record cal with `flags` in the owner's history."""
    try:
        owner._hist.record(cal, flags, owner.date_s() if owner.date_s is not None else 0)
    except Exception as e:  # noqa: BLE001 - as above
        failed(owner, e)


def failed(owner, e):
    owner.history_errors += 1
    owner.history_reason = "%s %s" % (type(e).__name__, e.args[0] if e.args else "")
