"""Reading a magnetometer log (CSV-like text) as real files come: streamed, bounded, forgiving
of the format and strict about the numbers.

    log = Log("run.csv")                    # or columns=(4, 5, 6), skip=3000
    for lineno, row in log.rows():          # row: three exact (mantissa, decimals) values
        ...
    log.skipped, log.warnings                # corrupt rows: counted, and the first few named

Format: UTF-8 (a BOM is dropped; other bytes above 127 are read as '?', so a latin-1 degree
sign or micro sign in a header does not matter), LF, CRLF or CR line ends, fields separated
by ',', ';', tab or spaces (the separator is the header's most frequent one; with ';' or tab
a decimal comma is accepted). Lines before the header (metadata such as 'Fs,50.00') and lines
starting with '#' are skipped. The x, y, z columns come from the header (HEADER_PREFIXES: mx,
my, mz / magX.. / mag_x.. / x, y, z ..., units in brackets or as a suffix) or from columns=
(1-based); header_units() is the unit those names state ('Mag_X (uT)', 'mx_mG', 'x [G]').

A corrupt data row - a field that is not a decimal number (text, nan, inf, an exponent beyond
+-30 such as 1e30000), a short or empty row, a line longer than MAX_LINE bytes - is skipped,
counted and named in a warning (the first MAX_WARNINGS of them); it never stops the file.
What makes the whole input unusable raises UsageError with one line: missing, a directory,
unreadable, binary (a NUL byte in the first block, or UTF-16), no header, no data rows.
"""
import os

from desktop.args import UsageError, parse_decimal

BLOCK = 4096              # bytes read at a time
MAX_LINE = 1024           # bytes: a longer line is no CSV row of three numbers
MAX_WARNINGS = 20         # corrupt rows named one by one; the rest are counted
HEADER_SEARCH = 50        # lines: the header must come within the first 50 (metadata above)
# Column names, normalised (lower case, letters and digits only, '(uT)' / '[raw]' dropped):
# a prefix followed by x, y, z; optionally a unit suffix. Magnetometer prefixes first, so an
# IMU log's 'ax, ay, az, ..., mx, my, mz' picks the magnetometer; bare 'x, y, z' last.
HEADER_PREFIXES = ("m", "mag", "magn", "magnet", "magnetometer", "magnetic", "compass",
                   "b", "h", "raw", "rawm", "rawmag", "magraw", "")
HEADER_SUFFIXES = ("", "ut", "mg", "nt", "g", "gauss", "raw", "lsb", "counts")
_SEPARATORS = (",", ";", "\t")
_DIR_MODE = 0o040000      # stat S_IFDIR
_TYPE_MASK = 0o170000


def _text(b):
    """bytes -> str: ASCII as is, every other byte '?' (headers, messages)."""
    try:
        s = b.decode()
    except UnicodeError:
        s = None
    if s is not None and len(s) == len(b):  # UTF-8: as long as its bytes only if ASCII
        return s
    return "".join([chr(c) if c < 128 else "?" for c in b])


def _short(b, n=40):
    s = _text(b)
    return repr(s if len(s) <= n else s[:n] + "...")


def normalise_name(name):
    """'Mag_X (uT)' -> 'magx'."""
    out = []
    depth = 0
    for c in name.lower():
        if c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1 if depth else 0
        elif depth == 0 and (c.isalpha() or c.isdigit()) and ord(c) < 128:
            out.append(c)
    return "".join(out)


def find_columns(names):
    """The 0-based indices of the x, y, z columns among header `names`, or None."""
    norm = [normalise_name(n) for n in names]
    for p in HEADER_PREFIXES:
        for u in HEADER_SUFFIXES:
            idx = []
            for a in "xyz":
                key = p + a + u
                if key in norm:
                    idx.append(norm.index(key))
            if len(idx) == 3:
                return tuple(idx)
    return None


def name_unit(name):
    """The unit a column's name states, as --units spells it: 'Mag_X (uT)' -> 'uT', 'x [G]' ->
    'G', 'mx_mG' -> 'mG', 'mz (\u00b5T)' -> 'uT', 'mx_raw' -> 'counts'; None when it states none.
    A non-ASCII byte reaches here as '?' (_text): '?T' / '??T' in brackets is a micro sign's."""
    from desktop.calopts import UNIT_NAMES, units
    word, depth = [], 0
    for c in name:
        if c in "([{":
            depth += 1
            word = []
        elif c in ")]}" and depth:
            depth -= 1
            k = "".join(word).strip()
            if k[:1] == "?" and k.strip("?") == "T":
                return "uT"
            try:
                return units(k)
            except ValueError:
                pass
        elif depth:
            word.append(c)
    n = normalise_name(name)
    for p in HEADER_PREFIXES:
        if n[:len(p)] == p and n[len(p):len(p) + 1] in ("x", "y", "z"):
            u = UNIT_NAMES.get(n[len(p) + 1:])
            if u is not None:
                return u
    return None


