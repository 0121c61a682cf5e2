"""How far to trust the heading: an accuracy level 0-3 with Android SensorManager's meaning,
so an app can ask the user to "move the board in a figure-8" at level <= 1.
"""
#     from firmware import accuracy
#     level, why = accuracy.assess(app)          # CompassApp: app.accuracy, status_line(app)
#     level, why = accuracy.level(model=10, fit_error=120, coverage=80, tilt=True)
#
# Levels (Android SensorManager): 0 UNRELIABLE (SENSOR_STATUS_UNRELIABLE), 1 LOW
# (SENSOR_STATUS_ACCURACY_LOW), 2 MEDIUM, 3 HIGH.
#
# The table (docs/accuracy.md has it too, with the measured headings behind it): the first row
# that applies gives the level and the reason.
#
#   level  reason            when
#   0      no_heading        the last step gave no heading (bus error, timeout, overflow,
#                            zero field or gravity)
#   0      uncalibrated      no calibration in force
#   0      mag_axes          the mounting check found MAG_AXES wrong for this board: the heading
#                            is wrong once it tilts (status "check MAG_AXES: ...",
#                            firmware/calibrate/mountcheck.py)
#   2      gyro_held         use_gyro(): the field is not used (a magnet, a fast turn) and the
#                            gyroscope holds the heading within its vouched uncertainty
#                            (docs/gyro.md; status "gyro held")
#   0      interference      the interference flag is up now (|b| or dip off the expected), or a
#                            spell holds the status (firmware/health.py FieldWatch: a fast
#                            change of |b| or dip, a heading jump, until the field is clean)
#   0      blackout_zone     the field model says H < 2000 nT here (WMM's blackout zone)
#   1      minmax            the min/max calibration (hard iron from the extremes, no fit)
#   1      fit_error_high    fit error above GOOD_FIT_ERROR (5 %, MotionCal's "good" limit);
#                            not for a quick calibration, whose fit error is a placeholder
#   1      field_mismatch    the calibration's B is off the field model's |B| here by more than
#                            firmware.calibrate.acceptance.FIELD_MATCH_PCT (made elsewhere, wrong range)
#   2      quick             a quick calibration (model 4, coverage 0: hard iron from a known
#                            heading): within 2 deg while soft iron is <= 3 %
#                            (docs/quick_calibration.md)
#   1      low_coverage      a fit over less than MIN_COVERAGE (35 %) of the sphere
#   2      hard_iron_only    a 4-element fit (no soft-iron correction)
#   2      no_tilt           no accelerometer: the heading is right only while the board is level
#   2      tilt_extreme      pitch beyond 80 deg or dip beyond 75 deg (firmware.compass's flags)
#   2      caution_zone      the field model says H < 6000 nT here (WMM's caution zone)
#   2      fit_error_fair    a 7/10 fit with fit error above _HIGH_FIT_ERROR (3.5 %)
#   2      coverage_fair     a 7/10 fit over less than _HIGH_COVERAGE (60 %) of the sphere
#   3      high              a 7- or 10-element fit within 3.5 % over >= 60 % of the sphere,
#                            tilt known, no flag up
# Thresholds: GOOD_FIT_ERROR is MotionCal's 5 %; _HIGH_FIT_ERROR NXP's 3.5 % (the fit error at
# which a higher-order model is trusted over a lower one, firmware.calibrate.acceptance); _HIGH_COVERAGE
# 60 % of the 100 sphere regions (a fit over more than half the sphere; full figure-8s reach
# 80-95 % in the simulator).
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
    # (level 0..3, reason) for the state described; see the table of the module's opening comment.
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
    # the table of the module's opening comment, first row that applies; f: the conditions (_F_ bits)
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
    if st is not None and st == app._axes_status:
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
