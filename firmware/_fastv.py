"""Viper kernels behind firmware/fast.py (MicroPython with the native emitter only).

Each kernel computes, operation for operation, what the plain firmware computes:
Compass.update (firmware/heading.py: _norm14, atan2, sin, cos and fixedpoint.isqrt inlined
into orient(), since a viper call costs about as much as the arithmetic it would save),
Calibration.correct (firmware/magcal.py), AxisMap.apply (firmware/axes.py); fast.Pipeline's
update() strings the three together with no call in between. Viper ints are machine words (32 bits
on the boards, 64 on the unix port); every intermediate here is below 2**30 for int16 inputs,
the bound firmware/heading.py and magcal.py prove for the plain code, so the words never wrap
and the results are the same bits. `//` and `>>` have Python's floor semantics in viper.
tests/test_fast.py checks the outputs against the plain code on MicroPython.

Tables: heading's atan and sine tables copied into array('i') (viper reads them with ptr32;
every entry is non-negative, so the unsigned load of the unix port changes nothing).
"""
import micropython
from array import array

from firmware.heading import _ATAN_T, _SIN_T

_AT = array("i", _ATAN_T)
_ST = array("i", _SIN_T)


@micropython.viper
def heading(c, b, g, level: int) -> int:
    """Compass.update(b, g) on Compass `c` (g ignored when level)."""
    if level:
        return int(orient(c, int(b[0]), int(b[1]), int(b[2]), 0, 0, 0, 1))
    return int(orient(c, int(b[0]), int(b[1]), int(b[2]), int(g[0]), int(g[1]), int(g[2]), 0))