def parse_columns(text):
    """'--columns 3,4,5' (1-based) -> (2, 3, 4); ValueError naming what is wrong."""
    parts = text.split(",")
    if len(parts) != 3:
        raise ValueError("expected three column numbers X,Y,Z (1-based), e.g. 4,5,6")
    cols = []
    for p in parts:
        p = p.strip()
        if not p.isdigit() or int(p) < 1 or int(p) > 1000:
            raise ValueError("column %r: expected a number 1..1000" % p)
        cols.append(int(p) - 1)
    if cols[0] == cols[1] or cols[0] == cols[2] or cols[1] == cols[2]:
        raise ValueError("the three columns must differ")
    return tuple(cols)


def check_readable(path):
    """UsageError (one line) unless `path` is an existing, readable, non-empty regular file."""
    try:
        st = os.stat(path)
    except OSError:
        raise UsageError("%s: no such file" % path)
    if st[0] & _TYPE_MASK == _DIR_MODE:
        raise UsageError("%s: is a directory, not a log file" % path)
    if st[6] == 0:
        raise UsageError("%s: empty file" % path)


def raw_lines(path):
    """Yield (lineno, bytes) for every line (without its end), reading BLOCK bytes at a time.
    A line longer than MAX_LINE is yielded as None (and the rest of it discarded)."""
    try:
        f = open(path, "rb")
    except OSError as e:
        raise UsageError("%s: cannot open (%s)" % (path, _oserr(e)))
    try:
        lineno = 0
        buf = b""
        first = True
        too_long = False
        while True:
            try:
                block = f.read(BLOCK)
            except OSError as e:
                raise UsageError("%s: cannot read (%s)" % (path, _oserr(e)))
            if first:
                first = False
                if block[:2] in (b"\xff\xfe", b"\xfe\xff"):
                    raise UsageError("%s: UTF-16 text; save it as UTF-8 (or ASCII)" % path)
                if b"\x00" in block:
                    raise UsageError("%s: binary data (NUL byte at offset %d), not a text log"
                                     % (path, block.index(b"\x00")))
                if block[:3] == b"\xef\xbb\xbf":
                    block = block[3:]
            if not block:
                break
            buf += block
            # a CR at the end of the block may be the first half of a CRLF
            end = len(buf) - 1 if buf[-1:] == b"\r" else len(buf)
            start = 0
            while True:
                i = _line_end(buf, start, end)
                if i < 0:
                    break
                lineno += 1
                yield lineno, (None if too_long or i - start > MAX_LINE else buf[start:i])
                too_long = False
                start = i + (2 if buf[i:i + 2] == b"\r\n" else 1)
            buf = buf[start:]
            if len(buf) > MAX_LINE + 1:
                too_long = True
                buf = buf[-1:] if buf[-1:] == b"\r" else b""
        if buf or too_long:
            lineno += 1
            yield lineno, (None if too_long else buf)
    finally:
        f.close()


def _line_end(buf, start, end):
    n = buf.find(b"\n", start, end)
    r = buf.find(b"\r", start, end)
    if r >= 0 and (n < 0 or r < n):
        return r
    return n


def _oserr(e):
    return e.args[1] if len(e.args) > 1 else "errno %s" % (e.args[0] if e.args else "?")


def split_fields(line, sep):
    """Fields of one line, stripped of spaces and quotes."""
    if sep is None:
        parts = line.split()
    else:
        parts = line.split(sep)
    out = []
    for p in parts:
        p = p.strip()
        if len(p) >= 2 and p[0] == p[-1] and p[0] in "\"'":
            p = p[1:-1].strip()
        out.append(p)
    return out


def guess_separator(line):
    best, n = None, 0
    for s in _SEPARATORS:
        k = line.count(s)
        if k > n:
            best, n = s, k
    return best


