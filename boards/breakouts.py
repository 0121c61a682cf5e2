"""Axis mounting of common breakouts: sensor -> body specs for firmware.axes.AxisMap.

    from boards.breakouts import breakout
    from firmware.axes import AxisMap
    maps = breakout("gy87")                 # {"mag": "x,-y,-z", "accel": "-x,y,z"}
    mag_map = AxisMap(maps["mag"])

Mounting assumed: the breakout lies flat, components up, its silkscreen X arrow pointing
forward (the direction the heading refers to). A board mounted another way needs its own
specs (e.g. upside down: "x,y,z" for the magnetometer, "-x,-y,-z" for the accelerometer).

Derivation from the physical facts (docs/hardware.md, frames):
- each chip's axes are right-handed, z out of the package top; on these breakouts the chip's
  x runs along the X arrow and y to its left. So, in the AN4248 body frame (x forward,
  y right, z down), chip x = body x, chip y = -body y, chip z = -body z.
- magnetometer: it reads the field along its axes, so body = (x, -y, -z) of the reading.
- accelerometer: it reads the specific force, +1 g on an axis pointing up; AN4248's gravity
  vector is its negative (+1 g on z down for a level board). So body = -(x, -y, -z) =
  (-x, y, z) of the reading.
tests/test_axes.py re-derives both from chip axis vectors and rotations and checks the
heading of a tilted board against its yaw.
"""

GY271 = {"mag": "x,-y,-z"}  # QMC5883L at 0x0D (or QMC5883P at 0x2C on newer boards)
GY273 = {"mag": "x,-y,-z"}  # HMC5883L at 0x1E
GY87 = {"mag": "x,-y,-z", "accel": "-x,y,z"}  # MPU6050 + HMC5883L (or QMC5883L) + BMP180

BREAKOUTS = {"gy271": GY271, "gy273": GY273, "gy87": GY87}


def breakout(name):
    """The specs of a breakout by name ('gy271', 'gy273', 'gy87'; case and '-' ignored)."""
    key = name.lower().replace("-", "").replace("_", "")
    if key not in BREAKOUTS:
        raise ValueError("unknown breakout %r; known: %s" % (name, ", ".join(sorted(BREAKOUTS))))
    return BREAKOUTS[key]
