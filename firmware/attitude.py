"""Gyro-aided heading: an integer attitude filter that integrates the MPU6050's gyroscope and
is corrected by gravity and by the calibrated magnetic field (docs/gyro.md).

    att = app.use_gyro()               # firmware/app.py: loads this module, one call per step
    att.heading_kang, att.source, att.since_mag_us, att.uncertainty_cdeg

Attitude(gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g, gain=500,
         mag_gain=500, bias_gain=125, accel_reject_cdeg=1000, mag_reject_cdeg=1000,
         recovery_us=5000000, max_uncertainty_cdeg=500)
  gyro, gravity, field  the app's body-frame arrays (AN4248 frame: x forward, y right, z
                 down): gyroscope counts, gravity (AN4248 Gp sign, +1 g down when level),
                 the calibrated field; read by update(), never copied.
  compass        the app's Compass: its roll, pitch and heading of the first good sample
                 start the filter.
  gain           accelerometer correction, 1/1000 rad/s per rad of tilt error (500: a 2 s
                 time constant); mag_gain the same for the heading error.
  bias_gain      the integral term, 1/1000 of the correction fed into the gyro bias each
                 second (0: off); the bias is also measured while the board is still.
  accel_reject_cdeg, mag_reject_cdeg  an accelerometer whose gravity direction differs
                 from the filter's by more (or whose |a| is off 1 g by more than 10 %), and a
                 field whose heading differs by more, are not used; after recovery_us of
                 continuous rejection they are used again (the filter, not the sensor, is
                 then the suspect: x-io's Fusion recovers the same way).
  max_uncertainty_cdeg  the gyro-held heading is vouched for while its uncertainty is
                 within this (5 deg).

update(dt_us, flags) -> heading (KANG, magnetic), -1 until started; flags: MAG_OK (the app's
field checks pass this sample), FIELD (a calibrated field was read), ACC_OK (a plausible
accelerometer). The filter starts (and, after reset(), starts again) at the compass's
attitude on the first sample with all three.
After it: heading_kang, pitch_kang, roll_kang (KANG, AN4248 theta and phi), source
(SOURCE_MAG: the last sample's field corrected the heading; SOURCE_GYRO: held by the gyro
alone), since_mag_us (since the last magnetic correction), uncertainty_cdeg (grows while
the field is not used, by the gyro bias uncertainty), vouched (the uncertainty is within
max_uncertainty_cdeg), bias (gyro bias per body axis, 1/4096 count), bias_estimates (still
spells measured), accel_rejected (the last sample's accelerometer was not used).

The filter (Mahony's complementary filter on a quaternion; the kinematics q' = q (0, w) / 2):
  state    q, body -> world (NED), Q28 in st[0..3]; the rotation matrix C (AN4248's R
           transposed) is built from q >> 14 (Q14) each sample.
  gyro     u = 16 x counts - bias (1/16 count; the mean of the sample and the one before it:
           the trapezoid rule), plus the corrections below as rates; the half
           angle of each axis h = u x dt x k, k from the range's counts per deg/s, with dt in
           chunks of < 32768 us (a slow loop integrates in several chunks); q += q (0, h).
  gravity  e = g x d (d = C's third row, the down direction the filter believes): the
           rotation that turns the belief toward the measurement, times gain; every other
           sample, held for the one between.
  field    m = C b, the field in the filter's level frame; its direction atan2(my, mx) is the
           heading error, corrected by a rotation about the down axis, times mag_gain.
  bias     the integral of the corrections (bias_gain; while every axis turns slower than 10
           deg/s: faster, the corrections carry the integration's own errors), and while the
           board is still, windows of 1 s (the first: 3 s) in which the gyro stays within
           1 deg/s of the window's first sample for the first estimate, then within 0.5
           deg/s of the bias, gravity within 1/64 g and the field within 1/64 of its size;
           a steady turn slower than ~0.7 deg/s can pass for bias until the integral sees
           it) the
           window's mean rate: the first window sets it, later ones move it a quarter of the
           way.
Every intermediate stays below 2**30 (a product a x b of a Q28 and a Q14 is taken as
(a >> 14) b + ((a & 0x3FFF) b >> 14), exact; a time in us likewise with 15 bits); the per-sample path allocates nothing: its
functions keep their frames within MicroPython's 11 words (see firmware/compass.py).
"""
from array import array

