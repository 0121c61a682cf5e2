"""Import a calibration file at boot: from a log fitted on the desktop to the board's store."""
#     from firmware.calfile.calimport import import_calibration
#     result = import_calibration("/calibration.json", store, mag)   # None: no file there
#     print(result[1])                         # 'imported ...' or 'rejected ...: why'
#
# A valid file is saved to the store and renamed NAME.imported (imported once); an invalid one
# is renamed NAME.rejected; a failed save leaves it for the next boot. The checks: docs/api.md
# (calibration import); the file's keys: docs/calibration.md. Boot-time code.
import json
import os

from firmware.calibration import MODELS, Calibration

FORMAT = "ecompass-calibration"   # the calibration file's "format" key
FORMAT_VERSION = 1                # the version this reader knows
IMPORTED_SUFFIX = ".imported"
REJECTED_SUFFIX = ".rejected"


def _int(d, key):
    v = d.get(key)
    if type(v) is not int:
        raise ValueError("%s = %r: expected an integer" % (key, v))
    return v


def _ints(d, key, n):
    v = d.get(key)
    if not isinstance(v, list) or len(v) != n:
        raise ValueError("%s = %r: expected a list of %d integers" % (key, v, n))
    for x in v:
        if type(x) is not int:
            raise ValueError("%s: %r is not an integer" % (key, x))
    return tuple(v)


def parse(text, kind, range_code):
    """The Calibration in a calibration file's text for a chip of `kind` at `range_code`;
    ValueError naming the key and value that make it unusable."""
    try:
        d = json.loads(text)
    except ValueError:
        raise ValueError("not a JSON calibration file")
    if not isinstance(d, dict):
        raise ValueError("not a JSON object")
    if d.get("format") != FORMAT:
        raise ValueError("format = %r: expected %r" % (d.get("format"), FORMAT))
    if _int(d, "version") != FORMAT_VERSION:
        raise ValueError("version = %d: this board reads version %d"
                         % (d["version"], FORMAT_VERSION))
    if d.get("sensor") != kind:
        raise ValueError("sensor = %r: this board's magnetometer is %s" % (d.get("sensor"), kind))
    if _int(d, "range_code") != range_code:
        raise ValueError("range_code = %d: the %s here runs at range code %d (made at another "
                         "range: refit with --range)" % (d["range_code"], kind, range_code))
    model = d.get("model")
    if model not in MODELS or isinstance(model, bool):
        raise ValueError("model = %r: expected one of minmax, 4, 7, 10" % (model,))
    return Calibration(model=model, offset=_ints(d, "offset_counts", 3),
                       invw=_ints(d, "invw_q15", 9), field=_int(d, "field_counts"),
                       field_out=_int(d, "field_out_counts"),
                       fit_error=_int(d, "fit_error_x100"), samples=_int(d, "samples"),
                       coverage=_int(d, "coverage_percent"))


def _read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None   # no file: nothing to import
    except UnicodeError:
        return ""     # unreadable text: parse() refuses it


def _rename(path, suffix):
    try:
        os.remove(path + suffix)  # an older one of the same name
    except OSError:
        pass
    try:
        os.rename(path, path + suffix)
    except OSError:
        pass


def import_calibration(path, store, mag):
    """Import the calibration file at `path` into `store` for the driver `mag`."""
    # Returns None when there is no file, (True, message) when it was stored (the file is
    # renamed PATH.imported), (False, reason) when it was refused (renamed PATH.rejected, store
    # untouched) or could not be saved (file left in place for the next boot). Never raises:
    # whatever reading or parsing the file raises (a nesting too deep for the JSON parser,
    # memory, encoding, I/O) refuses the file, and the board boots with its stored calibration.
    try:
        return _import(path, store, mag)
    except Exception as e:  # noqa: BLE001 - RecursionError/RuntimeError, MemoryError, ...
        _rename(path, REJECTED_SUFFIX)
        return False, "rejected %s: %s %s" % (path, type(e).__name__, e)


def _import(path, store, mag):
    try:
        from firmware.calibrate.acceptance import check_calibration
    except ImportError:  # the gate is the calibrate part's: the file waits for it
        return False, "not imported %s: install package-calibrate.json too" % path
    from firmware.errors import CalibrationRejected
    text = _read(path)
    if text is None:
        return None
    try:
        cal = parse(text, mag.KIND, mag.range_code)
        check_calibration(cal, getattr(mag, "counts_per_gauss", None))  # the board's own bar
    except CalibrationRejected as e:
        _rename(path, REJECTED_SUFFIX)
        return False, "rejected %s: %s: %s" % (path, e.reason, e.detail)
    except ValueError as e:
        _rename(path, REJECTED_SUFFIX)
        return False, "rejected %s: %s" % (path, e)
    text = None
    store.sensor = mag.KIND
    store.range_code = mag.range_code
    try:
        store.save(cal.to_bytes())
    except Exception as e:  # OSError, StoreError: the old record stays; retry next boot
        return False, "not imported %s: save failed (%s)" % (path, e)
    _rename(path, IMPORTED_SUFFIX)
    return True, "imported %s: model %s, fit error %d.%02d %%, %d samples" % (
        path, cal.model, cal.fit_error // 100, cal.fit_error % 100, cal.samples)
