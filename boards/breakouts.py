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
- a magnetometer inside an IMU's package has its axes where the package's datasheet draws
  them (IN_PACKAGE: each of its axes as an axis of the accelerometer beside it); the
  breakout's arrows are the accelerometer's. AK8963 in the MPU-9250: x along the
  accelerometer's y, y along its x, z against its z, so on a flat GY-9250 its x points left,
  y forward, z down: body = (y, -x, z). AK09916 in the ICM-20948: x along the
  accelerometer's x, y and z against its y and z: body = (x, y, z). Both are rotations of the
  accelerometer's frame (right-handed, as every chip here; docs/hardware.md).
tests/test_axes.py re-derives every map from chip axis vectors and rotations and checks the
heading of a tilted board against its yaw.
"""

GY271 = {"mag": "x,-y,-z"}  # QMC5883L at 0x0D (or QMC5883P at 0x2C on newer boards)
GY273 = {"mag": "x,-y,-z"}  # HMC5883L at 0x1E
GY87 = {"mag": "x,-y,-z", "accel": "-x,y,z"}  # MPU6050 + HMC5883L (or QMC5883L) + BMP180
GY9250 = {"mag": "y,-x,z", "accel": "-x,y,z"}  # MPU-9250 at 0x68 + its AK8963 (0x0C, bypass)
GY91 = GY9250                                  # the same MPU-9250 and a BMP280
ICM20948 = {"mag": "x,y,z", "accel": "-x,y,z"}  # ICM-20948 at 0x68/0x69 + its AK09916 (0x0C)

# the magnetometer's x, y, z as the accelerometer's axes, in the package (datasheets)
AK8963_IN_MPU9250 = ("y", "x", "-z")      # MPU-9250 product specification, 9.1
AK09916_IN_ICM20948 = ("x", "-y", "-z")   # ICM-20948 datasheet DS-000189, orientation of axes
IN_PACKAGE = {"gy9250": AK8963_IN_MPU9250, "gy91": AK8963_IN_MPU9250,
              "icm20948": AK09916_IN_ICM20948}

# single-chip modules named by their chip, lying as the others (x forward, y left printed)
LIS3MDL = {"mag": "x,-y,-z"}   # LIS3MDL at 0x1C or 0x1E
MMC5603 = {"mag": "x,-y,-z"}   # MMC5603NJ at 0x30
# the LIS2MDL's axes are a left-handed set (docs/hardware.md, LIS2MDL handedness): x, y as
# printed, its z into the board, so its map is a mirror (det -1; its driver's MIRROR)
LIS2MDL = {"mag": "x,-y,z"}
MIRRORED = {"lis2mdl"}

BREAKOUTS = {"gy271": GY271, "gy273": GY273, "gy87": GY87, "gy9250": GY9250, "gy91": GY91,
             "icm20948": ICM20948, "lis3mdl": LIS3MDL, "lis2mdl": LIS2MDL,
             "mmc5603": MMC5603}


def breakout(name):
    """The specs of a breakout by name ('gy271', 'gy273', 'gy87', 'gy9250', 'gy91', 'icm20948',
    'lis3mdl', 'lis2mdl', 'mmc5603'; case and '-' ignored)."""
    key = name.lower().replace("-", "").replace("_", "")
    if key not in BREAKOUTS:
        raise ValueError("unknown breakout %r; known: %s" % (name, ", ".join(sorted(BREAKOUTS))))
    return BREAKOUTS[key]