@micropython.viper
def orient(c, x: int, y: int, z: int, gx: int, gy: int, gz: int, level: int) -> int:
    """Compass.update((x, y, z), (gx, gy, gz)) on Compass `c` (gravity ignored when level):
    the same return value and public attributes (heading, pitch, roll, dip, magnitude,
    flags and the three booleans)."""
    at = ptr32(_AT)
    st = ptr32(_ST)
    # heading._norm14: the shift k putting the largest |component| in [2**13, 2**14)
    m = x if x >= 0 else 0 - x
    k = y if y >= 0 else 0 - y
    if k > m:
        m = k
    k = z if z >= 0 else 0 - z
    if k > m:
        m = k
    if m == 0:
        c.flags = 8  # FLAG_NO_FIELD
        return -1
    kb = 0
    while m < 0x2000:
        m <<= 1
        kb += 1
    while m >= 0x4000:
        m >>= 1
        kb -= 1
    if kb >= 0:
        v0 = x << kb
        v1 = y << kb
        v2 = z << kb
    else:  # heading._rshift: halves away from zero
        k = 0 - kb
        r = 1 << (k - 1)
        v0 = (x + r) >> k if x >= 0 else 0 - ((r - x) >> k)
        v1 = (y + r) >> k if y >= 0 else 0 - ((r - y) >> k)
        v2 = (z + r) >> k if z >= 0 else 0 - ((r - z) >> k)
    if level:
        c.roll_kang = 0
        c.pitch_kang = 0
        pitch = 0
        sphi = 0
        cphi = 32768
        sth = 0
        cth = 32768
    else:
        x = gx
        y = gy
        z = gz
        m = x if x >= 0 else 0 - x
        k = y if y >= 0 else 0 - y
        if k > m:
            m = k
        k = z if z >= 0 else 0 - z
        if k > m:
            m = k
        if m == 0:
            c.flags = 16  # FLAG_NO_GRAVITY
            return -1
        k = 0
        while m < 0x2000:
            m <<= 1
            k += 1
        while m >= 0x4000:
            m >>= 1
            k -= 1
        if k >= 0:
            x <<= k
            y <<= k
            z <<= k
        else:
            k = 0 - k
            r = 1 << (k - 1)
            x = (x + r) >> k if x >= 0 else 0 - ((r - x) >> k)
            y = (y + r) >> k if y >= 0 else 0 - ((r - y) >> k)
            z = (z + r) >> k if z >= 0 else 0 - ((r - z) >> k)
        # roll, AN4248 eq. 13
        # a = heading.atan2(y, z), inlined
        n = y if y >= 0 else 0 - y
        d = z if z >= 0 else 0 - z
        sw = 0
        if n > d:  # second octant: atan(n/d) = 90 deg - atan(d/n)
            e = n
            n = d
            d = e
            sw = 1
        a = 0
        if d:
            if n == d:
                a = 8192
            else:
                r = ((n << 15) + (d >> 1)) // d
                i = r >> 7
                e = at[i]
                a = ((e << 7) + (at[i + 1] - e) * (r & 127) + 0x4000) >> 15
            if sw:
                a = 16384 - a
            if z < 0:
                a = 32768 - a
            if y < 0:
                a = 0 - a
            elif a >= 32768:
                a = -32768
        c.roll_kang = a
        # sphi = heading.sin(roll), inlined
        e = a & 0xFFFF
        r = e & 0x3FFF
        if e & 0x4000:
            r = 0x4000 - r
        i = r >> 6
        n = st[i]
        r = ((n << 6) + (st[i + 1] - n) * (r & 63) + 0x200) >> 10
        if r > 32767:
            r = 32767
        sphi = 0 - r if e & 0x8000 else r
        # cphi = heading.cos(roll), inlined
        e = (a + 16384) & 0xFFFF
        r = e & 0x3FFF
        if e & 0x4000:
            r = 0x4000 - r
        i = r >> 6
        n = st[i]
        r = ((n << 6) + (st[i + 1] - n) * (r & 63) + 0x200) >> 10
        if r > 32767:
            r = 32767
        cphi = 0 - r if e & 0x8000 else r
        a = (y * sphi + z * cphi + 0x4000) >> 15
        x = 0 - x
        # pitch, eq. 15
        # pitch = heading.atan2(x, a), inlined
        n = x if x >= 0 else 0 - x
        d = a if a >= 0 else 0 - a
        sw = 0
        if n > d:  # second octant: atan(n/d) = 90 deg - atan(d/n)
            e = n
            n = d
            d = e
            sw = 1
        pitch = 0
        if d:
            if n == d:
                pitch = 8192
            else:
                r = ((n << 15) + (d >> 1)) // d
                i = r >> 7
                e = at[i]
                pitch = ((e << 7) + (at[i + 1] - e) * (r & 127) + 0x4000) >> 15
            if sw:
                pitch = 16384 - pitch
            if a < 0:
                pitch = 32768 - pitch
            if x < 0:
                pitch = 0 - pitch
            elif pitch >= 32768:
                pitch = -32768
        c.pitch_kang = pitch
        # sth = heading.sin(pitch), inlined
        e = pitch & 0xFFFF
        r = e & 0x3FFF
        if e & 0x4000:
            r = 0x4000 - r
        i = r >> 6
        n = st[i]
        r = ((n << 6) + (st[i + 1] - n) * (r & 63) + 0x200) >> 10
        if r > 32767:
            r = 32767
        sth = 0 - r if e & 0x8000 else r
        # cth = heading.cos(pitch), inlined
        e = (pitch + 16384) & 0xFFFF
        r = e & 0x3FFF
        if e & 0x4000:
            r = 0x4000 - r
        i = r >> 6
        n = st[i]
        r = ((n << 6) + (st[i + 1] - n) * (r & 63) + 0x200) >> 10
        if r > 32767:
            r = 32767
        cth = 0 - r if e & 0x8000 else r
    # eq. 19
    t = (v1 * sphi + v2 * cphi + 0x4000) >> 15
    bfy = (v1 * cphi - v2 * sphi + 0x4000) >> 15
    bfx = (v0 * cth + t * sth + 0x4000) >> 15
    bfz = (t * cth - v0 * sth + 0x4000) >> 15
    y = 0 - bfy
    # psi, eq. 22
    # h = heading.atan2(y, bfx), inlined
    n = y if y >= 0 else 0 - y
    d = bfx if bfx >= 0 else 0 - bfx
    sw = 0
    if n > d:  # second octant: atan(n/d) = 90 deg - atan(d/n)
        e = n
        n = d
        d = e
        sw = 1
    h = 0
    if d:
        if n == d:
            h = 8192
        else:
            r = ((n << 15) + (d >> 1)) // d
            i = r >> 7
            e = at[i]
            h = ((e << 7) + (at[i + 1] - e) * (r & 127) + 0x4000) >> 15
        if sw:
            h = 16384 - h
        if bfx < 0:
            h = 32768 - h
        if y < 0:
            h = 0 - h
        elif h >= 32768:
            h = -32768
    h &= 0xFFFF
    # field magnitude and interference (Compass._check_field)
    # m = fixedpoint.isqrt(v0 * v0 + v1 * v1 + v2 * v2), inlined (its < 2**30 branch)
    n = v0 * v0 + v1 * v1 + v2 * v2
    r = 0
    e = 0x10000000
    while e > n:
        e >>= 2
    while e:
        if n >= r + e:
            n -= r + e
            r = (r >> 1) + e
        else:
            r >>= 1
        e >>= 2
    m = r
    if kb > 0:
        m = (m + (1 << (kb - 1))) >> kb
    elif kb < 0:
        m <<= 0 - kb
    c.magnitude = m
    flags = 0
    bad = m < int(c._lo) or m > int(c._hi)
    c.interference = bad
    if bad:
        flags = 1  # FLAG_INTERFERENCE
    # dip and gimbal (Compass._check_dip)
    # x = fixedpoint.isqrt(bfx * bfx + bfy * bfy), inlined (its < 2**30 branch)
    n = bfx * bfx + bfy * bfy
    r = 0
    e = 0x10000000
    while e > n:
        e >>= 2
    while e:
        if n >= r + e:
            n -= r + e
            r = (r >> 1) + e
        else:
            r >>= 1
        e >>= 2
    x = r
    # a = heading.atan2(bfz, x), inlined
    n = bfz if bfz >= 0 else 0 - bfz
    d = x if x >= 0 else 0 - x
    sw = 0
    if n > d:  # second octant: atan(n/d) = 90 deg - atan(d/n)
        e = n
        n = d
        d = e
        sw = 1
    a = 0
    if d:
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
        if bfz < 0:
            a = 0 - a
        elif a >= 32768:
            a = -32768
    c.dip_kang = a
    bad = a > 13653 or a < -13653  # _DIP_LIMIT_KANG, 75 deg
    c.dip_high = bad
    if bad:
        flags |= 2  # FLAG_DIP_HIGH
    bad = pitch > 14564 or pitch < -14564  # _GIMBAL_PITCH_KANG, 80 deg
    c.gimbal = bad
    if bad:
        flags |= 4  # FLAG_GIMBAL
    c.flags = flags
    h = (h + int(c.declination_kang)) & 0xFFFF
    c.heading_kang = h
    return h


