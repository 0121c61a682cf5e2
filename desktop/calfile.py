"""The calibration file a board can load: what `python -m host_sim calibrate LOG --out FILE.json`
writes, as one JSON object (UTF-8, keys below, no others required; unknown keys are kept by
read() and ignored by validate(), so a later version may add some):

    format             "ecompass-calibration"
    version            1 (FORMAT_VERSION)
    sensor             the driver's KIND: a magnetometer of host_sim/chips.py ("qmc5883l", ...)
    range_gauss        the full scale the log was taken at, as that table gives it (QMC5883L
                       2 | 8, HMC5883L 0.88 | 1.3 | ... | 8.1, ...)
    range_code         the driver's .range_code for it (QMC5883L RNG, HMC5883L gain GN, ...):
                       the board refuses a calibration made at another range
    counts_per_gauss   the sensitivity at that range (datasheet)
    model              "minmax", 4, 7 or 10
    offset_counts      V, hard iron: 3 ints in int16, raw counts (AN4246 eq. 19)
    invw_q15           InvW, inverse soft iron: 9 ints, row-major, Q15 (32768 = 1), each row's
                       absolute sum <= 32767 (the small-int bound of Calibration.correct)
    field_counts       B, the fitted geomagnetic field, raw counts
    field_out_counts   |InvW (raw - V)| >> 15 on the fitted sphere: the magnitude correct()
                       outputs, the field the board's compass checks for interference
    fit_error_x100     fit error, hundredths of a percent (AN4246 section 5)
    samples            samples the fit used
    coverage_percent   of 100 equal-area sphere regions around V holding a sample, 0..100
    date               when it was made, ISO 8601 UTC, "YYYY-MM-DDTHH:MM:SSZ"
    forced             true if acceptance refused it and --force wrote it anyway
    refusal            with forced: the refusal reason it overrode ("" otherwise)

These are the fields of firmware/magcal.py's Calibration (to_bytes() payload) plus what the
board's store checks (firmware/calstore.py: sensor kind, range code) and provenance.
read() / validate() raise CalFileError naming the key and value; write() validates first and
replaces the file only once the new one is complete (a temporary file, then rename), so a
failed write leaves the previous file as it was. Plain Python (no firmware import), so a
board can use the same checks.
"""
import json
import os

from host_sim import chips

FORMAT = "ecompass-calibration"
FORMAT_VERSION = 1
MODELS = ("minmax", 4, 7, 10)
# Per sensor: (range in gauss as text, range code, counts per gauss), in range-code order, and
# the raw output range: host_sim/chips.py's table (tests/test_chips.py checks it against the
# drivers).
SENSORS = {m["kind"]: {"ranges": tuple(r[:3] for r in m["ranges"]), "output": m["output"],
                       "default_range": m["default"]} for m in chips.MAGS}
SENSOR_NAMES = chips.MAG_KINDS
KEYS = ("format", "version", "sensor", "range_gauss", "range_code", "counts_per_gauss", "model",
        "offset_counts", "invw_q15", "field_counts", "field_out_counts", "fit_error_x100",
        "samples", "coverage_percent", "date", "forced", "refusal")


class CalFileError(ValueError):
    """A calibration file or dict is not valid: the message names the key and the value."""


def range_entry(sensor, range_text):
    """(range_gauss text, range code, counts per gauss) for a sensor and a range given as text
    ('8', '1.3', '4' == '4.0'); ValueError listing the valid ones."""
    if sensor not in SENSORS:
        raise ValueError("unknown sensor %r: expected one of %s" % (sensor, ", ".join(SENSOR_NAMES)))
    for r in SENSORS[sensor]["ranges"]:
        if _same_number(r[0], range_text):
            return r
    raise ValueError("%s has no range %s G: expected one of %s" % (
        sensor, range_text, ", ".join([r[0] for r in SENSORS[sensor]["ranges"]])))


def _same_number(a, b):
    try:
        return float(a) == float(b)
    except (TypeError, ValueError):
        return False


def iso_date(t=None):
    """ISO 8601 UTC text of epoch seconds `t` (now if None)."""
    import time
    if t is None:
        t = time.time()
    g = time.gmtime(int(t))
    return "%04d-%02d-%02dT%02d:%02d:%02dZ" % (g[0], g[1], g[2], g[3], g[4], g[5])


def check_date(text):
    """ValueError unless text is 'YYYY-MM-DDTHH:MM:SSZ' with plausible fields."""
    ok = isinstance(text, str) and len(text) == 20 and text[4] == "-" and text[7] == "-" \
        and text[10] == "T" and text[13] == ":" and text[16] == ":" and text[19] == "Z"
    if ok:
        digits = text[0:4] + text[5:7] + text[8:10] + text[11:13] + text[14:16] + text[17:19]
        ok = digits.isdigit()
    if ok:
        mo, d, h, mi, s = (int(text[5:7]), int(text[8:10]), int(text[11:13]),
                           int(text[14:16]), int(text[17:19]))
        ok = 1 <= mo <= 12 and 1 <= d <= 31 and h <= 23 and mi <= 59 and s <= 60
    if not ok:
        raise ValueError("expected an ISO 8601 UTC date YYYY-MM-DDTHH:MM:SSZ, got %r" % (text,))
    return text


