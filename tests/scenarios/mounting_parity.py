# Parity: the mounting check (firmware/calibrate/mounting.py) on one simulated session, run on CPython and
# on MicroPython, must print the same lines. A GY-87 whose HMC5883L sits turned against the
# MPU6050 (x and y swapped, z flipped: mounting (2, 1, -3)) with the boards' usual MAG_AXES;
# a 40 s figure-8. Prints each check after an accepted fit (time, verdict, axes, sigma, best,
# bins), the pairs held, then the verdict on the same pairs and last calibration for every one
# of the 24 MAG_AXES a user could write.
import json
import sys

sys.path.append("tests/scenarios")
from desktop import mounting as M  # noqa: E402
from firmware.calibrate import mountcheck  # noqa: E402

s = M.Session("gy87", None, mount=(2, 1, -3))
for c in s.checks:
    print(json.dumps(["check"] + list(c)))
print(json.dumps(["pairs", s.pairs.count, list(s.pairs.data)]))
cal = s.app.calibration
for m in M.rotations():
    spec = M.mag_axes(m)
    print(json.dumps(["setting", spec] + list(mountcheck.check(s.pairs, cal, spec,
                                                                M.ACCEL_AXES))))