from firmware.compat import const, drop, kernels
from firmware.trig import ZERO_VECTOR, atan2, isqrt, norm14, sin

MAG_OK = const(1)
FIELD = const(2)
ACC_OK = const(4)
SOURCE_MAG = "magnetometer"
SOURCE_GYRO = "gyro"
# the app's statuses (firmware/app.py STATUS_*)
_OK = "ok"
_INTERFERENCE = "interference"
_JUMP = "heading jumped"
_GYRO_HELD = "gyro held"
_CHECK_MASK = const(63)  # every 64 steps the MPU6050's configuration is read back
_OFFER_US = const(1000000)  # follow(): clean samples in a spell before the field is offered
_GIMBAL = const(16135)    # sin(80 deg) in Q14: firmware/compass.py's gimbal limit

_ONE28 = const(0x10000000)
_M14 = const(0x3FFF)
_CHUNK_US = const(32767)
_KANG_90 = const(16384)
_STILL_US = const(1000000)  # a still window...
_FIRST_US = const(3000000)  # ...and the first: a slow turn has 3 s to move the field
_SINCE_CAP = const(0x20000000)
_DT_MAX = const(1000000)  # a longer gap counts as 1 s
_BIAS_MAX = const(1 << 25)  # 2**13 counts in 1/4096 count: 62 deg/s at +-250 deg/s
_WINDOW_MAX = const(4096)  # samples in a still window (the sums stay small)

# state slots (array 'i')
_Q = const(0)      # 0..3 q (w, x, y, z), Q28
_BIAS = const(4)   # 4..6 gyro bias, body frame, 1/4096 count
_U = const(7)      # 7..9 rate: 1/16 count, bias removed, corrections added
_R = const(10)     # 10..12 half angle per 32768 us, Q28 rad
_QH = const(13)    # 13..16 q >> 14
_D = const(17)     # 17..19 C's third row: down in the body frame, Q14
_G = const(20)     # 20..22 gravity / field scaled by norm14
_KI = const(23)    # rate scale: integer part...
_KF = const(24)    # ...and fraction / 16384
_KA = const(25)    # gain: (1/16 count rate) per Q14 error, Q12
_KM = const(26)    # mag_gain: (1/16 count rate) per KANG of heading error, Q12
_KB = const(27)    # bias_gain: bias (1/4096 count) per correction x 32768 us, Q6
_E = const(28)     # last heading error (KANG)
_SINCE = const(29)  # us since the last magnetic correction
_AREJ = const(30)  # us of accelerometer rejection in a row
_MREJ = const(31)  # us of the filter's own field rejection in a row
_WN = const(32)    # still window: samples
_WT = const(33)    # still window: us
_WS = const(34)    # 34..36 still window: gyro sums (counts)
_GP = const(37)    # 37..39 the last gyro sample (counts)
_WA = const(40)    # 40..42 still window: gravity at its start
_WB = const(43)    # 43..45 still window: field at its start
_ACC_LIM = const(46)  # sin of accel_reject, Q14, squared
_MAG_LIM = const(47)  # mag_reject, KANG
_HEAD = const(48)
_PITCH = const(49)
_ROLL = const(50)
_SCR = const(51)   # 51..53 scratch
_C = const(54)     # 54..56 the corrections (1/16 count) for the next sample's rates
_WLB = const(57)   # still window: the field's tolerance (counts)
_UNC = const(58)   # the heading's uncertainty grown since the last correction, 1/1000 cdeg
_WG = const(59)    # 59..61 still window: the gyro at its start (counts)
_CA = const(62)    # 62..64 the last gravity correction (1/16 count), held a sample
_SIZE = const(65)  # (firmware/fast.py's mirrors use these numbers)


def mul14(a, b):
    """floor(a * b / 2**14) for |a| < 2**30, |b| <= 2**14 without leaving the small ints."""
    return (a >> 14) * b + (((a & _M14) * b) >> 14)


def euler(st):
    """Heading (and d, q >> 14) of q."""
    q_hi(st)
    down(st)
    angles(st)


def tilt(st):
    """Pitch and roll (KANG) from d."""
    d = st[_D + 1]
    e = st[_D + 2]
    st[_ROLL] = atan2(d, e)
    st[_PITCH] = atan2(-st[_D], isqrt(d * d + e * e))


