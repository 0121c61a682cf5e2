"""The calibration program: run alone after a start, it calibrates, saves, reads back and
returns; boards/main.py then restarts the board into the heading (docs/calibration.md)."""
#     from firmware.calibrate.program import Program
#     p = Program(i2c, "/", mag_axes="x,-y,-z", accel_axes="-x,y,z")
#     cal = p.run()   # a progress line every 0.5 s; the saved Calibration, or None (p.reason)
#
# A sample is checked (firmware/health.py) and offered to the collector (calibrator.py);
# while a solve runs, sampling pauses and the drivers are let go. A fit meets the acceptance
# gate, the history's limits and the mounting check; a good one is saved power-safely and read
# back. Never raises for the hardware or the heap (docs/design.md, the calibration program).
import gc
from array import array

from firmware.calibrate.calibrator import Collector, release_solver
from firmware.calibration import GOOD_FIT_ERROR, STALE_AGE_S, UNCALIBRATED, Calibration
from firmware.compat import const, drop, free_bytes, ticks_diff, ticks_us
from firmware.health import Health
from firmware.i2cdevice import DEFAULT_PERIOD_US

_REINIT_AFTER = const(8)      # failed reads in a row before the chip is set up again
_SAVE_TRIES = const(3)        # saves of one fit before the program says it cannot keep it
_DONE_AFTER_US = const(4000000)  # ... or no better fit for 4 s: the heading within 5 s
_SHORT_GIVE_UP = const(3)  # solves or steps in a row short of heap: the program gives up


