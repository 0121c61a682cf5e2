# What CompassApp's constructor does, imported for it and dropped once the app is made
# (firmware.compat.drop): the options checked (a bad one raises TypeError / ValueError naming
# it and its unit), the chips detected when not given, the fast path chosen, the state of the
# per-sample steps made (firmware/app.py has its story).
from array import array

from firmware import compass, i2cdevice
from firmware.axes import AxisMap
from firmware.compass import Compass
from firmware.compat import const, drop, kernels, room, sleep_us, ticks_us, wall_clock
from firmware.fieldwatch import FieldWatch
from firmware.health import Health
from firmware.trig import cdeg_to_kang

_EVIDENCE_PERIODS = const(4)  # a step counts as at most 4 sample periods of evidence


def setup(i2c, mag, accel, mag_axes, accel_axes, model, declination_cdeg, store, delay_us,
          ticks_us_, solve_every, reinit_after, mag_options, fast):
    """The options checked, the chips, the clocks, the per-sample buffers and objects, as the
    tuple CompassApp._build assigns (its order)."""
    mag_map = AxisMap(mag_axes)
    acc_map = AxisMap(accel_axes)
    _check_options(model, declination_cdeg, solve_every, reinit_after)
    clock, wrap = _app_clock(acc_map, ticks_us_)
    wall, wall_diff = wall_clock()
    mag, acc = _sensors(i2c, mag, accel, mag_options, delay_us)
    room(mag)  # each step reads them (firmware/compat.py room)
    room(acc)
    if mag_map.det != (-1 if getattr(mag, "MIRROR", False) else 1):
        raise ValueError(
            "mag_axes %r is a %s: the %s's axes are %s (its datasheet), so is its map (e.g. %s)"
            % (mag_map.spec, "rotation" if mag_map.det > 0 else "mirror image",
               mag.KIND, "a mirror image of its accelerometer's" if mag_map.det > 0
               else "right-handed as the body frame", "x,y,-z" if mag_map.det > 0
               else "x,-y,-z"))
    health = Health(mag.counts_per_gauss, getattr(mag, "OVERFLOW", -32768),  # HMC5883L: -4096
                    acc.counts_per_g if acc is not None else 16384)
    health.tilt = acc is not None  # False: the level formula (no or implausible accel)
    body = array("h", (0, 0, 0))      # corrected, body frame (AN4248)
    kn = kernels() if fast is None or fast is True else None
    compass.use_kernels(kn or False)
    i2cdevice.use_kernels(kn or False)  # the drivers' decode
    c = Compass(declination_kang=cdeg_to_kang(declination_cdeg))
    watch = FieldWatch(c, body)  # firmware/fieldwatch.py
    return (i2c, mag, acc, accel is None, store, model, reinit_after, mag_map, acc_map,
            # the per-sample calls, looked up once: a driver's unguarded read where it has
            # one (inside the read guard), its configuration check, the axis maps' arrays
            getattr(mag, "sample_into", None) or mag.read_into,
            getattr(mag, "config_matches", None) or getattr(mag, "config_ok", None),
            mag_map.m, acc_map.m,
            delay_us if delay_us is not None else sleep_us, clock, wrap, wall, wall_diff,
            _EVIDENCE_PERIODS * getattr(mag, "period_us", i2cdevice.DEFAULT_PERIOD_US),
            array("h", (0, 0, 0)),   # raw: the last sample, chip axes, counts
            array("h", (0, 0, 0)),   # corrected, sensor axes
            body,
            array("h", (0, 0, 0)),   # the accelerometer's sample
            array("h", (0, 0, 0)),   # gravity: body frame, AN4248 sign (+1 g down, level)
            health, kn, c, watch)


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

def _app_clock(acc_map, clock):
    if acc_map.det != -1:
        raise ValueError("accel_axes %r is a rotation: an accelerometer's map to AN4248's "
                         "gravity sign is a mirror (see firmware/axes.py)"
                         % (acc_map.spec,))
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
