"""The fast path: viper mirrors of the per-sample steps, with the plain functions' signatures."""
# Imported only through firmware.compat.kernels(), inside try/except: a port without the native
# emitter (the WebAssembly port, CircuitPython) raises SyntaxError at compile time on
# @micropython.viper, and then everything runs the plain functions. Where it imports, the app
# and the Compass use these automatically; the results are the same bits (tests/test_fast.py).
# Which plain function each mirrors, and how the words stay within 32 bits: docs/design.md
# (module notes, fast).
import micropython

from firmware.trig_tables import ATAN_T, SIN_T

_AT = ATAN_T
_ST = SIN_T
_NONE = None  # viper compares an object with a global, not with the None literal


@micropython.viper
def atan2(y: int, x: int) -> int:
    """trig.atan2."""
    at = ptr32(_AT)
    n = y if y >= 0 else 0 - y
    d = x if x >= 0 else 0 - x
    sw = 0
    if n > d:  # second octant: atan(n/d) = 90 deg - atan(d/n)
        e = n
        n = d
        d = e
        sw = 1
    elif d == 0:
        return 0
    if n == d:
        a = 8192
    else:
        r = ((n << 15) + (d >> 1)) // d
        i = r >> 7
        e = at[i]
        a = ((e << 7) + (at[i + 1] - e) * (r & 127) + 0x4000) >> 15
    if sw:
        a = 16384 - a
    if x < 0:
        a = 32768 - a
    if y < 0:
        return 0 - a
    if a >= 32768:
        return -32768
    return a


@micropython.viper
def sin(angle: int) -> int:
    """trig.sin."""
    st = ptr32(_ST)
    a = angle & 0xFFFF
    r = a & 0x3FFF
    if a & 0x4000:
        r = 0x4000 - r
    i = r >> 6
    s = st[i]
    r = ((s << 6) + (st[i + 1] - s) * (r & 63) + 0x200) >> 10
    if r > 32767:
        r = 32767
    if a & 0x8000:
        return 0 - r
    return r


@micropython.viper
def cos(angle: int) -> int:
    """trig.cos."""
    return int(sin(angle + 16384))


