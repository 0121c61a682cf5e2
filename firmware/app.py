"""The compass app: detect, load the stored calibration, then read -> correct -> heading, while
the calibration improves in the background.

    from firmware.app import CompassApp, status_line
    app = CompassApp(i2c, store=CalStore("/"), declination_cdeg=150)
    app.run(None, report=lambda a: print(status_line(a)), every_us=500000)

CompassApp(i2c, mag=None, accel=None, mag_axes="x,-y,-z", accel_axes="-x,y,z", model=10,
           declination_cdeg=0, store=None, delay_us=None, ticks_us=None, capacity=None,
           solve_every=25, fallback=True, reinit_after=5, mag_options=None)
  mag      a magnetometer driver; None: firmware.sensors.detect(i2c, **mag_options)
  accel    an MPU6050 driver; None: sensors.detect_accel(i2c); False: none (level board)
  store    a firmware.calstore.CalStore (bound to the magnetometer's kind and range), or None
  delay_us the drivers' delay (the simulator's bus.sleep_us); None: time.sleep_us
  ticks_us the clock of the app's time (aging, timers): time.ticks_us on a board (wrapping,
           compared with ticks_diff), the simulator's clock on the host (plain ints)
  mag_options  driver options for detect() and for re-initialisation, e.g. {"range": 8}
  fallback     try 4 elements when the model lacks samples (see Solve policy)
  reinit_after failed reads in a row before the drivers are re-created
step() reads one sample and does a bounded amount of other work; True when it produced a
heading. run(n, report, every, every_us) calls step() n times (None: forever).

One step (AN4246 / AN4248 pipeline):
  read      mag.read_into(raw) (+ accel): a bus error, a data-ready timeout, an overflow
            set .status and keep the last good heading (STYLE: "try to continue returning
            last good data"); REINIT_AFTER failures in a row re-initialise the drivers.
  correct   calibration.correct(raw) (Q15), AxisMap to the body frame, Compass.update: the
            heading (KANG) and its flags. Allocation-free (tests/scenarios/app_alloc.py).
  feed      calibrator.add(raw) unless the field magnitude says interference: a magnet near
            the board would poison the fit (seed 004).
  solve     when a solve is running, a few slices of Calibrator.solve_steps(group=1) (NXP
            time-slices its solver the same way): each slice is at most solve.SLICE_OPS (40)
            long-int operations (make bench estimates 1-2 ms on an RP2040), and a step runs
            period / 4 ms of them (at least one): 1 at 200 Hz, 5 at 50 Hz, 16 at 15 Hz - a
            quarter to half of the sample period on an RP2040 - so a solve (~400 slices)
            takes ~2 s at any rate. Counted in slices, not measured time, so runs are
            repeatable on every interpreter.
            .worst_stall_us is the longest such step's solver work: the time the
            sample loop was held up by the solve, on the wall clock (time.ticks_us; CPython:
            perf_counter), never the simulated one, on which a solve takes no time. The
            data-ready wait is not a stall and not counted; a save is (.worst_save_us).
  accept    a calibration the Calibrator accepts (sour grapes: it must beat the current one,
            whose fit error ages with .age()) is put in force and saved to the store.

Solve policy. A solve starts when solve_every samples have been KEPT since the last one
started (the buffer keeps a sample only when it is new information, so this counts new
information, not time); or when samples were kept since then but none for _QUIET_US (the
user stopped moving: say now why it is not enough, e.g. "planar" after half a turn, rather
than wait for solve_every more); or when none ran for _SOLVE_IDLE_US and samples are held
(once the sphere is covered almost nothing is kept, yet aging can make a fit on the same
samples acceptable). solve_every = 25: a covered sphere holds ~225 samples, so about nine
solves while the user fills it, each ~2 s - the fit follows the
user without solving all the time. The configured model is tried; while no calibration of
4 elements or more is in force (or while relearning), a refusal for too_few_samples is
followed by a 4-element attempt: hard iron is the largest error (seed 004) and a 4-element
fit needs 40 samples where 10 elements need 100, so the user gets a usable heading early;
the Calibrator's own rule then lets the 10-element fit replace it (lower fit error, or
<= 3.5 % for a higher model, NXP). Once a 4-element fit is in force the fallback stops, so
.last_reason keeps saying what the configured model still lacks.

Interference. The field magnitude is compared with the calibration's field_out within
max(10 %, 3 x its fit error) - the fit's own RMS radial error is no evidence of a magnet. If
the flag stays up for _STALE_US (with no _CLEAN_US clean spell) the calibration no longer
describes the board (its hard iron changed): the samples are cleared, the current
calibration is aged out so that a new fit can replace it, and samples are fed until one is
accepted (.relearning).

Storage: load at start (StoreError or a payload Calibration.from_bytes refuses -> identity,
reason in .load_reason); save on every accept; a failed save (OSError, StoreError) is
counted in .save_errors, never stops the loop, and is retried every _SAVE_RETRY_US.
"""
import time
from array import array

