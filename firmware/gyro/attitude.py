"""Gyro-aided heading: an integer attitude filter that integrates the MPU6050's gyroscope and
is corrected by gravity and by the calibrated magnetic field (docs/gyro.md).
"""
#     att = app.use_gyro()               # firmware/app.py: loads this module, one call per step
#     att.heading_kang, att.source, att.since_mag_us, att.uncertainty_cdeg
#
# Attitude's options and what update() leaves: docs/api.md (gyro-aided heading); the filter
# (Mahony's complementary filter on a quaternion), its bias evidence and the held heading's
# uncertainty: docs/design.md (module notes, attitude) and docs/gyro.md. Every intermediate
# stays below 2**30 and the per-sample path allocates nothing (see firmware/compass.py).
from firmware.compat import const, drop, kernels, room
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
_SINCE_CAP = const(0x20000000)
_UNC_CAP = const(0x10000000)  # 2.7e5 cdeg: far past any max_uncertainty_cdeg
_DT_MAX = const(1000000)  # a longer gap counts as 1 s
_BIAS_MAX = const(1 << 25)  # 2**13 counts in 1/4096 count: 62 deg/s at +-250 deg/s
_BLOCK_US = const(2000000)  # the integral's evidence: 2 s of field-corrected, integrating time
_PAUSE_US = const(1000000)  # the integral's wait after a hold
_UNKNOWN_CDPS = const(2000)  # the bias before any evidence: the MPU6050's +-20 deg/s (product
#                              spec table 6.1, zero-rate output at power-up)
_KNOWN_CDPS = const(30)   # the bias counts as known within 0.3 deg/s...
_LOST_CDPS = const(100)   # ...and no longer past 1 deg/s
_FLOOR_CDPS = const(5)    # no evidence claims better than 0.05 deg/s
_AGREE_CDEG = const(200)  # a field ends a hold within its uncertainty, at most 2 deg
_SETTLE_US = const(6000000)  # 6 s of gravity's correction at the start-up gain: its
#                              integral has the bias about the level axes (3 time constants)

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
# 32..36: free
_GP = const(37)    # 37..39 the last gyro sample (counts)
# 40..45: free
_ACC_LIM = const(46)  # sin of accel_reject, Q14, squared
_MAG_LIM = const(47)  # mag_reject, KANG
_HEAD = const(48)
_PITCH = const(49)
_ROLL = const(50)
_SCR = const(51)   # 51..53 scratch
_C = const(54)     # 54..56 the corrections (1/16 count) for the next sample's rates
# 57: free
_UNC = const(58)   # the heading's uncertainty grown since the last correction, 1/1000 cdeg
# 59..61: free
_CA = const(62)    # 62..64 the last gravity correction (1/16 count), held a sample
_BLK = const(65)   # the integral's block: its time (< 0: none open; the wait after a hold)
_CPG = const(66)   # counts per g
_PULL = const(67)  # the field's recent pull on the heading (KANG x ms, decaying)
_DPREV = const(68)  # the last block's evidence (cdeg/s)
_SETTLE = const(69)  # gravity's correction still to run before the tilt holds (us)
_BOOST = const(70)  # the start-up gains in force: 0 (none) .. 3 (4 times the options')
_MG = const(71)    # mag_gain (1/1000 per s; at least 1)
_CDPS = const(72)  # bias (1/4096 count) per cdeg/s
_SNAP = const(73)  # 73..75 the bias at the block's start (or _sub()'s last call)
_RUN = const(76)   # predict(): the app step whose gyro step ran
_ACCOK = const(77)  # predict(): the accelerometer was plausible (app.tilt)
_SIZE = const(78)  # (firmware/gyro/attitude_fast.py's mirrors use these numbers)


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


def gravity(st, grav):
    """The filter's gravity, d x counts_per_g, in grav (int16 counts): the app's in place of
    an accelerometer that also senses an acceleration (attitude.predict)."""
    k = st[_CPG]
    grav[0] = (st[_D] * k) >> 14
    grav[1] = (st[_D + 1] * k) >> 14
    grav[2] = (st[_D + 2] * k) >> 14


