"""The calibration session of a CompassApp: collect, solve in slices, accept, judge against the
history, save; then leave. Imported by CompassApp.calibrate(), dropped when the session ends.
"""
#     app.calibrate()            # starts one (imports this module and the calibration machinery)
#     app.collector              # firmware.calibrate.calibrator.Collector while it runs, None after
#
# When a session ends and what leaves with it: docs/design.md#memory; its steps (solve,
# accept): docs/design.md (module notes, session).
from firmware.compat import const, drop, drop_part, kernels
from firmware.i2cdevice import DEFAULT_PERIOD_US

_FLAG_ACCEPTED = const(1)     # firmware.calibrate.history.FLAG_ACCEPTED
_FLAG_PENDING = const(2)      # firmware.calibrate.history.FLAG_PENDING
_FLAG_BASELINE = const(4)     # firmware.calibrate.history.FLAG_BASELINE
# what a finished session leaves for CompassApp's counters (accepted, refused, ...)
ENDED = ("accepted", "refused", "solves", "last_reason", "last_detail", "last_model")


def start(app, fast=True):
    """A collector for `app` (firmware.calibrate.calibrator.Collector), with the kernel set it
    chose (fast False: the plain functions)."""
    from firmware.calibrate import samples
    from firmware.calibrate.calibrator import Collector
    samples.use_kernels((kernels() if fast and app.fast else None) or False)
    c = Collector(model=app.model, capacity=app.capacity,
                  counts_per_gauss=app.mag.counts_per_gauss, current=app.calibration,
                  solve_every=app.solve_every, fallback=app.fallback,
                  overflow=getattr(app.mag, "OVERFLOW", None))
    if app.accel is not None:  # the mounting check's pairs (firmware/calibrate/mounting.py)
        from firmware.calibrate.mounting import Pairs
        c.pairs = Pairs(app.accel.counts_per_g,
                        getattr(app.mag, "period_us", DEFAULT_PERIOD_US))
    return c


def solve(app):
    t = app._wall()
    c = app.collector
    if c.job is None:
        app._slices_per_step = c.start(getattr(app.mag, "period_us", DEFAULT_PERIOD_US))
    n = app._slices_per_step
    while n and c.job is not None:
        cal = c.slice()
        if cal is not None:
            accept(app, cal)
        n -= 1
    d = app._wall_diff(app._wall(), t)
    app.slices = (app.slices + 1) & 0x3FFFFFFF
    if d > app.worst_stall_us:
        app.worst_stall_us = d
    if app.collector is not None and app.collector.job is None:
        end_if_done(app)


def accept(app, cal):
    from firmware.calibrate.acceptance import check_calibration
    from firmware.errors import CalibrationRejected
    try:  # the gate every calibration meets (firmware/calibrate/acceptance.py); the fit passed its parts
        check_calibration(cal, app.mag.counts_per_gauss)
    except CalibrationRejected as e:
        c = app.collector
        c.accepted -= 1
        c.refused += 1
        c.last_reason = e.reason
        c.last_detail = e.detail
        return
    jump = history_check(app, cal)
    if jump is None:
        app._use(cal)
        if app._hist is not None:
            app._hist_flags = _FLAG_ACCEPTED
        mount_check(app)  # before the save: its code and work are gone when the save runs
        app._save()
    else:
        app.pending = cal
        app.change = jump
        history_record(app, cal, _FLAG_PENDING)  # evidence, not in force
        # the calibration in force may not fit the board: its samples keep refining the
        # evidence, as while relearning (firmware.calibrate.calibrator.Collector.relearning)
        app.collector.relearning = True


def end_if_done(app):
    """End the session when its job is done (see the module's opening comment): the collector, the
    history and the calibration machinery leave. True when it ended."""
    c = app.collector
    if (app.learn or app.pending is not None or app._unsaved or c.relearning
            or c.job is not None or c.kept or c.since_kept_us < c.QUIET_US
            or not app._good_enough(app.calibration)):
        return False
    mount_check(app)  # once more with every pair kept, when no check could tell yet
    for name in ENDED:
        app._ended[name] = getattr(c, name)
    app.collector = None
    app._hist = None
    app._session = None
    drop_part("calibrate")
    return True


def mount_check(app):
    # The mounting check (firmware/calibrate/mountcheck.py: loaded for it, dropped after) of the pairs
    # kept against the calibration in force, until one gives an answer (ok or wrong) that is
    # kept for the next boot (firmware/mountnote.py save): app.mounting, and app._axes_status
    # the status while it names another MAG_AXES. Then the session's pairs go: a board short of
    # heap loads the check's code as seldom as that, and the next session checks afresh.
    # mountnote's code is loaded for a wrong setting, and for a right one only when a verdict
    # file is there to remove, by a string as firmware/app_persist.py load loads it: no name is
    # interned for it otherwise (a function of its own would intern its name too).
    c = app.collector
    p = c.pairs
    if p is None or app.calibration.model is None:
        return
    from firmware.calibrate.mounting import MIN_BINS
    if p.count < MIN_BINS:
        return  # too few directions of gravity yet
    name = "firmware.mountnote"
    try:
        from firmware.calibrate import mountcheck
        v = mountcheck.judge(app)
        mountcheck = None
        drop("calibrate.mountcheck")
        st = app.store
        if v == "ok" and st is not None:
            try:  # firmware.mountnote.NAME
                st.fs.open(st.prefix + "_mounting.txt", "rb").close()
            except (AttributeError, OSError):
                st = None  # no verdict file: nothing to remove
        if (v == "ok" or v == "wrong") and st is not None:
            __import__(name, None, None, ("save",)).save(app)
        if v == "ok" or v == "wrong":
            c.pairs = None
    except MemoryError:
        pass  # no room now: the next fit, or the session's end, checks again
    except OSError:
        pass  # the verdict could not be kept: the same
    drop("calibrate.mountcheck", name[9:], "store_slots")


def history_check(app, cal):
    # -> None (in limits, or no history to judge by) or (parameter, value, low, high)
    try:
        from firmware.calibrate.history import judge
    except MemoryError:
        return None  # evidence only: no room for it now
    return judge(app, cal)


def history_record(app, cal, flags):
    if app._hist is not None:
        from firmware.calibrate.history import keep
        keep(app, cal, flags)


def saved(app, flags):
    """The store took the calibration in force: the history follows it."""
    history_record(app, app.calibration, flags)


def accept_change(app):
    cal = app.pending
    app.pending = None
    app.change = None
    app.collector.relearning = False
    app._use(cal)
    if app._hist is not None:
        app._hist_flags = _FLAG_ACCEPTED | _FLAG_BASELINE
    app._save()
    end_if_done(app)


def discard_change(app):
    app.pending = None
    app.change = None
    c = app.collector
    c.relearning = False
    c.calibrator.current = app.calibration
    end_if_done(app)
