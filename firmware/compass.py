"""Tilt-compensated compass heading (Freescale AN4248), integer-only, angles in KANG."""
#     from firmware.compass import Compass
#     from firmware.trig import cdeg_to_kang, kang_to_str
#     compass = Compass(field=6000, declination_kang=cdeg_to_kang(-150))   # B in b's units, -1.5 deg
#     h = compass.update(b, g)       # b: corrected field, g: accelerometer, both body frame
#     print(kang_to_str(h), compass.interference, compass.dip_high, compass.gimbal)
#
# KANG: 65536 per turn. heading(b, g) is the one-shot form. The frame, the flags and why the
# per-sample path is split into small methods: docs/design.md (module notes, compass); the API
# in docs/api.md (heading).
from array import array

from firmware.compat import const, kernels, room
from firmware.trig import ZERO_VECTOR as _ZERO_VECTOR, atan2, isqrt, norm14, sin

_KANG_90 = const(16384)
_Q15_ONE = const(32768)
_ROUND15 = const(0x4000)  # half of 2**15: round a Q15 product to nearest
_DIP_LIMIT_KANG = const(13653)  # 75 deg: heading unreliable beyond this inclination (AN4248 sec. 6)
_GIMBAL_PITCH_KANG = const(14564)  # 80 deg: roll noise x 1/cos(80 deg) = 5.8 (gimbal lock at 90)
FIELD_TOL_PCT = const(10)  # +-10 %: twice the |B| spread MotionCal accepts (variance < 4.5 %)
_NO_LIMIT = const(0x3FFFFFFF)  # field window when no reference field is set

# The working state of one Compass, array('i') (the steps below read and write it):
#   0..2 b scaled by trig.norm14, 3..5 g likewise, 6 b's shift, 7/8 sin/cos of roll and
#   9/10 of pitch (Q15), 11 roll, 12 pitch (KANG), 13..15 the de-rotated field Bf (eq. 19);
#   16/17 the |b| window (lo, hi: 0..2**30 - 1), 18/19 the dip window (KANG), then the results
#   of the last good update: 20 |b|, 21 dip (KANG), 22 flags
_KB = const(6)
_SPHI = const(7)
_CPHI = const(8)
_STH = const(9)
_CTH = const(10)
_ROLL = const(11)
_PITCH = const(12)
_BFX = const(13)
_BFY = const(14)
_BFZ = const(15)
_LO = const(16)
_HI = const(17)
_DIP_LO = const(18)
_DIP_HI = const(19)
_MAG = const(20)
_DIP = const(21)
_FLAGS = const(22)
STATE_SIZE = const(23)


FLAG_INTERFERENCE = const(1)
FLAG_DIP_HIGH = const(2)
FLAG_GIMBAL = const(4)
FLAG_NO_FIELD = const(8)
FLAG_NO_GRAVITY = const(16)


def orient(st, b, g):
    """The magnetic heading 0..65535 (AN4248 eq. 22) of body-frame b and g (None: a level
    board), the tilt and Bf left in st; -1 when b is (0, 0, 0), -2 when g is."""
    k = norm14(b, st, 0)
    if k == _ZERO_VECTOR:
        return -1
    st[_KB] = k
    if g is None:
        level(st)
    elif norm14(g, st, 3) == _ZERO_VECTOR:
        return -2
    else:
        tilt(st)
    derotate(st)
    return atan2(-st[_BFY], st[_BFX]) & 0xFFFF  # psi = atan2(-Bfy, Bfx), eq. 22


def level(st):
    st[_ROLL] = 0
    st[_PITCH] = 0
    st[_SPHI] = 0
    st[_CPHI] = _Q15_ONE  # exact 1.0: the level path is the identity
    st[_STH] = 0
    st[_CTH] = _Q15_ONE


def tilt(st):
    """Roll (eq. 13) and pitch (eq. 15) from g in st[3..5], with their Q15 sines and cosines."""
    gy = st[4]
    gz = st[5]
    a = atan2(gy, gz)  # roll phi
    st[_ROLL] = a
    s = sin(a)
    c = sin(a + _KANG_90)
    st[_SPHI] = s
    st[_CPHI] = c
    a = (gy * s + gz * c + _ROUND15) >> 15  # = sqrt(Gy**2 + Gz**2) >= 0: eq. 15 denominator
    a = atan2(-st[3], a)  # pitch theta in [-90, 90] deg; defined at +-90 deg
    st[_PITCH] = a
    st[_STH] = sin(a)
    st[_CTH] = sin(a + _KANG_90)


