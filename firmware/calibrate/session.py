"""The calibration session of a CompassApp: collect, solve in slices, accept, judge against the
history, save; then leave. Imported by CompassApp.calibrate(), dropped when the session ends.
"""
#     app.calibrate()            # starts one (imports this module and the calibration machinery)
#     app.collector              # firmware.calibrate.calibrator.Collector while it runs, None after
#
# When a session ends and what leaves with it: docs/design.md#memory; its steps (solve,
# accept): docs/design.md (module notes, session).
from firmware.compat import const, drop, kernels
from firmware.i2cdevice import DEFAULT_PERIOD_US

_FLAG_ACCEPTED = const(1)     # firmware.calibrate.history.FLAG_ACCEPTED
_FLAG_PENDING = const(2)      # firmware.calibrate.history.FLAG_PENDING
_FLAG_BASELINE = const(4)     # firmware.calibrate.history.FLAG_BASELINE
# what a finished session leaves for CompassApp's counters (accepted, refused, ...)
ENDED = ("accepted", "refused", "solves", "last_reason", "last_detail", "last_model")
# the session's own, carried from one to the next: the history's errors, the solve's slices
# and the longest (us) a step spent in them
KEPT = ("history_errors", "history_reason", "slices", "worst_stall_us")


class Session:
    # One calibration session of `app`: its collector, the history, the pending change and
    # the flags of the history entry due; CompassApp holds it while it runs and drops it (and
    # this module) when end_if_done() says so. The owner firmware/calibrate/history.py
    # expects: .store, .calibration (the app's in force, set before each use), .date_s,
    # ._hist, .history_errors, .history_reason.

    def __init__(self, app, fast=True):
        self.collector = start(app, fast)
        self.pending = None  # a calibration whose parameters jumped (see History)
        self.change = None   # (parameter, value, low, high) of the jump
        self._hist = None    # firmware.calibrate.history.History, from the first accept on
        self.hist_flags = 0  # flags of the history entry due once the save succeeds
        self.slices_per_step = 1
        self.store = app.store
        self.calibration = app.calibration
        self.date_s = None
        for name in KEPT:
            setattr(self, name, getattr(app, name))

    def solve(self, app):
        """A few slices of the running solve, timed by the app's wall clock; True when the
        session ended."""
        t = app._wall()
        c = self.collector
        if c.job is None:
            self.slices_per_step = c.start(getattr(app.mag, "period_us", DEFAULT_PERIOD_US))
        n = self.slices_per_step
        while n and c.job is not None:
            cal = c.slice()
            if cal is not None:
                self.accept(app, cal)
            n -= 1
        done = c.job is None and self.end_if_done(app)
        d = app._wall_diff(app._wall(), t)
        self.slices = (self.slices + 1) & 0x3FFFFFFF
        if d > self.worst_stall_us:
            self.worst_stall_us = d
        return done

    def accept(self, app, cal):
        from firmware.calibrate.acceptance import check_calibration
        from firmware.errors import CalibrationRejected
        try:  # the gate every calibration meets (firmware/calibrate/acceptance.py); the fit passed its parts
            check_calibration(cal, app.mag.counts_per_gauss)
        except CalibrationRejected as e:
            c = self.collector
            c.accepted -= 1
            c.refused += 1
            c.last_reason = e.reason
            c.last_detail = e.detail
            return
        jump = self.history_check(app, cal)
        if jump is None:
            app._use(cal)
            if self._hist is not None:
                self.hist_flags = _FLAG_ACCEPTED
            self.mount_check(app)  # before the save: its code and work are gone when the save runs
            app._save()
        else:
            self.pending = cal
            self.change = jump
            self.history_record(app, cal, _FLAG_PENDING)  # evidence, not in force
            # the calibration in force may not fit the board: its samples keep refining the
            # evidence, as while relearning (firmware.calibrate.calibrator.Collector.relearning)
            self.collector.relearning = True

    def end_if_done(self, app):
        """True when the session's job is done (see the module's opening comment): then the
        app drops it (Learning.end, firmware/learning.py) with the calibration machinery."""
        c = self.collector
        if (app.learning.learn or self.pending is not None or app._unsaved or c.relearning
                or c.job is not None or c.kept or c.since_kept_us < c.QUIET_US
                or not app.calibration.good_for(app.model)):
            return False
        self.mount_check(app)  # once more with every pair kept, when no check could tell yet
        return True

    def ended(self):
        """What the app keeps of the session: its counters (ENDED, KEPT)."""
        d = {}
        for name in ENDED:
            d[name] = getattr(self.collector, name)
        for name in KEPT:
            d[name] = getattr(self, name)
        return d

    def mount_check(self, app):
        # The mounting check (firmware/calibrate/mountcheck.py: loaded for it, dropped after) of the pairs
        # kept against the calibration in force, until one gives an answer (ok or wrong) that is
        # kept for the next boot (firmware/mountnote.py save): app.mounting, and Health.axes_status
        # the status while it names another MAG_AXES (Health.mounted). Then the session's
        # pairs go: a board short of heap loads the check's code as seldom as that, and the next
        # session checks afresh. mountnote's code is loaded for a wrong setting, and for a right
        # one only when a verdict file is there to remove, by a string as firmware/app_persist.py
        # load loads it: no name is interned for it otherwise.
        c = self.collector
        p = c.pairs
        if p is None or app.calibration.model is None:
            return
        from firmware.calibrate.mounting import MIN_BINS
        if p.count < MIN_BINS:
            return  # too few directions of gravity yet
        name = "firmware.mountnote"
        try:
            from firmware.calibrate import mountcheck
            v, axes, shown = mountcheck.judge(app)
            mountcheck = None
            drop("calibrate.mountcheck")
            app.health.mounted(v, axes, shown)
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

    def history_check(self, app, cal):
        # -> None (in limits, or no history to judge by) or (parameter, value, low, high)
        try:
            from firmware.calibrate.history import judge
        except MemoryError:
            return None  # evidence only: no room for it now
        self.calibration = app.calibration
        return judge(self, cal)

    def history_record(self, app, cal, flags):
        if self._hist is not None:
            from firmware.calibrate.history import keep
            self.date_s = app.date_s
            keep(self, cal, flags)

    def saved(self, app):
        """The store took the calibration in force: the history follows it."""
        if self.hist_flags:
            self.history_record(app, app.calibration, self.hist_flags)
            self.hist_flags = 0

    def accept_change(self, app):
        """Put the pending calibration in force (CompassApp.accept_change); True when the
        session ended."""
        cal = self.pending
        self.pending = None
        self.change = None
        self.collector.relearning = False
        app._use(cal)
        if self._hist is not None:
            self.hist_flags = _FLAG_ACCEPTED | _FLAG_BASELINE
        app._save()
        return self.end_if_done(app)

    def discard_change(self, app):
        """Drop the pending calibration (CompassApp.discard_change); True when the session
        ended."""
        self.pending = None
        self.change = None
        c = self.collector
        c.relearning = False
        c.calibrator.current = app.calibration
        return self.end_if_done(app)


def start(app, fast=True):
    """A collector for `app` (firmware.calibrate.calibrator.Collector), with the kernel set it
    chose (fast False: the plain functions)."""
    from firmware.calibrate import samples
    from firmware.calibrate.calibrator import DEFAULT_CAPACITY, Collector
    samples.use_kernels((kernels() if fast and app.fast else None) or False)
    lr = app.learning  # the app's options for its sessions
    c = Collector(model=app.model, capacity=lr.capacity or DEFAULT_CAPACITY,
                  counts_per_gauss=app.mag.counts_per_gauss, current=app.calibration,
                  solve_every=lr.solve_every, fallback=lr.fallback,
                  overflow=getattr(app.mag, "OVERFLOW", None))
    if app.accel is not None:  # the mounting check's pairs (firmware/calibrate/mounting.py)
        from firmware.calibrate.mounting import Pairs
        c.pairs = Pairs(app.accel.counts_per_g,
                        getattr(app.mag, "period_us", DEFAULT_PERIOD_US))
    return c
