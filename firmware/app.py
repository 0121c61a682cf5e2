"""The compass app: detect, load the stored calibration, then read -> correct -> heading; when
there is no good calibration yet, collect and solve one in the background.

    from firmware.app import CompassApp, status_line
    from firmware.store import CalStore
    app = CompassApp(i2c, store=CalStore("/"), declination_cdeg=150)
    app.run(None, report=lambda a: print(status_line(a)), every_us=500000)

CompassApp(i2c, mag=None, accel=None, mag_axes="x,-y,-z", accel_axes="-x,y,z", model=10,
           declination_cdeg=0, store=None, delay_us=None, ticks_us=None, capacity=None,
           solve_every=25, fallback=True, reinit_after=5, mag_options=None, learn=None,
           fast=None)
  mag      a magnetometer driver; None: firmware.detect.detect(i2c, **mag_options)
  accel    an MPU6050 driver; None: detect.detect_accel(i2c); False: none (level board)
  store    a firmware.store.CalStore (bound to the magnetometer's kind and range), or None
  delay_us the drivers' delay (the simulator's bus.sleep_us); None: the port's sleep_us
  ticks_us the clock of the app's time (aging, timers): the port's ticks_us on a board (wrapping,
           compared with ticks_diff; firmware.compat), the simulator's clock on the host (plain
           ints)
  mag_options  driver options for detect(), e.g. {"range": 8}
  fallback     try 4 elements when the model lacks samples (firmware.calibrator.Collector)
  reinit_after failed reads in a row before the drivers are re-initialised
  learn    None: collect unless the stored calibration is of the configured model with a fit
           error <= 5 % (and whenever the one in force goes stale); True: always collect;
           False: only after calibrate() or when the calibration goes stale
  fast     None: firmware/fast.py's kernels where the port has the native emitter, False:
           the plain functions (same bits; .fast says which is in use; the compass's kernel
           set is module-wide, firmware.compass.use_kernels)
step() reads one sample and does a bounded amount of other work; True when it produced a
heading; it never raises. run(n, report, every, every_us) calls step() n times (None: forever).
calibrate() starts collecting now (e.g. after a new mounting).

Memory: a board that boots from a stored calibration imports only the driver, the
calibration record, the compass, the store and this module; firmware.calibrator (with the
sample buffer, the moment sums and the solver) is imported when collecting starts
(tests/test_layout.py checks which modules are loaded).

One step, as named steps (AN4246 / AN4248 pipeline):
  _clock    the app's time since the last step: aging and the timers below.
  _read     mag.read_into(raw) (+ accel): a bus error, a data-ready timeout, an overflow
            set .status and keep the last good heading (Hinch's fusion: "try to continue
            returning last good data"); reinit_after failures in a row re-initialise the
            drivers.
  _heading  correct (Calibration.k with InvW in Q15), map to the body frame, Compass.update:
            the heading (KANG) and its flags. Allocation-free (tests/scenarios/app_alloc.py).
  _check    the field against the calibration's (firmware/health.py FieldWatch): |B| and
            the dip in their windows, steady over the last samples, the heading not jumping;
            a flag starts a spell whose status lasts until the evidence says the field is
            clean again. Interference (a magnet, a motor, a steel table near the board)
            keeps the sample out of the fit; flags for _STALE_US mean the board's iron
            changed.
  _select   offer the raw sample to the collector (its SampleBuffer keeps new information).
  _solve    when a solve is running or due, a few slices of it: each slice is at most
            solve.SLICE_OPS (40) long-int operations (make bench estimates 1-2 ms on an
            RP2040), and a step runs period / 4 ms of them (at least one): 1 at 200 Hz, 5 at
            50 Hz - a quarter to half of the sample period on an RP2040 - so a solve (~400
            slices) takes ~2 s at any rate. Counted in slices, not time, so runs are
            repeatable on every interpreter. .worst_stall_us is the longest such step's
            solver work on the wall clock (never the simulated one).
  _accept   a calibration the Calibrator accepts (sour grapes: it must beat the current one,
            whose fit error ages) is put in force and saved to the store (.worst_save_us).

Interference. The field magnitude is compared with the calibration's field_out within
max(10 %, 3 x its fit error) - the fit's own RMS radial error is no evidence of a magnet -
and, with an accelerometer, the dip with the calibration's dip within max(3 deg, 3 x its
fit error as an angle): the dip saved with the record, else learned from its first 0.5 s of
steady clean samples (.dip, firmware/health.py DipCheck; an accepted fit is saved at once,
and once more with its dip when it is learned). A fast change of |B| or the dip (a magnet
moving in) is interference too, and a heading that jumps by > 4 deg between two samples
while the tilt holds still is "heading jumped". Any of these starts a spell (FieldWatch):
the status stays until the field is back where it was before, or the board has turned ~30
deg with clean samples for 2 s, or 10 s of clean samples (docs/faults.md). If the flags
keep coming for _STALE_US (a spell never ended meanwhile) the calibration no longer
describes the board (its hard iron changed): collection restarts (.relearning) and any new
accepted fit replaces the stale one.

Storage: load at start: the newest slot whose record is intact AND whose payload
Calibration.from_bytes accepts (the store skips a torn, unreadable or meaningless slot and
falls back to an older one); when none is usable, identity with the reason in .load_reason.
Save on every accept; a failed save (OSError, StoreError, MemoryError) is counted in
.save_errors, never stops the loop, and is retried every _SAVE_RETRY_US.

History (firmware.history, imported at the first accept): before an accepted calibration
replaces the one in force it is compared with the store's history of accepted calibrations.
Inside the limits, it is put in force, saved and, once saved, recorded. Outside, it is kept as evidence
(.pending, recorded as a pending entry) and NOT put in force: .status reads "hardware
changed?" (in place of ok or interference: the heading still uses the old calibration) and .change names the parameter as
(parameter, value, low, high). accept_change() puts it in force and starts a new baseline
(a new mounting); discard_change() drops it. A pending change lives in RAM: after a reboot
the old calibration is in force, the evidence is in the history, and the next fit that shows
the same jump is flagged again. .date_s: None, or a function returning the date in seconds
when the board knows it (e.g. after NTP), written with each entry. History errors are
counted in .history_errors (the last one in .history_reason) and never stop the loop.
"""
from array import array

