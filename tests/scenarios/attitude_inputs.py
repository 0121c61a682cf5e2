# Integer-only sensor inputs for the attitude filter's scenarios (attitude_alloc, attitude_parity):
# a level-ish board turning about the vertical with a slow tilt wobble, its gyroscope (body
# axes, counts at 65.5 per deg/s) with a bias, gravity and a field made with firmware.trig -
# the same bits on every interpreter. step(i, gyro, grav, field) fills the arrays for sample i
# (20 ms apart) without allocating; flags(i) says what the app would pass; filter() makes the
# arrays, a Compass on sample 0 and an Attitude on them.
from array import array

from firmware.trig import cos, sin

CPS_X10 = 655
CPG = 16384
RATE_KANG = 33       # heading step per sample: 33 KANG / 20 ms = 9.1 deg/s
BIAS = (120, -60, 200)  # gyro bias, counts (1.8, -0.9, 3.1 deg/s)


def step(i, gyro, grav, field):
    yaw = (i * RATE_KANG) & 0xFFFF
    roll = sin(i * 91) >> 4         # +-11 deg wobble (KANG)
    cr = cos(roll)
    sr = sin(roll)
    # gravity (AN4248 Gp, level +z) of a board rolled by `roll`
    grav[0] = 0
    grav[1] = (CPG * sr) >> 15
    grav[2] = (CPG * cr) >> 15
    # the field: 2000 counts north, 3464 down, in the rolled body frame
    bx = (2000 * cos(yaw)) >> 15
    by = -(2000 * sin(yaw)) >> 15
    bz = 3464
    field[0] = bx
    field[1] = (by * cr + bz * sr) >> 15
    field[2] = (bz * cr - by * sr) >> 15
    # yaw rate about world z seen in the body, roll rate about x, plus the bias
    gyro[0] = BIAS[0] + ((sin(i * 91 + 16384) * 91 >> 4) * 50 // 32768 * CPS_X10) // 6554
    gyro[1] = BIAS[1] + (((RATE_KANG * 50 * 360 * CPS_X10) >> 16) * sr >> 15) // 10
    gyro[2] = BIAS[2] + (((RATE_KANG * 50 * 360 * CPS_X10) >> 16) * cr >> 15) // 10


def flags(i):
    # the field checks flag a stretch (a magnet), the accelerometer another (braking)
    f = 7
    if 600 <= i < 850:
        f &= ~1
    if 1000 <= i < 1100:
        f &= ~4
    return f


def filter():
    """(attitude, gyro, grav, field, compass) for sample 0: the arrays are the filter's inputs
    (firmware.gyro.attitude is imported here: a scenario may pick its kernels first)."""
    from firmware.gyro.attitude import Attitude
    from firmware.compass import Compass
    gyro = array("h", (0, 0, 0))
    grav = array("h", (0, 0, 0))
    field = array("h", (0, 0, 0))
    c = Compass()
    step(0, gyro, grav, field)
    c.update(field, grav)
    return Attitude(gyro, grav, field, c, CPS_X10, CPG), gyro, grav, field, c