from firmware import sensors
from firmware.axes import AxisMap
from firmware.fixedpoint import micropython
from firmware.errors import (CalibrationRejected, DataReadyTimeout, SensorNotFound,
                             SensorOverflow, StoreError)
from firmware.heading import FLAG_NO_GRAVITY, Compass, cdeg_to_kang, kang_to_str
from firmware.magcal import (DEFAULT_CAPACITY, REASON_TOO_FEW_SAMPLES, UNCALIBRATED,
                             Calibration, Calibrator)

try:
    from micropython import const
except ImportError:  # CPython
    def const(x):
        return x

try:
    _ticks_us = time.ticks_us
    _ticks_diff = time.ticks_diff
except AttributeError:  # CPython: only the wall clock for stall figures
    _ticks_us = None
    _ticks_diff = None
try:
    _sleep_us = time.sleep_us
except AttributeError:
    _sleep_us = None

STATUS_OK = "ok"
STATUS_INTERFERENCE = "interference"  # a heading, but |field| is off: a magnet or steel near
STATUS_BUS_ERROR = "bus_error"        # NACK / EIO: the chip did not answer
STATUS_TIMEOUT = "timeout"            # no data-ready within the driver's bound
STATUS_OVERFLOW = "overflow"          # QMC5883L OVL, HMC5883L -4096: sample dropped
STATUS_NO_FIELD = "no_field"          # corrected field (0, 0, 0): no heading
STATUS_NO_GRAVITY = "no_gravity"      # accelerometer (0, 0, 0): asleep after a reset, or free fall
STATUS_STARTING = "starting"          # before the first step

LOAD_BAD_PAYLOAD = "bad_payload"      # .load_reason: the record is intact, its payload is not
LOAD_IO_ERROR = "io_error"            # .load_reason: the filesystem raised OSError
REASON_SOLVER_ERROR = "solver_error"  # .last_reason: the solver raised something unexpected
REASON_NO_MEMORY = "no_memory"        # .last_reason: MemoryError during a solve

SOLVE_EVERY = const(25)       # kept samples between solves: ~1/9 of a full sphere (225 held)
REINIT_AFTER = const(5)       # failed reads in a row before the drivers are re-initialised
_REINIT_MAX_SHIFT = const(4)  # failed re-inits back off to every 2**4 x REINIT_AFTER reads
_SOLVE_IDLE_US = const(60000000)   # 60 s without a solve: solve again on what is held
_QUIET_US = const(3000000)    # 3 s without a kept sample after some were kept: solve now
_STALE_US = const(30000000)   # 30 s of interference: the calibration no longer fits the board
_CLEAN_US = const(2000000)    # 2 s without interference ends an interference spell
_STALE_AGE_S = const(1200000)  # age that makes any fit error "worse" (> 16 doublings)
_SAVE_RETRY_US = const(60000000)  # a failed save is retried after 60 s
_ERROR_BACKOFF_US = const(20000)  # after a bus error: do not hammer a dead bus
_FIELD_TOL_PCT = const(10)    # interference window floor, % (heading.Compass's default)
_FIELD_TOL_MAX_PCT = const(50)
_FIT_SIGMAS = const(3)        # window >= 3 x the fit's RMS radial error
_US_PER_S = const(1000000)
REPORT_EVERY = const(25)      # run(): steps between reports (0.5 s at 50 Hz)

# Range option of each magnetometer by range code, to re-create a driver after a reset
# (the drivers' own tables: qmc5883l.py, qmc5883p.py; hmc5883l's gain IS its code).
_RANGE_OPTION = {"qmc5883l": ("range", (2, 8)), "qmc5883p": ("range", (30, 12, 8, 2)),
                 "hmc5883l": ("gain", (0, 1, 2, 3, 4, 5, 6, 7))}
