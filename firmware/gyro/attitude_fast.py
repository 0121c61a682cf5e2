# The attitude filter's per-sample steps as viper mirrors of firmware/gyro/attitude_plain.py: the
# same names, signatures and bits. attitude.use_kernels() imports this module, inside
# try/except, where the port has the native emitter (firmware/fast.py loaded: its atan2 is
# used here); on any other port it is never imported.
#
# The state is an array('i') of values up to 2**30 in magnitude: a load is sign-extended from
# 31 bits, ((v + 2**30) & (2**31 - 1)) - 2**30, with both constants made at run time (2**30 is
# no small int on a 32-bit port, so a literal would be an object); values below 2**17 use the
# 18-bit form of firmware/fast.py. The gyro, gravity and field arrays are array('h') (ptr16,
# sign-extended by hand). Slot numbers are attitude.py's: 0 q, 4 bias, 7 u, 10 r, 13 q >> 14,
# 17 d, 20 scaled vector, 23..27 KI KF KA KM KB, 37 last gyro, 46 ACC_LIM, 48 heading,
# 51 scratch, 54 corrections. Every intermediate is below 2**30 (the plain functions' bound),
# so a 32-bit word never wraps; tests/test_attitude.py compares each function with its plain
# original on the native tiers.
import micropython

from firmware.fast import apply, atan2  # (apply: the app's axis map, firmware/axes.py)


@micropython.viper
def rates(st, gyro) -> int:
    """attitude_plain.rates."""
    s = ptr32(st)
    g = ptr16(gyro)
    h = 1
    h <<= 30  # at run time: the literal 2**30 would be an object on a 32-bit port
    m = h + (h - 1)
    r = 0
    for i in range(3):
        v = ((g[i] + 0x8000) & 0xFFFF) - 0x8000
        p = ((s[37 + i] + h) & m) - h
        b = (((s[4 + i] + h) & m) - h) >> 8
        c = ((s[54 + i] + h) & m) - h
        s[7 + i] = ((v + p) << 3) - b + c
        s[37 + i] = v
        d = (v << 4) - b
        if d < 0:
            d = 0 - d
        if d > r:
            r = d
    return r


@micropython.viper
def q_hi(st):
    """attitude_plain.q_hi."""
    s = ptr32(st)
    h = 1
    h <<= 30  # at run time: the literal 2**30 would be an object on a 32-bit port
    m = h + (h - 1)
    for i in range(4):
        s[13 + i] = (((s[i] + h) & m) - h) >> 14


@micropython.viper
def down(st):
    """attitude_plain.down."""
    s = ptr32(st)
    w = ((s[13] + 0x20000) & 0x3FFFF) - 0x20000
    x = ((s[14] + 0x20000) & 0x3FFFF) - 0x20000
    y = ((s[15] + 0x20000) & 0x3FFFF) - 0x20000
    z = ((s[16] + 0x20000) & 0x3FFFF) - 0x20000
    s[17] = (x * z - w * y) >> 13
    s[18] = (y * z + w * x) >> 13
    s[19] = 16384 - ((x * x + y * y) >> 13)


@micropython.viper
def tilt_error(st) -> int:
    """attitude_plain.tilt_error."""
    s = ptr32(st)
    g0 = ((s[20] + 0x20000) & 0x3FFFF) - 0x20000
    g1 = ((s[21] + 0x20000) & 0x3FFFF) - 0x20000
    g2 = ((s[22] + 0x20000) & 0x3FFFF) - 0x20000
    d0 = ((s[17] + 0x20000) & 0x3FFFF) - 0x20000
    d1 = ((s[18] + 0x20000) & 0x3FFFF) - 0x20000
    d2 = ((s[19] + 0x20000) & 0x3FFFF) - 0x20000
    s[51] = (g1 * d2 - g2 * d1) >> 14
    s[52] = (g2 * d0 - g0 * d2) >> 14
    s[53] = (g0 * d1 - g1 * d0) >> 14
    return g0 * g0 + g1 * g1 + g2 * g2


