# The attitude filter's per-sample steps (firmware/gyro/attitude.py), plain: loaded by
# attitude.use_kernels() on a port without the native emitter (or with fast=False); where the
# emitter exists firmware/gyro/attitude_fast.py's viper mirrors run instead (the same bits), and
# this module is not loaded. Each function works on the filter's state `st` (array('i'); the
# slot numbers below are attitude.py's) and the app's int16 arrays; each keeps its frame within
# the 11 words MicroPython holds on the C stack (see firmware/compass.py), so nothing is
# allocated. Products of a Q28 and a Q14 are written out as (a >> 14) b + ((a & 0x3FFF) b >>
# 14), exact, and below 2**30 (tests/test_attitude.py drives an instrumented copy).
from firmware.compat import const
from firmware.axes import apply  # (the app's axis map, re-exported for the kernel set)
from firmware.trig import atan2

_ONE28 = const(0x10000000)
_M14 = const(0x3FFF)
_BIAS_MAX = const(1 << 25)  # 2**13 counts in 1/4096 count: 62 deg/s at +-250 deg/s

# attitude.py's slots (tests/test_attitude.py checks they agree)
_Q = const(0)
_BIAS = const(4)
_U = const(7)
_R = const(10)
_QH = const(13)
_D = const(17)
_G = const(20)
_KI = const(23)
_KF = const(24)
_KA = const(25)
_KM = const(26)
_KB = const(27)
_GP = const(37)
_ACC_LIM = const(46)
_HEAD = const(48)
_SCR = const(51)
_C = const(54)
_CHUNK_US = const(32767)


def rates(st, gyro):
    """u = 16 x the mean of this and the last gyro sample (the trapezoid rule: the rate is
    sampled at the ends of the interval) - bias + the corrections (1/16 count). Returns the
    largest |16 x gyro - bias| over the axes: how fast the board turns."""
    g = gyro[0]
    b = st[_BIAS] >> 8
    st[_U] = ((g + st[_GP]) << 3) - b + st[_C]
    st[_GP] = g
    m = (g << 4) - b
    if m < 0:
        m = -m
    g = gyro[1]
    b = st[_BIAS + 1] >> 8
    st[_U + 1] = ((g + st[_GP + 1]) << 3) - b + st[_C + 1]
    st[_GP + 1] = g
    b = (g << 4) - b
    if b < 0:
        b = -b
    if b > m:
        m = b
    g = gyro[2]
    b = st[_BIAS + 2] >> 8
    st[_U + 2] = ((g + st[_GP + 2]) << 3) - b + st[_C + 2]
    st[_GP + 2] = g
    b = (g << 4) - b
    if b < 0:
        b = -b
    return b if b > m else m


def q_hi(st):
    st[_QH] = st[_Q] >> 14
    st[_QH + 1] = st[_Q + 1] >> 14
    st[_QH + 2] = st[_Q + 2] >> 14
    st[_QH + 3] = st[_Q + 3] >> 14


def down(st):
    """d = (C31, C32, C33), the down direction in the body frame, Q14."""
    w = st[_QH]
    x = st[_QH + 1]
    y = st[_QH + 2]
    z = st[_QH + 3]
    st[_D] = (x * z - w * y) >> 13
    st[_D + 1] = (y * z + w * x) >> 13
    st[_D + 2] = 16384 - ((x * x + y * y) >> 13)


def tilt_error(st):
    """e = g x d (Q14 x Q14 >> 14), g the scaled gravity in st[_G..]; returns |e|^2 relative
    to |g|^2 in Q28 (sin^2 of the angle between them)."""
    g0 = st[_G]
    g1 = st[_G + 1]
    g2 = st[_G + 2]
    st[_SCR] = (g1 * st[_D + 2] - g2 * st[_D + 1]) >> 14
    st[_SCR + 1] = (g2 * st[_D] - g0 * st[_D + 2]) >> 14
    st[_SCR + 2] = (g0 * st[_D + 1] - g1 * st[_D]) >> 14
    return g0 * g0 + g1 * g1 + g2 * g2


