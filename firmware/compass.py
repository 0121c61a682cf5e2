"""Tilt-compensated compass heading (Freescale AN4248), integer-only, angles in KANG.

    from firmware.compass import Compass
    from firmware.trig import cdeg_to_kang, kang_to_str
    compass = Compass(field=6000, declination_kang=cdeg_to_kang(-150))   # B in b's units, -1.5 deg
    h = compass.update(b, g)       # b: corrected field, g: accelerometer, both body frame
    print(kang_to_str(h), compass.interference, compass.dip_high, compass.gimbal)

KANG (T. Judd): 65536 per turn, so angle arithmetic wraps like an int16 (0.0055 deg resolution).
Frame: AN4248 body frame, x forward, y right, z down; a level board's accelerometer reads +1 g
on z (common.md). b is Calibration.correct's output mapped to the body frame (firmware.axes);
g is the accelerometer in the same frame and sign. Both at any scale, components int16.

heading(b, g=None, declination=0)
               heading in KANG 0..65535, clockwise from magnetic north plus declination (KANG,
               east positive); g None means a level board. ValueError for a zero b or g.
Compass        the same heading plus pitch, roll, field magnitude and dip, and the flags below,
               all updated in place: the per-sample path allocates nothing.
The angle arithmetic (atan2, sin, norm14, isqrt) is firmware/trig.py's, or firmware/fast.py's
viper mirror of the same functions where the port has the native emitter: use_kernels() picks
(at import), use_kernels(trig) forces the plain ones, .KERNELS says which. Same bits either way.

Flags (Compass.flags bits; the booleans mirror the first three):
  FLAG_INTERFERENCE  .interference: |b| is outside field * (1 +- field_tol_pct %) (or the
                     window set_window() gave), or the dip is outside the window set_dip() gave.
                     A magnet, a motor or a steel table adds to Earth's field (the heading
                     guide, docs/references.md); the heading is suspect. Off when no reference
                     field is set (field=0); the dip window is off until set_dip().
  FLAG_DIP_HIGH      .dip_high: |dip| > 75 deg. The horizontal field is < 26 % of B and the
                     heading noise grows by 1/cos(dip) (the heading guide: use another heading source).
  FLAG_GIMBAL        .gimbal: |pitch| > 80 deg. Roll comes from Gy, Gz ~ g cos(pitch), so its
                     noise (and the heading's) grows by >= 1/cos(80 deg) = 5.8; at +-90 deg
                     (gimbal lock) roll is taken as 0 and the heading stays defined.
  FLAG_NO_FIELD      b was (0, 0, 0): no heading; update() returns -1, the last good values stay.
  FLAG_NO_GRAVITY    g was (0, 0, 0) (free fall): likewise.

Per-sample path (Compass.update and the trig steps it calls):
every intermediate stays below 2**30
(tests/test_heading.py drives tests/intcheck over the whole int16 input space) and nothing is
allocated, not even a call frame: MicroPython puts the frame of a function whose arguments,
locals and stack exceed 11 words on the heap (py/objfun.c VM_MAX_STATE_ON_STACK), so the work
is split into small methods that keep their state on the Compass object.
"""
from firmware import trig
from firmware.compat import const, kernels

_KANG_90 = const(16384)
_Q15_ONE = const(32768)
_ROUND15 = const(0x4000)  # half of 2**15: round a Q15 product to nearest
_DIP_LIMIT_KANG = const(13653)  # 75 deg: heading unreliable beyond this inclination (AN4248 sec. 6)
_GIMBAL_PITCH_KANG = const(14564)  # 80 deg: roll noise x 1/cos(80 deg) = 5.8 (gimbal lock at 90)
_FIELD_TOL_PCT = const(10)  # +-10 %: twice the |B| spread MotionCal accepts (variance < 4.5 %)
_NO_LIMIT = const(0x3FFFFFFF)  # field window when no reference field is set
_ZERO_VECTOR = const(-128)  # trig.norm14's answer for (0, 0, 0)

# The steps' kernels, module-wide: firmware.trig's functions, or their viper mirrors in
# firmware.fast where this port has the native emitter (same bits; see use_kernels). Globals,
# not attributes: a global costs no extra word in the calling frame.
_atan2 = trig.atan2
_sin = trig.sin
_norm14 = trig.norm14
_isqrt = trig.isqrt
KERNELS = trig


