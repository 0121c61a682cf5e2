"""The status line of a CompassApp, and its progress() dictionary: what a board prints every
half second (boards/main.py), imported at the first report.

    from firmware.app import status_line   # a thin front: it imports this module
    print(status_line(app))
"""
# progress(app) the calibration's state as a dict; view(app) one line in a buffer this module
# holds (a memoryview, valid until the next call: it allocates nothing else); line(app) the
# same as a str. What the line says: docs/calibration.md; why it allocates 16 bytes:
# docs/design.md (memory).
from firmware.compat import const, free_bytes
from firmware.hints import HINTS

_STATUS_INTERFERENCE = "interference"  # firmware.app.STATUS_INTERFERENCE
_LINE_MAX = const(400)  # bytes: the longest line (a jump, the location, a hint) fits
# the heap the calibration program completes from (.mpy, x86-32, boards/main.py; make bench's
# figure in docs/benchmarks.md, at most 4 KB below it: tests/test_program_need.py)
PROGRAM_NEED_KB = const(132)
_buf = bytearray(_LINE_MAX)
_mv = memoryview(_buf)
_n = 0
_seen_app = None  # the app whose line was made last, and its .stored when it said "saved"
_seen = 0


def progress(app):
    c = app.calibration
    col = app.collector
    solving = app.solving
    return {"coverage": app.coverage(),
            "samples": col.calibrator.count if col is not None else 0,
            "model": c.model, "fit_error": c.fit_error if c.model is not None else None,
            "last_reason": app.last_reason, "last_detail": app.last_detail,
            "accepted": app.accepted, "refused": app.refused,
            "collecting": col is not None, "solving": solving,
            "solve_model": col.job_model if solving else None,
            "status": app.status,
            "interference": (app.compass is not None and app.compass.interference
                             or app.status == _STATUS_INTERFERENCE),
            "relearning": app.relearning, "stored": app.stored,
            "save_errors": app.save_errors, "load_reason": app.load_reason,
            "worst_stall_us": app.worst_stall_us, "change": app.change,
            "history_errors": app.history_errors}


# --- writing into the buffer: a str's characters are small ints (no copy is made) ----------
def _put(s):
    global _n
    n = _n
    for i in range(len(s)):
        if n >= _LINE_MAX:
            break
        _buf[n] = ord(s[i])
        n += 1
    _n = n


def _int(v):
    global _n
    if v < 0:
        _put("-")
        v = -v
    d = 1
    while d * 10 <= v:
        d *= 10
    n = _n
    while d:
        if n < _LINE_MAX:
            _buf[n] = 48 + v // d
            n += 1
        v %= d
        d //= 10
    _n = n


def _any(v):  # a model (4, 7, 10 or "minmax"), a reason: as %s would
    if type(v) is int:
        _int(v)
    elif v is None:
        _put("None")
    else:
        _put(v)


def _sep():
    _put(" | ")


