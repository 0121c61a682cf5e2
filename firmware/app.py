"""The compass app: detect, load the stored calibration, then read -> correct -> heading; when
there is no good calibration yet, collect and solve one in the background.
"""
#     from firmware.app import CompassApp, status_line
#     from firmware.store import CalStore
#     app = CompassApp(i2c, store=CalStore("/"), declination_cdeg=150)
#     app.run(None, report=lambda a: print(status_line(a)), every_us=500000)
#
# step() reads one sample and does a bounded amount of other work (never raises); run() calls
# it; calibrate() starts collecting now. Options and attributes: docs/api.md (the app). One
# step's named stages, interference, storage and history, and what is loaded when: the app in
# docs/design.md (module notes) and docs/design.md#memory.
from firmware.axes import apply
from firmware.calibration import UNCALIBRATED, correct
from firmware.compass import FLAG_NO_GRAVITY
from firmware.compat import ROOM_NAMES, const, drop, need, room, sleep_us, ticks_diff
from firmware.errors import SensorOverflow
# (fieldwatch loads with the app: loaded during construction, it raised the boot's peak by a
# 4 KB step of make bench's sweep)
from firmware.fieldwatch import W_FLAG, W_JUMP, W_KEEP
from firmware.health import STATUS_OK, status_of
from firmware.learning import LOAD_NO_MEMORY, Learning

STATUS_INTERFERENCE = "interference"  # a heading, but |field| is off: a magnet or steel near
STATUS_NO_FIELD = "no_field"          # corrected field (0, 0, 0): no heading
STATUS_NO_GRAVITY = "no_gravity"      # accelerometer (0, 0, 0): asleep after a reset, or free fall
STATUS_STARTING = "starting"          # before the first step
STATUS_CHANGED = "hardware changed?"  # a new fit jumped outside its history's limits: pending
# field faults (firmware/health.py, docs/faults.md): user words, never "ok" while they last
STATUS_TILT = "tilt unavailable"      # the accelerometer is implausible: level-board heading
STATUS_INTERNAL = "internal error"    # step() caught an unexpected exception (e.g. MemoryError)
STATUS_JUMP = "heading jumped"        # it moved past the jump limit (docs/faults.md) in a
#                                       sample or a few: a magnet moving in, a turn too fast
STATUS_NO_MEMORY = "out of memory"  # the heap cannot hold a job the board needs (.no_memory
#                                       says which: "start", "load", "calibrate", "heading");
#                                       it keeps running and tries again
STATUS_GYRO_HELD = "gyro held"        # use_gyro(): the field is not used (interference), the
#                                       gyroscope holds the heading and still vouches for it
#                                       (firmware/gyro/attitude.py)


SOLVE_EVERY = const(25)       # kept samples between solves: ~1/9 of a full sphere (225 held)
_REINIT_AFTER = const(5)     # failed reads in a row before the drivers are re-initialised
_SAVE_RETRY_US = const(60000000)  # a failed save is retried after 60 s
_US_PER_S = const(1000000)
_RETRY_PAUSE_US = const(5000)   # the pause of a step while the app itself does not fit
_GAP_CAP_US = const(0x10000000)  # the time since the last read stops counting at 268 s
_REPORT_EVERY = const(25)    # run(): steps between reports (0.5 s at 50 Hz)


_READ_ERRORS = (OSError, SensorOverflow)  # a module constant: a literal tuple is built per call


class _StepGuard:
    """`with` block around a whole step: any exception (MemoryError included) is kept and
    becomes the status "internal error"; step() never raises. Same frame rule as below."""

    def __init__(self):
        self.error = None

    def __enter__(self):
        self.error = None

    def __exit__(self, kind, value, tb):
        if value is None or not isinstance(value, Exception):
            return False
        self.error = value
        return True


class _ReadGuard:
    # `with` block around the sensor reads: keeps the exception of a failed read (bus error,
    # data-ready timeout, overflow) and lets the step go on. A `with` frame stays within the
    # 11 words MicroPython keeps on the C stack, where `except ... as e` would not. The drivers'
    # unguarded sample_into() / config_matches() run inside it (one guard for the step's reads,
    # not one more per driver call): .dev names the device being read, whose BusGuard maps a
    # port's OSError to the BusError naming address and register, as the driver's own would.

    def __init__(self):
        self.error = None
        self.dev = None

    def __enter__(self):
        self.error = None

    def __exit__(self, kind, value, tb):
        if value is None:
            return False
        if isinstance(value, _READ_ERRORS):
            guard = getattr(self.dev, "guard", None)
            self.error = guard.mapped(value) if guard is not None else value
            return True
        return False


