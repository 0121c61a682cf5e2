"""When a CompassApp learns its calibration: its options for sessions, the session beside the
heading line while one runs (firmware/calibrate/session.py), what the last one left, and the
relearning a changed board asks for.
"""
# The app holds one (app.learning); relearn_due, not_installed and the last session's counters
# read as the app's own (docs/api.md).
#     app.calibrate()              # Learning.start: a session, or None (no room, not installed)
#     app.learning.session         # the running Session, None between sessions
#     app.relearn_due              # the iron changed and no session fits: the program's job
#
# When a session starts, ends and what leaves with it: docs/design.md#memory.
from firmware.calibration import STALE_AGE_S
from firmware.compat import const, drop_part, free_bytes

# free heap (bytes, after a collection) a session needs beside the heading line: below it,
# calibrating is the calibration program's job (firmware/calibrate/program.py, run by
# boards/main.py after a restart). The session completes reliably from ~128 KB free after
# boot (x86-32 build, boards/main.py; docs/benchmarks.md).
SESSION_ROOM = const(128 * 1024)
_CAL_RETRY_US = const(60000000)  # a session that found no room: again in 60 s
_LOAD_RETRY_US = const(5000000)  # a load that found no room: again in 5 s
LOAD_NO_MEMORY = "no_memory"  # .load_reason / .save_reason: MemoryError (app_persist.py)


class Learning:
    def __init__(self, learn, capacity, solve_every, fallback):
        # the app's options for its sessions (docs/api.md, the app)
        self.learn = learn  # True: always, False: never, None: while not calibrated well
        self.capacity = capacity  # samples held (None: the calibrator's default)
        self.solve_every = solve_every  # kept samples between solves
        self.fallback = fallback  # a 4-element fit while a model lacks samples
        self.session = None  # firmware.calibrate.session.Session while one runs
        self.ended = {}  # the counters the last session left (Session.ended)
        self.relearn_due = False  # the iron changed and no session fitted beside the heading
        self.not_installed = None  # "calibrate": package-calibrate.json is not on the board

    def begin(self, app):
        """After a load: a session when asked for or while no good calibration is in force
        (docs/api.md), or the load again in 5 s when it found no room."""
        if app.load_reason == LOAD_NO_MEMORY:
            app._no_room("load", _LOAD_RETRY_US)
        elif self.learn or self.learn is None and not app.calibration.good_for(app.model):
            app.calibrate()

    def start(self, app):
        """A session beside the heading line: its collector, or None (no room: app.no_memory
        "calibrate", again in 60 s; or the part not installed)."""
        f = free_bytes()
        if f is not None and f < SESSION_ROOM:
            return app._no_room("calibrate", _CAL_RETRY_US)
        try:
            from firmware.calibrate import session
            self.session = session.Session(app)
        except ImportError:
            self.not_installed = "calibrate"
            return None
        except MemoryError:  # no room beside the heading line after all
            self.session = session = None
            drop_part("calibrate")
            return app._no_room("calibrate", _CAL_RETRY_US)
        return self.session.collector

    def solve(self, app):
        """A few timed slices of the session's solve (Session.solve); True when it ended."""
        if self.session.solve(app):
            self.end()
            return True
        return False

    def end(self):
        # the session's job is done: its counters stay, it and the calibration machinery go
        self.ended = self.session.ended()
        self.session = None
        drop_part("calibrate")

    def change(self, app, accept):
        """Put the pending calibration in force, or drop it: None when none is pending, else
        True when the session ended with it."""
        s = self.session
        if s is None or s.pending is None:
            return None
        if s.accept_change(app) if accept else s.discard_change(app):
            self.end()
            return True
        return False

    def relearn(self, app):
        """The board's iron changed (FieldWatch.check): a session relearns, or when none fits
        beside the heading, relearn_due (app.run() returns; boards/main.py restarts into the
        calibration program)."""
        c = app.calibrate()
        if c is not None:
            c.relearn(STALE_AGE_S)
        else:
            self.relearn_due = True