from firmware.axes import AxisMap
from firmware.calibration import UNCALIBRATED, Calibration
from firmware import compass
from firmware.compass import FLAG_NO_GRAVITY, Compass
from firmware.compat import const, kernels, ticks_diff, ticks_us, sleep_us, wall_clock
from firmware.errors import SensorNotFound, SensorOverflow, StoreError, DataReadyTimeout
from firmware.health import SPELL_FIELD, SPELL_JUMP, FieldWatch, Health
from firmware import i2cdevice
from firmware.trig import cdeg_to_kang, kang_to_str

STATUS_OK = "ok"
STATUS_INTERFERENCE = "interference"  # a heading, but |field| is off: a magnet or steel near
STATUS_BUS_ERROR = "bus_error"        # NACK / EIO: the chip did not answer
STATUS_TIMEOUT = "timeout"            # no data-ready within the driver's bound
STATUS_OVERFLOW = "overflow"          # QMC5883L OVL, HMC5883L -4096: sample dropped
STATUS_NO_FIELD = "no_field"          # corrected field (0, 0, 0): no heading
STATUS_NO_GRAVITY = "no_gravity"      # accelerometer (0, 0, 0): asleep after a reset, or free fall
STATUS_STARTING = "starting"          # before the first step
STATUS_CHANGED = "hardware changed?"  # a new fit jumped outside its history's limits: pending
# field faults (firmware/health.py, docs/faults.md): user words, never "ok" while they last
STATUS_STALE = "stale data"           # the magnetometer repeats its last sample: no new data
STATUS_RESET = "sensor reset"         # its control registers no longer hold our configuration
STATUS_TILT = "tilt unavailable"      # the accelerometer is implausible: level-board heading
STATUS_INTERNAL = "internal error"    # step() caught an unexpected exception (e.g. MemoryError)
STATUS_JUMP = "heading jumped"        # it moved > 4 deg since the last sample: a magnet moving
#                                       in, or a turn too fast for the sample rate to follow

LOAD_BAD_PAYLOAD = "bad_payload"      # .load_reason: the record is intact, its payload is not
LOAD_IO_ERROR = "io_error"            # .load_reason: the filesystem raised OSError
LOAD_NO_MEMORY = "no_memory"          # .load_reason / .save_reason: MemoryError
REASON_SOLVER_ERROR = "solver_error"  # .last_reason: the solver raised something unexpected
REASON_NO_MEMORY = "no_memory"        # .last_reason: MemoryError during a solve

SOLVE_EVERY = const(25)       # kept samples between solves: ~1/9 of a full sphere (225 held)
REINIT_AFTER = const(5)       # failed reads in a row before the drivers are re-initialised
DEFAULT_CAPACITY = const(300)  # samples held while collecting (firmware.calibrator's default)
_REINIT_MAX_SHIFT = const(4)  # failed re-inits back off to every 2**4 x REINIT_AFTER reads
_STALE_US = const(30000000)   # 30 s of interference: the calibration no longer fits the board
_STALE_AGE_S = const(1200000)  # age that makes any fit error "worse" (> 16 doublings)
_SAVE_RETRY_US = const(60000000)  # a failed save is retried after 60 s
_ERROR_BACKOFF_US = const(20000)  # after a bus error: do not hammer a dead bus
_GOOD_FIT_ERROR = const(500)  # 5 %: a stored fit this good needs no collecting (MotionCal
#                               enables Send Cal below 5 %)
_FIELD_TOL_PCT = const(10)    # interference window floor, % (firmware.compass's default)
_FIELD_TOL_MAX_PCT = const(50)
_FIT_SIGMAS = const(3)        # window >= 3 x the fit's RMS radial error
_US_PER_S = const(1000000)
CONFIG_EVERY = const(1)       # samples between configuration read-backs (docs/faults.md)
_EVIDENCE_PERIODS = const(4)  # a step counts as at most 4 sample periods of evidence
_GAP_CAP_US = const(0x10000000)  # the time since the last read stops counting at 268 s
_ACCEL_RETRY_US = const(5000000)   # an accelerometer absent at boot is looked for every 5 s
_ACCEL_REINIT_EVERY = const(16)    # implausible accelerometer samples between its re-inits
_HMC_OVERFLOW = const(-4096)
_DEFAULT_PERIOD_US = const(20000)  # a driver without .period_us: assume 50 Hz
_QUIET_HINT_US = const(3000000)  # status_line: no new direction for 3 s before "planar"
REPORT_EVERY = const(25)      # run(): steps between reports (0.5 s at 50 Hz)


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
    """`with` block around the sensor reads: keeps the exception of a failed read (bus error,
    data-ready timeout, overflow) and lets the step go on. A `with` frame stays within the
    11 words MicroPython keeps on the C stack, where `except ... as e` would not. The drivers'
    unguarded sample_into() / config_matches() run inside it (one guard for the step's reads,
    not one more per driver call): .dev names the device being read, whose BusGuard maps a
    port's OSError to the BusError naming address and register, as the driver's own would."""

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