class Program:
    # See docs/design.md, module notes. Attributes: mag, accel, store, collector, status,
    # reason (why run() returned None), samples, bad (samples refused by the checks), reinits,
    # saved (the Calibration saved and read back), saved_us, save_errors, short (solves in a
    # row without room), free_at_solve, mounting ((verdict, MAG_AXES) or None).

    def __init__(self, i2c, store_dir, mag_axes="x,-y,-z", accel_axes="-x,y,z", model=10,
                 capacity=300, mag=None, accel=None, fs=None, ticks_us_=None, delay_us=None,
                 report=None, every_us=500000, mag_options=None, renew=False):
        from firmware.axes import AxisMap
        from firmware.store import CalStore
        if model not in (4, 7, 10):
            raise ValueError("model=%r: expected 4, 7 or 10" % (model,))
        self._mag_map = AxisMap(mag_axes)
        self._acc_map = AxisMap(accel_axes)
        self.i2c = i2c
        self._opts = opts = dict(mag_options or {})
        if delay_us is not None:
            opts["delay_us"] = delay_us
        self._found = mag is None  # found here: let go during each solve, found again after
        if mag is None:
            self._sensors()
        else:
            self._use_sensors(mag, accel)
        mag = self.mag
        accel = self.accel
        self.cpg = mag.counts_per_gauss
        self.model = model
        self.report = report if report is not None else print
        self.every_us = every_us
        self._ticks = ticks_us_ if ticks_us_ is not None else ticks_us
        self._delay = delay_us
        self.store = CalStore(store_dir, sensor=mag.KIND, range_code=mag.range_code, fs=fs,
                              validate=Calibration.from_bytes)
        self.current = self._stored()
        self.health = Health(mag.counts_per_gauss,
                             getattr(mag, "OVERFLOW", -32768),  # HMC5883L: -4096
                             accel.counts_per_g if accel is not None else 16384)
        self.collector = c = Collector(model=model, capacity=capacity,
                                       counts_per_gauss=mag.counts_per_gauss,
                                       current=self.current,
                                       overflow=getattr(mag, "OVERFLOW", None))
        if renew:  # asked for: the stored fit is aged so that any good one replaces it
            c.calibrator.age(STALE_AGE_S)
        self.period_us = getattr(mag, "period_us", DEFAULT_PERIOD_US)
        if accel is not None:  # the mounting check's pairs (firmware/calibrate/mounting.py)
            from firmware.calibrate.mounting import Pairs
            c.pairs = Pairs(accel.counts_per_g, self.period_us)
        self.raw = array("h", (0, 0, 0))
        self._acc = array("h", (0, 0, 0))
        self.status = "collecting"
        self.reason = None
        self.samples = 0
        self.bad = 0
        self.reinits = 0
        self.solves = 0
        self.saved = None
        self.saved_us = None       # the program's clock at the last save
        self.save_errors = 0
        self.mounting = None
        self._axes_status = None
        self._fails = 0
        self._tilt = False
        self._due = None
        self.short = 0
        self.free_at_solve = None
        self._since_save = 0
        self._hist = None
        self._t = self._ticks()
        self._since_report = 0

    def _sensors(self):
        from firmware import detect
        mag = detect.detect(self.i2c, **self._opts)
        self._use_sensors(mag, detect.detect_accel(self.i2c))
        detect = None
        drop("detect", "devinit")

    def _use_sensors(self, mag, accel):
        self.mag = mag
        self.accel = accel
        self._read = getattr(mag, "sample_into", None) or mag.read_into
        self._cfg = getattr(mag, "config_matches", None) or getattr(mag, "config_ok", None)

    def _pause(self):
        # a wait as long as a sample's before the chips are looked for again
        if self._delay is not None:
            self._delay(self.period_us)
        else:
            from firmware.compat import sleep_us
            sleep_us(self.period_us)

    def _let_go(self):
        # the drivers and their code while a solve runs: found again after it (the chips
        # set up afresh: a few milliseconds on the bus)
        self.mag = self.accel = self._read = self._cfg = None
        drop("qmc5883l", "hmc5883l", "qmc5883p", "mpu6050", "i2cdevice")

    def _stored(self):
        # the calibration in force before this program: a new fit must beat it (sour grapes)
        try:
            return Calibration.from_bytes(self.store.load())
        except Exception:  # noqa: BLE001 - none, torn, unreadable, no room: nothing to beat
            return UNCALIBRATED
        finally:
            drop("store_slots")  # the store's slot code: again for the save

    def done(self):
        """True once a good-enough fit is saved and read back, and no better one came for
        _DONE_AFTER_US or the board stopped bringing new directions (as a CompassApp's
        session ends: firmware/calibrate/session.py)."""
        c = self.collector
        return (self.saved is not None and c.job is None
                and (not c.kept and c.since_kept_us >= c.QUIET_US
                     or self._since_save >= _DONE_AFTER_US))

    def run(self, limit_s=None):
        """Collect, solve, accept and save until a good-enough fit is kept; None (with
        .reason) when limit_s seconds passed or the heap cannot hold a solve (.short).
        Returns the saved Calibration."""
        left = limit_s * 1000000 if limit_s is not None else None
        while not self.done() and self.short < _SHORT_GIVE_UP:
            dt = self.step()
            if left is not None:
                left -= dt
                if left <= 0:
                    self.reason = "time"
                    break
        if self.short >= _SHORT_GIVE_UP:
            self.reason = "out of memory"
        self.line()
        return self.saved if self.done() else None

    def step(self):
        """One sample (and a solve when one is due); the microseconds it took. Never raises
        MemoryError: a step short of heap is counted (.short, in a row) and tried again."""
        c = self.collector
        try:
            n = c.solves
            dt = self._step()
            if c.solves != n:  # a solve ran: did it have room?
                self.short = self.short + 1 if c.last_reason == "no_memory" else 0
            return dt
        except MemoryError:
            self.short += 1
            self.reason = "out of memory"
            self.status = "collecting"
            gc.collect()
            return 0

    def _step(self):
        if self.mag is None:  # found again after a solve that left no room for it, or lost
            try:
                self._sensors()
                self.reason = None
            except OSError as e:  # SensorNotFound, BusError: wiring or power; said, retried
                self.reason = "no sensor: %s" % e
                self.bad += 1
                self._pause()
                return 0
        now = self._ticks()
        dt = ticks_diff(now, self._t) if self._ticks is ticks_us else now - self._t
        self._t = now
        if dt < 0:
            dt = 0
        c = self.collector
        c.tick(dt)
        if self.saved is not None:
            self._since_save += dt
        if self._sample():
            c.feed(self.raw)
            if c.pairs is not None and self._tilt:
                c.pairs.feed(self.raw, self._acc)
        if c.due():
            self._solve()
        self._since_report += dt
        if self._since_report >= self.every_us:
            self._since_report = 0
            self.line()
        return dt

    # --- a sample ----------------------------------------------------------------------
    def _sample(self):
        acc = self.accel
        try:
            self._read(self.raw)
            if acc is not None:
                acc.sample_into(self._acc)
            ok = self._cfg is None or self._cfg()  # no sample at another gain or range
        except (OSError, ValueError):  # BusError, DataReadyTimeout; SensorOverflow
            ok = False
        h = self.health
        if ok and (h.saturated(self.raw) or h.mag_stale(self.raw,
                                                         getattr(self.mag, "suspect", False))):
            ok = False
        if not ok:
            self.bad += 1
            self._fails += 1
            if self._fails >= _REINIT_AFTER:
                self._fails = 0
                self._reinit()
            return False
        self._fails = 0
        self.samples += 1
        self._tilt = acc is not None and h.tilt_ok(self._acc)
        return True

    def _reinit(self):
        try:
            self.mag.configure()
            if self.accel is not None:
                self.accel.configure()
            self.reinits += 1
        except OSError:
            pass  # the next failed reads try again
        self.health.reset()

    # --- a solve: sampling pauses ------------------------------------------------------
    def _solve(self):
        c = self.collector
        self.status = "solving"
        self.solves += 1
        if self._found:
            self._let_go()
        drop("hints")
        self.free_at_solve = free_bytes()  # after a collection
        c.start(self.period_us)
        while c.job is not None:
            cal = c.slice()
            if cal is not None:
                release_solver()  # what follows (gate, history, save) does not hold it
                self._accept(cal)
        release_solver()
        gc.collect()
        if self._found:
            try:
                self._sensors()
            except OSError:
                pass  # the next step looks again (and says so)
        self.status = "collecting"
        if self._due is not None:
            self._save(*self._due)
            self._due = None
        self._t = self._ticks()  # the pause is no evidence of a quiet board

    def _accept(self, cal):
        from firmware.calibrate.acceptance import check_calibration
        from firmware.errors import CalibrationRejected
        c = self.collector
        try:
            check_calibration(cal, self.cpg)
        except CalibrationRejected as e:
            c.accepted -= 1
            c.refused += 1
            c.last_reason = e.reason
            c.last_detail = e.detail
            return
        release_solver()  # the gate loaded the solver's code
        from firmware.calibrate import history
        jump = history.judge(self, cal)  # evidence: a jump is a new baseline here
        history = None
        drop("calibrate.history")
        self._check_mounting(cal)
        c.calibrator.current = cal  # later fits must beat this one
        if (cal.model == self.model or cal.model == 10) and cal.fit_error <= GOOD_FIT_ERROR:
            self._due = (cal, jump)  # saved once the solve is over and the chips are back

    def _check_mounting(self, cal):
        p = self.collector.pairs
        if p is None:
            return
        try:
            from firmware.calibrate.mounting import MIN_BINS
            if p.count < MIN_BINS:
                return
            from firmware.calibrate import mountcheck
            v, axes, _, _ = mountcheck.check(p, cal, self._mag_map.m, self._acc_map.m)
            mountcheck = None
            drop("calibrate.mountcheck")
            if v == "ok" or v == "wrong":
                self.mounting = (v, axes)
                self._axes_status = ('check MAG_AXES: the data say "%s"' % axes
                                     if v == "wrong" else None)
        except MemoryError:
            pass  # no room now: the next fit checks again

    def _save(self, cal, jump):
        # power-safe (firmware/store.py: slots, CRC, verify), then read back from the store
        for _ in range(_SAVE_TRIES):
            gc.collect()
            try:
                self.store.save(cal.to_bytes())
                back = Calibration.from_bytes(self.store.load())
                if back == cal:
                    self.saved = back
                    self.saved_us = self._t
                    self._since_save = 0
                    break
                self.reason = "read back differs"
            except MemoryError:
                self.reason = "save failed: no_memory"
            except Exception as e:  # noqa: BLE001 - OSError, StoreError: tried again
                self.reason = "save failed: %s" % (e,)
            self.save_errors += 1
        drop("store_slots")
        if self.saved is None:
            return
        self.reason = None
        if self._hist is not None:  # the history follows the store (a jump: a new baseline)
            from firmware.calibrate import history
            history.keep(self, cal, history.FLAG_ACCEPTED | (
                history.FLAG_BASELINE if jump is not None else 0))
            history = None
            drop("calibrate.history", "store_slots")
        if self.mounting is not None:
            try:
                __import__("firmware.mountnote", None, None, ("save",)).save(self)
            except (OSError, MemoryError):
                pass  # the verdict is not kept: the next calibration checks again
            drop("mountnote", "store_slots")

    # --- what firmware.calibrate.history's judge() and keep() read -----------------------
    @property
    def calibration(self):
        return self.collector.calibrator.current

    date_s = None
    history_errors = 0
    history_reason = None

    # --- the progress line -------------------------------------------------------------
    def line(self):
        """Print one progress line (report()); none when the heap has no room for it."""
        try:
            self._line()
        except MemoryError:
            pass

    def _line(self):
        c = self.collector
        cal = c.calibrator.current
        parts = ["calibrating: %s" % self.status,
                 "coverage %d %% (%d samples)" % (c.coverage(), c.calibrator.count)]
        if cal.model is not None:
            parts.append("model %s fit %d.%02d %%" % (cal.model, cal.fit_error // 100,
                                                     cal.fit_error % 100))
        reason = c.last_reason
        if reason == "planar" and c.since_kept_us < c.QUIET_US:
            reason = "too_few_samples"
        if self.short:
            parts.append("out of memory while solving (%s KB free before it): needs more heap"
                         % (self.free_at_solve // 1024 if self.free_at_solve else "?"))
        if self.done():
            parts.append("saved and read back: restarting into the heading")
        elif self.saved is not None:
            parts.append("saved: turn on to refine, or hold still to finish")
        elif self.reason is not None:
            parts.append(self.reason)
        elif reason and reason != "not_better" and reason != "no_memory":
            from firmware.hints import HINTS  # (let go while a solve runs)
            parts.append(HINTS.get(reason, reason))
        elif cal.model is None or cal.model != self.model:
            parts.append("keep turning")
        if self._axes_status is not None:
            parts.append(self._axes_status)
        elif self.mounting is not None:
            parts.append("axes ok")
        if self.bad:
            parts.append("%d bad reads" % self.bad)
        self.report(" | ".join(parts))