@micropython.viper
def isqrt(n: int) -> int:
    # fixedpoint.isqrt for 0 <= n < 2**30. The floor square root is one number whatever the
    # method: here Newton's iteration from above (x0 = 2**15 > sqrt(n); each step is
    # floor((x + n // x) / 2) and decreases until it would not), where fixedpoint's bytecode
    # takes the digit-by-digit loop, which needs no division.
    if n < 2:
        return n
    x = 0x8000
    y = (x + n // x) >> 1
    while y < x:
        x = y
        y = (x + n // x) >> 1
    return x


@micropython.viper
def _rshift(v: int, n: int) -> int:
    # trig.rshift: v / 2**n rounded half away from zero
    if v < 0:
        return 0 - ((0 - v + (1 << (n - 1))) >> n)
    return (v + (1 << (n - 1))) >> n


@micropython.viper
def orient(st, b, g) -> int:
    """compass.orient."""
    p = ptr32(st)
    k = int(norm14(b, st, 0))
    if k == -128:  # trig.ZERO_VECTOR
        return -1
    p[6] = k
    if g is _NONE:
        level(st)
    elif int(norm14(g, st, 3)) == -128:
        return -2
    else:
        tilt(st)
    derotate(st)
    y = ((p[14] + 0x20000) & 0x3FFFF) - 0x20000
    x = ((p[13] + 0x20000) & 0x3FFFF) - 0x20000
    return int(atan2(0 - y, x)) & 0xFFFF


@micropython.viper
def level(st):
    """compass.level."""
    p = ptr32(st)
    p[11] = 0
    p[12] = 0
    p[7] = 0
    p[8] = 32768
    p[9] = 0
    p[10] = 32768


@micropython.viper
def tilt(st):
    """compass.tilt."""
    p = ptr32(st)
    gx = ((p[3] + 0x20000) & 0x3FFFF) - 0x20000
    gy = ((p[4] + 0x20000) & 0x3FFFF) - 0x20000
    gz = ((p[5] + 0x20000) & 0x3FFFF) - 0x20000
    a = int(atan2(gy, gz))
    p[11] = a
    s = int(sin(a))
    c = int(sin(a + 16384))
    p[7] = s
    p[8] = c
    a = int(atan2(0 - gx, (gy * s + gz * c + 0x4000) >> 15))
    p[12] = a
    p[9] = int(sin(a))
    p[10] = int(sin(a + 16384))


@micropython.viper
def derotate(st):
    """compass.derotate: Bf = Ry(-theta) Rx(-phi) Bp (AN4248 eq. 19) into 13..15, from the
    scaled b (0..2) and the sines and cosines of roll (7, 8) and pitch (9, 10)."""
    p = ptr32(st)
    x = ((p[0] + 0x20000) & 0x3FFFF) - 0x20000
    y = ((p[1] + 0x20000) & 0x3FFFF) - 0x20000
    z = ((p[2] + 0x20000) & 0x3FFFF) - 0x20000
    s = ((p[7] + 0x20000) & 0x3FFFF) - 0x20000
    c = ((p[8] + 0x20000) & 0x3FFFF) - 0x20000
    t = (y * s + z * c + 0x4000) >> 15
    p[14] = (y * c - z * s + 0x4000) >> 15
    s = ((p[9] + 0x20000) & 0x3FFFF) - 0x20000
    c = ((p[10] + 0x20000) & 0x3FFFF) - 0x20000
    p[13] = (x * c + t * s + 0x4000) >> 15
    p[15] = (t * c - x * s + 0x4000) >> 15


@micropython.viper
def magnitude(st) -> int:
    """compass.magnitude."""
    p = ptr32(st)
    n = 0
    for i in range(3):
        v = ((p[i] + 0x20000) & 0x3FFFF) - 0x20000
        n += v * v
    m = int(isqrt(n))
    k = ((p[6] + 0x20000) & 0x3FFFF) - 0x20000
    if k > 0:
        return (m + (1 << (k - 1))) >> k
    if k < 0:
        return m << (0 - k)
    return m


@micropython.viper
def dip(st) -> int:
    """compass.dip."""
    p = ptr32(st)
    n = 0
    for i in range(13, 15):
        v = ((p[i] + 0x20000) & 0x3FFFF) - 0x20000
        n += v * v
    return int(atan2(((p[15] + 0x20000) & 0x3FFFF) - 0x20000, int(isqrt(n))))


@micropython.viper
def judge(st) -> int:
    """compass.judge. |b| (20) and the |b| window (16, 17) are non-negative: their zero-extended
    loads are right as they are; the dip (21), its window (18, 19) and the pitch (12) are
    sign-extended."""
    p = ptr32(st)
    m = int(p[20])
    f = 1 if m < int(p[16]) or m > int(p[17]) else 0  # FLAG_INTERFERENCE
    m = ((p[21] + 0x20000) & 0x3FFFF) - 0x20000
    if m < ((p[18] + 0x20000) & 0x3FFFF) - 0x20000:
        f = 1
    if m > ((p[19] + 0x20000) & 0x3FFFF) - 0x20000:
        f = 1
    if m > 13653 or m < -13653:
        f |= 2  # FLAG_DIP_HIGH
    m = ((p[12] + 0x20000) & 0x3FFFF) - 0x20000
    if m > 14564 or m < -14564:
        f |= 4  # FLAG_GIMBAL
    return f


@micropython.viper
def measure(st, b, g) -> int:
    """compass.measure."""
    h = int(orient(st, b, g))
    if h >= 0:
        p = ptr32(st)
        p[20] = int(magnitude(st))
        p[21] = int(dip(st))
        p[22] = int(judge(st))
    return h


@micropython.viper
def norm14(src, dst, o: int) -> int:
    """trig.norm14. The shift is found on the largest |component| m without changing it:
    up while m << k < 2**13, down while m >> k >= 2**14 (trig's loop shifts m itself)."""
    x = int(src[0])
    y = int(src[1])
    z = int(src[2])
    m = x if x >= 0 else 0 - x
    k = y if y >= 0 else 0 - y
    if k > m:
        m = k
    k = z if z >= 0 else 0 - z
    if k > m:
        m = k
    if m == 0:
        return -128  # trig.ZERO_VECTOR
    k = 0
    if m < 0x2000:
        while (m << k) < 0x2000:
            k += 1
        dst[o] = x << k
        dst[o + 1] = y << k
        dst[o + 2] = z << k
        return k
    while (m >> k) >= 0x4000:
        k += 1
    if k == 0:
        dst[o] = x
        dst[o + 1] = y
        dst[o + 2] = z
        return 0
    dst[o] = _rshift(x, k)
    dst[o + 1] = _rshift(y, k)
    dst[o + 2] = _rshift(z, k)
    return 0 - k


@micropython.viper
def correct(k, raw, out):
    """calibration.correct; k = array('h') of InvW (0..8) then V (9..11)."""
    p = ptr16(k)
    # int16 from the unsigned 16-bit load: (u ^ 0x8000) - 0x8000
    x = int(raw[0]) - ((p[9] ^ 0x8000) - 0x8000)
    y = int(raw[1]) - ((p[10] ^ 0x8000) - 0x8000)
    z = int(raw[2]) - ((p[11] ^ 0x8000) - 0x8000)
    if x > 32767:
        x = 32767
    elif x < -32768:
        x = -32768
    if y > 32767:
        y = 32767
    elif y < -32768:
        y = -32768
    if z > 32767:
        z = 32767
    elif z < -32768:
        z = -32768
    a = (p[0] ^ 0x8000) - 0x8000
    b = (p[1] ^ 0x8000) - 0x8000
    c = (p[2] ^ 0x8000) - 0x8000
    out[0] = (a * x + b * y + c * z + 16384) >> 15
    a = (p[3] ^ 0x8000) - 0x8000
    b = (p[4] ^ 0x8000) - 0x8000
    c = (p[5] ^ 0x8000) - 0x8000
    out[1] = (a * x + b * y + c * z + 16384) >> 15
    a = (p[6] ^ 0x8000) - 0x8000
    b = (p[7] ^ 0x8000) - 0x8000
    c = (p[8] ^ 0x8000) - 0x8000
    out[2] = (a * x + b * y + c * z + 16384) >> 15


@micropython.viper
def apply(m, src, dst):
    """axes.apply; m = AxisMap.m, array('b'): source axes of body x, y, z, then negations."""
    p = ptr8(m)
    x = int(src[p[0]])
    y = int(src[p[1]])
    z = int(src[p[2]])
    if p[3]:
        x = 32767 if x == -32768 else 0 - x
    if p[4]:
        y = 32767 if y == -32768 else 0 - y
    if p[5]:
        z = 32767 if z == -32768 else 0 - z
    dst[0] = x
    dst[1] = y
    dst[2] = z


# --- samples.SampleBuffer.offer's rejection test ------------------------------------------
# The candidate and the buffer's scalars travel in its scratch array q (array('i'): 0..2 the
# candidate, 3..5 its cell, 6..8 the cell probed, 9 the separation s, 10 s * s, 11 the table
# mask, 12/13 the cells and entries counted); data and cells are array('h') (ptr16, unsigned:
# sign-extended by hand), the table array('H'). Every value is below 2**17 in magnitude but
# s * s (< 2**30, non-negative) and the mask: the 18-bit sign extension as above.

@micropython.viper
def _near(q, data, j: int) -> int:
    # samples.SampleBuffer._near: 1 when held sample data[j..j+2] is closer than s
    p = ptr32(q)
    d = ptr16(data)
    s = int(p[9])
    a = ((d[j] ^ 0x8000) - 0x8000) - (((p[0] + 0x20000) & 0x3FFFF) - 0x20000)
    if a <= 0 - s or a >= s:
        return 0
    b = ((d[j + 1] ^ 0x8000) - 0x8000) - (((p[1] + 0x20000) & 0x3FFFF) - 0x20000)
    if b <= 0 - s or b >= s:
        return 0
    c = ((d[j + 2] ^ 0x8000) - 0x8000) - (((p[2] + 0x20000) & 0x3FFFF) - 0x20000)
    if c <= 0 - s or c >= s:
        return 0
    return 1 if a * a + b * b + c * c < int(p[10]) else 0


@micropython.viper
def _chain(q, data, cells, table) -> int:
    # samples.SampleBuffer._probe: the chain of the cell in q[6..8]; 0 far (an empty entry
    # ends it), 1 taken (the cell's occupant), 2 near (a sample within s met on the way)
    p = ptr32(q)
    c = ptr16(cells)
    t = ptr16(table)
    cx = ((p[6] + 0x20000) & 0x3FFFF) - 0x20000
    cy = ((p[7] + 0x20000) & 0x3FFFF) - 0x20000
    cz = ((p[8] + 0x20000) & 0x3FFFF) - 0x20000
    h = (cx * 0x2F1B) ^ (cy * 0x1D4F) ^ (cz * 0x3A95)  # samples._hash
    h = (h ^ (h >> 13)) & 0x7FFF
    h *= 0x5BD1
    i = (h ^ (h >> 15)) & int(p[11])
    p[12] = p[12] + 1
    while True:
        p[13] = p[13] + 1
        e = int(t[i])
        if e == 0:
            return 0
        e = 3 * (e - 1)
        if int(_near(q, data, e)):
            return 2
        if (((c[e] ^ 0x8000) - 0x8000) == cx and ((c[e + 1] ^ 0x8000) - 0x8000) == cy
                and ((c[e + 2] ^ 0x8000) - 0x8000) == cz):
            return 1
        i = (i + 1) & int(p[11])


@micropython.viper
def _gap(q, k: int, side: int) -> int:
    # samples.SampleBuffer._gaps, one entry: the squared gap to the cell below (side 0) or
    # above (side 1) the candidate's on axis k
    p = ptr32(q)
    s = int(p[9])
    u = (((p[k] + 0x20000) & 0x3FFFF) - 0x20000) - (((p[3 + k] + 0x20000) & 0x3FFFF)
                                                   - 0x20000) * s + 1
    if side:
        u = s + 1 - u
    return u * u


@micropython.viper
def _around(q, data, cells, table) -> int:
    # samples.SampleBuffer._neighbours (with _plane and _row): 1 when a neighbour cell holds
    # a sample within s; the cells whose nearest point is s or more away are skipped
    p = ptr32(q)
    s2 = int(p[10])
    a = -1
    while a <= 1:
        ga = int(_gap(q, 0, a + 1 >> 1)) if a else 0
        if ga < s2:
            p[6] = p[3] + a
            b = -1
            while b <= 1:
                gb = ga + (int(_gap(q, 1, b + 1 >> 1)) if b else 0)
                if gb < s2:
                    p[7] = p[4] + b
                    c = -1
                    while c <= 1:
                        gc = gb + (int(_gap(q, 2, c + 1 >> 1)) if c else 0)
                        if gc < s2 and gc != 0:
                            p[8] = p[5] + c
                            if int(_chain(q, data, cells, table)) == 2:
                                return 1
                        c += 1
                b += 1
        a += 1
    return 0


@micropython.viper
def screen(b) -> int:
    """samples.screen."""
    q = b._q
    p = ptr32(q)
    data = b.data
    cells = b._cells
    table = b._table
    s = int(b.separation)
    p[9] = s
    p[10] = int(b._s2)
    p[11] = int(b._mask)
    p[12] = 0
    p[13] = 0
    r = 1
    last = int(b._last)
    if last < 0 or not int(_near(q, data, 3 * last)):
        p[3] = (((p[0] + 0x20000) & 0x3FFFF) - 0x20000) // s
        p[4] = (((p[1] + 0x20000) & 0x3FFFF) - 0x20000) // s
        p[5] = (((p[2] + 0x20000) & 0x3FFFF) - 0x20000) // s
        p[6] = p[3]
        p[7] = p[4]
        p[8] = p[5]
        if int(_chain(q, data, cells, table)) == 0:
            r = int(_around(q, data, cells, table))
    b.last_cells = int(p[12])
    b.last_probes = int(p[13])
    return r


@micropython.viper
def int16x3_into(d, buf, msb: int):
    """i2cdevice.int16x3_into."""
    p = ptr8(d)
    h = 1 - msb
    v = (p[h] << 8) | p[msb]
    buf[0] = v - 0x10000 if v & 0x8000 else v
    v = (p[2 + h] << 8) | p[2 + msb]
    buf[1] = v - 0x10000 if v & 0x8000 else v
    v = (p[4 + h] << 8) | p[4 + msb]
    buf[2] = v - 0x10000 if v & 0x8000 else v