def use_kernels(kn=None):
    """Route every Compass's angle arithmetic through the kernel set `kn`: a module with
    trig's atan2, sin, norm14 and isqrt (firmware.trig, firmware.fast); None picks
    firmware.fast where the native emitter exists, else firmware.trig. Returns the set now
    in use (.KERNELS)."""
    global _atan2, _sin, _norm14, _isqrt, KERNELS
    if kn is None:
        kn = kernels() or trig
    _atan2 = kn.atan2
    _sin = kn.sin
    _norm14 = kn.norm14
    _isqrt = kn.isqrt
    KERNELS = kn
    return kn


FLAG_INTERFERENCE = const(1)
FLAG_DIP_HIGH = const(2)
FLAG_GIMBAL = const(4)
FLAG_NO_FIELD = const(8)
FLAG_NO_GRAVITY = const(16)


class Compass:
    """Heading, tilt and field checks for one sample at a time, updated in place.

    field            expected |b| (the calibration's B, in b's units); 0 turns the
                     interference check off.
    declination_kang added to the magnetic heading (east positive), e.g. cdeg_to_kang(1150).
    field_tol_pct    interference window around field, percent (default 10).

    update(b, g=None) -> heading_kang (0..65535), or -1 for a zero b or g (see flags).
    After update: heading_kang, pitch_kang, roll_kang (int16 KANG, AN4248 theta and phi),
    dip_kang (inclination, positive down), magnitude (|b| in b's units), flags, interference,
    dip_high, gimbal. A failed update leaves the last good values and sets only flags.
    With g None the board is taken as level: pitch = roll = 0, and dip assumes it too.
    """

    def __init__(self, field=0, declination_kang=0, field_tol_pct=_FIELD_TOL_PCT):
        # the steps' kernels: firmware.trig, or its viper mirror firmware.fast (same bits)
        self.declination_kang = declination_kang
        self.heading_kang = 0
        self.pitch_kang = 0
        self.roll_kang = 0
        self.dip_kang = 0
        self.magnitude = 0
        self.flags = 0
        self.interference = False
        self.dip_high = False
        self.gimbal = False
        self._v = [0, 0, 0, 0, 0, 0]  # b then g, normalised by trig.norm14
        self._kb = 0  # b's shift, to scale |b| back
        self._sphi = 0  # Q15 sin/cos of roll and pitch
        self._cphi = _Q15_ONE
        self._stheta = 0
        self._ctheta = _Q15_ONE
        self._bfx = 0  # de-rotated field, AN4248 eq. 19
        self._bfy = 0
        self._bfz = 0
        self.field = 0
        self.field_tol_pct = field_tol_pct
        self._lo = 0
        self._hi = _NO_LIMIT
        self._dip_lo = -_KANG_90  # the dip window: off (every dip is within +-90 deg)
        self._dip_hi = _KANG_90
        self.set_field(field, field_tol_pct)

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
        self._lo = field - d if field else 0
        self._hi = field + d if field else _NO_LIMIT

    def set_window(self, lo, hi):
        """Interference window on |b| given by its ends (b's units), e.g. one spanning the field
        model's |B| and the calibration's (firmware/location.py); set_field() replaces it."""
        if not 0 <= lo <= hi:
            raise ValueError("field window %d..%d: need 0 <= lo <= hi" % (lo, hi))
        self._lo = lo
        self._hi = hi

    def set_dip(self, dip_kang=None, tol_kang=0):
        """Expected dip (inclination, KANG, down positive) and its tolerance: a measured dip
        outside it raises the interference flag (PX4's EKF2 checks inclination the same way).
        None turns the check off. Only meaningful with a gravity vector: the level-board path
        assumes pitch = roll = 0."""
        if dip_kang is None:
            self._dip_lo = -_KANG_90
            self._dip_hi = _KANG_90
            return
        if not -_KANG_90 <= dip_kang <= _KANG_90 or not 0 <= tol_kang <= _KANG_90:
            raise ValueError("dip %d +- %d KANG: need |dip| <= 16384 and 0 <= tol <= 16384"
                             % (dip_kang, tol_kang))
        self._dip_lo = dip_kang - tol_kang
        self._dip_hi = dip_kang + tol_kang

    def update(self, b, g=None):
        h = self._orient(b, g)
        if h < 0:
            return h
        self._check_field()
        self._check_dip()
        h = (h + self.declination_kang) & 0xFFFF
        self.heading_kang = h
        return h

    def _orient(self, b, g):
        """Magnetic heading 0..65535 (eq. 22); -1 and a flag when b or g is zero."""
        v = self._v
        k = _norm14(b, v, 0)
        if k == _ZERO_VECTOR:
            self.flags = FLAG_NO_FIELD
            return -1
        self._kb = k
        if g is None:
            self._level()
        elif _norm14(g, v, 3) == _ZERO_VECTOR:
            self.flags = FLAG_NO_GRAVITY
            return -1
        else:
            self._tilt()
        self._derotate()
        self.flags = 0
        return _atan2(-self._bfy, self._bfx) & 0xFFFF  # psi = atan2(-Bfy, Bfx), eq. 22

    def _level(self):
        self.roll_kang = 0
        self.pitch_kang = 0
        self._sphi = 0
        self._cphi = _Q15_ONE  # exact 1.0: the level path is the identity
        self._stheta = 0
        self._ctheta = _Q15_ONE

    def _tilt(self):
        v = self._v
        gy = v[4]
        gz = v[5]
        a = _atan2(gy, gz)  # roll phi, eq. 13
        self.roll_kang = a
        s = _sin(a)
        c = _sin(a + _KANG_90)
        self._sphi = s
        self._cphi = c
        a = (gy * s + gz * c + _ROUND15) >> 15  # = sqrt(Gy**2 + Gz**2) >= 0: eq. 15 denominator
        a = _atan2(-v[3], a)  # pitch theta in [-90, 90] deg, eq. 15; defined at +-90 deg
        self.pitch_kang = a
        self._stheta = _sin(a)
        self._ctheta = _sin(a + _KANG_90)

    def _derotate(self):
        """Bf = Ry(-theta) Rx(-phi) Bp, AN4248 eq. 19 (b already hard/soft-iron corrected)."""
        v = self._v
        s = self._sphi
        c = self._cphi
        t = (v[1] * s + v[2] * c + _ROUND15) >> 15  # By sin(phi) + Bz cos(phi)
        self._bfy = (v[1] * c - v[2] * s + _ROUND15) >> 15
        s = self._stheta
        c = self._ctheta
        self._bfx = (v[0] * c + t * s + _ROUND15) >> 15
        self._bfz = (t * c - v[0] * s + _ROUND15) >> 15

    def _check_field(self):
        v = self._v
        m = _isqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        k = self._kb
        if k > 0:  # undo norm14's shift, rounding
            m = (m + (1 << (k - 1))) >> k
        elif k < 0:
            m <<= -k
        self.magnitude = m
        self.interference = m < self._lo or m > self._hi
        self.flags |= FLAG_INTERFERENCE if self.interference else 0

    def _check_dip(self):
        x = self._bfx
        y = self._bfy
        x = _atan2(self._bfz, _isqrt(x * x + y * y))  # inclination: vertical over horizontal field
        self.dip_kang = x
        if x < self._dip_lo or x > self._dip_hi:
            self.interference = True
            self.flags |= FLAG_INTERFERENCE
        self.dip_high = x > _DIP_LIMIT_KANG or x < -_DIP_LIMIT_KANG
        x = self.pitch_kang
        self.gimbal = x > _GIMBAL_PITCH_KANG or x < -_GIMBAL_PITCH_KANG
        x = self.flags
        if self.dip_high:
            x |= FLAG_DIP_HIGH
        if self.gimbal:
            x |= FLAG_GIMBAL
        self.flags = x


use_kernels()
_PLAIN = Compass()  # scratch for heading(): one sample at a time, like the sensor loop


def heading(b, g=None, declination=0):
    """Tilt-compensated heading in KANG 0..65535 (see the module docstring)."""
    h = _PLAIN._orient(b, g)
    if h < 0:
        if _PLAIN.flags == FLAG_NO_FIELD:
            raise ValueError("heading: zero field vector b=%r" % (b,))
        raise ValueError("heading: zero gravity vector g=%r" % (g,))
    return (h + declination) & 0xFFFF