def derotate(st):
    """Bf = Ry(-theta) Rx(-phi) Bp, AN4248 eq. 19 (b already hard/soft-iron corrected)."""
    s = st[_SPHI]
    c = st[_CPHI]
    t = (st[1] * s + st[2] * c + _ROUND15) >> 15  # By sin(phi) + Bz cos(phi)
    st[_BFY] = (st[1] * c - st[2] * s + _ROUND15) >> 15
    s = st[_STH]
    c = st[_CTH]
    st[_BFX] = (st[0] * c + t * s + _ROUND15) >> 15
    st[_BFZ] = (t * c - st[0] * s + _ROUND15) >> 15


def magnitude(st):
    """|b| in b's units, from the scaled b in st and its shift."""
    m = isqrt(st[0] * st[0] + st[1] * st[1] + st[2] * st[2])
    k = st[_KB]
    if k > 0:  # undo norm14's shift, rounding
        return (m + (1 << (k - 1))) >> k
    if k < 0:
        return m << -k
    return m


def dip(st):
    """Inclination (KANG, positive down): vertical over horizontal de-rotated field."""
    x = st[_BFX]
    y = st[_BFY]
    return atan2(st[_BFZ], isqrt(x * x + y * y))


def judge(st):
    """The flags of the sample in st: |b| and the dip against their windows (interference),
    the dip and pitch limits (AN4248 sec. 6)."""
    m = st[_MAG]
    x = st[_DIP]
    f = 0
    if m < st[_LO] or m > st[_HI] or x < st[_DIP_LO] or x > st[_DIP_HI]:
        f = FLAG_INTERFERENCE
    if x > _DIP_LIMIT_KANG or x < -_DIP_LIMIT_KANG:
        f |= FLAG_DIP_HIGH
    x = st[_PITCH]
    if x > _GIMBAL_PITCH_KANG or x < -_GIMBAL_PITCH_KANG:
        f |= FLAG_GIMBAL
    return f


def measure(st, b, g):
    """Compass.update's work on the state: orient, then |b|, the dip and the flags into st.
    The magnetic heading 0..65535, or orient's -1 / -2 (st's results then untouched)."""
    h = orient(st, b, g)
    if h >= 0:
        st[_MAG] = magnitude(st)
        st[_DIP] = dip(st)
        st[_FLAGS] = judge(st)
    return h


# The step a Compass runs, module-wide: measure above, or its viper mirror in firmware.fast
# where this port has the native emitter (same bits; see use_kernels). A global, not an
# attribute: a global costs no extra word in the calling frame.
_measure = measure
_orient = orient  # heading()'s
KERNELS = None


def use_kernels(kn=None):
    """Run every Compass's steps with the kernel set `kn`: None picks firmware.fast where the
    native emitter exists (else the plain functions), False the plain functions, a module
    (firmware.fast) its mirrors. Returns the set in use (None for the plain functions)."""
    global _measure, _orient, KERNELS
    if kn is None:
        kn = kernels()
    if not kn:
        _measure = measure
        _orient = orient
        KERNELS = None
        return None
    _measure = kn.measure
    _orient = kn.orient
    KERNELS = kn
    return kn


def _slot(i):
    # a Compass attribute that reads state slot i
    return property(lambda self: self.st[i])


def _flag(bit):
    # a Compass attribute that is True while the last good update set this flag
    return property(lambda self: self.st[_FLAGS] & bit != 0)