class Log:
    """One pass over the log per rows() call (see the module docstring)."""

    def __init__(self, path, columns=None, skip=0):
        self.path = path
        self.columns = columns
        self.skip = skip
        self.sep = None
        self.header_line = None
        self.names = None
        self.skipped = 0          # corrupt rows of the last pass
        self.rows_read = 0        # valid rows yielded by the last pass (after skip)
        self.warnings = []        # (lineno, message) of the first MAX_WARNINGS corrupt rows
        self._first_data = None   # line number where the data begins (known after a pass)
        check_readable(path)

    def bad(self, lineno, message):
        """Count a corrupt row (also called by the caller for a value it cannot use)."""
        self.skipped += 1
        if len(self.warnings) < MAX_WARNINGS:
            self.warnings.append((lineno, message))

    def column_names(self):
        if self.names is not None:
            return [self.names[c] for c in self.columns]
        return ["column %d" % (c + 1) for c in self.columns]

    def header_units(self):
        """The unit the x, y, z columns' header names state (name_unit), or None: no header
        (known after a pass of rows()), no unit named, or the three disagree."""
        if self.names is None:
            return None
        found = set()
        for c in self.columns:
            u = name_unit(self.names[c]) if c < len(self.names) else None
            if u is not None:
                found.add(u)
        return found.pop() if len(found) == 1 else None

    def _start(self, lines):
        """Consume preamble and header; returns the first data line or None. A later pass
        starts where the first one found the data."""
        if self._first_data is not None:
            for lineno, b in lines:
                if lineno >= self._first_data:
                    return lineno, b
            return None
        for lineno, b in lines:
            if b is None:
                continue
            s = _text(b).strip()
            if not s or s[0] == "#":
                continue
            sep = guess_separator(s)
            fields = split_fields(s, sep)
            if self.columns is None:
                cols = find_columns(fields)
                if cols is not None:
                    self.columns = cols
                    self.sep = sep
                    self.names = fields
                    self.header_line = lineno
                    self._first_data = lineno + 1
                    return None
            else:
                self.sep = sep
                if self._numeric(fields):
                    self._first_data = lineno
                    return lineno, b
                # a header (or metadata) line above the data
                self.header_line = lineno
                self.names = fields if len(fields) > max(self.columns) else None
            if lineno >= HEADER_SEARCH:
                break
        if self.columns is None:
            raise UsageError("%s: no header line naming the x, y, z columns in its first %d "
                             "lines (names such as mx,my,mz / x,y,z / magX,magY,magZ); "
                             "give --columns X,Y,Z (1-based) for a file without one%s"
                             % (self.path, HEADER_SEARCH, self._glued_hint()))
        raise UsageError("%s: no line with numbers in columns %d,%d,%d in its first %d lines"
                         % ((self.path,) + tuple(c + 1 for c in self.columns)
                            + (HEADER_SEARCH,)))

    def _glued_hint(self):
        """'; ...' when the data's fields are label and value in one ('Mx:34,My:-292'), which
        --columns cannot split: the labels must go first."""
        for lineno, b in raw_lines(self.path):
            s = _text(b).strip() if b is not None else ""
            if not s or s[0] == "#":
                continue
            glued = []
            for k, f in enumerate(split_fields(s, guess_separator(s))):
                for mark in (":", "="):
                    if mark in f:
                        label, value = f.split(mark, 1)
                        try:
                            parse_decimal(value)
                        except ValueError:
                            continue
                        if label.strip() and not self._numeric_any([label]):
                            glued.append(k + 1)
                        break
            if len(glued) >= 3:
                return ("; its values carry their labels (%s): remove the labels first, e.g. "
                        "sed -E 's/[A-Za-z_]+ *[:=] *//g' %s > clean.csv, then --columns %s"
                        % (_short(b), self.path, "%d,%d,%d" % tuple(glued[:3])
                           if len(glued) == 3 else "X,Y,Z"))
            return ""
        return ""

    def _numeric(self, fields):
        if len(fields) <= max(self.columns):
            return False
        for c in self.columns:
            try:
                self._value(fields[c])
            except ValueError:
                return False
        return True

    @staticmethod
    def _numeric_any(fields):
        for f in fields:
            try:
                parse_decimal(f)
                return True
            except ValueError:
                pass
        return False

    def _value(self, text):
        if self.sep in (";", "\t") and "," in text and "." not in text:
            text = text.replace(",", ".")  # decimal comma
        return parse_decimal(text)

    def rows(self):
        """Yield (lineno, [(m, d)] * 3) per valid data row; counts and names corrupt ones."""
        self.skipped = 0
        self.rows_read = 0
        self.warnings = []
        lines = raw_lines(self.path)
        first = self._start(lines)
        n = 0
        cols = self.columns
        need = max(cols) + 1
        pending = [first] if first is not None else []
        while True:
            if pending:
                lineno, b = pending.pop()
            else:
                try:
                    lineno, b = next(lines)
                except StopIteration:
                    break
            if b is None:
                n += 1
                if n > self.skip:
                    self.bad(lineno, "longer than %d bytes" % MAX_LINE)
                continue
            s = _text(b).strip()
            if s[:1] == "#":
                continue
            n += 1
            if n <= self.skip:
                continue
            if not s:
                self.bad(lineno, "empty row")
                continue
            fields = split_fields(s, self.sep)
            if len(fields) < need:
                self.bad(lineno, "%d fields, columns %s need %d: %s"
                         % (len(fields), ",".join([str(c + 1) for c in cols]), need,
                            _short(b)))
                continue
            row = []
            for k in range(3):
                t = fields[cols[k]]
                try:
                    row.append(self._value(t))
                except ValueError:
                    row = None
                    self.bad(lineno, "%s %s is not a decimal number"
                             % (self.column_names()[k], _short(t.encode(), 24)))
                    break
            if row is not None:
                self.rows_read += 1
                yield lineno, row