@micropython.viper
def correct(k, raw, out):
    """Calibration.correct(raw, out); k = array('h') of InvW (0..8) then V (9..11)."""
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
    """AxisMap.apply(src, dst); m = array('b'): the source axes of body x, y, z, then
    1 where that axis is negated."""
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


class PipelineKernel:
    """Base of fast.Pipeline: update() as one viper method, with correct() and apply()
    inlined (a viper call costs ~50 ns and a bytecode frame of 5 arguments would come from
    the heap), then orient()."""

    @micropython.viper
    def update(self, raw, araw, b, g) -> int:
        """b = mag map of correct(raw); g = accel map of araw (unless level); then the
        heading of (b, g) on self.compass."""
        p = ptr16(self._k)
        # Calibration.correct, as correct() above
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
        b1 = (p[1] ^ 0x8000) - 0x8000
        c = (p[2] ^ 0x8000) - 0x8000
        u0 = (a * x + b1 * y + c * z + 16384) >> 15
        a = (p[3] ^ 0x8000) - 0x8000
        b1 = (p[4] ^ 0x8000) - 0x8000
        c = (p[5] ^ 0x8000) - 0x8000
        u1 = (a * x + b1 * y + c * z + 16384) >> 15
        a = (p[6] ^ 0x8000) - 0x8000
        b1 = (p[7] ^ 0x8000) - 0x8000
        c = (p[8] ^ 0x8000) - 0x8000
        u2 = (a * x + b1 * y + c * z + 16384) >> 15
        # AxisMap.apply of the magnetometer, as apply() above (it may read any slot)
        m = ptr8(self._mm)
        x = u0 if m[0] == 0 else (u1 if m[0] == 1 else u2)
        y = u0 if m[1] == 0 else (u1 if m[1] == 1 else u2)
        z = u0 if m[2] == 0 else (u1 if m[2] == 1 else u2)
        if m[3]:
            x = 32767 if x == -32768 else 0 - x
        if m[4]:
            y = 32767 if y == -32768 else 0 - y
        if m[5]:
            z = 32767 if z == -32768 else 0 - z
        b[0] = x
        b[1] = y
        b[2] = z
        if int(self._level):
            return int(orient(self.compass, x, y, z, 0, 0, 0, 1))
        m = ptr8(self._am)
        u0 = int(araw[m[0]])
        u1 = int(araw[m[1]])
        u2 = int(araw[m[2]])
        if m[3]:
            u0 = 32767 if u0 == -32768 else 0 - u0
        if m[4]:
            u1 = 32767 if u1 == -32768 else 0 - u1
        if m[5]:
            u2 = 32767 if u2 == -32768 else 0 - u2
        g[0] = u0
        g[1] = u1
        g[2] = u2
        return int(orient(self.compass, x, y, z, u0, u1, u2, 0))