class Compass:
    """Heading, tilt and field checks for one sample at a time, updated in place."""
    # field            expected |b| (the calibration's B, in b's units); 0 turns the
    #                  interference check off.
    # declination_kang added to the magnetic heading (east positive), e.g. cdeg_to_kang(1150).
    # field_tol_pct    interference window around field, percent (default 10).
    #
    # update(b, g=None) -> heading_kang (0..65535), or -1 for a zero b or g (see flags).
    # After update: heading_kang, pitch_kang, roll_kang (int16 KANG, AN4248 theta and phi),
    # dip_kang (inclination, positive down), magnitude (|b| in b's units), flags, interference,
    # dip_high, gimbal. A failed update leaves the last good values and sets only flags.
    # With g None the board is taken as level: pitch = roll = 0, and dip assumes it too.

    def __init__(self, field=0, declination_kang=0, field_tol_pct=FIELD_TOL_PCT):
        self.declination_kang = declination_kang
        self.heading_kang = 0
        self._failed = 0  # FLAG_NO_FIELD / FLAG_NO_GRAVITY after a failed update, else 0
        self.st = array("i", bytearray(4 * STATE_SIZE))  # the steps' working state
        level(self.st)
        self.field = 0
        self.field_tol_pct = field_tol_pct
        self.set_field(field, field_tol_pct)
        self.set_dip(None)

    def set_field(self, field, field_tol_pct=None):
        """Reference |b| for the interference check (0: off), and optionally its tolerance."""
        if field_tol_pct is not None:
            if not 0 <= field_tol_pct <= 100:
                raise ValueError("field_tol_pct %d outside 0..100" % field_tol_pct)
            self.field_tol_pct = field_tol_pct
        if field < 0:
            raise ValueError("reference field %d is negative" % field)
        self.field = field
        d = field * self.field_tol_pct // 100
        self.st[_LO] = field - d if field else 0
        self.st[_HI] = field + d if field else _NO_LIMIT

    # The results live in the state (the kernel writes them); a failed update leaves the last
    # good ones and sets only flags.
    roll_kang = _slot(_ROLL)
    pitch_kang = _slot(_PITCH)
    magnitude = _slot(_MAG)
    dip_kang = _slot(_DIP)
    interference = _flag(FLAG_INTERFERENCE)
    dip_high = _flag(FLAG_DIP_HIGH)
    gimbal = _flag(FLAG_GIMBAL)

    @property
    def flags(self):
        return self._failed or self.st[_FLAGS]

    def mark_interference(self):
        """Raise the interference flag of this sample from a check made outside the compass
        (the dip against the calibration's, firmware/health.py)."""
        self.st[_FLAGS] |= FLAG_INTERFERENCE

    def set_window(self, lo, hi):
        """Interference window on |b| given by its ends (b's units), e.g. one spanning the field
        model's |B| and the calibration's (firmware/field/location.py); set_field() replaces it."""
        if not 0 <= lo <= hi:
            raise ValueError("field window %d..%d: need 0 <= lo <= hi" % (lo, hi))
        self.st[_LO] = lo if lo < _NO_LIMIT else _NO_LIMIT
        self.st[_HI] = hi if hi < _NO_LIMIT else _NO_LIMIT

    def set_dip(self, dip_kang=None, tol_kang=0):
        """Expected dip (inclination, KANG, down positive) and its tolerance: a measured dip
        outside it raises the interference flag. None turns the check off."""
        # PX4's EKF2 checks inclination the same way. Only meaningful with a gravity vector:
        # the level-board path assumes pitch = roll = 0.
        if dip_kang is None:  # off: every dip is within +-90 deg
            self.st[_DIP_LO] = -_KANG_90
            self.st[_DIP_HI] = _KANG_90
            return
        if not -_KANG_90 <= dip_kang <= _KANG_90 or not 0 <= tol_kang <= _KANG_90:
            raise ValueError("dip %d +- %d KANG: need |dip| <= 16384 and 0 <= tol <= 16384"
                             % (dip_kang, tol_kang))
        self.st[_DIP_LO] = dip_kang - tol_kang
        self.st[_DIP_HI] = dip_kang + tol_kang

    def update(self, b, g=None):
        h = _measure(self.st, b, g)
        if h < 0:
            self._failed = FLAG_NO_FIELD if h == -1 else FLAG_NO_GRAVITY
            return -1
        if self._failed:
            self._failed = 0
        h = (h + self.declination_kang) & 0xFFFF
        self.heading_kang = h
        return h


room(Compass)  # its methods' table too (firmware/compat.py room)


use_kernels()
_PLAIN = Compass()  # scratch for heading(): one sample at a time, like the sensor loop


def heading(b, g=None, declination=0):
    """Tilt-compensated heading in KANG 0..65535 (see docs/design.md, module notes)."""
    h = _orient(_PLAIN.st, b, g)
    if h < 0:
        if h == -1:
            raise ValueError("heading: zero field vector b=%r" % (b,))
        raise ValueError("heading: zero gravity vector g=%r" % (g,))
    return (h + declination) & 0xFFFF