def _status_of(e):
    if isinstance(e, DataReadyTimeout):
        return STATUS_TIMEOUT
    if isinstance(e, SensorOverflow):
        return STATUS_OVERFLOW
    return STATUS_BUS_ERROR


def _collector_attr(name, default):
    # an app attribute that is the collector's (`default` while not collecting)
    return property(lambda self: getattr(self.collector, name) if self.collector is not None
                    else default)


class CompassApp:
    """See the module docstring. Attributes after each step(): heading_kang, compass, raw,
    body, gravity, status, calibration, calibrator (None until collecting), collector,
    last_reason, last_detail, accepted, refused, worst_stall_us, errors, stored,
    save_errors, load_reason, reinits, relearning, fast, pending, change, history_errors,
    location, quick, accuracy, watch (firmware/health.py FieldWatch), dip (its DipCheck)."""

    location = None  # a firmware.location.Location after set_location()
    quick = None     # the firmware.quickcal.QuickCal of the last quick_calibrate()

    def __init__(self, i2c, mag=None, accel=None, mag_axes="x,-y,-z", accel_axes="-x,y,z",
                 model=10, declination_cdeg=0, store=None, delay_us=None, ticks_us=None,
                 capacity=None, solve_every=SOLVE_EVERY, fallback=True,
                 reinit_after=REINIT_AFTER, mag_options=None, learn=None, fast=None):
        self.i2c = i2c
        self._mag_map = AxisMap(mag_axes)
        self._acc_map = AxisMap(accel_axes)
        self._check_options(model, declination_cdeg, solve_every, reinit_after)
        self._delay = delay_us if delay_us is not None else sleep_us
        self._ticks, self._wrap = self._app_clock(ticks_us)
        self._wall, self._wall_diff = wall_clock()
        self.mag, self.accel = self._sensors(i2c, mag, accel, mag_options, delay_us)
        self.model = model
        self.capacity = capacity if capacity else DEFAULT_CAPACITY
        self.solve_every = solve_every
        self.fallback = fallback
        self.reinit_after = reinit_after
        self.learn = learn

        kn = kernels() if fast is None or fast is True else None
        self.fast = kn is not None
        if kn is None:
            from firmware import axes, calibration
            self._correct = calibration.correct
            self._apply = axes.apply
        else:
            self._correct = kn.correct
            self._apply = kn.apply
        compass.use_kernels(kn or False)
        i2cdevice.use_kernels(kn or False)  # the drivers' decode

        self.raw = array("h", (0, 0, 0))       # the last sample, chip axes, counts
        self._cor = array("h", (0, 0, 0))      # corrected, sensor axes
        self.body = array("h", (0, 0, 0))      # corrected, body frame (AN4248)
        self._acc = array("h", (0, 0, 0))
        self.gravity = array("h", (0, 0, 0))   # body frame, AN4248 sign (+1 g down, level)
        self._guard = _ReadGuard()
        self._step_guard = _StepGuard()
        # the per-sample calls, looked up once: a driver's unguarded read where it has one
        # (inside the read guard), the axis maps' arrays
        self._mag_into = getattr(self.mag, "sample_into", None) or self.mag.read_into
        self._mm = self._mag_map.m
        self._am = self._acc_map.m
        self._accel_auto = accel is None    # detected: look again later when absent
        self.health = Health(self.mag.counts_per_gauss,
                             _HMC_OVERFLOW if self.mag.KIND == "hmc5883l" else -32768,
                             self.accel.counts_per_g if self.accel is not None else 16384)
        self._mag_cfg = (getattr(self.mag, "config_matches", None)
                         or getattr(self.mag, "config_ok", None))
        self.tilt = self.accel is not None  # False: the level formula (no or implausible accel)
        self._tilt_bad = 0
        self._since_cfg = 0
        self._cfg_due = True        # the first good sample reads the configuration back
        self.verify_every = CONFIG_EVERY
        self._accel_wait_us = 0
        self.accel_retries = 0
        self._ok = False
        self._cfg_ok = True
        self.heading_kang = -1
        self.status = STATUS_STARTING
        self.errors = {}
        self.last_error = None      # the exception behind the last failed read
        self.worst_stall_us = 0
        self.slices = 0             # solver slices run
        self.stored = 0
        self.save_errors = 0
        self.save_reason = None
        self.worst_save_us = 0
        self.reinits = 0
        self.reinit_failures = 0
        self.steps = 0
        self.pending = None         # a calibration whose parameters jumped (see History)
        self.change = None          # (parameter, value, low, high) of the jump
        self.history_errors = 0
        self.history_reason = None
        self._hist = None           # firmware.history.History, from the first accept on
        self._hist_flags = 0        # flags of the history entry due once the save succeeds

        self.store = store
        self.compass = Compass(declination_kang=cdeg_to_kang(declination_cdeg))
        self.watch = FieldWatch(self.compass, self.body)  # firmware/health.py
        self.dip = self.watch.dip   # the calibration's dip (DipCheck)
        self._dip_unsaved = False   # this app saved the fit in force before its dip was known
        self.collector = None
        self.calibration = None
        self._use(self._load())

        self._slices_per_step = 1
        self._fails = 0             # failed reads in a row
        self._reinit_level = 0
        self._t_last = self._ticks()
        self._dt = 0                # us since the previous step, capped: evidence, not time
        self._gap_us = 0            # us since the magnetometer was last read successfully
        self._stalled = False       # the last read came after a gap (a stall, bus errors)
        self._dt_cap = _EVIDENCE_PERIODS * getattr(self.mag, "period_us", _DEFAULT_PERIOD_US)
        self._age_us = 0
        self._interf_us = 0
        self._clean_us = 0
        self._unsaved = False
        self._save_wait_us = 0
        if learn or learn is None and not self._good_enough(self.calibration):
            self.calibrate()

    @staticmethod
    def _check_options(model, declination_cdeg, solve_every, reinit_after):
        if model not in ("minmax", 4, 7, 10, "auto"):
            raise ValueError("model=%r: expected 'minmax', 4, 7, 10 or 'auto'" % (model,))
        if type(declination_cdeg) is not int:
            raise TypeError("declination_cdeg=%r: expected an int in hundredths of a degree "
                            "(e.g. 150 for 1.5 deg east)" % (declination_cdeg,))
        if not -18000 <= declination_cdeg <= 18000:
            raise ValueError("declination_cdeg=%d: expected -18000..18000 hundredths of a "
                             "degree" % declination_cdeg)
        if type(solve_every) is not int or solve_every < 1:
            raise ValueError("solve_every=%r: expected an int >= 1 (kept samples)"
                             % (solve_every,))
        if type(reinit_after) is not int or reinit_after < 1:
            raise ValueError("reinit_after=%r: expected an int >= 1 (failed reads)"
                             % (reinit_after,))

    def _app_clock(self, clock):
        if self._mag_map.det != 1:
            raise ValueError("mag_axes %r is a mirror image: a magnetometer's map is a rotation "
                             "(chip and body frames are both right-handed)"
                             % (self._mag_map.spec,))
        if self._acc_map.det != -1:
            raise ValueError("accel_axes %r is a rotation: an accelerometer's map to AN4248's "
                             "gravity sign is a mirror (see firmware/axes.py)"
                             % (self._acc_map.spec,))
        if clock is None:
            if ticks_us is None:
                raise ValueError("ticks_us is needed off MicroPython (the simulator's clock)")
            return ticks_us, True  # the port's ticks_us wraps: compare with ticks_diff
        return clock, False

    @staticmethod
    def _sensors(i2c, mag, accel, mag_options, delay_us):
        if mag is None or accel is None:
            from firmware import detect
            if mag is None:
                opts = dict(mag_options or {})
                if delay_us is not None:
                    opts["delay_us"] = delay_us
                mag = detect.detect(i2c, **opts)
            if accel is None:
                accel = detect.detect_accel(i2c)
        return mag, (accel if accel else None)

    # --- storage ----------------------------------------------------------------------
    def _load(self):
        self.load_reason = None
        st = self.store
        if st is None:
            self.load_reason = "no_store"
            return UNCALIBRATED
        # records are tied to the sensor and its range: bind the store to the chip found
        st.sensor = self.mag.KIND
        st.range_code = self.mag.range_code
        # a record that is intact but means nothing valid is skipped like a torn one
        st.validate = Calibration.from_bytes
        try:
            return Calibration.from_bytes(st.load())
        except StoreError as e:
            self.load_reason = e.reason
        except ValueError:
            self.load_reason = LOAD_BAD_PAYLOAD
        except OSError:
            self.load_reason = LOAD_IO_ERROR
        except MemoryError:
            self.load_reason = LOAD_NO_MEMORY
        return UNCALIBRATED

    def _save(self, dip_only=False):
        # dip_only: the fit in force again, now with its dip (not counted in .stored)
        if self.store is None:
            return
        t = self._wall()
        try:
            self.store.save(self._record())
            if not dip_only:
                self.stored += 1
            self._dip_unsaved = not self.dip.armed
            self._unsaved = False
            self.save_reason = None
            if self._hist_flags and not dip_only:  # the history follows the store
                self._history_record(self.calibration, self._hist_flags)
                self._hist_flags = 0
        except StoreError as e:
            self._save_failed(e.reason)
        except OSError as e:
            self._save_failed("os_error %s" % (e.args[0] if e.args else "?"))
        except MemoryError:
            self._save_failed(LOAD_NO_MEMORY)
        except ValueError as e:  # a payload the store refuses: a bug, never a crash
            self._save_failed("bad_payload %s" % (e,))
        d = self._wall_diff(self._wall(), t)
        if d > self.worst_save_us:
            self.worst_save_us = d

    def _save_failed(self, reason):
        self._dip_unsaved = False  # the retry saves the record with the dip known then
        self.save_errors += 1
        self.save_reason = reason
        self._unsaved = True
        self._save_wait_us = 0

    # --- calibration in force ---------------------------------------------------------
    def _good_enough(self, cal):
        """A loaded calibration that makes collecting unnecessary: the configured model, fit
        within _GOOD_FIT_ERROR."""
        m = self.model
        return (cal.model is not None and cal.fit_error <= _GOOD_FIT_ERROR
                and (cal.model == m or m == "auto" and cal.model != "minmax"))

    def _use(self, cal):
        # another calibration: its dip (saved with it, else learned afresh), the short
        # averages and any spell start over (firmware/health.py FieldWatch.use)
        self.watch.use(cal)
        self.calibration = cal
        self._k = cal.k  # _heading's
        tol = _FIT_SIGMAS * cal.fit_error // 100
        if tol < _FIELD_TOL_PCT:
            tol = _FIELD_TOL_PCT
        elif tol > _FIELD_TOL_MAX_PCT:
            tol = _FIELD_TOL_MAX_PCT
        self.compass.set_field(cal.field_out if cal.model is not None else 0, tol)
        self._locate()

    def _dip_learned(self):
        # the dip reference is armed: a fit this app saved before it knew its dip (an
        # accepted fit, use_calibration, quick_calibrate) is saved again, once, with it; a
        # record loaded without one (made elsewhere or by older firmware) is not rewritten
        # at boot: its dip is learned at each boot
        if self._dip_unsaved and not self._unsaved:
            self._save(True)

    def _record(self):
        # the payload saved: the calibration in force with the dip it measures, when known
        c = self.calibration
        d = self.dip
        if d.armed and c.model is not None and c.dip_kang != d.ref:
            c = c.with_dip(d.ref)
        return c.to_bytes()

    def use_calibration(self, cal, save=True):
        """Put `cal` (a Calibration made outside the app, e.g. from MotionCal's packet by
        firmware/motioncal_mode.py) in force now, and save it to the store when `save`."""
        self._use(cal)
        if save:
            self._save()

    def calibrate(self):
        """Start collecting samples for a new calibration (imports the calibration machinery);
        the calibration in force stays until a better one is accepted."""
        if self.collector is None:
            from firmware import samples
            from firmware.calibrator import Collector
            samples.use_kernels(compass.KERNELS or False)  # the kernel set the app chose
            self.collector = Collector(model=self.model, capacity=self.capacity,
                                       counts_per_gauss=self.mag.counts_per_gauss,
                                       current=self.calibration, solve_every=self.solve_every,
                                       fallback=self.fallback)
            self._locate()
        return self.collector

    # --- where the board is (firmware/location.py, firmware/quickcal.py) ----------------
    def set_location(self, lat_e7, lon_e7, year_e3=None, table=None):
        """The board's place (1e-7 deg, north and east positive) and date (decimal year *
        1000, firmware.field.decimal_year_e3; None: unknown). With a usable field model the
        declination becomes the model's, a new fit's B is checked against the model's |B|
        (field_mismatch) and the interference window and dip come from the model
        (firmware/location.py). Returns the location's status: "ok", "no date", "caution
        zone", "blackout zone", or why the model cannot be used ("no field model: ...",
        "outside model validity") - then the declination given to the constructor stays.
        TypeError / ValueError name a bad argument and its unit. `table`: the table file
        (None: wmm2025.bin next to firmware/field.py)."""
        from firmware.location import Location
        loc = Location(lat_e7, lon_e7, year_e3, table)
        prev = self.location
        loc.manual_declination_kang = (prev.manual_declination_kang if prev is not None
                                       else self.compass.declination_kang)
        self.location = loc
        self._use(self.calibration)  # the window afresh, then the location applied
        return loc.status

    def _locate(self):
        if self.location is not None:
            self.location.apply(self)

    def quick_calibrate(self, true_heading_cdeg, refine=False, samples=32):
        """Hard iron from this pose and its known true heading (centidegrees, 0..35999,
        clockwise from true north) with the field model's field: reads `samples` samples
        (the board held still; tilt from the accelerometer, or level without one), puts the
        result in force and saves it (firmware/quickcal.py). refine=True adds this pose to
        those of the previous quick_calibrate() calls and averages them (poses at opposite
        headings cancel most soft-iron error). Returns the Calibration; raises
        CalibrationRejected (.reason: no_location, blackout_zone, no_samples,
        offset_out_of_range, field_mismatch) and keeps the calibration in force; TypeError
        / ValueError for bad arguments. Needs set_location() first."""
        from firmware.quickcal import QuickCal
        if type(true_heading_cdeg) is not int:
            raise TypeError("true_heading_cdeg=%r: expected an int in hundredths of a degree "
                            "(e.g. 9000 for east)" % (true_heading_cdeg,))
        if not 0 <= true_heading_cdeg < 36000:
            raise ValueError("true_heading_cdeg=%d: expected 0..35999 hundredths of a degree"
                             % true_heading_cdeg)
        if type(samples) is not int or not 1 <= samples <= 128:
            raise ValueError("samples=%r: expected an int in 1..128 (samples averaged)"
                             % (samples,))
        qc = self.quick
        if not refine or qc is None or qc.location is not self.location:
            qc = QuickCal(self.location, self.mag.counts_per_gauss, self._mag_map)
        n, raw, g = self._still_samples(samples)
        qc.add(raw, g, n, cdeg_to_kang(true_heading_cdeg))
        cal = qc.result()
        self.quick = qc
        self._use(cal)
        if self.collector is not None:
            self.collector.calibrator.current = cal  # a later full fit must beat it
        self._save()
        return cal

    def _still_samples(self, n):
        """Sum of n good raw samples (chip axes) and of their body gravity (None without an
        accelerometer), read through step(); at most 4n tries."""
        raw = [0, 0, 0]
        g = [0, 0, 0] if self.accel is not None else None
        k = 0
        tries = 0
        while k < n and tries < 4 * n:
            tries += 1
            if not self.step():
                continue
            k += 1
            for i in range(3):
                raw[i] += self.raw[i]
                if g is not None:
                    g[i] += self.gravity[i]
        return k, raw, g

    @property
    def accuracy(self):
        """Accuracy level 0..3, Android's meaning (firmware/accuracy.py has the table)."""
        from firmware.accuracy import assess
        return assess(self)[0]

    def accuracy_reason(self):
        """Why the accuracy level is what it is (a reason of firmware/accuracy.py's table)."""
        from firmware.accuracy import assess
        return assess(self)[1]

    # --- the loop ---------------------------------------------------------------------
    def step(self):
        """One sample and a bounded slice of background work; True if a heading came out.
        Never raises: an unexpected exception becomes the status "internal error"."""
        self.steps = (self.steps + 1) & 0x3FFFFFFF  # a small int for years at 200 Hz
        g = self._step_guard
        with g:
            self._step()
        if g.error is not None:
            self._internal(g.error)
        return self._ok

    def _step(self):
        self._ok = False
        self._clock()
        st = self._read()
        if st == STATUS_OK:
            st = self._vet()
        if st == STATUS_OK:
            st = self._heading()
        if st != STATUS_OK:
            self._failed(st)
        else:
            self._ok = True
            self._fails = 0
            self._reinit_level = 0
            if self._check():
                self._select()
            if not self.tilt and (self.accel is not None or self._accel_auto) \
                    and self.status == STATUS_OK:
                self._flag(STATUS_TILT)
        c = self.collector
        if c is not None and (c.job is not None or c.due()):
            self._solve()
        if self.pending is not None and (self.status == STATUS_OK
                                         or self.status == STATUS_INTERFERENCE):
            self.status = STATUS_CHANGED  # the likely cause of the interference, too

    def _internal(self, e):
        self._ok = False
        self.last_error = e
        self._flag(STATUS_INTERNAL)
        c = self.collector
        if c is not None and c.job is not None:
            c.job = None  # a solve that raised is abandoned (the next one starts afresh)

    def _flag(self, st):
        self.status = st
        self.errors[st] = self.errors.get(st, 0) + 1

    def _clock(self):
        now = self._ticks()
        if self._wrap:
            dt = ticks_diff(now, self._t_last)
        else:
            dt = now - self._t_last
        self._t_last = now
        if dt < 0:
            dt = 0
        if self._unsaved:
            self._retry_save(dt)
        if self.accel is None and self._accel_auto:
            self._look_for_accel(dt)
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

    def _look_for_accel(self, dt):
        self._accel_wait_us += dt
        if self._accel_wait_us < _ACCEL_RETRY_US:
            return
        self._accel_wait_us = 0
        self.accel_retries += 1
        try:
            from firmware import detect
            acc = detect.detect_accel(self.i2c)
        except OSError:
            acc = None
        if acc is not None:
            self.accel = acc
            self.health.set_accel(acc.counts_per_g)
            self.tilt = False  # until its first plausible sample

    def _read(self):
        g = self._guard
        acc = self.accel
        with g:
            g.dev = self.mag
            self._mag_into(self.raw)
            if acc is not None:
                g.dev = acc
                acc.sample_into(self._acc)
        if g.error is None:
            self._stalled = self._gap_us > self._dt_cap
            self._gap_us = 0
            return STATUS_OK
        self.last_error = g.error
        return _status_of(g.error)

    def _vet(self):
        """The sample's plausibility (firmware/health.py) and, every _CONFIG_EVERY samples or
        after an anomaly, the chip's configuration read back."""
        h = self.health
        if h.saturated(self.raw):
            return STATUS_OVERFLOW
        if h.mag_stale(self.raw, getattr(self.mag, "suspect", False)):
            return STATUS_STALE
        if self._stalled and getattr(self.mag, "suspect", False):
            # after a gap (a stall, a run of bus errors) a QMC5883L still holds the set that
            # followed the last read: DOR says later ones were skipped, so it is that old
            return STATUS_STALE
        if self.accel is not None:
            self._tilt_check()
        self._since_cfg += 1
        if (self._cfg_due or self._since_cfg >= self.verify_every
                or self.collector is not None):
            return self._verify()
        return STATUS_OK

    def _verify(self):
        self._since_cfg = 0
        self._cfg_due = False
        if self._mag_cfg is None:
            return STATUS_OK
        self._read_config()
        e = self._guard.error
        if e is not None:
            self.last_error = e
            return _status_of(e)
        return STATUS_OK if self._cfg_ok else STATUS_RESET

    def _read_config(self):
        self._cfg_ok = True
        g = self._guard
        with g:
            g.dev = self.mag
            self._cfg_ok = self._mag_cfg()

    def _tilt_check(self):
        if self.health.tilt_ok(self._acc):
            self.tilt = True
            self._tilt_bad = 0
            return
        self.tilt = False
        self._tilt_bad += 1
        if self._tilt_bad % _ACCEL_REINIT_EVERY == 1:
            self._wake_accel()

    def _wake_accel(self):
        # an MPU6050 asleep since a reset or a glitch write: its configure() wakes it
        g = self._guard
        with g:
            if not self.accel.config_ok():
                self.accel.configure()
                self.reinits += 1

    def _heading(self):
        self._correct(self._k, self.raw, self._cor)
        self._apply(self._mm, self._cor, self.body)
        if self.accel is None or not self.tilt:
            h = self.compass.update(self.body)
        else:
            self._apply(self._am, self._acc, self.gravity)
            h = self.compass.update(self.body, self.gravity)
        if h < 0:
            return STATUS_NO_GRAVITY if self.compass.flags & FLAG_NO_GRAVITY else STATUS_NO_FIELD
        self.heading_kang = h
        return STATUS_OK

    def _check(self):
        """Interference bookkeeping (firmware/health.py FieldWatch: the windows, the dip,
        shifts, jumps and the spell they start); True when the sample may go to the
        collector."""
        w = self.watch
        k = w.sample(self.tilt and self.accel is not None, self._dt)
        if k == SPELL_FIELD:
            return self._interfered()
        if w.spell:
            return self._spelled(k)
        self.status = STATUS_OK
        self._interf_us = 0
        if w.learned:
            self._dip_learned()
        return True

    def _spelled(self, k):
        # a spell: its status until the evidence says the field is clean. The collector
        # still takes the samples that raise no flag, and a jump's (a fast turn while
        # calibrating looks the same): a rough calibration in force must not stop the fit
        # that replaces it
        st = STATUS_JUMP if self.watch.spell == SPELL_JUMP else STATUS_INTERFERENCE
        if k:
            self._flag(st)
        else:
            self.status = st
        return self.relearning or k == 0 or k == SPELL_JUMP

    def _interfered(self):
        self._flag(STATUS_INTERFERENCE)
        self._cfg_due = True
        if self.relearning:
            return True  # the calibration in force is the one that does not fit
        self._interf_us += self._dt
        if self._interf_us >= _STALE_US:
            self._stale()
        return False

    def _select(self):
        # while collecting, _vet read the configuration back after every sample: no sample
        # taken at another gain or range reaches the fit
        if self.collector is not None:
            self.collector.feed(self.raw)

    def _failed(self, st):
        self._flag(st)
        w = self.watch
        w.restart()
        if st == STATUS_STALE:
            w.forget(self.health.same)  # a spell begun by this run of repeats: not a field
        self._cfg_due = True  # any anomaly: read the configuration back at the next sample
        if st == STATUS_OVERFLOW:
            return  # the chip answered; re-initialising would not move the magnet
        if st == STATUS_RESET:
            self._fails = self.reinit_after << self._reinit_level  # re-initialise now
        if st == STATUS_BUS_ERROR:
            self._delay(_ERROR_BACKOFF_US)
        self._fails += 1
        lvl = self._reinit_level
        if self._fails >= self.reinit_after << lvl:
            self._fails = 0
            if lvl < _REINIT_MAX_SHIFT:
                self._reinit_level = lvl + 1
            self.reinit()

    def _stale(self):
        # The flag has been up for _STALE_US: not a passing magnet but a board whose iron
        # changed. Collect afresh and let any new fit replace the stale one.
        self._interf_us = 0
        self.dip.reset()  # the dip too is learned afresh
        self.calibrate().relearn(_STALE_AGE_S)

    def reinit(self):
        """Re-initialise the drivers (a sensor reset by a brown-out powers up in standby):
        each driver re-applies its own configuration. Returns True when both answered; the
        app keeps whatever did."""
        ok = True
        acc = self.accel
        if acc is not None:
            try:
                acc.configure()
            except OSError as e:  # the magnetometer may still be reachable: go on
                ok = False
                self.last_error = e
        try:
            try:
                self.mag.configure()
            except OSError:
                if acc is None:
                    raise
                acc.enable_bypass()  # GY-87: a reset MPU6050 hides the magnetometer again
                self.mag.configure()
        except OSError as e:  # SensorNotFound, BusError, DataReadyTimeout: still not back
            ok = False
            self.last_error = e
        if ok:
            self.reinits += 1
        else:
            self.reinit_failures += 1
        self._cfg_due = True  # (the runs of repeats go on: a cured chip ends them itself)
        return ok

    # --- background solve -------------------------------------------------------------
    def _solve(self):
        t = self._wall()
        c = self.collector
        if c.job is None:
            self._slices_per_step = c.start(getattr(self.mag, "period_us", _DEFAULT_PERIOD_US))
        n = self._slices_per_step
        while n and c.job is not None:
            cal = c.slice()
            if cal is not None:
                self._accept(cal)
            n -= 1
        d = self._wall_diff(self._wall(), t)
        self.slices = (self.slices + 1) & 0x3FFFFFFF
        if d > self.worst_stall_us:
            self.worst_stall_us = d

    def _accept(self, cal):
        jump = self._history_check(cal)
        if jump is None:
            self._use(cal)
            if self._hist is not None:
                self._hist_flags = 1  # firmware.history.FLAG_ACCEPTED
            self._save()
        else:
            self.pending = cal
            self.change = jump
            self._history_record(cal, 2)  # FLAG_PENDING: evidence, not in force
            # the calibration in force may not fit the board: its samples keep refining the
            # evidence, as while relearning (firmware.calibrator.Collector.relearning)
            self.collector.relearning = True

    # --- history: a jump is not made current silently ------------------------------------
    def _history_check(self, cal):
        # -> None (in limits, or no history to judge by) or (parameter, value, low, high)
        try:
            if self._hist is None:
                if self.store is None or not hasattr(self.store, "prefix"):
                    return None
                from firmware.history import History
                self._hist = History(self.store)
            return self._hist.check(cal, self.calibration)
        except Exception as e:  # noqa: BLE001 - evidence only: never stop the loop for it
            self._history_failed(e)
        return None

    def _history_record(self, cal, flags):
        h = self._hist
        if h is None:
            return
        try:
            h.record(cal, flags, self.date_s() if self.date_s is not None else 0)
        except Exception as e:  # noqa: BLE001 - as above
            self._history_failed(e)

    def _history_failed(self, e):
        self.history_errors += 1
        self.history_reason = "%s %s" % (type(e).__name__, e.args[0] if e.args else "")

    date_s = None  # a function returning the date in seconds, when the board knows it

    def accept_change(self):
        """Put the pending calibration in force: the hardware did change (a new mounting, a
        new chip). It is saved and starts a new baseline of the history. False when none
        is pending."""
        cal = self.pending
        if cal is None:
            return False
        self.pending = None
        self.change = None
        self.collector.relearning = False
        self._use(cal)
        if self._hist is not None:
            self._hist_flags = 5  # FLAG_ACCEPTED | FLAG_BASELINE
        self._save()
        if self.status == STATUS_CHANGED:
            self.status = STATUS_OK
        return True

    def discard_change(self):
        """Drop the pending calibration: the one in force stays (the evidence stays in the
        history); new fits are again judged against it. False when none is pending."""
        if self.pending is None:
            return False
        self.pending = None
        self.change = None
        self.collector.relearning = False
        self.collector.calibrator.current = self.calibration
        if self.status == STATUS_CHANGED:
            self.status = STATUS_OK
        return True

    # --- reporting --------------------------------------------------------------------
    @property
    def calibrator(self):
        return self.collector.calibrator if self.collector is not None else None

    accepted = _collector_attr("accepted", 0)
    refused = _collector_attr("refused", 0)
    solves = _collector_attr("solves", 0)
    last_reason = _collector_attr("last_reason", None)
    last_detail = _collector_attr("last_detail", None)
    last_model = _collector_attr("last_model", None)
    relearning = _collector_attr("relearning", False)

    @property
    def solving(self):
        c = self.collector
        return c is not None and c.job is not None

    def coverage(self):
        """Percent of the sphere covered by the held samples (0 when not collecting)."""
        return self.collector.coverage() if self.collector is not None else 0

    def progress(self):
        c = self.calibration
        col = self.collector
        return {"coverage": self.coverage(),
                "samples": col.calibrator.count if col is not None else 0,
                "model": c.model, "fit_error": c.fit_error if c.model is not None else None,
                "last_reason": self.last_reason, "last_detail": self.last_detail,
                "accepted": self.accepted, "refused": self.refused,
                "collecting": col is not None, "solving": self.solving,
                "solve_model": col.job_model if self.solving else None,
                "status": self.status,
                "interference": self.compass.interference or self.status == STATUS_INTERFERENCE,
                "relearning": self.relearning, "stored": self.stored,
                "save_errors": self.save_errors, "load_reason": self.load_reason,
                "worst_stall_us": self.worst_stall_us, "change": self.change,
                "history_errors": self.history_errors}

    def run(self, n=None, report=None, every=REPORT_EVERY, every_us=None):
        """step() n times (None: forever); report(app) every `every` steps, or every
        `every_us` microseconds of the app's clock. Returns the steps with a heading."""
        good = 0
        i = 0
        last = self._ticks()
        while n is None or i < n:
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


def status_line(app):
    """One readable line: heading (marked when not tilt-compensated), status and flags, the
    calibration's stage in words (collecting with its coverage, solving, saved once,
    calibrated, and what to do when a fit is refused), accuracy, location."""
    p = app.progress()
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
    if app.relearning:
        parts.append("relearning")
    if app.save_errors:
        parts.append("save failed: %s" % app.save_reason)
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
