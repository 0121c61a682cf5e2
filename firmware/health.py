"""Is this sample believable? Per-sample plausibility checks of the sensors' outputs, for the app."""
#     from firmware.health import Health
#     h = Health(counts_per_gauss=12000, overflow=-32768, counts_per_g=16384)
#     h.saturated(raw)   # True: an axis at the output limit: not a measurement
#     h.mag_stale(raw)   # True: the same sample again, more times than noise allows
#     h.tilt_ok(acc)     # False: |g| outside 0.75..1.25 g, or the same reading again
#
# What each check catches and why its limits: docs/design.md (module notes, health); the fault
# campaign's figures: docs/faults.md. The field checks are firmware/fieldwatch.py; the shared
# constants (DIP_TOL_KANG, SPELL_*) are here. Allocation-free (tests/scenarios/app_alloc.py).
from array import array

from firmware.compat import const, room
from firmware.errors import DataReadyTimeout, SensorOverflow

# a step's outcome (CompassApp.status): the sample's and the chip's
STATUS_OK = "ok"
STATUS_BUS_ERROR = "bus_error"        # NACK / EIO: the chip did not answer
STATUS_TIMEOUT = "timeout"            # no data-ready within the driver's bound
STATUS_OVERFLOW = "overflow"          # QMC5883L OVL, HMC5883L -4096: sample dropped
STATUS_STALE = "stale data"           # the magnetometer repeats its last sample: no new data
STATUS_RESET = "sensor reset"         # its control registers no longer hold our configuration

_SAT_HI = const(32767)
_SAT_LO = const(-32768)
_G_SHIFT = const(4)          # |a|^2 on a >> 4: int16 input -> < 3 * 2**22
_G_LO_PCT = const(75)        # |g| window, percent of 1 g
_G_HI_PCT = const(125)
_ACCEL_REPEATS = const(3)    # exact repeats of all three axes that mean a frozen accelerometer
_RUN_CAP = const(0x3FFF)
CONFIG_EVERY = const(1)     # samples between configuration read-backs (docs/faults.md)
_REINIT_MAX_SHIFT = const(4)  # failed re-inits back off to every 2**4 x reinit_after reads
_ERROR_BACKOFF_US = const(20000)  # after a bus error: do not hammer a dead bus
_ACCEL_RETRY_US = const(5000000)   # an accelerometer absent at boot is looked for every 5 s
_ACCEL_REINIT_EVERY = const(16)    # implausible accelerometer samples between its re-inits
DIP_TOL_KANG = const(546)       # 3 deg (65536 KANG per turn): firmware/fieldwatch.py DipCheck
SPELL_JUMP = const(1)           # FieldWatch spells, by weight: a heading jump...
SPELL_SHIFT = const(2)          # ...|B| or the dip left their short averages...
SPELL_FIELD = const(3)          # ...|B| or the dip outside their windows


def status_of(e):
    """The status of a failed read's exception."""
    if isinstance(e, DataReadyTimeout):
        return STATUS_TIMEOUT
    if isinstance(e, SensorOverflow):
        return STATUS_OVERFLOW
    return STATUS_BUS_ERROR


def mag_repeats(counts_per_gauss):
    """The run of exact repeats that marks a magnetometer's output as stale (module doc)."""
    c = counts_per_gauss or 0
    if c >= 6000:
        return 2
    if c >= 2000:
        return 3
    if c >= 1000:
        return 8
    return 32


def _run(p, v, n):
    # the run of exact repeats after sample v: n + 1 (capped) when v repeats p, the previous
    # sample; else 0, and p takes v
    if v[0] != p[0] or v[1] != p[1] or v[2] != p[2]:
        p[0] = v[0]
        p[1] = v[1]
        p[2] = v[2]
        return 0
    return n + 1 if n < _RUN_CAP else n


