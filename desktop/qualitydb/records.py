"""One calibration record: a JSON object with the fields of `python -m host_sim calibrate
--json` plus `device` and `time` (and optionally `source`).

validate(obj) -> the stored row (a dict of columns) or raises RecordError naming the field.
Fields the calibrate command adds later (or any other extra field) are kept in the stored
JSON text but not checked or used.
"""
import datetime
import hashlib
import json
import math

MODELS = ("minmax", 4, 7, 10)          # firmware/magcal.py MODELS: the calibrate --model results
SOURCES = ("cli", "board", "motioncal")

# Checked parameters: hard iron V (AN4246 eq. 3, `offset`), geomagnetic field B, the soft-iron
# InvW (the calibrate command's `invw`, W^-1 scaled to det 1) and the fit error.
PARAMETERS = ("offset_x", "offset_y", "offset_z", "field",
              "invw_xx", "invw_yy", "invw_zz", "invw_xy", "invw_xz", "invw_yz",
              "fit_error", "coverage")
# Checked when no limits file says otherwise: hard iron, field, InvW diagonal, fit error.
DEFAULT_PARAMETERS = ("offset_x", "offset_y", "offset_z", "field",
                      "invw_xx", "invw_yy", "invw_zz", "fit_error")
_INVW_CELLS = {"invw_xx": (0, 0), "invw_yy": (1, 1), "invw_zz": (2, 2),
               "invw_xy": (0, 1), "invw_xz": (0, 2), "invw_yz": (1, 2)}

# Stored columns, in table order (store.py builds the schema from this list).
COLUMNS = (("device", "TEXT NOT NULL"), ("time", "TEXT NOT NULL"),
           ("t_epoch", "DOUBLE PRECISION NOT NULL"), ("source", "TEXT"),
           ("model", "TEXT NOT NULL"),
           ("offset_x", "DOUBLE PRECISION NOT NULL"), ("offset_y", "DOUBLE PRECISION NOT NULL"),
           ("offset_z", "DOUBLE PRECISION NOT NULL"), ("field", "DOUBLE PRECISION NOT NULL"),
           ("invw_xx", "DOUBLE PRECISION NOT NULL"), ("invw_yy", "DOUBLE PRECISION NOT NULL"),
           ("invw_zz", "DOUBLE PRECISION NOT NULL"), ("invw_xy", "DOUBLE PRECISION NOT NULL"),
           ("invw_xz", "DOUBLE PRECISION NOT NULL"), ("invw_yz", "DOUBLE PRECISION NOT NULL"),
           ("fit_error", "DOUBLE PRECISION NOT NULL"), ("coverage", "DOUBLE PRECISION NOT NULL"),
           ("samples", "INTEGER NOT NULL"), ("digest", "TEXT NOT NULL"),
           ("record", "TEXT NOT NULL"))
COLUMN_NAMES = tuple(c for c, _ in COLUMNS)


class RecordError(ValueError):
    """A record that cannot be stored; .field names the offending field (or None)."""

    def __init__(self, field, message):
        ValueError.__init__(self, message)
        self.field = field


def _number(obj, name):
    v = obj.get(name)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise RecordError(name, "field %r: expected a number, got %s" % (name, _show(v)))
    if not math.isfinite(v):
        raise RecordError(name, "field %r: expected a finite number, got %s" % (name, v))
    return float(v)


def _show(v):
    if v is None:
        return "nothing (missing)"
    t = json.dumps(v)
    return t if len(t) <= 40 else t[:37] + "..."


def parse_time(text):
    """ISO-8601 text -> aware UTC datetime; a time without a zone is taken as UTC."""
    if not isinstance(text, str):
        raise RecordError("time", "field 'time': expected ISO-8601 text, got %s" % _show(text))
    try:
        t = datetime.datetime.fromisoformat(text.strip())
    except ValueError:
        raise RecordError("time", "field 'time': %r is not an ISO-8601 date-time "
                          "(e.g. 2025-03-01T14:05:00Z)" % text)
    if t.tzinfo is None:
        t = t.replace(tzinfo=datetime.timezone.utc)
    return t.astimezone(datetime.timezone.utc)