def _int(d, key, lo=None, hi=None):
    v = d.get(key)
    if not isinstance(v, int) or isinstance(v, bool):
        raise CalFileError("%s = %r: expected an integer" % (key, v))
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise CalFileError("%s = %d: expected %s..%s" % (key, v, lo, hi))
    return v


def _ints(d, key, n, lo, hi):
    v = d.get(key)
    if not isinstance(v, list) or len(v) != n:
        raise CalFileError("%s = %r: expected a list of %d integers" % (key, v, n))
    for k, x in enumerate(v):
        if not isinstance(x, int) or isinstance(x, bool) or not lo <= x <= hi:
            raise CalFileError("%s[%d] = %r: expected an integer in %d..%d" % (key, k, x, lo, hi))
    return v


def validate(d):
    """Return d if it is a valid calibration (see the module docstring), else CalFileError."""
    if not isinstance(d, dict):
        raise CalFileError("expected a JSON object, got %s" % type(d).__name__)
    for k in KEYS:
        if k not in d:
            raise CalFileError("missing key %r" % k)
    if d["format"] != FORMAT:
        raise CalFileError("format = %r: expected %r" % (d["format"], FORMAT))
    if _int(d, "version") != FORMAT_VERSION:
        raise CalFileError("version = %d: this reader knows version %d"
                           % (d["version"], FORMAT_VERSION))
    s = d["sensor"]
    if s not in SENSORS:
        raise CalFileError("sensor = %r: expected one of %s" % (s, ", ".join(SENSOR_NAMES)))
    code = _int(d, "range_code", 0, len(SENSORS[s]["ranges"]) - 1)
    rg, _, cpg = SENSORS[s]["ranges"][code]
    if not _same_number(d["range_gauss"], rg):
        raise CalFileError("range_gauss = %r does not match range_code %d of %s (%s G)"
                           % (d["range_gauss"], code, s, rg))
    if _int(d, "counts_per_gauss") != cpg:
        raise CalFileError("counts_per_gauss = %d: %s at %s G has %d"
                           % (d["counts_per_gauss"], s, rg, cpg))
    if d["model"] not in MODELS or isinstance(d["model"], bool):
        raise CalFileError("model = %r: expected one of minmax, 4, 7, 10" % (d["model"],))
    _ints(d, "offset_counts", 3, -32768, 32767)
    q = _ints(d, "invw_q15", 9, -32767, 32767)
    for i in range(3):
        t = abs(q[3 * i]) + abs(q[3 * i + 1]) + abs(q[3 * i + 2])
        if t > 32767:
            raise CalFileError("invw_q15 row %d: absolute sum %d > 32767" % (i, t))
    _int(d, "field_counts", 1, 2 ** 31 - 1)
    _int(d, "field_out_counts", 1, 2 ** 31 - 1)
    _int(d, "fit_error_x100", 0, 2 ** 31 - 1)
    _int(d, "samples", 0, 2 ** 31 - 1)
    _int(d, "coverage_percent", 0, 100)
    try:
        check_date(d["date"])
    except ValueError as e:
        raise CalFileError("date: %s" % e)
    if not isinstance(d["forced"], bool):
        raise CalFileError("forced = %r: expected true or false" % (d["forced"],))
    if not isinstance(d["refusal"], str) or (d["forced"] and not d["refusal"]):
        raise CalFileError("refusal = %r: expected the overridden reason when forced, else \"\""
                           % (d["refusal"],))
    return d


def read(path):
    """The validated dict of a calibration file; CalFileError (also for unreadable files)."""
    try:
        with open(path) as f:
            text = f.read()
    except (OSError, UnicodeError) as e:
        raise CalFileError("%s: cannot read (%s)" % (path, e))
    try:
        d = json.loads(text)
    except ValueError as e:
        raise CalFileError("%s: not JSON (%s)" % (path, e))
    try:
        return validate(d)
    except CalFileError as e:
        raise CalFileError("%s: %s" % (path, e))


def dumps(d):
    """The file's text: one key per line, in KEYS order (diffable), then any others."""
    keys = list(KEYS) + sorted([k for k in d if k not in KEYS])
    return "{\n" + ",\n".join(["  %s: %s" % (json.dumps(k), json.dumps(d[k])) for k in keys]) \
        + "\n}\n"


def write(path, d):
    """Validate d and write it to path (temporary file, then rename over the old one)."""
    validate(d)
    text = dumps(d)
    tmp = path + ".tmp"
    try:
        with open(tmp, "w") as f:
            f.write(text)
        os.rename(tmp, path)
    except OSError as e:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise CalFileError("%s: cannot write (%s)" % (path, e))