class Health:
    """The state of the per-sample checks (see docs/design.md, module notes). overflow: the chip's
    overflow code besides the int16 limits (HMC5883L -4096; else -32768)."""

    def __init__(self, counts_per_gauss=None, overflow=_SAT_LO, counts_per_g=16384):
        self.last = array("h", (0, 0, 0))    # the previous magnetometer sample
        self.same = 0                        # exact repeats of it in a row
        self.repeats = mag_repeats(counts_per_gauss)
        self.overflow = overflow
        self.alast = array("h", (0, 0, 0))   # the previous accelerometer sample
        self.asame = 0
        self.g_lo = 0
        self.g_hi = 0
        # the drivers' faults (below): each written by a step, so here from the start
        self.fails = self.level = self.since_cfg = self.tilt_bad = self.accel_wait_us = 0
        self.reinits = self.reinit_failures = self.accel_retries = 0
        self.cfg_due = self.cfg_ok = True
        self.tilt = False  # the app's last accelerometer sample was plausible: a tilt to use
        self.last_error = None
        self.mounting = None     # the mounting check's last answer: (verdict, MAG_AXES)
        self.axes_status = None  # the app's status while that answer names other MAG_AXES
        self.set_accel(counts_per_g)
        room(self)  # (firmware/compat.py room)

    def mounted(self, verdict, axes, status):
        """A mounting check's answer (firmware/calibrate/mountcheck.py); status False: the
        status is kept."""
        self.mounting = (verdict, axes)
        if status is not False:
            self.axes_status = status

    def set_accel(self, counts_per_g):
        c = counts_per_g >> _G_SHIFT
        lo = c * _G_LO_PCT // 100
        hi = c * _G_HI_PCT // 100
        self.g_lo = lo * lo
        self.g_hi = hi * hi

    def reset(self):
        """Forget the runs (after a re-initialisation)."""
        self.same = 0
        self.asame = 0

    def saturated(self, raw):
        return self._sat(raw[0]) or self._sat(raw[1]) or self._sat(raw[2])

    def _sat(self, v):
        return v == _SAT_HI or v == _SAT_LO or v == self.overflow

    def mag_stale(self, raw, suspect=False):
        """suspect: the chip's status hinted at old data (QMC5883L DOR, HMC5883L LOCK): then
        one exact repeat is enough."""
        n = _run(self.last, raw, self.same)
        self.same = n
        return n > 0 and (suspect or n >= self.repeats)

    def _g2(self, a):
        x = a[0] >> _G_SHIFT
        y = a[1] >> _G_SHIFT
        z = a[2] >> _G_SHIFT
        return x * x + y * y + z * z

    def _frozen(self, a):
        n = _run(self.alast, a, self.asame)
        self.asame = n
        return n >= _ACCEL_REPEATS

    def tilt_ok(self, a):
        n = self._g2(a)
        if self._frozen(a):
            return False
        return self.g_lo <= n <= self.g_hi

    # --- the drivers' faults (CompassApp: its read guard, drivers, watch and reinit_after) ---
    # fails: failed reads in a row; level: failed re-inits back off to every 2**level x
    # reinit_after; cfg_due: read the configuration back at the next sample (the first one,
    # after any anomaly); since_cfg: samples since the last read-back.

    def vet(self, app):
        """The app's sample: STATUS_OK when it is plausible and, every CONFIG_EVERY samples,
        after an anomaly or while collecting, the chip's configuration read back holds."""
        raw = app.raw
        if self.saturated(raw):
            return STATUS_OVERFLOW
        suspect = getattr(app.mag, "suspect", False)
        if self.mag_stale(raw, suspect):
            return STATUS_STALE
        if app._stalled and suspect:
            # a QMC5883L's set after a gap is that old (docs/design.md, app)
            return STATUS_STALE
        if app.accel is not None:  # every _ACCEL_REINIT_EVERY implausible samples: wake()
            self.tilt = self.tilt_ok(app._acc)
            if self.tilt:
                self.tilt_bad = 0
            else:
                self.tilt_bad += 1
                if self.tilt_bad % _ACCEL_REINIT_EVERY == 1:
                    self.wake(app, True)
        self.since_cfg += 1
        if self.cfg_due or self.since_cfg >= CONFIG_EVERY or app.collector is not None:
            return self.verify(app)
        return STATUS_OK

    def wake(self, app, check):
        # an MPU6050 asleep since a reset or a glitch write (or, check False, one whose
        # gyroscope setting changed: firmware/gyro/attitude.py): its configure() wakes it
        g = app._guard
        with g:
            if not check or not app.accel.config_ok():
                app.accel.configure()
                self.reinits += 1

    def verify(self, app):
        """The magnetometer's configuration read back (every CONFIG_EVERY samples, after an
        anomaly, and while collecting): STATUS_RESET when it no longer holds ours."""
        self.since_cfg = 0
        self.cfg_due = False
        if app._mag_cfg is None:
            return STATUS_OK
        self._read_config(app)
        e = app._guard.error
        if e is not None:
            self.last_error = e
            return status_of(e)
        return STATUS_OK if self.cfg_ok else STATUS_RESET

    def _read_config(self, app):
        # its own small frame: inlined in vet(), the `with` made each sample allocate
        # (tests/scenarios/app_alloc.py)
        self.cfg_ok = True
        g = app._guard
        with g:
            g.dev = app.mag
            self.cfg_ok = app._mag_cfg()

    def failed(self, app, st):
        """A step that gave no heading: its status counted, the field watch restarted, and
        after reinit_after failures in a row (backing off) the drivers re-initialised."""
        app._flag(st)
        w = app.watch
        if w is not None:
            w.restart()
            if st == STATUS_STALE:
                w.forget(self.same)  # a spell begun by this run of repeats: not a field
        self.cfg_due = True  # any anomaly: read the configuration back at the next sample
        if st == STATUS_OVERFLOW:
            return  # the chip answered; re-initialising would not move the magnet
        if st == STATUS_RESET:
            self.fails = app.reinit_after << self.level  # re-initialise now
        if st == STATUS_BUS_ERROR:
            app._delay(_ERROR_BACKOFF_US)
        self.fails += 1
        lvl = self.level
        if self.fails >= app.reinit_after << lvl:
            self.fails = 0
            if lvl < _REINIT_MAX_SHIFT:
                self.level = lvl + 1
            app.reinit()

    def look_for_accel(self, i2c, dt):
        """An accelerometer absent at boot, looked for every _ACCEL_RETRY_US: its driver
        when one answered (its window set), else None."""
        self.accel_wait_us += dt
        if self.accel_wait_us < _ACCEL_RETRY_US:
            return None
        self.accel_wait_us = 0
        self.accel_retries += 1
        try:
            from firmware import detect
            acc = detect.detect_accel(i2c)
        except OSError:
            return None
        if acc is not None:
            room(acc)
            self.set_accel(acc.counts_per_g)
            self.tilt = False  # until its first plausible sample
        return acc