@micropython.viper
def tilt_sine(st, n: int):
    """attitude_plain.tilt_sine."""
    s = ptr32(st)
    for i in range(3):
        v = ((s[51 + i] + 0x20000) & 0x3FFFF) - 0x20000
        s[51 + i] = (v << 14) // n


@micropython.viper
def accel_apply(st) -> int:
    """attitude_plain.accel_apply (1 / 0 for True / False)."""
    s = ptr32(st)
    e0 = ((s[51] + 0x20000) & 0x3FFFF) - 0x20000
    e1 = ((s[52] + 0x20000) & 0x3FFFF) - 0x20000
    e2 = ((s[53] + 0x20000) & 0x3FFFF) - 0x20000
    h = 1
    h <<= 30  # at run time: the literal 2**30 would be an object on a 32-bit port
    m = h + (h - 1)
    if e0 * e0 + e1 * e1 + e2 * e2 > ((s[46] + h) & m) - h:
        return 0
    k = s[25]
    for i in range(3):
        e = ((s[51 + i] + 0x20000) & 0x3FFFF) - 0x20000
        s[7 + i] = (((s[7 + i] + h) & m) - h) + ((e * k) >> 12)
    return 1


@micropython.viper
def field_error(st) -> int:
    """attitude_plain.field_error."""
    s = ptr32(st)
    w = ((s[13] + 0x20000) & 0x3FFFF) - 0x20000
    x = ((s[14] + 0x20000) & 0x3FFFF) - 0x20000
    y = ((s[15] + 0x20000) & 0x3FFFF) - 0x20000
    z = ((s[16] + 0x20000) & 0x3FFFF) - 0x20000
    b0 = ((s[20] + 0x20000) & 0x3FFFF) - 0x20000
    b1 = ((s[21] + 0x20000) & 0x3FFFF) - 0x20000
    b2 = ((s[22] + 0x20000) & 0x3FFFF) - 0x20000
    c1 = 16384 - ((y * y + z * z) >> 13)
    c2 = (x * y - w * z) >> 13
    c3 = (x * z + w * y) >> 13
    s[51] = c1
    s[52] = c2
    s[53] = c3
    mx = (c1 * b0 + c2 * b1 + c3 * b2) >> 14
    c1 = (x * y + w * z) >> 13
    c2 = 16384 - ((x * x + z * z) >> 13)
    c3 = (y * z - w * x) >> 13
    s[51] = c1
    s[52] = c2
    s[53] = c3
    return int(atan2((c1 * b0 + c2 * b1 + c3 * b2) >> 14, mx))


@micropython.viper
def yaw_rate(st, e: int):
    """attitude_plain.yaw_rate."""
    s = ptr32(st)
    h = 1
    h <<= 30  # at run time: the literal 2**30 would be an object on a 32-bit port
    m = h + (h - 1)
    c = 0 - ((e * s[26]) >> 12)
    if c > 65535:
        c = 65535
    elif c < -65535:
        c = -65535
    for i in range(3):
        d = ((s[17 + i] + 0x20000) & 0x3FFFF) - 0x20000
        s[7 + i] = (((s[7 + i] + h) & m) - h) + ((c * d) >> 14)


