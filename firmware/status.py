"""The status line of a CompassApp, and its progress() dictionary: what a board prints every
half second (boards/main.py), imported at the first report.

    from firmware.app import status_line   # a thin front: it imports this module
    print(status_line(app))

progress(app)  the calibration's state as a dict (coverage, samples, model, fit error, the
               last refusal, counters, status, interference, store and history figures).
line(app)      one readable line: heading (marked when not tilt-compensated), status and
               flags, the calibration's stage in words (collecting with its coverage, solving,
               saved once, calibrated, and what to do when a fit is refused), the gyro-aided
               heading's source (use_gyro: on field, or held for how long and how well),
               accuracy (firmware/accuracy.py), location. docs/calibration.md explains every field.
"""
from firmware.compat import const, free_bytes

_QUIET_HINT_US = const(3000000)  # no new direction for 3 s before "planar"
_STATUS_INTERFERENCE = "interference"  # firmware.app.STATUS_INTERFERENCE


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


def _pct(x100):
    return "%d.%02d %%" % (x100 // 100, x100 % 100)


# what a refusal asks the user to do (status_line); a reason not here is shown as is
_HINTS = {"planar": "rotate about another axis, not only around",
          "too_few_samples": "keep turning",
          "low_coverage": "turn through more directions",
          "fit_error_high": "move slowly, away from metal",
          "field_out_of_range": "field implausible: a magnet near, or the wrong range?",
          "field_mismatch": "field differs from the model here: wrong range, or a magnet?",
          "soft_iron_out_of_range": "strong soft iron: move away from steel",
          "inconsistent_samples": "the field changed while collecting (a magnet, a motor?): "
                                  "samples dropped, keep turning",
          "no_memory": "out of memory while solving"}


def _story(app, p):
    """The calibration's stage in words: collecting (coverage), solving, saved (once),
    calibrated, and why not yet."""
    out = []
    model = p["model"]
    col = app.collector
    if app.stored != app.__dict__.get("_saved_shown", 0):
        app._saved_shown = app.stored
        out.append("saved")  # shown once after each save
    if col is None:
        out.append("calibrated: model %s fit %s" % (model, _pct(p["fit_error"]))
                   if model is not None else "uncalibrated")
        if app.not_installed:
            out.append("cannot calibrate: install package-%s.json" % app.not_installed)
        return out
    out.append("%s; collecting %d %% (%d samples)" % (
        "model %s fit %s" % (model, _pct(p["fit_error"])) if model is not None
        else "uncalibrated", p["coverage"], p["samples"]))
    if p["solving"]:
        out.append("solving %s" % (p["solve_model"],))
    reason = p["last_reason"]
    # "planar" only once the user has stopped adding new directions (the collector is quiet):
    # the first samples of a correct figure-8 lie near a plane too
    if reason == "planar" and col.since_kept_us < _QUIET_HINT_US:
        reason = "too_few_samples"
    if reason and reason != "not_better":
        out.append(_HINTS.get(reason, reason))
    return out


def _gyro(a):
    if not a.started:
        return "gyro: starting"
    if a.source == "magnetometer":
        return "gyro: on field"
    t = a.since_mag_us // 100000
    u = a.uncertainty_cdeg
    return "gyro: held %d.%d s +-%d.%d deg%s" % (t // 10, t % 10, u // 100, u % 100 // 10,
                                                  "" if a.vouched else " (too long)")


def _free_kb():
    f = free_bytes()
    return "?" if f is None else "%d" % (f >> 10)


def _no_memory(app):
    """What the heap could not hold, and what to do instead (docs/design.md, memory)."""
    what = app.no_memory
    if what == "load":
        return "stored calibration not loaded: out of memory, %s KB free (retrying)" % (
            _free_kb(),)
    if what == "calibrate":
        from firmware.calmode import MODE_NEED_KB
        return ("calibration needs ~%d KB, this board has %s KB free: calibrate in the "
                "browser page (docs/web.md) or MotionCal mode, or use a .mpy / frozen "
                "install" % (MODE_NEED_KB, _free_kb()))
    return "out of memory (%s)" % (what,)


def _calibrating(app):
    """Calibration mode (firmware/calmode.py): no heading; the session's progress."""
    p = progress(app)
    parts = ["calibration mode (no heading)", app.status]
    parts.extend(_story(app, p))
    if app.save_reason is not None:
        parts.append("save failed: %s" % app.save_reason)
    return " | ".join(parts)


def line(app):
    """One readable line: heading (marked when not tilt-compensated), status and flags, the
    calibration's stage in words (collecting with its coverage, solving, saved once,
    calibrated, and what to do when a fit is refused), accuracy, location."""
    if app._args is not None:  # the app itself did not fit (CompassApp tries again)
        return ("out of memory: the app did not fit in %s KB free: use a .mpy or frozen "
                "install (docs/design.md, memory); retrying" % _free_kb())
    if app.mode != "heading":
        return _calibrating(app)
    from firmware.trig import kang_to_str
    p = progress(app)
    h = app.heading_kang
    parts = ["heading %s deg%s" % ("---.-" if h < 0 else kang_to_str(h),
                                   "" if app.accel is not None and app.tilt
                                   else " (level, no tilt)"), app.status]
    c = app.compass
    flags = [n for n, f in (("interference", c.interference), ("dip>75", c.dip_high),
                            ("pitch>80", c.gimbal)) if f]
    if flags:
        parts.append("flags " + ",".join(flags))
    parts.extend(_story(app, p))
    a = app.attitude
    if a is not None:  # use_gyro() (docs/gyro.md)
        parts.append(_gyro(a))
    if app.relearning:
        parts.append("relearning")
    if app.save_reason is not None:  # the last save failed (a later one succeeded: None)
        parts.append("save failed: %s" % app.save_reason)
    if app.no_memory is not None:
        parts.append(_no_memory(app))
    if app.change is not None:
        parts.append("jump: %s %d outside %d..%d, accept_change() or discard_change()"
                     % app.change)
    from firmware.accuracy import NAMES, assess
    lvl, why = assess(app)
    parts.append("accuracy %d %s%s" % (lvl, NAMES[lvl], "" if why == NAMES[lvl]
                                       else " (%s)" % why))
    loc = app.location
    if loc is not None:
        parts.append("decl %s deg (model)" % kang_to_str(loc.declination_kang, True)
                     if loc.usable else "decl manual")
        if loc.status != "ok":
            parts.append("location: %s" % loc.status)
    return " | ".join(parts)
