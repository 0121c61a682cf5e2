"""The Earth's field where the board is: the World Magnetic Model 2025, integer-only."""
#     from firmware.field.wmm import FieldModel, decimal_year_e3
#     wmm = FieldModel()                       # opens wmm2025.bin next to this module
#     decl_cdeg, incl_cdeg, field_nt, status = wmm.at(-339000000, 1512000000, decimal_year_e3(2026, 3, 1))
#
# Units, the statuses, the errors and how a query interpolates the table: docs/design.md
# (module notes, wmm); the table format and the measured errors: docs/field_model.md. The file
# stays open (close() or `with` releases it); a query allocates its result tuple.
try:
    from binascii import crc32 as _crc32
except ImportError:  # a port without binascii.crc32: firmware.store_slots', imported when needed
    _crc32 = None

from firmware.compat import const
from firmware.errors import Refusal
from firmware.fixedpoint import bit_length, isqrt
from firmware.trig import atan2, kang_to_cdeg

STATUS_OK = "ok"
STATUS_NO_DATE = "no date"
STATUS_CAUTION = "caution zone"
STATUS_BLACKOUT = "blackout zone"
STATUS_OUTSIDE = "outside model validity"

REASON_MISSING = "missing"
REASON_TRUNCATED = "truncated"
REASON_BAD_MAGIC = "bad_magic"
REASON_UNKNOWN_VERSION = "unknown_version"
REASON_BAD_HEADER = "bad_header"
REASON_BAD_CRC = "bad_crc"

TABLE_NAME = "wmm2025.bin"
_HEADER = const(32)  # bytes before the first record (desktop/wmm.py: file layout)
_RECORD = const(12)  # X0 Y0 Z0 SX SY SZ, int16 each
_MAIN_NT = const(4)  # nT per count of X0, Y0, Z0
_SV_PER_NT = const(8)  # counts per nT/year of SX, SY, SZ
_SV_DIV = const(16000)  # dt (1e-3 yr) * SV (1/8 nT/yr) is nT * 8000: / 16000 gives 2 nT units
_ONE = const(4096)  # Q12: interpolation weights and the fraction of a cell
_LAT_U4 = const(900000)  # 90 deg in 1e-4 deg, the grid's coordinate unit
_LON_U4 = const(1800000)
_TURN_U4 = const(3600000)
_LAT_E7 = const(900000000)  # 90 deg in 1e-7 deg (180 and 360 deg are long ints on a 32-bit
# board: the header check divides by them once, and lon_e7 is checked in 1e-4 deg)
_BLACKOUT_NT = const(2000)  # WMM2025 report: H below 2000 nT, compasses unreliable
_CAUTION_NT = const(6000)  # WMM2025 report: H below 6000 nT, compass accuracy degraded
_NORM_BITS = const(14)  # atan2 and isqrt inputs: |v| < 2**14 keeps v*v + w*w below 2**30

# days before each month in a common year, for decimal_year_e3()
_CUM_DAYS = (0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334)


class FieldTableError(Refusal):
    """The field-model table cannot be used: .reason (a REASON_* name) and .detail."""


def _check_int(v, name, unit):
    if type(v) is not int:
        raise TypeError("%s must be an int in %s, got %s" % (name, unit, type(v).__name__))


def _leap(year):
    return year % 4 == 0 and (year % 100 != 0 or year % 400 == 0)


def decimal_year_e3(year, month, day):
    """Calendar date -> decimal year * 1000, as WMM counts it: year + (day of year - 1) / days
    in the year, rounded to the nearest thousandth (2026-07-02 -> 2026499)."""
    _check_int(year, "year", "years")
    _check_int(month, "month", "1..12")
    _check_int(day, "day", "days")
    if not 1 <= month <= 12:
        raise ValueError("month %d outside 1..12" % month)
    leap = _leap(year)
    last = (31, 29 if leap else 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31)[month - 1]
    if not 1 <= day <= last:
        raise ValueError("day %d outside 1..%d for month %d" % (day, last, month))
    days = 366 if leap else 365
    doy0 = _CUM_DAYS[month - 1] + (1 if leap and month > 2 else 0) + day - 1
    return year * 1000 + (doy0 * 2000 + days) // (2 * days)


def _i16(b, k):
    v = b[k] | (b[k + 1] << 8)
    return v - 0x10000 if v & 0x8000 else v


def _u16(b, k):
    return b[k] | (b[k + 1] << 8)


def _u32(b, k):
    return _u16(b, k) | (_u16(b, k + 2) << 16)