def set_euler(st, yaw, pitch, roll):
    """q = qz(yaw) qy(pitch) qx(roll) (KANG): the filter's start from the compass."""
    ca = sin((roll >> 1) + _KANG_90)
    sa = sin(roll >> 1)
    cb = sin((pitch >> 1) + _KANG_90)
    sb = sin(pitch >> 1)
    cc = sin((yaw >> 1) + _KANG_90)
    sc = sin(yaw >> 1)
    st[_SCR] = (cc * cb) >> 15
    st[_SCR + 1] = (sc * sb) >> 15
    st[_SCR + 2] = (cc * sb) >> 15
    st[_QH] = (sc * cb) >> 15
    st[_Q] = (st[_SCR] * ca + st[_SCR + 1] * sa) >> 2
    st[_Q + 1] = (st[_SCR] * sa - st[_SCR + 1] * ca) >> 2
    st[_Q + 2] = (st[_SCR + 2] * ca + st[_QH] * sa) >> 2
    st[_Q + 3] = (st[_QH] * ca - st[_SCR + 2] * sa) >> 2


def turn(st, e):
    """q = qz(-e) q: the heading turned by -e (KANG), exactly (the recovery's snap)."""
    c = sin(_KANG_90 - (e >> 1)) >> 1  # Q14
    s = -sin(e >> 1) >> 1
    w = st[_Q]
    x = st[_Q + 1]
    st[_Q] = mul14(w, c) - mul14(st[_Q + 3], s)
    st[_Q + 3] = mul14(st[_Q + 3], c) + mul14(w, s)
    st[_Q + 1] = mul14(x, c) - mul14(st[_Q + 2], s)
    st[_Q + 2] = mul14(st[_Q + 2], c) + mul14(x, s)


def _near(a, b, o, lim):
    # |a[i] - b[o + i]| <= lim on every axis
    d = a[0] - b[o]
    if d > lim or d < -lim:
        return False
    d = a[1] - b[o + 1]
    if d > lim or d < -lim:
        return False
    d = a[2] - b[o + 2]
    return -lim <= d <= lim


def _copy3(a, b, o):
    b[o] = a[0]
    b[o + 1] = a[1]
    b[o + 2] = a[2]


def _bias_from_window(st, first):
    # the window's mean rate (1/4096 count): the bias, or a quarter of the way to it
    n = st[_WN]
    _blend(st, 0, n, first)
    _blend(st, 1, n, first)
    _blend(st, 2, n, first)