_ACCEL_RANGE = {16384: 2, 8192: 4, 4096: 8, 2048: 16}  # MPU6050 counts/g -> accel_range


_SLICE_US = const(1000)        # budget per solver slice (make bench: ~1-2 ms on an RP2040)
_SOLVE_SHARE = const(4)        # slices per step = period / (4 x _SLICE_US), at least one
_DEFAULT_PERIOD_US = const(20000)  # a driver without .period_us: assume 50 Hz


def _sub(a, b):
    return a - b


def _wall_clock():
    if _ticks_us is not None:
        return _ticks_us, _ticks_diff
    return (lambda: time.perf_counter_ns() // 1000), _sub  # CPython: stalls only


def _no_delay(us):
    pass


class CompassApp:
    """See the module docstring. Attributes after each step(): heading_kang, compass, raw,
    body, gravity, status, calibration, calibrator, last_reason, last_detail, accepted,
    refused, worst_stall_us, errors, stored, save_errors, load_reason, reinits, relearning."""

    def __init__(self, i2c, mag=None, accel=None, mag_axes="x,-y,-z", accel_axes="-x,y,z",
                 model=10, declination_cdeg=0, store=None, delay_us=None, ticks_us=None,
                 capacity=None, solve_every=SOLVE_EVERY, fallback=True,
                 reinit_after=REINIT_AFTER, mag_options=None):
        self.i2c = i2c
        self._mag_map = AxisMap(mag_axes)
        self._acc_map = AxisMap(accel_axes)
        if self._mag_map.det != 1:
            raise ValueError("mag_axes %r is a mirror image: a magnetometer's map is a rotation "
                             "(chip and body frames are both right-handed)" % (mag_axes,))
        if self._acc_map.det != -1:
            raise ValueError("accel_axes %r is a rotation: an accelerometer's map to AN4248's "
                             "gravity sign is a mirror (see firmware/axes.py)" % (accel_axes,))
        if solve_every < 1 or reinit_after < 1:
            raise ValueError("solve_every and reinit_after must be >= 1")
        self._delay_opt = delay_us
        self._delay = delay_us if delay_us is not None else (_sleep_us or _no_delay)
        if ticks_us is None:
            if _ticks_us is None:
                raise ValueError("ticks_us is needed off MicroPython (the simulator's clock)")
            ticks_us = _ticks_us
        self._ticks = ticks_us
        self._wrap = ticks_us is _ticks_us  # time.ticks_us wraps: compare with ticks_diff
        self._wall, self._wall_diff = _wall_clock()
        self._mag_options = dict(mag_options or {})
        if mag is None:
            opts = dict(self._mag_options)
            if delay_us is not None:
                opts["delay_us"] = delay_us
            mag = sensors.detect(i2c, **opts)
        if accel is None:
            accel = sensors.detect_accel(i2c)
        self.mag = mag
        self.accel = accel if accel else None
        self.model = model
        self.solve_every = solve_every
        self.fallback = fallback
        self.reinit_after = reinit_after

        self.raw = array("h", (0, 0, 0))       # the last sample, chip axes, counts
        self._cor = array("h", (0, 0, 0))      # corrected, sensor axes
        self.body = array("h", (0, 0, 0))      # corrected, body frame (AN4248)
        self._acc = array("h", (0, 0, 0))
        self.gravity = array("h", (0, 0, 0))   # body frame, AN4248 sign (+1 g down, level)
        self.heading_kang = -1
        self.status = STATUS_STARTING
        self.errors = {}
        self.last_error = None      # the exception behind the last failed read
        self.accepted = 0
        self.refused = 0
        self.last_reason = None
        self.last_detail = None
        self.last_model = None      # the model of the last solve attempt
        self.worst_stall_us = 0
        self.slices = 0             # solver slices run
        self.solves = 0             # solves started
        self.stored = 0
        self.save_errors = 0
        self.save_reason = None
        self.worst_save_us = 0
        self.reinits = 0
        self.reinit_failures = 0
        self.relearning = False
        self.steps = 0

        self.store = store
        cal = self._load()
        self.calibration = cal
        self.calibrator = Calibrator(model=model,
                                     capacity=capacity if capacity else DEFAULT_CAPACITY,
                                     counts_per_gauss=mag.counts_per_gauss, current=cal)
        self.compass = Compass(declination_kang=cdeg_to_kang(declination_cdeg))
        self._use(cal)

        self._job = None
        self._job_model = None
        self._slices_per_step = 1
        self._next_model = None     # a fallback model to try at the next slice
        self._kept = 0              # samples kept since the last solve started
        self._fails = 0             # failed reads in a row
        self._reinit_level = 0
        self._t_last = ticks_us()
        self._dt = 0                # us since the previous step
        self._age_us = 0
        self._idle_us = 0
        self._quiet_us = 0          # us since the last kept sample (while _kept > 0)
        self._interf_us = 0
        self._clean_us = 0
        self._unsaved = False
        self._save_wait_us = 0
        self._cov = 0
        self._cov_dirty = True

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
        try:
            return Calibration.from_bytes(st.load())
        except StoreError as e:
            self.load_reason = e.reason
        except ValueError:
            self.load_reason = LOAD_BAD_PAYLOAD
        except OSError:
            self.load_reason = LOAD_IO_ERROR
        return UNCALIBRATED

    def _save(self):
        if self.store is None:
            return
        t = self._wall()
        try:
            self.store.save(self.calibration.to_bytes())
            self.stored += 1
            self._unsaved = False
            self.save_reason = None
        except StoreError as e:
            self._save_failed(e.reason)
        except OSError as e:
            self._save_failed("os_error %s" % (e.args[0] if e.args else "?"))
        d = self._wall_diff(self._wall(), t)
        if d > self.worst_save_us:
            self.worst_save_us = d

    def _save_failed(self, reason):
        self.save_errors += 1
        self.save_reason = reason
        self._unsaved = True
        self._save_wait_us = 0

    # --- calibration in force ---------------------------------------------------------
    def _use(self, cal):
        self.calibration = cal
        tol = _FIT_SIGMAS * cal.fit_error // 100
        if tol < _FIELD_TOL_PCT:
            tol = _FIELD_TOL_PCT
        elif tol > _FIELD_TOL_MAX_PCT:
            tol = _FIELD_TOL_MAX_PCT
        self.compass.set_field(cal.field_out if cal.model is not None else 0, tol)

    # --- the loop ---------------------------------------------------------------------
    def step(self):
        """One sample and a bounded slice of background work; True if a heading came out."""
        self.steps = (self.steps + 1) & 0x3FFFFFFF  # a small int for years at 200 Hz
        self._clock()
        ok = self._sample()
        if self._job is not None or self._due():
            self._slice()
        return ok

    def _clock(self):
        now = self._ticks()
        if self._wrap:
            dt = _ticks_diff(now, self._t_last)
        else:
            dt = now - self._t_last
        self._t_last = now
        if dt < 0:
            dt = 0
        self._dt = dt
        a = self._age_us + dt
        if a >= _US_PER_S:
            self._age(a)
        else:
            self._age_us = a
        if self._idle_us < _SOLVE_IDLE_US:
            self._idle_us += dt
        if self._kept and self._quiet_us < _QUIET_US:
            self._quiet_us += dt
        if self._unsaved:
            self._save_wait_us += dt
            if self._save_wait_us >= _SAVE_RETRY_US:
                self._save()
                self._save_wait_us = 0

    def _age(self, a):
        s = a // _US_PER_S
        self.calibrator.age(s)  # NXP: the current fit error ages, so it can be replaced
        self._age_us = a - s * _US_PER_S

    def _sample(self):
        st = self._read()
        if st != STATUS_OK:
            self._failed(st)
            return False
        self.calibration.correct(self.raw, self._cor)
        self._mag_map.apply(self._cor, self.body)
        if self.accel is None:
            h = self.compass.update(self.body)
        else:
            self._acc_map.apply(self._acc, self.gravity)
            h = self.compass.update(self.body, self.gravity)
        if h < 0:
            self._failed(STATUS_NO_GRAVITY if self.compass.flags & FLAG_NO_GRAVITY
                         else STATUS_NO_FIELD)
            return False
        self.heading_kang = h
        self._fails = 0
        self._reinit_level = 0
        if self.compass.interference:
            self._interfered()
        else:
            self.status = STATUS_OK
            self._clean()
            self._feed()
        return True

    @micropython.native
    def _read(self):
        # Native: a bytecode frame with try/except would exceed the 11 words MicroPython keeps
        # on the C stack and come from the heap on every sample (tests/scenarios/app_alloc.py).
        try:
            self.mag.read_into(self.raw)
            if self.accel is not None:
                self.accel.read_accel_into(self._acc)
        except DataReadyTimeout as e:
            self.last_error = e
            return STATUS_TIMEOUT
        except SensorOverflow as e:
            self.last_error = e
            return STATUS_OVERFLOW
        except OSError as e:
            self.last_error = e
            return STATUS_BUS_ERROR
        return STATUS_OK

    def _feed(self):
        r = self.raw
        if self.calibrator.add(r[0], r[1], r[2]):
            self._kept += 1
            self._quiet_us = 0
            self._cov_dirty = True

    def _failed(self, st):
        self.status = st
        self.errors[st] = self.errors.get(st, 0) + 1
        if st == STATUS_OVERFLOW:
            return  # the chip answered; re-initialising would not move the magnet
        if st == STATUS_BUS_ERROR:
            self._delay(_ERROR_BACKOFF_US)
        self._fails += 1
        lvl = self._reinit_level
        if self._fails >= self.reinit_after << lvl:
            self._fails = 0
            if lvl < _REINIT_MAX_SHIFT:
                self._reinit_level = lvl + 1
            self.reinit()

    def _interfered(self):
        self.status = STATUS_INTERFERENCE
        self.errors[STATUS_INTERFERENCE] = self.errors.get(STATUS_INTERFERENCE, 0) + 1
        self._clean_us = 0
        if self.relearning:
            self._feed()  # the calibration in force is the one that does not fit
            return
        self._interf_us += self._dt
        if self._interf_us >= _STALE_US:
            self._stale()

    def _clean(self):
        if self._interf_us:
            self._clean_us += self._dt
            if self._clean_us >= _CLEAN_US:
                self._interf_us = 0
                self._clean_us = 0

    def _stale(self):
        # The flag has been up for _STALE_US: not a passing magnet but a board whose iron
        # changed. Collect afresh and let any new fit replace the stale one.
        self.relearning = True
        self._interf_us = 0
        self._job = None
        self.calibrator.clear()
        self.calibrator.age(_STALE_AGE_S)
        self._cov_dirty = True

    def reinit(self):
        """Re-create the drivers (a sensor reset by a brown-out powers up in standby).
        Returns True when both answered; the app keeps whatever did."""
        ok = True
        acc = self.accel
        if acc is not None:
            try:
                from firmware.mpu6050 import MPU6050
                acc = MPU6050(self.i2c, address=acc.address,
                              accel_range=_ACCEL_RANGE.get(acc.counts_per_g, 2))
                self.accel = acc
            except OSError as e:  # the magnetometer may still be reachable: go on
                ok = False
                self.last_error = e
        try:
            try:
                mag = self._new_mag()
            except SensorNotFound:
                if acc is None:
                    raise
                acc.enable_bypass()  # GY-87: a reset MPU6050 hides the magnetometer again
                mag = self._new_mag()
            if mag.range_code != self.mag.range_code:  # the calibration would not apply
                raise SensorNotFound("0x%02X came back at range code %d, not %d"
                                     % (mag.address, mag.range_code, self.mag.range_code))
            self.mag = mag
        except OSError as e:  # SensorNotFound, BusError, DataReadyTimeout: still not back
            ok = False
            self.last_error = e
        if ok:
            self.reinits += 1
        else:
            self.reinit_failures += 1
        return ok

    def _new_mag(self):
        old = self.mag
        opts = dict(self._mag_options)
        ro = _RANGE_OPTION.get(old.KIND)
        if ro is not None and ro[0] not in opts and old.range_code < len(ro[1]):
            opts[ro[0]] = ro[1][old.range_code]
        if self._delay_opt is not None:
            opts["delay_us"] = self._delay_opt
        opts["timeout_us"] = old.timeout_us
        return type(old)(self.i2c, address=old.address, **opts)

    # --- background solve -------------------------------------------------------------
    def _due(self):
        if self._kept >= self.solve_every or self._next_model is not None:
            return True
        if self._quiet_us >= _QUIET_US:
            return True
        return self._idle_us >= _SOLVE_IDLE_US and self.calibrator.count > 0

    def _slice(self):
        t = self._wall()
        if self._job is None:
            self._start()
        n = self._slices_per_step
        while n and self._job is not None:
            self._advance()
            n -= 1
        d = self._wall_diff(self._wall(), t)
        self.slices = (self.slices + 1) & 0x3FFFFFFF
        if d > self.worst_stall_us:
            self.worst_stall_us = d

    def _start(self):
        m = self._next_model
        self._next_model = None
        if m is None:
            m = self.model
        self._kept = 0
        self._quiet_us = 0
        self._idle_us = 0
        self.solves += 1
        self._job_model = m
        self.last_model = m
        self._job = self.calibrator.solve_steps(m, group=1)
        period = getattr(self.mag, "period_us", _DEFAULT_PERIOD_US)
        n = period // (_SOLVE_SHARE * _SLICE_US)
        self._slices_per_step = n if n > 0 else 1

    def _advance(self):
        try:
            next(self._job)
            return
        except StopIteration as e:
            cal = e.value
        except CalibrationRejected as e:
            self._job = None
            self._refused(e.reason, e.detail)
            return
        except MemoryError:
            self._job = None
            self._refused(REASON_NO_MEMORY, "heap exhausted during the solve")
            return
        except Exception as e:  # noqa: BLE001 - the sample loop must outlive a solver bug
            self._job = None
            self._refused(REASON_SOLVER_ERROR, repr(e))
            return
        self._job = None
        self._idle_us = 0
        self.accepted += 1
        self.relearning = False
        self.last_reason = None  # refusals before an acceptance are no longer news
        self.last_detail = None
        self._use(cal)
        self._save()

    def _refused(self, reason, detail):
        self.refused += 1
        self._idle_us = 0
        m = self._job_model
        cur = self.calibration.model
        if reason == REASON_TOO_FEW_SAMPLES:
            if (m in (7, 10) and self.fallback
                    and (cur is None or cur == "minmax" or self.relearning)):
                self._next_model = 4
            elif m == 4 and self.last_reason == REASON_TOO_FEW_SAMPLES:
                return  # keep the configured model's message: it says what is needed
        self.last_reason = reason
        self.last_detail = detail

    # --- reporting --------------------------------------------------------------------
    def coverage(self):
        """Percent of the sphere covered by the held samples (cached until one is kept)."""
        if self._cov_dirty:
            self._cov = self.calibrator.coverage()
            self._cov_dirty = False
        return self._cov

    def progress(self):
        c = self.calibration
        return {"coverage": self.coverage(), "samples": self.calibrator.count,
                "model": c.model, "fit_error": c.fit_error if c.model is not None else None,
                "last_reason": self.last_reason, "last_detail": self.last_detail,
                "accepted": self.accepted, "refused": self.refused,
                "solving": self._job is not None, "solve_model": self._job_model
                if self._job is not None else None, "status": self.status,
                "interference": self.compass.interference, "relearning": self.relearning,
                "stored": self.stored, "save_errors": self.save_errors,
                "load_reason": self.load_reason, "worst_stall_us": self.worst_stall_us}

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
                if (_ticks_diff(now, last) if self._wrap else now - last) >= every_us:
                    last = now
                    report(self)
            elif i % every == 0:
                report(self)
        return good


def _pct(x100):
    return "%d.%02d %%" % (x100 // 100, x100 % 100)


def status_line(app):
    """One readable line: heading, status and flags, calibration, progress, last refusal."""
    p = app.progress()
    h = app.heading_kang
    parts = ["heading %s deg" % ("---.-" if h < 0 else kang_to_str(h)), app.status]
    c = app.compass
    flags = [n for n, f in (("interference", c.interference), ("dip>75", c.dip_high),
                            ("pitch>80", c.gimbal)) if f]
    if flags:
        parts.append("flags " + ",".join(flags))
    if p["model"] is None:
        parts.append("uncalibrated")
    else:
        parts.append("model %s fit %s" % (p["model"], _pct(p["fit_error"])))
    parts.append("coverage %d %% samples %d" % (p["coverage"], p["samples"]))
    if p["solving"]:
        parts.append("solving %s" % (p["solve_model"],))
    if app.relearning:
        parts.append("relearning")
    if p["last_reason"]:
        parts.append("last refusal: %s" % p["last_reason"])
    if app.save_errors:
        parts.append("save failed: %s" % app.save_reason)
    return " | ".join(parts)