def format_time(t):
    s = t.strftime("%Y-%m-%dT%H:%M:%S")
    if t.microsecond:
        s += ".%06d" % t.microsecond
    return s + "Z"


def validate(obj):
    """A parsed JSON value -> the row dict (COLUMN_NAMES), or RecordError."""
    if not isinstance(obj, dict):
        raise RecordError(None, "expected a JSON object, got %s" % _show(obj))
    if "rejected" in obj and "offset" not in obj:
        raise RecordError("rejected", "a refused calibration (%s) has no parameters to store"
                          % _show(obj.get("rejected")))
    dev = obj.get("device")
    if not isinstance(dev, str) or not dev.strip():
        raise RecordError("device", "field 'device': expected a non-empty string, got %s"
                          % _show(dev))
    t = parse_time(obj.get("time"))
    src = obj.get("source")
    if src is not None and src not in SOURCES:
        raise RecordError("source", "field 'source': expected one of %s, got %s"
                          % ("/".join(SOURCES), _show(src)))
    model = obj.get("model")
    if isinstance(model, bool) or model not in MODELS:
        raise RecordError("model", "field 'model': unknown model %s (expected minmax, 4, 7 "
                          "or 10)" % _show(model))
    off = obj.get("offset")
    if (not isinstance(off, list) or len(off) != 3
            or any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in off)):
        raise RecordError("offset", "field 'offset': expected a list of 3 numbers, got %s"
                          % _show(off))
    invw = obj.get("invw")
    if (not isinstance(invw, list) or len(invw) != 3
            or any(not isinstance(r, list) or len(r) != 3 for r in invw)
            or any(isinstance(v, bool) or not isinstance(v, (int, float))
                   for r in invw for v in r)):
        raise RecordError("invw", "field 'invw': expected 3 rows of 3 numbers, got %s"
                          % _show(invw))
    if not all(math.isfinite(v) for v in off + [v for r in invw for v in r]):
        raise RecordError("offset/invw", "fields 'offset' and 'invw' must be finite numbers")
    field = _number(obj, "field")
    if field <= 0:
        raise RecordError("field", "field 'field': expected a positive field strength, got %s"
                          % field)
    fit = _number(obj, "fit_error_percent")
    if fit < 0:
        raise RecordError("fit_error_percent", "field 'fit_error_percent': expected >= 0 %%, "
                          "got %s" % fit)
    cov = _number(obj, "coverage_percent")
    if not 0 <= cov <= 100:
        raise RecordError("coverage_percent", "field 'coverage_percent': expected 0..100 %%, "
                          "got %s" % cov)
    samples = obj.get("samples_used")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 0:
        raise RecordError("samples_used", "field 'samples_used': expected a count >= 0, got %s"
                          % _show(samples))
    row = {"device": dev.strip(), "time": format_time(t), "t_epoch": t.timestamp(),
           "source": src, "model": str(model),
           "offset_x": float(off[0]), "offset_y": float(off[1]), "offset_z": float(off[2]),
           "field": field, "fit_error": fit, "coverage": cov, "samples": samples}
    for name, (i, j) in _INVW_CELLS.items():
        row[name] = float(invw[i][j])
    row["digest"] = digest(row)
    row["record"] = json.dumps(obj, sort_keys=True, separators=(",", ":"))
    return row


def digest(row):
    """Identity of a calibration for duplicate detection: device, time and parameters."""
    key = [row["device"], row["time"], row["model"]] + [repr(row[p]) for p in PARAMETERS]
    return hashlib.sha256(json.dumps(key).encode()).hexdigest()[:32]


def iter_file(f, name):
    """(line number, row) per non-blank line of a JSON-lines stream; RecordError names the
    line: 'NAME:LINE: field ...'."""
    for n, line in enumerate(f, 1):
        if not line.strip():
            continue
        try:
            obj = json.loads(line)
        except ValueError as e:
            raise RecordError(None, "%s:%d: not JSON (%s)" % (name, n, e))
        try:
            yield n, validate(obj)
        except RecordError as e:
            raise RecordError(e.field, "%s:%d: %s" % (name, n, e))
