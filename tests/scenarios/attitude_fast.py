# Native tiers only: every viper mirror of the attitude filter (firmware/gyro/attitude_fast.py)
# against its plain original (firmware/gyro/attitude_plain.py) on the same state, over the integer inputs of
# attitude_inputs (the filter's own states along the way). Prints one JSON object: the first
# mismatch per function (none: {}) and how many comparisons ran.
import json
from array import array

from firmware.gyro import attitude
from firmware.gyro import attitude_fast as F
from firmware.gyro import attitude_plain as A
from tests.scenarios import attitude_inputs as I

attitude.use_kernels(False)
a, gyro, grav, field, c = I.filter()
a.update(20000, 7)
G = "gyro"
PAIRS = (("rates", A.rates, F.rates, (G,)), ("q_hi", A.q_hi, F.q_hi, ()),
         ("down", A.down, F.down, ()), ("tilt_error", A.tilt_error, F.tilt_error, ()),
         ("tilt_sine", A.tilt_sine, F.tilt_sine, (12345,)),
         ("accel_apply", A.accel_apply, F.accel_apply, ()),
         ("field_error", A.field_error, F.field_error, ()),
         ("yaw_rate", A.yaw_rate, F.yaw_rate, (-700,)),
         ("advance", A.advance, F.advance, (70000,)),
         ("advance_20ms", A.advance, F.advance, (20000,)),
         ("angles", A.angles, F.angles, ()))


def norm(r):
    return 1 if r is True else (0 if r is False or r is None else r)


bad = {}
n = 0
for i in range(1, 1500):
    I.step(i, gyro, grav, field)
    a.update(20000 if i % 5 else 90000, I.flags(i))
    for name, p, v, args in PAIRS:
        args = tuple(gyro if x == G else x for x in args)
        s1 = array("i", a.st)
        if name in ("tilt_sine", "accel_apply"):
            A.tilt_error(s1)  # their input, as the filter calls them (after tilt_error)
            if name == "accel_apply":
                A.tilt_sine(s1, 12345)
        s2 = array("i", s1)
        r1 = norm(p(s1, *args))
        r2 = norm(v(s2, *args))
        n += 1
        if (list(s1) != list(s2) or r1 != r2) and name not in bad:
            bad[name] = [i, r1, r2, [[k, s1[k], s2[k]] for k in range(len(s1)) if s1[k] != s2[k]][:4]]
print(json.dumps({"mismatch": bad, "compared": n}))