def _weights(t, w):
    """Cubic Lagrange weights through the nodes -1, 0, 1, 2 at t / 4096 (0 <= t <= 4096),
    Q12, written into w[0..3]; they sum to exactly 4096 and every product stays below 2**30:
      w-1 = -t(1-t)(2-t)/6   w0 = (1+t)(1-t)(2-t)/2   w1 = (1+t)t(2-t)/2   w2 = (1+t)t(t-1)/6"""
    u = 2 * _ONE - t  # 2 - t, in 4096..8192; each product is cut to 16 bits, rounded, first
    w[0] = -((((t * (_ONE - t) + 32) >> 6) * u + (3 << 18)) // (6 << 18))
    w[1] = (((_ONE * _ONE - t * t + 128) >> 8) * u + (1 << 16)) // (2 << 16)
    w[2] = ((((t + _ONE) * t + 256) >> 9) * u + (1 << 15)) // (2 << 15)
    w[3] = _ONE - w[0] - w[1] - w[2]


def _norm_shift(m):
    """Right shift that brings m (>= 0) below 2**14 (negative: a left shift)."""
    return bit_length(m) - _NORM_BITS


def _shift(v, s):
    return v >> s if s >= 0 else v << -s


class FieldModel:
    """The World Magnetic Model from a table file; see docs/design.md, module notes."""

    def __init__(self, path=None):
        if path is None:
            path = _default_path()
        self.path = path
        try:
            self._f = open(path, "rb")
        except OSError:
            raise FieldTableError(REASON_MISSING, "no field-model table at %s" % path)
        try:
            self._read_header()
        except Exception:
            self._f.close()
            raise
        self._buf = bytearray(_RECORD)
        self._wi = [0, 0, 0, 0]
        self._wj = [0, 0, 0, 0]
        self._i = self._j = 0
        self._x = self._y = self._z = self._h = 0
        self.declination_kang = self.inclination_kang = None
        self.declination_cdeg = self.inclination_cdeg = None
        self.field_nt = self.north_nt = self.east_nt = self.down_nt = self.horizontal_nt = None
        self.status = None

    def _bad(self, reason, what):
        raise FieldTableError(reason, "%s: %s" % (self.path, what))

    def _read_header(self):
        f = self._f
        h = bytearray(_HEADER)
        n = f.readinto(h)
        if n != _HEADER:
            self._bad(REASON_TRUNCATED, "%d header bytes, expected %d" % (n, _HEADER))
        if h[0:4] != b"WMMT":
            self._bad(REASON_BAD_MAGIC, "not a field-model table (magic %r)" % bytes(h[0:4]))
        if h[4] != 1:
            self._bad(REASON_UNKNOWN_VERSION, "version %d, this firmware reads 1" % h[4])
        self._pad = h[5]
        self._n_lat = _u16(h, 6)
        self._n_lon = _u16(h, 8)
        step_e7 = _u32(h, 10)
        self.epoch_e3 = _u32(h, 14)
        self.life_e3 = _u16(h, 18)
        if (h[20] != _MAIN_NT or h[21] != _SV_PER_NT or h[22] != _RECORD or step_e7 == 0
                or step_e7 % 1000 or 1800000000 % step_e7 or self._pad < 1
                or self._n_lat != 1800000000 // step_e7 + 1 + 2 * self._pad
                or self._n_lon != 3600000000 // step_e7 or self.life_e3 == 0):
            self._bad(REASON_BAD_HEADER, "inconsistent grid or units")
        self._step = step_e7 // 1000  # 1e-4 deg
        size = _HEADER + self._n_lat * self._n_lon * _RECORD
        end = f.seek(0, 2)
        if end != size:
            self._bad(REASON_TRUNCATED if end < size else REASON_BAD_HEADER,
                      "%d bytes, the header describes %d" % (end, size))
        got = self._crc(size)
        # compared as 16-bit halves: a CRC above 2**30 is a long int on a 32-bit board
        if got & 0xFFFF != _u16(h, 24) or got >> 16 != _u16(h, 26):
            self._bad(REASON_BAD_CRC, "crc 0x%08x, stored 0x%04x%04x"
                      % (got, _u16(h, 26), _u16(h, 24)))

    def _crc(self, size):
        f = self._f
        f.seek(_HEADER)
        chunk = bytearray(256)
        mv = memoryview(chunk)
        crc = 0
        left = size - _HEADER
        while left > 0:
            n = f.readinto(mv[:min(left, 256)])
            if not n:
                break
            if _crc32 is not None:
                crc = _crc32(mv[:n], crc)
            else:
                from firmware.store_slots import crc32_int
                crc = crc32_int(mv[:n], crc)
            left -= n
        return crc  # unsigned, as binascii.crc32 and crc32_int return it

    def close(self):
        self._f.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def at(self, lat_e7, lon_e7, year_e3=None):
        """(declination_cdeg, inclination_cdeg, field_nt, status) at a point and date."""
        _check_int(lat_e7, "lat_e7", "1e-7 deg")
        _check_int(lon_e7, "lon_e7", "1e-7 deg")
        if not -_LAT_E7 <= lat_e7 <= _LAT_E7:
            raise ValueError("lat_e7 %d outside -900000000..900000000 (1e-7 deg)" % lat_e7)
        lon_u4 = lon_e7 // 1000  # small even where lon_e7 itself is a long int (> 2**30)
        if lon_u4 < -_LON_U4 or lon_u4 > _LON_U4 or (lon_u4 == _LON_U4 and lon_e7 % 1000):
            raise ValueError("lon_e7 %d outside -1800000000..1800000000 (1e-7 deg)" % lon_e7)
        if year_e3 is None:
            dt = self.life_e3 >> 1
            status = STATUS_NO_DATE
        else:
            _check_int(year_e3, "year_e3", "decimal years * 1000")
            dt = year_e3 - self.epoch_e3
            if dt < 0 or dt > self.life_e3:
                return self._outside()
            status = STATUS_OK
        self._cell(lat_e7 // 1000, lon_u4)
        self._interpolate(dt)
        self._derive(status)
        return (self.declination_cdeg, self.inclination_cdeg, self.field_nt, self.status)

    def _outside(self):
        self.declination_kang = self.inclination_kang = None
        self.declination_cdeg = self.inclination_cdeg = None
        self.field_nt = self.north_nt = self.east_nt = self.down_nt = self.horizontal_nt = None
        self.status = STATUS_OUTSIDE
        return (None, None, None, STATUS_OUTSIDE)

    def _cell(self, lat_u4, lon_u4):
        """Grid row and column of the node south-west of the point, and the Q12 weights."""
        step = self._step
        p = lat_u4 + _LAT_U4 + self._pad * step
        i = p // step
        t = ((p - i * step) << 12) // step
        if i > self._n_lat - 3:  # exactly 90 deg north: the last row inside the pad
            i = self._n_lat - 3
            t = _ONE
        self._i = i
        _weights(t, self._wi)
        p = (lon_u4 + _LON_U4) % _TURN_U4
        j = p // step
        self._j = j
        _weights(((p - j * step) << 12) // step, self._wj)

    def _interpolate(self, dt):
        """X, Y, Z at the point and date, Q14 in units of 2 nT (8192 per nT): four rows of
        four nodes along longitude (sums < 1.25 * 2**12 * 2**15.1), each row cut to Q2, then
        the rows along latitude (< 1.25 * 2**12 * 2**17.4 < 2**30)."""
        x = y = z = 0
        n_lon = self._n_lon
        wj = self._wj
        for a in range(4):
            rx = ry = rz = 0
            base = (self._i - 1 + a) * n_lon
            for b in range(4):
                self._read(base + (self._j - 1 + b) % n_lon)
                w = wj[b]
                rx += w * self._node(0, dt)
                ry += w * self._node(2, dt)
                rz += w * self._node(4, dt)
            w = self._wi[a]
            x += w * (rx >> 10)
            y += w * (ry >> 10)
            z += w * (rz >> 10)
        self._x = x
        self._y = y
        self._z = z

    def _read(self, index):
        f = self._f
        f.seek(_HEADER + index * _RECORD)
        if f.readinto(self._buf) != _RECORD:
            raise FieldTableError(REASON_TRUNCATED, "%s: record %d unreadable" % (self.path, index))

    def _node(self, k, dt):
        """One component of the node in self._buf at the date, in 2 nT units (|v| < 34100)."""
        b = self._buf
        return 2 * _i16(b, k) + (dt * _i16(b, k + 6) + (_SV_DIV >> 1)) // _SV_DIV

    def _derive(self, status):
        x = self._x
        y = self._y
        s = _norm_shift(max(abs(x), abs(y)))
        xn = _shift(x, s)
        yn = _shift(y, s)
        self.declination_kang = atan2(yn, xn)
        self._h = _shift(isqrt(xn * xn + yn * yn), -s)
        self._incl_field()
        self.declination_cdeg = kang_to_cdeg(self.declination_kang)
        self.inclination_cdeg = kang_to_cdeg(self.inclination_kang)
        self.north_nt = (x + 4096) >> 13
        self.east_nt = (y + 4096) >> 13
        self.down_nt = (self._z + 4096) >> 13
        self.horizontal_nt = h = (self._h + 4096) >> 13
        if h < _BLACKOUT_NT:
            status = STATUS_BLACKOUT
        elif h < _CAUTION_NT:
            status = STATUS_CAUTION
        self.status = status

    def _incl_field(self):
        h = self._h
        z = self._z
        s = _norm_shift(max(h, abs(z)))
        hn = _shift(h, s)
        zn = _shift(z, s)
        self.inclination_kang = atan2(zn, hn)
        f = isqrt(hn * hn + zn * zn)  # F = |(H, Z)|, then back from Q14 2 nT units to nT
        s -= 13
        self.field_nt = f << s if s >= 0 else (f + (1 << (-s - 1))) >> -s


def _default_path():
    try:
        here = __file__
    except NameError:  # frozen without __file__: the mip install location
        return "/lib/firmware/field/" + TABLE_NAME
    k = here.rfind("/")
    return (here[:k + 1] if k >= 0 else "") + TABLE_NAME