# The steps the filter runs, module-wide: firmware/gyro/attitude_plain.py's functions, or their
# viper mirrors in firmware/gyro/attitude_fast.py where the port has the native emitter (the same
# bits); only the set in use is loaded (see use_kernels).
_KERNEL_NAMES = ("rates", "advance", "q_hi", "down", "tilt_error", "tilt_sine", "accel_apply",
                 "field_error", "yaw_rate", "angles", "apply")
rates = advance = q_hi = down = tilt_error = tilt_sine = accel_apply = None
field_error = yaw_rate = angles = apply = None  # apply: firmware/axes.py's, or its mirror
KERNELS = None


def use_kernels(kn=None):
    """Run the filter with the kernel set `kn`: None picks firmware/gyro/attitude_fast.py where the
    native emitter exists (firmware.compat.kernels()), else firmware/gyro/attitude_plain.py; False
    the plain set; a module with the same names, that module. Returns the module in use."""
    if kn is None:
        kn = False
        if kernels():
            try:
                from firmware.gyro import attitude_fast as kn
            except (ImportError, SyntaxError, ValueError, MemoryError):
                kn = False  # no emitter after all, an .mpy of another architecture, no room
    if kn is False:
        from firmware.gyro import attitude_plain as kn
    g = globals()
    for name in _KERNEL_NAMES:
        g[name] = getattr(kn, name)
    g["KERNELS"] = kn
    return kn