def tilt_sine(st, n):
    """e = (g x d) / |g| in st[_SCR..] (Q14: the sine of the tilt error); n = |g| scaled."""
    st[_SCR] = (st[_SCR] << 14) // n
    st[_SCR + 1] = (st[_SCR + 1] << 14) // n
    st[_SCR + 2] = (st[_SCR + 2] << 14) // n


def accel_apply(st):
    """Add gain x e to the rates; False (nothing added) when e is past accel_reject."""
    e = st[_SCR]
    m = e * e
    e = st[_SCR + 1]
    m += e * e
    e = st[_SCR + 2]
    if m + e * e > st[_ACC_LIM]:
        return False
    k = st[_KA]
    st[_U] += (st[_SCR] * k) >> 12
    st[_U + 1] += (st[_SCR + 1] * k) >> 12
    st[_U + 2] += (e * k) >> 12
    return True


def field_error(st):
    """The heading error (KANG): the direction of m = C b in the filter's level frame, b the
    scaled field in st[_G..] (C's first two rows from q >> 14)."""
    w = st[_QH]
    x = st[_QH + 1]
    y = st[_QH + 2]
    z = st[_QH + 3]
    st[_SCR] = 16384 - ((y * y + z * z) >> 13)  # C11
    st[_SCR + 1] = (x * y - w * z) >> 13        # C12
    st[_SCR + 2] = (x * z + w * y) >> 13        # C13
    mx = (st[_SCR] * st[_G] + st[_SCR + 1] * st[_G + 1] + st[_SCR + 2] * st[_G + 2]) >> 14
    st[_SCR] = (x * y + w * z) >> 13            # C21
    st[_SCR + 1] = 16384 - ((x * x + z * z) >> 13)  # C22
    st[_SCR + 2] = (y * z - w * x) >> 13        # C23
    return atan2((st[_SCR] * st[_G] + st[_SCR + 1] * st[_G + 1]
                  + st[_SCR + 2] * st[_G + 2]) >> 14, mx)


def yaw_rate(st, e):
    """Turn the rates about the down axis by mag_gain x the heading error e (KANG), at most
    65535 (1/16 count: 4096 counts, 31 deg/s and more: c x d stays below 2**30)."""
    c = -((e * st[_KM]) >> 12)
    if c > 65535:
        c = 65535
    elif c < -65535:
        c = -65535
    st[_U] += (c * st[_D]) >> 14
    st[_U + 1] += (c * st[_D + 1]) >> 14
    st[_U + 2] += (c * st[_D + 2]) >> 14


def integral(st, dt):
    """The bias takes bias_gain of the corrections over dt (within +-2**13 counts)."""
    k = st[_KB]
    c = st[_C]
    bias_step(st, 0, (((c >> 15) * dt + (((c & 0x7FFF) * dt) >> 15)) * k) >> 6)
    c = st[_C + 1]
    bias_step(st, 1, (((c >> 15) * dt + (((c & 0x7FFF) * dt) >> 15)) * k) >> 6)
    c = st[_C + 2]
    bias_step(st, 2, (((c >> 15) * dt + (((c & 0x7FFF) * dt) >> 15)) * k) >> 6)


def bias_step(st, i, d):
    d = st[_BIAS + i] - d
    st[_BIAS + i] = d if -_BIAS_MAX <= d <= _BIAS_MAX else (_BIAS_MAX if d > 0 else -_BIAS_MAX)


def half_angles(st):
    """r = u x k: the half angle per 32768 us, Q28 rad (mul14 written out, here and below:
    a call costs more than the product)."""
    i = st[_KI]
    f = st[_KF]
    u = st[_U]
    st[_R] = u * i + (u >> 14) * f + (((u & _M14) * f) >> 14)
    u = st[_U + 1]
    st[_R + 1] = u * i + (u >> 14) * f + (((u & _M14) * f) >> 14)
    u = st[_U + 2]
    st[_R + 2] = u * i + (u >> 14) * f + (((u & _M14) * f) >> 14)


def integrate(st, dt):
    """q += q (0, h) with h = r x dt / 32768 (dt < 32768 us): Q28."""
    r = st[_R]
    st[_SCR] = (r >> 15) * dt + (((r & 0x7FFF) * dt) >> 15)
    r = st[_R + 1]
    st[_SCR + 1] = (r >> 15) * dt + (((r & 0x7FFF) * dt) >> 15)
    r = st[_R + 2]
    st[_SCR + 2] = (r >> 15) * dt + (((r & 0x7FFF) * dt) >> 15)
    q_hi(st)
    dq_wx(st)
    dq_yz(st)