# The state the app's owners keep, read through the app (CompassApp.__getattr__: one method,
# where a property each would cost ~140 B of heap): the collector's while collecting and the
# session's while it runs, else what the last session left (firmware/calibrate/session.py ENDED,
# KEPT); Health's (firmware/health.py). Default 0 for the counts, False for relearning, else None.
_COLLECTED = ("accepted", "refused", "solves", "relearning", "last_reason", "last_detail",
              "last_model", "calibrator", "solving")
_SESSION_KEPT = ("history_errors", "pending", "change", "history_reason", "slices",
                 "worst_stall_us")
_HEALTH_KEPT = ("reinits", "reinit_failures", "accel_retries", "last_error", "tilt", "mounting")
_COUNTS = ("accepted", "refused", "solves", "history_errors", "reinits", "reinit_failures",
           "accel_retries", "slices", "worst_stall_us")


def _settle(app):
    # the class's declared state copied into the app's own table first thing, so that no
    # step grows it (a table that grows allocates); the copies of both tables read here are
    # garbage before construction's peak
    d = app.__dict__  # (a copy on MicroPython)
    c = CompassApp.__dict__
    for k in c:  # (keys, not items(): no tuple, no slice allocated per name)
        if k not in d and not k.startswith("__") and k not in ROOM_NAMES:
            # (room()'s names: the class's own spare slots stay its own)
            v = c[k]
            if not callable(v) and not isinstance(v, property):
                setattr(app, k, v)