class Attitude:
    """See the module's opening comment."""

    raw = None     # attach(): the gyroscope's counts in the sensor's axes
    axes = None    # attach(): their map to the body frame (firmware/axes.py AxisMap.m)
    _at = -2       # follow(): the app step that last ran the filter
    _cal = None    # follow(): the calibration in force when the filter started

    def __init__(self, gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g,
                 **options):
        from firmware.gyro.attitude_setup import init  # construction only: dropped after it
        init(self, gyro, gravity, field, compass, counts_per_dps_x10, counts_per_g, options)
        init = None
        drop("gyro.attitude_setup")
        self._use(_UNKNOWN_CDPS)
        self._at = -2  # (the class's defaults in its own table: its size final, then room)
        self._cal = None
        self.config_ok = True  # (_verify's: the MPU6050's configuration read back)
        self.raw = self.axes = None  # the gyroscope's sample and axes (attitude_setup.attach)
        room(self)

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
        """The heading's uncertainty (0.01 deg): the base while the field corrects it, plus the
        lag a bias error of bias_cdps leaves behind the field's pull (bias_cdps / mag_gain),
        plus, sample by sample since the last correction, bias_cdps of the moment times the
        time."""
        st = self.st
        return self.base_cdeg + self.bias_cdps * 1000 // st[_MG] + st[_UNC] // 1000

    def _use(self, v):
        # how well the bias is known (cdeg/s), and what follows from it: the uncertainty's
        # growth and lag; the start-up gains until it is known
        st = self.st
        self.bias_cdps = v
        self.unc_rate = v
        k = v <= (_LOST_CDPS if self.known else _KNOWN_CDPS)
        if k and not self.known:
            st[_SETTLE] = 0  # (the tilt holds)
            st[_ACC_LIM] = self.acc_lim
        self.known = k
        # the start-up gains: the options' times v / 0.3 deg/s, 4 at most (a ramp down as
        # the bias becomes known)
        v = 0 if k else v // _KNOWN_CDPS - 1
        v = 3 if v > 3 else v
        if v != st[_BOOST]:
            st[_BOOST] = v
            k = self._k
            st[_KA] = k[3 * v]
            st[_KM] = k[3 * v + 1]
            st[_KB] = self.kb = k[3 * v + 2]
            st[_BLK] = -1  # the evidence of another bias_gain is not this one's

    def _verify(self):
        # the integral's evidence: over a block of field-corrected time the bias moved by
        # bias_gain x the mean correction, and the mean correction is the bias error the
        # filter still carries (the field's and gravity's pull balances it), so |moved| /
        # (bias_gain x time) bounds the error; the larger of the last two blocks is taken
        st = self.st
        m = self._sub()  # cdeg/s moved
        d = self._k[12 + st[_BOOST]] * (st[_BLK] // 1000)  # 1/10**6 per s x ms
        st[_BLK] = 0
        if d <= 0:
            return
        self.bias_estimates += 1
        m = m * 1000000 // d
        d = st[_DPREV]
        st[_DPREV] = m
        if d > m:
            m = d
        self._use(m if m > _FLOOR_CDPS else _FLOOR_CDPS)

    @property
    def vouched(self):
        return self.started and self.uncertainty_cdeg <= self.max_uncertainty_cdeg

    def reset(self):
        """Start again from the next good sample (the bias estimate is kept)."""
        self.started = False
        st = self.st
        st[_PULL] = 0
        st[_SINCE] = 0
        st[_UNC] = 0
        st[_BLK] = -1
        if not self.known:  # the bias not known and the tilt not held: gravity is taken as
            st[_SETTLE] = _SETTLE_US  # it comes (no rejection: the gyro cannot vouch
            st[_ACC_LIM] = 0x3FFFFFFF  # for the tilt) until _SETTLE_US of correction

    # --- the app's step (attach, CompassApp.use_gyro) ------------------------------------
    _run = -2  # predict(): the app step whose gyro step ran
    _acc_ok = False  # predict(): the accelerometer was plausible (app.tilt)
    shown_kang = -1  # follow(): the heading the app shows (with the declination)

    def predict(self, app):
        # The app's step before its compass update, on the sample just read: the
        # accelerometer's gravity mapped into app.gravity (a plausible one), the gyro step and
        # gravity's correction. Once the filter's tilt holds (the bias known, or gravity's
        # correction settled at the start-up gain), a gravity further from the filter's than
        # 1/32 g on an axis (1/16 g until the bias is known) - an acceleration, a bump,
        # vibration - is replaced by the filter's, and so is an accelerometer bumped out of the
        # app's 0.75..1.25 g window (not one that is frozen or reads nothing: the chip's
        # fault): the compass's tilt and the field checks (the dip, its steadiness:
        # firmware/health.py) then see the filter's gravity, and a clean field keeps
        # correcting the heading while the board accelerates. True when app.gravity holds the
        # gravity to use (Health's tilt then holds: CompassApp._heading).
        t = app.health.tilt
        if t:
            apply(app._am, app._acc, app.gravity)
        elif app.health.asame:  # frozen (firmware/health.py): the chip's fault, not a bump
            self._gap(app, False)
            return False
        st = self.st
        st[_ACCOK] = t
        if self._gap(app, True):
            return t  # started again: the next clean sample starts the filter
        st[_RUN] = app.steps
        if not self.started:
            return t
        if self._step(app._dt, 6 if t else 2) and t or not (  # FIELD | ACC_OK; turning
                self.known or st[_SETTLE] <= 0):  # fast, the accelerometer is taken as it is
            return t
        gravity(st, self.gravity)  # (a bumped accelerometer: gravity is the filter's)
        return True

    def follow(self, app):
        # One call per app step after its field checks: the field's correction, and the
        # filter's heading becomes the app's once the bias is known (until then the app shows
        # the compass's heading and status: never worse than the compass alone). The field is
        # offered to the filter when the checks pass, on a heading jump (a turn the gyro
        # confirms) and, unless the filter holds a heading it no longer vouches for, once an
        # interference spell has seen 1 s of samples that raise no flag (firmware/health.py
        # FieldWatch: the magnet has gone, or holds still); the filter takes it only within mag_reject of its own
        # heading, and to end a hold within the held heading's uncertainty. While it holds the heading
        # without the field and vouches for it the status is "gyro held" in place of
        # interference / heading jumped; "ok" when this sample's field corrected it. Returns
        # the status to show with the heading .shown_kang (CompassApp._step), None to keep the
        # compass's.
        n = app.steps
        st = self.st
        if st[_RUN] != n:  # predict() found a gap, or did not run: the next clean
            if self._at != n:  # sample starts the filter
                self.reset()
            return None
        s = app.status
        f = 6 if st[_ACCOK] else 2  # FIELD | ACC_OK
        if s == _OK or s == _JUMP or (s == _INTERFERENCE and app.watch.clean_us >= _OFFER_US
                                      and (self.vouched or not self.known)):
            f += 1  # | MAG_OK
        h = self._correct(app._dt, f) if self.started else self._start(f)
        if h < 0 or not self.known:
            return None
        n = st[_D]  # -sin(pitch), Q14
        if n > _GIMBAL or n < -_GIMBAL:  # near vertical the heading is the compass's: a
            return None  # small tilt error moves psi by tan(pitch) (AN4248 sec. 6)
        self.shown_kang = (h + self.compass.declination_kang) & 0xFFFF
        if st[_SINCE] == 0:  # this sample's field corrected the heading
            return _OK
        if s == _OK or s == _INTERFERENCE or s == _JUMP:
            return _GYRO_HELD if self.vouched else _INTERFERENCE
        return s

    def _gap(self, app, ok):
        # The gyroscope into the body frame (.axes: the accelerometer's axis map negated, as
        # the map turns specific force into AN4248 gravity, Gp = -f, and a rate keeps its sign).
        # True after a step without the gyro (a failed read, a stall: time the filter did not
        # integrate), when another calibration was put in force (the field it followed was
        # another), with an implausible accelerometer (the gyro's own chip: its burst is
        # suspect too), a rate past the range or a chip that lost its setting: the filter then
        # starts again from the compass at the next clean sample.
        apply(self.axes, self.raw, self.gyro)
        n = app.steps
        skip = n != self._at + 1 or app._stalled or not ok
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
            app.health.wake(app, False)  # configure() under the app's read guard (.reinits)
        return self.config_ok

    def update(self, dt, flags):
        if not self.started:
            return self._start(flags)
        self._step(dt, flags)
        return self._correct(dt, flags)

    def _step(self, dt, flags):
        # the gyro step, and gravity's correction (every other sample, held for the one
        # between while the accelerometer stays plausible: its 2 s time constant misses
        # nothing; the plain path's cost)
        if dt > _DT_MAX or dt < 0:
            dt = _DT_MAX if dt > 0 else 0
        st = self.st
        m = rates(st, self.gyro)  # the rate, plus the corrections the last sample asked
        #                           for; m: how fast it turns
        if m > self.kb_counts:  # turning fast: the corrections carry the integration's
            st[_KB] = 0  # errors, not the bias (nor does the tilt hold against a bias not
            if not self.known:  # known: reset() says why)
                st[_SETTLE] = _SETTLE_US
                st[_ACC_LIM] = 0x3FFFFFFF
            m = 1
        else:  # nor does it just after a hold (_field)
            m = st[_BLK]
            st[_KB] = self.kb if m >= 0 or m == -_PAUSE_US else 0
            m = 0
        advance(st, dt)
        down(st)  # from normalise's q >> 14 (q before its last, tiny, step)
        self._odd = not self._odd
        if not flags & ACC_OK:
            self.accel_rejected = True
            self._gravity_held(0)
        elif self._odd:
            self._gravity(dt << 1)
        else:
            self._gravity_held(1)
        return m

    def _correct(self, dt, flags):
        # the field's correction; the corrections become the next sample's rates
        if dt > _DT_MAX or dt < 0:
            dt = _DT_MAX if dt > 0 else 0
        st = self.st
        self._field(dt, flags)
        st[_C] = st[_U]
        st[_C + 1] = st[_U + 1]
        st[_C + 2] = st[_U + 2]
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
                    if st[_SETTLE] > 0:
                        st[_SETTLE] -= dt
                        if st[_SETTLE] <= 0:
                            st[_ACC_LIM] = self.acc_lim  # the tilt holds: rejection on
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
        st[_ACC_LIM] = self.acc_lim if st[_SETTLE] <= 0 else 0x3FFFFFFF
        self.accel_rejected = False

    def _field(self, dt, flags):
        st = self.st
        if flags & (MAG_OK | FIELD) != MAG_OK | FIELD or norm14(
                self.field, st, _G) == ZERO_VECTOR:  # not offered: the heading error of
            self._hold(dt)  # the last field offered stays in .heading_error_kang
            return
        e = field_error(st)
        st[_E] = e
        lim = st[_MAG_LIM] if st[_SINCE] == 0 else self._lim()
        if -lim <= e <= lim:
            st[_MREJ] = 0
        else:
            st[_MREJ] += dt
            if self.known and (st[_MREJ] <= self.recovery_us or self.vouched):
                self._hold(dt)
                return
            turn(st, e)  # the gyro lost the heading (e.g. past its range), or cannot vouch
            #              for it (the bias not known, or held too long): the field's
            st[_MREJ] = 0
            e = 0
        yaw_rate(st, e)
        st[_SINCE] = 0
        st[_UNC] = 0
        p = st[_PULL]  # the field's recent pull: its error x time, decaying in ~0.5 s
        st[_PULL] = p + (e - (p >> 9)) * (dt >> 10)  # (KANG x ms)
        self._clean(dt)

    def _lim(self):
        # the agreement a field needs to end a hold the gyro vouches for: the held heading's
        # uncertainty (a field further off is still disturbed: a magnet that stays put),
        # within mag_reject
        m = self.st[_MAG_LIM]
        if not (self.known and self.vouched):
            return m
        u = self.uncertainty_cdeg
        u = (u if u < _AGREE_CDEG else _AGREE_CDEG) * 182 // 100  # cdeg -> KANG
        return u if u < m else m

    def _clean(self, dt):
        # a field-corrected sample: the integral's block goes on (while it integrates), or
        # after a hold its wait (its heading error is no evidence of the bias: the integral
        # waits _PAUSE_US while the field pulls it in)
        st = self.st
        b = st[_BLK]
        if b < 0:
            b += dt
            if b >= 0:
                self._sub()  # the block starts: the bias now
                b = 0
            st[_BLK] = b
        elif st[_KB]:
            b += dt
            st[_BLK] = b
            if b >= _BLOCK_US:
                self._verify()

    def _mark(self):
        # a hold begins: its uncertainty starts at what the field pulled the heading by in
        # its last ~0.5 s (a magnet creeping in before the app's checks flag it: mag_gain x
        # its error x time) and grows at the bias uncertainty, or at what the integral moved
        # the bias by since the block began if more (that pull reached the bias too)
        st = self.st
        r = self.bias_cdps
        if st[_BLK] >= 0:
            p = self._sub()
            r = p if p > r else r
        self.unc_rate = r
        st[_BLK] = -_PAUSE_US  # a block is field-corrected throughout
        r = st[_MG] * (st[_BOOST] + 1)  # mag_gain in force (1/1000 per s)
        p = st[_PULL]
        p = (p if p > 0 else -p) // 1000 * (r if r < 1000 else 1000) // 1000  # KANG
        st[_PULL] = 0
        st[_UNC] = (p if p < 16384 else 16384) * 36000 // 65536 * 1000  # (90 deg at most)

    def _hold(self, dt):
        st = self.st
        if st[_SINCE] == 0 and self.started:
            self._mark()
        if st[_SINCE] < _SINCE_CAP:
            st[_SINCE] += dt
        if st[_UNC] < _UNC_CAP:  # cdeg/s x us / 1000 (dt <= 10**6 us, the rate <= 2000)
            r = self.unc_rate
            st[_UNC] += dt // 1000 * r + dt % 1000 * r // 1000

    def _sub(self):
        # how far the bias moved since the last call, worst axis, cdeg/s (at most 1000)
        st = self.st
        m = 0
        for i in range(3):
            d = st[_BIAS + i] - st[_SNAP + i]
            st[_SNAP + i] = st[_BIAS + i]
            if d < 0:
                d = -d
            if d > m:
                m = d
        m //= st[_CDPS]
        return m if m < 1000 else 1000


room(Attitude)  # its methods' table too (firmware/compat.py room)



use_kernels()
