"""The browser calibrator's Python side (docs/web.md): runs on the MicroPython WebAssembly
port in the page, next to the repository's firmware/ files, and drives OUR integer
calibrator (firmware/calibrate/calibrator.py) and heading (firmware/compass.py) on the samples the page
reads from a board's `Raw:` lines.

Units: the page feeds the magnetometer in MotionCal's 0.1 uT counts (notes: MotionCal
protocol, section 1), so the calibrator runs with counts_per_gauss = 1000 (1 G = 100 uT) and
its offset V and field B come out in 0.1 uT.

Solve policy (the same as a replay on CPython, tests/test_web.py): a solve after every
SOLVE_EVERY samples the buffer KEPT (firmware/calibrate/calibrator.py's SOLVE_EVERY); each solve is
logged with the number of samples fed before it and its result (a calibration's integers) or
its refusal reason. An accepted solve becomes the calibrator's current calibration, which the
next ones must beat (firmware/calibrate/acceptance.py check_better).

The page calls these with JSON text in and reads JSON text back through the port's globals:
    reset()          forget everything
    feed(samples)    [[mx, my, mz], ...] in 0.1 uT; solves when due
    state()          -> JSON: fed, held, log entries since the last state(), current
    held()           -> JSON: the buffer's samples [[x, y, z], ...]
    headings(mag, acc) -> JSON: heading before (raw) and after (current calibration), KANG
"""
import json

from firmware.calibrate.calibrator import SOLVE_EVERY, Calibrator
from firmware.compass import heading
from firmware.errors import CalibrationRejected

COUNTS_PER_GAUSS = 1000   # MotionCal's 0.1 uT: 1 G = 100 uT = 1000 counts
MODEL = 10

_cal = None
_fed = 0
_kept = 0
_log = []
_unread = 0
_out = [0, 0, 0]


def reset():
    global _cal, _fed, _kept, _log, _unread
    _cal = Calibrator(model=MODEL, counts_per_gauss=COUNTS_PER_GAUSS)
    _fed = 0
    _kept = 0
    _log = []
    _unread = 0


def cal_dict(c):
    return {"model": c.model, "offset": list(c.offset), "invw": list(c.invw),
            "field": c.field, "field_out": c.field_out, "fit_error": c.fit_error,
            "samples": c.samples, "coverage": c.coverage}


def _solve():
    try:
        c = _cal.solve()
        _log.append({"n": _fed, "cal": cal_dict(c)})
    except CalibrationRejected as e:
        _log.append({"n": _fed, "reason": e.reason, "detail": str(e.detail)})
    except ValueError as e:  # bad input the solver refuses outright
        _log.append({"n": _fed, "reason": "value_error", "detail": str(e)})


def feed(samples):
    global _fed, _kept
    for s in samples:
        kept = _cal.add(s[0], s[1], s[2])
        _fed += 1
        if kept:
            _kept += 1
            if _kept >= SOLVE_EVERY:
                _kept = 0
                _solve()


def state():
    global _unread
    cur = _cal.current
    new = _log[_unread:]
    _unread = len(_log)
    return json.dumps({"fed": _fed, "held": _cal.count, "solves": len(_log), "new": new,
                       "current": cal_dict(cur) if cur.model is not None else None})


def held():
    d = _cal.buffer.data
    return json.dumps([[d[j], d[j + 1], d[j + 2]] for j in range(0, 3 * _cal.count, 3)])


def _heading(b, g):
    try:
        return heading(b, g)
    except ValueError:   # a zero field or zero gravity: no heading
        return None


def headings(mag, acc):
    if not (acc[0] or acc[1] or acc[2]):
        acc = None       # a sketch without an accelerometer: taken as level
    before = _heading(mag, acc)
    after = None
    cur = _cal.current
    if cur.model is not None:
        cur.correct(mag, _out)
        after = _heading(_out, acc)
    return json.dumps({"before": before, "after": after})


reset()