@micropython.viper
def advance(st, dt: int):
    """attitude_plain.advance (half_angles, integrate and integral in chunks, normalise)."""
    s = ptr32(st)
    h = 1
    h <<= 30  # at run time: the literal 2**30 would be an object on a 32-bit port
    m = h + (h - 1)
    ki = s[23]
    kf = s[24]
    kb = s[27]
    lim = 1 << 25  # attitude._BIAS_MAX
    for i in range(3):
        u = ((s[7 + i] + h) & m) - h
        s[10 + i] = u * ki + (u >> 14) * kf + (((u & 0x3FFF) * kf) >> 14)
    r0 = ((s[10] + h) & m) - h
    r1 = ((s[11] + h) & m) - h
    r2 = ((s[12] + h) & m) - h
    while dt > 0:
        c = dt if dt < 32767 else 32767
        h0 = (r0 >> 15) * c + (((r0 & 0x7FFF) * c) >> 15)
        h1 = (r1 >> 15) * c + (((r1 & 0x7FFF) * c) >> 15)
        h2 = (r2 >> 15) * c + (((r2 & 0x7FFF) * c) >> 15)
        s[51] = h0
        s[52] = h1
        s[53] = h2
        w = (((s[0] + h) & m) - h) >> 14
        x = (((s[1] + h) & m) - h) >> 14
        y = (((s[2] + h) & m) - h) >> 14
        z = (((s[3] + h) & m) - h) >> 14
        for i in range(4):
            s[13 + i] = (((s[i] + h) & m) - h) >> 14
        # attitude.mul14 written out (a call would box its arguments, and cost code)
        d = ((h0 >> 14) * x + (((h0 & 0x3FFF) * x) >> 14)
             + (h1 >> 14) * y + (((h1 & 0x3FFF) * y) >> 14)
             + (h2 >> 14) * z + (((h2 & 0x3FFF) * z) >> 14))
        s[0] = (((s[0] + h) & m) - h) - d
        d = ((h0 >> 14) * w + (((h0 & 0x3FFF) * w) >> 14)
             + (h2 >> 14) * y + (((h2 & 0x3FFF) * y) >> 14)
             - ((h1 >> 14) * z + (((h1 & 0x3FFF) * z) >> 14)))
        s[1] = (((s[1] + h) & m) - h) + d
        d = ((h1 >> 14) * w + (((h1 & 0x3FFF) * w) >> 14)
             + (h0 >> 14) * z + (((h0 & 0x3FFF) * z) >> 14)
             - ((h2 >> 14) * x + (((h2 & 0x3FFF) * x) >> 14)))
        s[2] = (((s[2] + h) & m) - h) + d
        d = ((h2 >> 14) * w + (((h2 & 0x3FFF) * w) >> 14)
             + (h1 >> 14) * x + (((h1 & 0x3FFF) * x) >> 14)
             - ((h0 >> 14) * y + (((h0 & 0x3FFF) * y) >> 14)))
        s[3] = (((s[3] + h) & m) - h) + d
        if kb:
            for i in range(3):
                e = ((s[54 + i] + h) & m) - h
                e = (((e >> 15) * c + (((e & 0x7FFF) * c) >> 15)) * kb) >> 6
                v = (((s[4 + i] + h) & m) - h) - e
                if v > lim:
                    v = lim
                elif v < 0 - lim:
                    v = 0 - lim
                s[4 + i] = v
        # normalise, after each chunk: |q| back to 1 before the next (a long gap's many chunks)
        w = (((s[0] + h) & m) - h) >> 14
        x = (((s[1] + h) & m) - h) >> 14
        y = (((s[2] + h) & m) - h) >> 14
        z = (((s[3] + h) & m) - h) >> 14
        s[13] = w
        s[14] = x
        s[15] = y
        s[16] = z
        e = ((1 << 28) - (w * w + x * x + y * y + z * z)) >> 15
        if e > 8191:
            e = 8191
        elif e < -8191:
            e = -8191
        for i in range(4):
            q = ((s[i] + h) & m) - h
            s[i] = q + (q >> 14) * e + (((q & 0x3FFF) * e) >> 14)
        dt -= c


@micropython.viper
def angles(st):
    """attitude_plain.angles."""
    s = ptr32(st)
    w = ((s[13] + 0x20000) & 0x3FFFF) - 0x20000
    x = ((s[14] + 0x20000) & 0x3FFFF) - 0x20000
    y = ((s[15] + 0x20000) & 0x3FFFF) - 0x20000
    z = ((s[16] + 0x20000) & 0x3FFFF) - 0x20000
    s[48] = int(atan2((x * y + w * z) >> 13, 16384 - ((y * y + z * z) >> 13))) & 0xFFFF
