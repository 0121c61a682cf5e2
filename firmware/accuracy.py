"""How far to trust the heading: an accuracy level 0-3 with Android SensorManager's meaning
(0 UNRELIABLE .. 3 HIGH), so an app can ask for a figure-8 at level <= 1."""
#     from firmware import accuracy
#     level, why = accuracy.assess(app)          # CompassApp: app.accuracy, status_line(app)
#     level, why = accuracy.level(model=10, fit_error=120, coverage=80, tilt=True)
#
# The table of levels and reasons, first row that applies, and its thresholds:
# docs/accuracy.md (with the measured headings behind it).
from firmware.calibration import GOOD_FIT_ERROR
from firmware.compat import const

UNRELIABLE = const(0)
LOW = const(1)
MEDIUM = const(2)
HIGH = const(3)
NAMES = ("unreliable", "low", "medium", "high")

_HIGH_FIT_ERROR = const(350)  # NXP: a higher-order fit is trusted at <= 3.5 %
MIN_COVERAGE = const(35)      # % of sphere regions: below, a fit saw too little of the sphere
_HIGH_COVERAGE = const(60)   # % of sphere regions for "high"
_BLACKOUT = "blackout zone"   # firmware.field.wmm's statuses (field is not imported here)
_CAUTION = "caution zone"
# The table's conditions as the bits of one small int: the status line asks for the level at
# every report, and MicroPython takes a call frame of more than 11 words (arguments, locals
# and stack; py/objfun.c VM_MAX_STATE_ON_STACK) from the heap: level()'s ten arguments would.
_F_NO_HEADING = const(1)
_F_HELD = const(2)
_F_INTERFERENCE = const(4)
_F_BLACKOUT = const(8)
_F_MISMATCH = const(16)
_F_NO_TILT = const(32)
_F_EXTREME = const(64)
_F_CAUTION = const(128)


def level(model=None, fit_error=0, coverage=0, heading=True, interference=False, tilt=True,
          extreme=False, zone=None, mismatch=False, held=False):
    # (level 0..3, reason) for the state described; see the table in docs/accuracy.md.
    # model: None, 'minmax', 4, 7, 10; fit_error hundredths of a percent; coverage %; heading:
    # the last step gave one; tilt: an accelerometer is in use; extreme: pitch > 80 deg or dip
    # > 75 deg; zone: the field model's status, or None; mismatch: the calibration's B is off
    # the field model.
    f = _zone(zone)
    if not heading:
        f |= _F_NO_HEADING
    if held:
        f |= _F_HELD
    if interference:
        f |= _F_INTERFERENCE
    if mismatch:
        f |= _F_MISMATCH
    if not tilt:
        f |= _F_NO_TILT
    if extreme:
        f |= _F_EXTREME
    return _table(model, fit_error, coverage, f)


def _zone(zone):
    return _F_BLACKOUT if zone == _BLACKOUT else _F_CAUTION if zone == _CAUTION else 0


def _table(model, fit_error, coverage, f):
    # the table in docs/accuracy.md, first row that applies; f: the conditions (_F_ bits)
    if f & _F_NO_HEADING:
        return UNRELIABLE, "no_heading"
    if model is None:
        return UNRELIABLE, "uncalibrated"
    if f & _F_HELD:
        return MEDIUM, "gyro_held"
    if f & _F_INTERFERENCE:
        return UNRELIABLE, "interference"
    if f & _F_BLACKOUT:
        return UNRELIABLE, "blackout_zone"
    if model == "minmax":
        return LOW, "minmax"
    if fit_error > GOOD_FIT_ERROR and not (model == 4 and coverage == 0):
        return LOW, "fit_error_high"
    if f & _F_MISMATCH:
        return LOW, "field_mismatch"
    if coverage == 0 and model == 4:
        return MEDIUM, "quick"
    if coverage < MIN_COVERAGE:
        return LOW, "low_coverage"
    if model == 4:
        return MEDIUM, "hard_iron_only"
    if f & _F_NO_TILT:
        return MEDIUM, "no_tilt"
    if f & _F_EXTREME:
        return MEDIUM, "tilt_extreme"
    if f & _F_CAUTION:
        return MEDIUM, "caution_zone"
    if fit_error > _HIGH_FIT_ERROR:
        return MEDIUM, "fit_error_fair"
    if coverage < _HIGH_COVERAGE:
        return MEDIUM, "coverage_fair"
    return HIGH, "high"


def assess(app):
    """level() for a CompassApp's current state; allocates nothing (the status line calls it
    at every report)."""
    c = app.compass
    if c is None:  # the app did not fit
        return UNRELIABLE, "no_heading"
    st = app.status
    if st is not None and st == app.health.axes_status:
        return UNRELIABLE, "mag_axes"
    f = _conditions(app, c, st)
    cal = app.calibration
    return _table(cal.model, cal.fit_error, cal.coverage, f)


def _conditions(app, c, st):
    # level()'s arguments for the app as _F_ bits (c: its Compass, st: its status)
    f = 0
    if st == "gyro held":
        f = _F_HELD
    elif st != "ok" and st != "interference" and st != "heading jumped":
        f = _F_NO_HEADING
    if c.interference or st == "interference" or st == "heading jumped":
        f |= _F_INTERFERENCE
    if app.accel is None:
        f |= _F_NO_TILT
    if c.gimbal or c.dip_high:
        f |= _F_EXTREME
    loc = app.location
    if loc is not None:
        if loc.usable:
            f |= _zone(loc.status)
        if loc.cal_mismatch:
            f |= _F_MISMATCH
    return f
