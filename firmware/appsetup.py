# What CompassApp's constructor does, imported for it and dropped once the app is made
# (firmware.compat.drop): the options checked (a bad one raises TypeError / ValueError naming
# it and its unit), the chips detected when not given, the fast path chosen, the state of the
# per-sample steps made (firmware/app.py has its story).
from array import array

from firmware import compass, i2cdevice
from firmware.axes import AxisMap
from firmware.compass import Compass
from firmware.compat import const, drop, kernels, sleep_us, ticks_us, wall_clock
from firmware.fieldwatch import FieldWatch
from firmware.health import Health
from firmware.trig import cdeg_to_kang

DEFAULT_CAPACITY = const(300)  # samples held while collecting (firmware.calibrate.calibrator's default)
_CONFIG_EVERY = const(1)     # samples between configuration read-backs (docs/faults.md)
_EVIDENCE_PERIODS = const(4)  # a step counts as at most 4 sample periods of evidence
_HMC_OVERFLOW = const(-4096)
_DEFAULT_PERIOD_US = const(20000)  # a driver without .period_us: assume 50 Hz
_STATUS_STARTING = "starting"  # firmware.app.STATUS_STARTING


def setup(app, i2c, mag, accel, mag_axes, accel_axes, model, declination_cdeg, store,
          delay_us, ticks_us_, capacity, solve_every, fallback, reinit_after, mag_options,
          learn, fast):
    app.i2c = i2c
    app._mag_map = AxisMap(mag_axes)
    app._acc_map = AxisMap(accel_axes)
    _check_options(model, declination_cdeg, solve_every, reinit_after)
    app._delay = delay_us if delay_us is not None else sleep_us
    app._ticks, app._wrap = _app_clock(app, ticks_us_)
    app._wall, app._wall_diff = wall_clock()
    app.mag, app.accel = _sensors(i2c, mag, accel, mag_options, delay_us)
    if app._mag_map.det != (-1 if getattr(app.mag, "MIRROR", False) else 1):
        raise ValueError(
            "mag_axes %r is a %s: the %s's axes are %s (its datasheet), so is its map (e.g. %s)"
            % (app._mag_map.spec, "rotation" if app._mag_map.det > 0 else "mirror image",
               app.mag.KIND, "a mirror image of its accelerometer's" if app._mag_map.det > 0
               else "right-handed as the body frame", "x,y,-z" if app._mag_map.det > 0
               else "x,-y,-z"))
    app.model = model
    app.capacity = capacity if capacity else DEFAULT_CAPACITY
    app.solve_every = solve_every
    app.fallback = fallback
    app.reinit_after = reinit_after
    app.learn = learn

    app._fast_opt = fast

    app.raw = array("h", (0, 0, 0))       # the last sample, chip axes, counts
    app._cor = array("h", (0, 0, 0))      # corrected, sensor axes
    app.body = array("h", (0, 0, 0))      # corrected, body frame (AN4248)
    app._acc = array("h", (0, 0, 0))
    app.gravity = array("h", (0, 0, 0))   # body frame, AN4248 sign (+1 g down, level)
    # the per-sample calls, looked up once: a driver's unguarded read where it has one
    # (inside the read guard), the axis maps' arrays
    app._mag_into = getattr(app.mag, "sample_into", None) or app.mag.read_into
    app._mm = app._mag_map.m
    app._am = app._acc_map.m
    app._accel_auto = accel is None    # detected: look again later when absent
    app.health = Health(app.mag.counts_per_gauss,
                         _HMC_OVERFLOW if app.mag.KIND == "hmc5883l" else -32768,
                         app.accel.counts_per_g if app.accel is not None else 16384)
    app._mag_cfg = (getattr(app.mag, "config_matches", None)
                     or getattr(app.mag, "config_ok", None))
    app.tilt = app.accel is not None  # False: the level formula (no or implausible accel)
    app._tilt_bad = 0
    app._since_cfg = 0
    app._cfg_due = True        # the first good sample reads the configuration back
    app.verify_every = _CONFIG_EVERY
    app._accel_wait_us = 0
    app.accel_retries = 0
    app._ok = False
    app._cfg_ok = True
    app.heading_kang = -1
    app.status = _STATUS_STARTING
    app.errors = {}
    app.last_error = None      # the exception behind the last failed read
    app.worst_stall_us = 0
    app.slices = 0             # solver slices run
    app.stored = 0
    app.save_errors = 0
    app.save_reason = None
    app.worst_save_us = 0
    app.reinits = 0
    app.reinit_failures = 0
    app.steps = 0

    app.store = store
    heading_line(app, cdeg_to_kang(declination_cdeg))
    app._dip_unsaved = False   # this app saved the fit in force before its dip was known
    app.collector = None
    app._ended = {}            # the counters the last session left (firmware/calibrate/session.py)
    app.calibration = None

    app._fails = 0             # failed reads in a row
    app._reinit_level = 0
    app._t_last = app._ticks()
    app._dt = 0                # us since the previous step, capped: evidence, not time
    app._gap_us = 0            # us since the magnetometer was last read successfully
    app._stalled = False       # the last read came after a gap (a stall, bus errors)
    app._dt_cap = _EVIDENCE_PERIODS * getattr(app.mag, "period_us", _DEFAULT_PERIOD_US)
    app._age_us = 0
    app._interf_us = 0
    app._clean_us = 0
    app._unsaved = False
    app._save_wait_us = 0


def heading_line(app, declination_kang):
    """What showing a heading needs beside the drivers: the kernel set (firmware/fast.py where
    the port has the emitter), the Compass and the field watch."""
    fast = app._fast_opt
    kn = kernels() if fast is None or fast is True else None
    app.fast = kn is not None
    if kn is None:
        from firmware import axes, calibration
        app._correct = calibration.correct
        app._apply = axes.apply
    else:
        app._correct = kn.correct
        app._apply = kn.apply
    compass.use_kernels(kn or False)
    i2cdevice.use_kernels(kn or False)  # the drivers' decode
    app.compass = Compass(declination_kang=declination_kang)
    app.watch = FieldWatch(app.compass, app.body)  # firmware/fieldwatch.py
    app.dip = app.watch.dip   # the calibration's dip (DipCheck)


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

def _app_clock(app, clock):
    if app._acc_map.det != -1:
        raise ValueError("accel_axes %r is a rotation: an accelerometer's map to AN4248's "
                         "gravity sign is a mirror (see firmware/axes.py)"
                         % (app._acc_map.spec,))
    if clock is None:
        if ticks_us is None:
            raise ValueError("ticks_us is needed off MicroPython (the simulator's clock)")
        return ticks_us, True  # the port's ticks_us wraps: compare with ticks_diff
    return clock, False

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
        detect = None
        drop("detect")  # boot only (the accelerometer's retry imports it again)
    return mag, (accel if accel else None)