class CompassApp:
    # the documented state (docs/api.md, the app), here too so that it exists at every heap
    calibration = UNCALIBRATED
    location = compass = collector = load_reason = save_reason = health = learning = None
    no_memory = _args = quick = attitude = date_s = None
    stored = save_errors = worst_save_us = steps = _retry_us = 0
    _dt = _gap_us = _age_us = _save_wait_us = 0
    _unsaved = _dip_unsaved = _stalled = _ok = False
    heading_kang = -1

    def __init__(self, i2c, mag=None, accel=None, mag_axes="x,-y,-z", accel_axes="-x,y,z",
                 model=10, declination_cdeg=0, store=None, delay_us=None, ticks_us=None,
                 capacity=None, solve_every=SOLVE_EVERY, fallback=True,
                 reinit_after=_REINIT_AFTER, mag_options=None, learn=None, fast=None):
        self._guard = _ReadGuard()
        self._step_guard = _StepGuard()
        self.errors = {}
        self.steps = 0
        self.learning = Learning(learn, capacity, solve_every, fallback)  # (at every heap)
        args = (i2c, mag, accel, mag_axes, accel_axes, model, declination_cdeg, store,
                delay_us, ticks_us, solve_every, reinit_after, mag_options, fast)
        try:
            self._build(args)
        except MemoryError:  # no room for the app: step() tries again (docs/api.md)
            self._args = args
            self.no_memory = "start"
            self.status = STATUS_NO_MEMORY
            from firmware import compat  # run()'s clock meanwhile
            self._ticks = ticks_us or compat.ticks_us
            self._wrap = ticks_us is None

    def _build(self, args):
        _settle(self)
        from firmware import app_setup  # construction only: dropped when the app is made
        try:
            (self.i2c, self.mag, self.accel, self._accel_auto, self.store, self.model,
             self.reinit_after, self._mag_map, self._acc_map, self._mag_into, self._mag_cfg,
             self._mm, self._am, self._delay, self._ticks, self._wrap, self._wall,
             self._wall_diff, self._dt_cap, self.raw, self._cor, self.body, self._acc,
             self.gravity, self.health, self._kn, self.compass, self.watch) = app_setup.setup(*args)
        finally:
            app_setup = None
            drop("app_setup", "devinit")  # the drivers' start-up and error texts too
        self.fast = self._kn is not None
        self.dip = self.watch.dip
        self._t_last = self._ticks()
        self.status = STATUS_STARTING
        self._args = self.no_memory = None
        self._use(self._load())
        self.learning.begin(self)
        room(self, 75)  # a step misses its table for a dozen methods (firmware/compat.py room)

    def _load(self):
        try:
            from firmware import app_persist
            cal, self.load_reason = app_persist.load(self)
        except MemoryError:  # no room for the store's code: not "uncalibrated" (_retry)
            cal, self.load_reason = UNCALIBRATED, LOAD_NO_MEMORY
        app_persist = None
        drop("app_persist", "store_slots")
        return cal

    def _save(self, dip_only=False):
        # the store's figures after the save (firmware/app_persist.py), retried when it failed
        try:
            from firmware import app_persist
            r = app_persist.save(self, dip_only)
        except MemoryError:  # no room for the store's code: as a failed save
            r = (self.stored, False, self.save_errors + 1, 0, True, LOAD_NO_MEMORY,
                 self.worst_save_us)
        app_persist = None
        drop("app_persist", "store_slots")
        if r is not None:  # (None: no store)
            (self.stored, self._dip_unsaved, self.save_errors, self._save_wait_us,
             self._unsaved, self.save_reason, self.worst_save_us) = r

    def _use(self, cal):
        # the compass's |B| window, its dip, the short averages and any spell start over
        self.calibration = cal
        self._k = cal.k  # _heading's
        self.watch.use(cal)  # (FieldWatch.use)
        self._locate()

    def use_calibration(self, cal, save=True, collect=True):
        """Put the Calibration `cal` in force (docs/api.md)."""
        if not collect and self.collector is not None:
            self.learning.end()  # the user's choice stands: the session and its code go
            self.collector = None
        self._use(cal)
        if save:
            self._save()

    def calibrate(self):
        """Start a calibration session beside the heading line (docs/api.md)."""
        if self.collector is None and self._args is None:  # (no app yet: nothing to collect for)
            self.collector = self.learning.start(self)
            if self.collector is not None:
                self._locate()
        return self.collector

    def _no_room(self, what, us):
        # the heap could not hold `what` (.no_memory): _retry tries again in `us`
        self.no_memory = what
        self._retry_us = us

    def set_location(self, lat_e7, lon_e7, year_e3=None, table=None):
        """The board's place and date; returns the location's status (docs/api.md)."""
        m = need("field.location", "set_location()")  # an optional part
        loc = self.location = m.place(self, lat_e7, lon_e7, year_e3, table)
        self._use(self.calibration)  # the window afresh, then the location applied
        return loc.status

    def _locate(self):
        if self.location is not None:
            self.location.apply(self)

    def quick_calibrate(self, true_heading_cdeg, refine=False, samples=32):
        """Hard iron from this pose and its true heading, in force and saved (docs/api.md)."""
        m = need("field.quickcal", "quick_calibrate()")
        self.quick, cal = m.quick_calibrate(self, true_heading_cdeg, refine, samples)
        return cal

    def use_gyro(self, **options):
        """The MPU6050's gyroscope holds the heading; returns the Attitude (docs/gyro.md)."""
        m = need("gyro.attitude_setup", "use_gyro()")
        a = self.attitude = m.attach(self, need("gyro.attitude", "use_gyro()"), options)
        drop("gyro.attitude_setup")
        return a

    @property
    def accuracy(self):
        """Accuracy level 0..3, Android's meaning (firmware/accuracy.py)."""
        from firmware.accuracy import assess
        return assess(self)[0]

    def accuracy_reason(self):
        """Why the accuracy level is what it is (firmware/accuracy.py)."""
        from firmware.accuracy import assess
        return assess(self)[1]

    def step(self):
        """One sample and a bounded slice of background work; True if a heading came out. Never
        raises: an exception becomes the status "internal error" (MemoryError "out of memory")."""
        self.steps = (self.steps + 1) & 0x3FFFFFFF  # a small int for years at 200 Hz
        g = self._step_guard
        with g:
            if self._args is not None:
                self._retry_build()
            else:
                self._step()
        if g.error is not None:
            self._internal(g.error)
        return self._ok

    def _retry_build(self):
        # the app itself did not fit: a pause per step (no spinning), a try every 256 steps
        (self._args[8] or sleep_us)(_RETRY_PAUSE_US)  # delay_us, else the port's
        if self.steps & 0xFF == 0:
            self.collector = self.attitude = self.learning.session = None  # (a build cut short)
            self._build(self._args)

    def _step(self):
        self._ok = False
        self._clock()
        st = self._read()
        if st == STATUS_OK:
            st = self.health.vet(self)
        if st == STATUS_OK:
            st = self._heading()
        if st != STATUS_OK:
            self.health.failed(self, st)
        else:
            self._ok = True
            self.health.fails = 0
            self.health.level = 0
            if self._check():
                self._select()
            a = self.attitude
            if a is not None:  # use_gyro(): the filter's step, its heading and status
                st = a.follow(self)
                if st is not None:
                    self.heading_kang = a.shown_kang
                    self.status = st
            if not self.health.tilt and (self.accel is not None or self._accel_auto) \
                    and self.status == STATUS_OK:
                self._flag(STATUS_TILT)
        c = self.collector  # the session's solve: a few timed slices (Learning.solve)
        if c is not None:
            if (c.job is not None or c.due()) and self.learning.solve(self):
                self.collector = None  # the session ended
            elif self.learning.session.pending is not None and (
                    self.status == STATUS_OK or self.status == STATUS_INTERFERENCE):
                self.status = STATUS_CHANGED  # the likely cause of the interference, too
        st = self.health.axes_status  # MAG_AXES is wrong (the interference's cause too)
        if st is not None and (self.status == STATUS_OK or self.status == STATUS_INTERFERENCE):
            self.status = st
        if self.no_memory is not None and self._ok:
            self.status = STATUS_NO_MEMORY  # a heading, but not the calibrated one it should be

    def _internal(self, e):
        self._ok = False
        if self.health is not None:
            self.health.last_error = e
        if isinstance(e, MemoryError):
            return self._flag(STATUS_NO_MEMORY)
        self._flag(STATUS_INTERNAL)
        if self.collector is not None:
            self.collector.job = None  # a solve that raised is abandoned (the next starts afresh)

    def _flag(self, st):
        self.status = st
        self.errors[st] = self.errors.get(st, 0) + 1

    def _clock(self):
        now = self._ticks()
        dt = ticks_diff(now, self._t_last) if self._wrap else now - self._t_last
        self._t_last = now
        if dt < 0:
            dt = 0
        if self._unsaved:
            self._retry_save(dt)
        if self.no_memory is not None:
            self._retry(dt)
        if self.accel is None and self._accel_auto:  # None until one answers
            self.accel = self.health.look_for_accel(self.i2c, dt)
        if self._gap_us < _GAP_CAP_US:
            self._gap_us += dt
        if dt > self._dt_cap:
            dt = self._dt_cap  # a stalled loop saw nothing: time without samples is no evidence
        self._dt = dt
        a = self._age_us + dt
        if a >= _US_PER_S:
            self._age(a)
        else:
            self._age_us = a
        if self.collector is not None:
            self.collector.tick(dt)

    def _age(self, a):
        s = a // _US_PER_S
        if self.collector is not None:
            self.collector.calibrator.age(s)  # NXP: the fit error ages, so it can be replaced
        self._age_us = a - s * _US_PER_S

    def _retry_save(self, dt):
        self._save_wait_us += dt
        if self._save_wait_us >= _SAVE_RETRY_US:
            self._save()
            self._save_wait_us = 0

    def _retry(self, dt):
        # what the heap could not hold, again: the load every 5 s, a session every 60 s
        self._retry_us -= dt
        if self._retry_us > 0:
            return
        what = self.no_memory
        self.no_memory = None
        if what == "load":
            cal = self._load()
            if self.load_reason != LOAD_NO_MEMORY:
                self._use(cal)
            self.learning.begin(self)  # (or "load" again, while it finds no room)
        elif what == "calibrate":
            self.calibrate()

    def _read(self):
        g = self._guard
        acc = self.accel
        with g:
            g.dev = self.mag
            self._mag_into(self.raw)
            if acc is not None:
                g.dev = acc
                acc.sample_into(self._acc)  # and the gyroscope after use_gyro()
        if g.error is None:
            self._stalled = self._gap_us > self._dt_cap
            self._gap_us = 0
            return STATUS_OK
        self.health.last_error = g.error
        return status_of(g.error)

    def _heading(self):
        kn = self._kn  # the kernel set chosen at construction: firmware.fast, or the plain
        if kn is None:  # functions (the same bits, tests/test_tiers.py)
            correct(self._k, self.raw, self._cor)
            apply(self._mm, self._cor, self.body)
        else:
            kn.correct(self._k, self.raw, self._cor)
            kn.apply(self._mm, self._cor, self.body)
        a = self.attitude  # use_gyro(): the gyro step maps gravity (the filter's if bumped)
        if a is not None and a.predict(self):
            self.health.tilt = True  # (a bumped accelerometer: gravity is the filter's)
            h = self.compass.update(self.body, self.gravity)
        elif self.accel is None or not self.health.tilt:
            h = self.compass.update(self.body)
        else:
            if kn is None:
                apply(self._am, self._acc, self.gravity)
            else:
                kn.apply(self._am, self._acc, self.gravity)
            h = self.compass.update(self.body, self.gravity)
        if h < 0:
            return STATUS_NO_GRAVITY if self.compass.flags & FLAG_NO_GRAVITY else STATUS_NO_FIELD
        self.heading_kang = h
        return STATUS_OK

    def _check(self):
        """The field checks (firmware/fieldwatch.py FieldWatch.check); True when the sample
        may be kept."""
        k = self.watch.check(self)
        if k == 0:
            self.status = STATUS_OK
            if self.watch.learned and self._dip_unsaved and not self._unsaved:
                self._save(True)  # saved before its dip was known: once more, with it
            return True
        # a spell's status until the field is clean (docs/design.md, app, interference)
        st = STATUS_JUMP if k & W_JUMP else STATUS_INTERFERENCE
        if k & W_FLAG:
            self._flag(st)
        else:
            self.status = st
        return (k & W_KEEP) != 0

    def _select(self):
        c = self.collector  # (while collecting, Health.vet reads the configuration back)
        if c is not None:
            c.feed(self.raw)
            if c.pairs is not None and self.health.tilt:  # the mounting check's pairs
                c.pairs.feed(self.raw, self._acc)

    def reinit(self):
        """Re-initialise the drivers; True when both answered (docs/api.md)."""
        from firmware import devinit  # the drivers' start-up code and error texts
        ok = devinit.restart(self.health, self.mag, self.accel)
        devinit = None
        drop("devinit")
        return ok

    def accept_change(self):
        """Put the pending calibration in force (docs/api.md); False when none is pending."""
        return self._change(True)

    def discard_change(self):
        """Drop the pending calibration (docs/api.md); False when none is pending."""
        return self._change(False)

    def _change(self, accept):
        r = self.learning.change(self, accept)  # (None: nothing pending)
        if r:
            self.collector = None  # the session ended with it
        if r is not None and self.status == STATUS_CHANGED:
            self.status = STATUS_OK
        return r is not None

    def __getattr__(self, name):
        # (names the app does not hold: _COLLECTED, _SESSION_KEPT, _HEALTH_KEPT, Learning's)
        lr = self.learning
        if name in _COLLECTED:
            o = self.collector
        elif name in _SESSION_KEPT:
            o = lr.session
        elif name in _HEALTH_KEPT:
            o = self.health  # (None: the app did not fit; .ended holds none of its names)
        elif name == "relearn_due" or name == "not_installed":
            o = lr
        else:
            raise AttributeError(name)
        if o is not None:
            return getattr(o, name)
        return lr.ended.get(name, 0 if name in _COUNTS else
                            False if name == "relearning" or name == "solving" else None)

    def coverage(self):
        """Percent of the sphere covered by the held samples (0 when not collecting)."""
        return self.collector.coverage() if self.collector is not None else 0

    def progress(self):
        """The calibration's state as a dict (firmware/status.py progress)."""
        from firmware.status import progress
        return progress(self)

    def run(self, n=None, report=None, every=_REPORT_EVERY, every_us=None):
        """step() n times, report(app) every `every` steps or `every_us` (docs/api.md)."""
        # in the class: a cold module could find no room (firmware/runner.py retries run())
        good = i = 0
        last = self._ticks()
        while (n is None or i < n) and not self.learning.relearn_due:
            if self.step():
                good += 1
            i += 1
            if report is None:
                continue
            if every_us:
                now = self._ticks()
                if (ticks_diff(now, last) if self._wrap else now - last) >= every_us:
                    last = now
                    report(self)
            elif i % every == 0:
                report(self)
        return good


room(CompassApp)  # its methods' table too (firmware/compat.py room)


_NO_MEMORY_LINE = ("status line: out of memory (a frozen or ROMFS build needs the least heap: "
                   "docs/design.md, memory)")


def status_line(app):
    """One readable line of the app's state (firmware/status.py line, docs/calibration.md).
    Never raises MemoryError: without room for the line, a fixed one says so."""
    try:
        from firmware.status import line
        return line(app)
    except MemoryError:
        return _NO_MEMORY_LINE


_NO_MEMORY_VIEW = (b"status line: out of memory (a frozen or ROMFS build needs the least heap: "
                   b"docs/design.md, memory)")


def status_view(app):
    """status_line() as a memoryview of a buffer firmware/status.py holds (valid until the
    next call), allocating nothing else: what boards/main.py writes every half second."""
    try:
        import firmware.status as status  # (`from ... import` would build a tuple each call)
        return status.view(app)
    except MemoryError:
        return _NO_MEMORY_VIEW