# ---- the file's magnitude: which power of ten brings it into int16 -------------------------
ROBUST_FACTOR = 4   # a row whose largest |value| exceeds 4x the median row's is not used to
                    # choose the scale: on a sphere of radius B around V every row's largest
                    # component lies within |V| + B and at least (|V| + B) / sqrt(3) / 2 or so,
                    # so a larger one is a corrupt value, and it must not shrink the whole file


def _bucket(m, d):
    # (exponent, leading digit) of m / 10**d > 0 as one sortable int; value < (D+1) 10**(e-1)
    s = str(m)
    return (len(s) - d) * 10 + int(s[0])


def _lt(a, b):
    return a[0] * 10 ** b[1] < b[0] * 10 ** a[1]


class Magnitude:
    """Per-row largest |value| statistics gathered while reading (exact, no floats)."""

    def __init__(self):
        self.hist = {}       # bucket -> rows
        self.top = {}        # bucket -> its largest (m, d)
        self.decimals = 0    # most decimals of any value
        self.rows = 0

    def add(self, row):
        big = (0, 0)
        for m, d in row:
            if d > self.decimals:
                self.decimals = d
            a = (-m if m < 0 else m, d)
            if _lt(big, a):
                big = a
        self.rows += 1
        if big[0] == 0:
            return
        b = _bucket(big[0], big[1])
        self.hist[b] = self.hist.get(b, 0) + 1
        t = self.top.get(b)
        if t is None or _lt(t, big):
            self.top[b] = big

    def robust_max(self):
        """The largest row maximum within ROBUST_FACTOR x the median row's (exact (m, d)),
        or None when every value is 0."""
        keys = sorted(self.hist)
        if not keys:
            return None
        total = 0
        for k in keys:
            total += self.hist[k]
        acc = 0
        med = keys[-1]
        for k in keys:
            acc += self.hist[k]
            if 2 * acc >= total:
                med = k
                break
        e, lead = med // 10, med % 10
        # limit = ROBUST_FACTOR (lead + 1) 10**(e - 1), as (m, d)
        lim = (ROBUST_FACTOR * (lead + 1) * (10 ** (e - 1) if e >= 1 else 1), 0 if e >= 1 else 1 - e)
        best = None
        for k in keys:
            t = self.top[k]
            if not _lt(lim, t) and (best is None or _lt(best, t)):
                best = t
        return best

    def power(self, limit=32767, most=12):
        """The largest power of ten p (<= most; <= 0 for an integer file) that keeps the
        robust maximum within `limit` after scaling by 10**p."""
        big = self.robust_max()
        cap = most if self.decimals else 0
        if big is None:
            return 0
        p = cap
        while p > -30 and scale_value(big[0], big[1], p) > limit:
            p -= 1
        return p


def rdiv(n, d):
    """n / d rounded half away from zero (d > 0)."""
    if n >= 0:
        return (n + d // 2) // d
    return -((-n + d // 2) // d)


def scale_value(m, d, p):
    """m / 10**d times 10**p, rounded to an int."""
    k = p - d
    return m * 10 ** k if k >= 0 else rdiv(m, 10 ** (-k))


def convert(m, d, num, den):
    """m / 10**d times num / den, rounded to an int (den > 0)."""
    return rdiv(m * num, den * 10 ** d)