def _blend(st, i, n, first):
    m = st[_WS + i]
    m = ((m // n) << 12) + (((m % n) << 12) // n)  # the mean, 1/4096 count
    if not first:
        m = st[_BIAS + i] + ((m - st[_BIAS + i]) >> 2)
    st[_BIAS + i] = m if -_BIAS_MAX <= m <= _BIAS_MAX else (_BIAS_MAX if m > 0 else -_BIAS_MAX)


# The steps the filter runs, module-wide: firmware/attitude_plain.py's functions, or their
# viper mirrors in firmware/attitude_fast.py where the port has the native emitter (the same
# bits); only the set in use is loaded (see use_kernels).
_KERNEL_NAMES = ("rates", "advance", "q_hi", "down", "tilt_error", "tilt_sine", "accel_apply",
                 "field_error", "yaw_rate", "angles")
rates = advance = q_hi = down = tilt_error = tilt_sine = accel_apply = None
field_error = yaw_rate = angles = None
KERNELS = None


def use_kernels(kn=None):
    """Run the filter with the kernel set `kn`: None picks firmware/attitude_fast.py where the
    native emitter exists (firmware.compat.kernels()), else firmware/attitude_plain.py; False
    the plain set; a module with the same names, that module. Returns the module in use."""
    if kn is None:
        kn = False
        if kernels():
            try:
                from firmware import attitude_fast as kn
            except (ImportError, SyntaxError, ValueError, MemoryError):
                kn = False  # no emitter after all, an .mpy of another architecture, no room
    if kn is False:
        from firmware import attitude_plain as kn
    g = globals()
    for name in _KERNEL_NAMES:
        g[name] = getattr(kn, name)
    g["KERNELS"] = kn
    return kn


class Attitude:
    """See the module docstring."""

    raw = None     # attach(): the gyroscope's counts in the sensor's axes
    axes = None    # attach(): their map to the body frame (firmware/axes.py AxisMap.m)
    _at = -2       # follow(): the app step that last ran the filter
    _cal = None    # follow(): the calibration in force when the filter started

    def __init__(self, gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g,
                 **options):
        from firmware.gyrosetup import scales  # construction only: dropped after it
        k = scales(counts_per_dps_x10, options)
        scales = None
        drop("gyrosetup")
        self.gyro = gyro
        self.gravity = gravity
        self.field = field
        self.compass = compass
        self.recovery_us = k[7]
        self.max_uncertainty_cdeg = k[8]
        self.still_counts = counts_per_dps_x10 * 8 // 10  # 0.5 deg/s in 1/16 count
        self.first_counts = counts_per_dps_x10 // 10  # 1 deg/s in counts
        self.still_g = counts_per_g >> 6
        self.base_cdeg = 100            # the field-corrected heading: ~1 deg
        self.bias_cdeg_per_s = 20       # bias measured while still: within 0.2 deg/s
        self.unknown_bias_cdeg_per_s = 100  # never still yet: the integral's ~1 deg/s
        self.bias_estimates = 0
        self.unc_rate = self.unknown_bias_cdeg_per_s  # _hold's, cdeg/s
        self.started = False
        self.accel_rejected = True
        self._odd = False  # _correct: gravity's turn
        self._cpg = counts_per_g
        self.st = st = array("i", bytearray(4 * _SIZE))
        st[_KI] = k[0]
        st[_KF] = k[1]
        st[_KA] = k[2]
        st[_KM] = k[3]
        st[_KB] = self.kb = k[4]
        self.kb_counts = counts_per_dps_x10 * 16  # 10 deg/s in 1/16 count: the integral's limit
        st[_ACC_LIM] = self.acc_lim = k[5]
        st[_MAG_LIM] = k[6]
        st[_Q] = _ONE28

    # results
    heading_kang = property(lambda self: self.st[_HEAD])
    @property
    def pitch_kang(self):
        tilt(self.st)
        return self.st[_PITCH]

    @property
    def roll_kang(self):
        tilt(self.st)
        return self.st[_ROLL]
    since_mag_us = property(lambda self: self.st[_SINCE])
    heading_error_kang = property(lambda self: self.st[_E])

    @property
    def bias(self):
        st = self.st
        return (st[_BIAS], st[_BIAS + 1], st[_BIAS + 2])

    @property
    def source(self):
        return SOURCE_MAG if self.st[_SINCE] == 0 and self.started else SOURCE_GYRO

    @property
    def uncertainty_cdeg(self):
        """The heading's uncertainty (0.01 deg): the base while the field corrects it, plus,
        sample by sample since the last correction, the gyro bias uncertainty of the moment
        times the time (unknown_bias_cdeg_per_s until a still window measured the bias,
        bias_cdeg_per_s after)."""
        return self.base_cdeg + self.st[_UNC] // 1000

    @property
    def vouched(self):
        return self.started and self.uncertainty_cdeg <= self.max_uncertainty_cdeg

    def reset(self):
        """Start again from the next good sample (the bias estimate is kept)."""
        self.started = False
        self.st[_SINCE] = 0
        self.st[_UNC] = 0

    # --- the app's step (attach, CompassApp.use_gyro) ------------------------------------
    def follow(self, app):
        """One call per app step after its field checks: the filter's heading becomes the
        app's. The field is offered to the filter when the checks pass, on a heading jump (a
        turn the gyro confirms) and once an interference spell has seen 1 s of samples that
        raise no flag (firmware/health.py FieldWatch: the magnet has gone, or holds still);
        the filter takes it only within mag_reject of its own heading. While it holds the
        heading without the field and vouches for it the status is "gyro held" in place of
        interference / heading jumped; "ok" when this sample's field corrected it."""
        if self._gap(app):
            return
        s = app.status
        f = 6  # FIELD | ACC_OK
        if s == _OK or s == _JUMP or s == _INTERFERENCE and app.watch.clean_us >= _OFFER_US:
            f = 7  # | MAG_OK
        h = self.update(app._dt, f)
        if h < 0:
            return
        p = self.st[_D]  # -sin(pitch), Q14
        if p > _GIMBAL or p < -_GIMBAL:  # near vertical the heading is the compass's: a
            return  # small tilt error moves psi by tan(pitch) (AN4248 sec. 6)
        app.heading_kang = (h + self.compass.declination_kang) & 0xFFFF
        if self.st[_SINCE] == 0:  # this sample's field corrected the heading
            if s != _OK:
                app.status = _OK
        elif s == _OK or s == _INTERFERENCE or s == _JUMP:
            app.status = _GYRO_HELD if self.vouched else _INTERFERENCE

    def _gap(self, app):
        # The gyroscope into the body frame (.axes: the accelerometer's axis map negated, as
        # the map turns specific force into AN4248 gravity, Gp = -f, and a rate keeps its sign).
        # True after a step without the gyro (a failed read, a stall: time the filter did not
        # integrate), when another calibration was put in force (the field it followed was
        # another), with an implausible accelerometer (the gyro's own chip: its burst is
        # suspect too), a rate past the range or a chip that lost its setting: the filter then
        # starts again from the compass at the next clean sample.
        app._apply(self.axes, self.raw, self.gyro)
        n = app.steps
        skip = n != self._at + 1 or app._stalled or not app.tilt
        self._at = n
        if app.calibration is not self._cal:
            self._cal = app.calibration
            skip = True
        if skip or self._bad(app):
            self.reset()
            return True
        return False

    def _bad(self, app):
        g = self.raw
        if (g[0] == 32767 or g[0] == -32768 or g[1] == 32767 or g[1] == -32768
                or g[2] == 32767 or g[2] == -32768):
            return True
        if app.steps & _CHECK_MASK:
            return False
        return not self._config(app)

    def _config(self, app):
        # GYRO_CONFIG (and the accelerometer's) read back, rewritten when it changed; a
        # failed read counts as changed
        r = app._guard
        self.config_ok = False
        with r:
            r.dev = app.accel
            self.config_ok = app.accel.config_ok()
        if not self.config_ok:
            self._configure(app)
        return self.config_ok

    def _configure(self, app):
        r = app._guard
        with r:
            app.accel.configure()
            app.reinits += 1

    def update(self, dt, flags):
        if dt > _DT_MAX or dt < 0:
            dt = _DT_MAX if dt > 0 else 0
        if not self.started:
            return self._start(flags)
        st = self.st
        m = rates(st, self.gyro)  # the rate, plus the corrections the last sample asked
        #                           for; m: how fast it turns
        self._still(dt, flags, m)
        st[_KB] = self.kb if m <= self.kb_counts else 0  # turning fast: the corrections
        advance(st, dt)  # carry the integration's errors, not the bias
        self._correct(dt, flags)
        angles(st)
        return st[_HEAD]

    def _start(self, flags):
        if flags != MAG_OK | FIELD | ACC_OK:  # a clean field and gravity: the compass's word
            return -1
        c = self.compass
        st = self.st
        set_euler(st, c.heading_kang - c.declination_kang, c.pitch_kang, c.roll_kang)
        g = self.gyro
        st[_GP] = g[0]
        st[_GP + 1] = g[1]
        st[_GP + 2] = g[2]
        st[_C] = 0
        st[_C + 1] = 0
        st[_C + 2] = 0
        self.started = True
        euler(st)
        return st[_HEAD]

    def _correct(self, dt, flags):
        # the corrections this sample's gravity and field ask for, as rates for the next one;
        # gravity's every other sample (its 2 s time constant does not miss one: the plain
        # path's cost), held for the sample between while the accelerometer stays plausible
        st = self.st
        down(st)  # from normalise's q >> 14 (q before its last, tiny, step)
        self._odd = not self._odd
        if not flags & ACC_OK:
            self.accel_rejected = True
            self._gravity_held(0)
        elif self._odd:
            self._gravity(dt << 1)
        else:
            self._gravity_held(1)
        self._field(dt, flags)
        st[_C] = st[_U]
        st[_C + 1] = st[_U + 1]
        st[_C + 2] = st[_U + 2]

    def _gravity(self, dt):
        st = self.st
        st[_U] = 0
        st[_U + 1] = 0
        st[_U + 2] = 0
        self.accel_rejected = True
        k = norm14(self.gravity, st, _G)
        if k != ZERO_VECTOR:
            self._accel(dt, tilt_error(st), k)
        st[_CA] = st[_U]
        st[_CA + 1] = st[_U + 1]
        st[_CA + 2] = st[_U + 2]

    def _gravity_held(self, keep):
        # the last gravity correction (keep) or none, as the start of this sample's
        st = self.st
        if not keep:
            st[_CA] = 0
            st[_CA + 1] = 0
            st[_CA + 2] = 0
        st[_U] = st[_CA]
        st[_U + 1] = st[_CA + 1]
        st[_U + 2] = st[_CA + 2]

    def _accel(self, dt, n2, k):
        # n2: |g|^2 scaled by 4**k (norm14); c: 1 g scaled the same way (a power of 2, as
        # counts_per_g is): |g| within 10 % of it is (0.81 .. 1.21) c^2, no square root
        st = self.st
        c = self._cpg << k if k >= 0 else self._cpg >> -k
        if 4096 < c < 32768:  # else |g| is nowhere near 1 g (|g| scaled is 2**13..2**14.8)
            q = c * c // 100
            if 81 * q <= n2 <= 121 * q:
                tilt_sine(st, c)  # the sine to within |g| / c, 0.9..1.1: a gain, no more
                if accel_apply(st):
                    st[_AREJ] = 0
                    self.accel_rejected = False
                    return
        if st[_AREJ] <= self.recovery_us:
            st[_AREJ] += dt
        else:  # the filter is the suspect: believe gravity again
            self._believe_gravity(st)

    def _believe_gravity(self, st):
        # the cross product afresh (the branch above may have scaled it), by the true |g|
        n = isqrt(tilt_error(st))
        tilt_sine(st, n)
        st[_ACC_LIM] = 0x3FFFFFFF
        accel_apply(st)
        st[_ACC_LIM] = self.acc_lim
        self.accel_rejected = False

    def _field(self, dt, flags):
        st = self.st
        if flags & (MAG_OK | FIELD) != MAG_OK | FIELD or norm14(
                self.field, st, _G) == ZERO_VECTOR:  # not offered: the heading error of
            self._hold(dt)  # the last field offered stays in .heading_error_kang
            return
        e = field_error(st)
        st[_E] = e
        lim = st[_MAG_LIM]
        if -lim <= e <= lim:
            st[_MREJ] = 0
        else:
            st[_MREJ] += dt
            if st[_MREJ] <= self.recovery_us:
                self._hold(dt)
                return
            turn(st, e)  # the gyro lost the heading (e.g. past its range): the field's
            st[_MREJ] = 0
            e = 0
        yaw_rate(st, e)
        st[_SINCE] = 0
        st[_UNC] = 0

    def _hold(self, dt):
        st = self.st
        if st[_SINCE] < _SINCE_CAP:
            st[_SINCE] += dt
            st[_UNC] += self.unc_rate * dt // 1000

    def _still(self, dt, flags, m):
        """Still-board windows: the gyro's mean rate over 1 s without motion is its bias (m:
        rates(), how fast it turns)."""
        st = self.st
        if self.bias_estimates:
            if m > self.still_counts:
                st[_WN] = 0  # turning: no window (the next slow sample starts one)
                return
        elif st[_WN] and not _near(self.gyro, st, _WG, self.first_counts):
            st[_WN] = 0  # no bias known yet: the gyro must hold within 1 deg/s of the start
        if st[_WN] == 0 or not self._steady(flags):
            self._window(flags)
            return
        g = self.gyro
        st[_WN] += 1
        st[_WT] += dt
        st[_WS] += g[0]
        st[_WS + 1] += g[1]
        st[_WS + 2] += g[2]
        if st[_WT] >= (_STILL_US if self.bias_estimates else _FIRST_US) or \
                st[_WN] >= _WINDOW_MAX:
            _bias_from_window(st, self.bias_estimates == 0)
            self.bias_estimates += 1
            self.unc_rate = self.bias_cdeg_per_s
            self._window(flags)

    def _steady(self, flags):
        # gravity within 1/64 g and the field within 1/64 of its components' sum of the
        # window's start (the gyro less its bias is within 0.5 deg/s: _still)
        st = self.st
        if flags & ACC_OK and not _near(self.gravity, st, _WA, self.still_g):
            return False
        return not flags & FIELD or _near(self.field, st, _WB, st[_WLB])

    def _window(self, flags):
        st = self.st
        g = self.gyro
        st[_WN] = 1
        st[_WT] = 0
        _copy3(g, st, _WS)
        _copy3(g, st, _WG)
        if flags & ACC_OK:
            _copy3(self.gravity, st, _WA)
        if flags & FIELD:
            f = self.field
            _copy3(f, st, _WB)
            st[_WLB] = (abs(f[0]) + abs(f[1]) + abs(f[2])) >> 6


use_kernels()