def _fixed(v, div):
    # v / div with one digit per power of ten in div, e.g. 1234 / 100 -> "12.34"
    if v < 0:
        _put("-")
        v = -v
    _int(v // div)
    _put(".")
    div //= 10
    r = v % (div * 10)
    while div:
        _int(r // div)
        r %= div
        div //= 10


def _deg(angle_kang, signed=False):
    # loaded for a heading only: a line without one never loads trig and its tables
    import firmware.trig as trig
    _fixed(trig.kang_decideg(angle_kang, signed), 10)


def _pct(x100):
    _fixed(x100, 100)
    _put(" %")


def _model_fit(c):
    _put("model ")
    _any(c.model)
    _put(" fit ")
    _pct(c.fit_error)


def _story(app):
    """The calibration's stage in words: collecting (coverage), solving, saved (once),
    calibrated, and why not yet."""
    c = app.calibration
    col = app.collector
    global _seen_app, _seen
    if _seen_app is not app:  # another app: none of its saves shown yet
        _seen_app = app
        _seen = 0
    if app.stored != _seen:
        _seen = app.stored
        _sep()
        _put("saved")  # shown once after each save
    _sep()
    if col is None:
        if c.model is not None:
            _put("calibrated: ")
            _model_fit(c)
        else:
            _put("uncalibrated")
        if app.not_installed:
            _put(" | cannot calibrate: install package-")
            _put(app.not_installed)
            _put(".json")
        return
    if c.model is not None:
        _model_fit(c)
    else:
        _put("uncalibrated")
    _put("; collecting ")
    _int(app.coverage())
    _put(" % (")
    _int(col.calibrator.count)
    _put(" samples)")
    if col.job is not None:
        _put(" | solving ")
        _any(col.job_model)
    reason = app.last_reason
    # "planar" only once the user has stopped adding new directions (the collector is quiet):
    # the first samples of a correct figure-8 lie near a plane too
    if reason == "planar" and col.since_kept_us < col.QUIET_US:
        reason = "too_few_samples"
    if reason and reason != "not_better":
        _sep()
        _put(HINTS.get(reason, reason))


def _gyro(a):
    _sep()
    if not a.started:
        _put("gyro: starting")
        return
    if a.source == "magnetometer":
        _put("gyro: on field")
        return
    _put("gyro: held ")
    _fixed(a.since_mag_us // 100000, 10)
    _put(" s +-")
    _fixed(a.uncertainty_cdeg // 10, 10)
    _put(" deg")
    if not a.vouched:
        _put(" (too long)")


def _free_kb():
    f = free_bytes()
    if f is None:
        _put("?")
    else:
        _int(f >> 10)


def _no_memory(app):
    """What the heap could not hold, and what to do instead (docs/design.md, memory)."""
    what = app.no_memory
    _sep()
    if what == "load":
        _put("stored calibration not loaded: out of memory, ")
        _free_kb()
        _put(" KB free (retrying)")
    elif what == "calibrate":
        _put("no room to calibrate beside the heading (")
        _free_kb()
        _put(" KB free): the calibration program needs ~")
        _int(PROGRAM_NEED_KB)
        _put(" KB of heap (calibrate() at the REPL); or calibrate on the desktop, in the "
             "browser or with MotionCal (docs/calibration.md)")
    else:
        _put("out of memory (")
        _any(what)
        _put(")")


def _save_failed(app):
    if app.save_reason is not None:  # the last save failed (a later one succeeded: None)
        _put(" | save failed: ")
        _put(app.save_reason)


def _accuracy(app):
    # `import ... as`: `from firmware.accuracy import ...` would build its tuple of names
    import firmware.accuracy as accuracy
    lvl, why = accuracy.assess(app)
    name = accuracy.NAMES[lvl]
    _put(" | accuracy ")
    _int(lvl)
    _put(" ")
    _put(name)
    if why != name:
        _put(" (")
        _put(why)
        _put(")")


def _heading_line(app):
    # its frame (arguments, locals, stack) stays within the 11 words MicroPython keeps on the C
    # stack (py/objfun.c VM_MAX_STATE_ON_STACK; beyond, every call takes it from the heap):
    # parts with locals of their own are functions of their own
    h = app.heading_kang
    _put("heading ")
    if h < 0:
        _put("---.-")
    else:
        _deg(h)
    _put(" deg")
    if app.accel is None or not app.tilt:
        _put(" (level, no tilt)")
    _sep()
    _put(app.status)
    c = app.compass
    if c.interference or c.dip_high or c.gimbal:
        _put(" | flags ")
        k = _n
        if c.interference:
            _put("interference")
        if c.dip_high:
            _put("," if _n > k else "")
            _put("dip>75")
        if c.gimbal:
            _put("," if _n > k else "")
            _put("pitch>80")
    _story(app)
    a = app.attitude
    if a is not None:  # use_gyro() (docs/gyro.md)
        _gyro(a)
    if app.relearning:
        _put(" | relearning")
    _save_failed(app)
    if app.no_memory is not None:
        _no_memory(app)
    ch = app.change
    if ch is not None:
        _put(" | jump: ")
        _put(ch[0])
        _put(" ")
        _int(ch[1])
        _put(" outside ")
        _int(ch[2])
        _put("..")
        _int(ch[3])
        _put(", accept_change() or discard_change()")
    _accuracy(app)
    loc = app.location
    if loc is not None:
        if loc.usable:
            _put(" | decl ")
            _deg(loc.declination_kang, True)
            _put(" deg (model)")
        else:
            _put(" | decl manual")
        if loc.status != "ok":
            _put(" | location: ")
            _put(loc.status)


def view(app):
    """The line in this module's buffer: a memoryview, valid until the next call."""
    global _n
    _n = 0
    if app._args is not None:  # the app itself did not fit (CompassApp tries again)
        _put("out of memory: the app did not fit in ")
        _free_kb()
        _put(" KB free: a frozen or ROMFS build needs the least heap (docs/design.md, "
             "memory); retrying")
    else:
        _heading_line(app)
    return _mv[:_n]


def line(app):
    """One readable line (view()'s, as a str)."""
    return bytes(view(app)).decode()