def dq_wx(st):
    # w -= x h0 + y h1 + z h2;  x += w h0 + y h2 - z h1  (q (0, h): q before the step)
    h0 = st[_SCR]
    h1 = st[_SCR + 1]
    h2 = st[_SCR + 2]
    q = st[_QH + 1]
    d = (h0 >> 14) * q + (((h0 & _M14) * q) >> 14)
    q = st[_QH + 2]
    d += (h1 >> 14) * q + (((h1 & _M14) * q) >> 14)
    q = st[_QH + 3]
    d += (h2 >> 14) * q + (((h2 & _M14) * q) >> 14)
    st[_Q] -= d
    q = st[_QH]
    d = (h0 >> 14) * q + (((h0 & _M14) * q) >> 14)
    q = st[_QH + 2]
    d += (h2 >> 14) * q + (((h2 & _M14) * q) >> 14)
    q = st[_QH + 3]
    d -= (h1 >> 14) * q + (((h1 & _M14) * q) >> 14)
    st[_Q + 1] += d


def dq_yz(st):
    # y += w h1 + z h0 - x h2;  z += w h2 + x h1 - y h0
    h0 = st[_SCR]
    h1 = st[_SCR + 1]
    h2 = st[_SCR + 2]
    q = st[_QH]
    d = (h1 >> 14) * q + (((h1 & _M14) * q) >> 14)
    q = st[_QH + 3]
    d += (h0 >> 14) * q + (((h0 & _M14) * q) >> 14)
    q = st[_QH + 1]
    d -= (h2 >> 14) * q + (((h2 & _M14) * q) >> 14)
    st[_Q + 2] += d
    q = st[_QH]
    d = (h2 >> 14) * q + (((h2 & _M14) * q) >> 14)
    q = st[_QH + 1]
    d += (h1 >> 14) * q + (((h1 & _M14) * q) >> 14)
    q = st[_QH + 2]
    d -= (h0 >> 14) * q + (((h0 & _M14) * q) >> 14)
    st[_Q + 3] += d


def normalise(st):
    """q x (3 - |q|^2) / 2 (one Newton step toward |q| = 1; the drift per sample is tiny)."""
    q_hi(st)
    e = st[_QH]
    n = e * e
    e = st[_QH + 1]
    n += e * e
    e = st[_QH + 2]
    n += e * e
    e = st[_QH + 3]
    e = (_ONE28 - n - e * e) >> 15  # (1 - |q|^2) / 2, Q14
    if e > 8191:
        e = 8191
    elif e < -8191:
        e = -8191
    q = st[_Q]
    st[_Q] = q + (q >> 14) * e + (((q & _M14) * e) >> 14)
    q = st[_Q + 1]
    st[_Q + 1] = q + (q >> 14) * e + (((q & _M14) * e) >> 14)
    q = st[_Q + 2]
    st[_Q + 2] = q + (q >> 14) * e + (((q & _M14) * e) >> 14)
    q = st[_Q + 3]
    st[_Q + 3] = q + (q >> 14) * e + (((q & _M14) * e) >> 14)


def advance(st, dt):
    """The gyro step over dt in chunks below 32768 us (the integral term with each), |q|
    back to 1 after each (a long gap's many chunks would otherwise grow it past what one
    Newton step brings back)."""
    half_angles(st)
    while dt > 0:
        c = dt if dt < _CHUNK_US else _CHUNK_US
        integrate(st, c)
        if st[_KB]:
            integral(st, c)
        normalise(st)
        dt -= c


def angles(st):
    """The heading, psi = atan2(C21, C11), from q >> 14 as it is (the corrections just made
    it from this q); pitch and roll are computed when asked for (attitude.tilt())."""
    w = st[_QH]
    x = st[_QH + 1]
    y = st[_QH + 2]
    z = st[_QH + 3]
    st[_HEAD] = atan2((x * y + w * z) >> 13, 16384 - ((y * y + z * z) >> 13)) & 0xFFFF
