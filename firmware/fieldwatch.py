"""The heading line's field checks: the dip against the calibration's (DipCheck) and the spells
of a field that moved (FieldWatch). Loaded with the heading line."""
#     from firmware.fieldwatch import FieldWatch
#     w = FieldWatch(compass, body)   # app.watch (firmware/app_setup.py); w.dip: its DipCheck
#
# Why 3 deg of dip, what a shift and a jump are, and when a spell ends: docs/design.md (module
# notes, fieldwatch) and docs/faults.md. Allocation-free (tests/scenarios/app_alloc.py).
from array import array

from firmware.compat import const, room
from firmware.compass import FIELD_TOL_PCT
from firmware.health import DIP_TOL_KANG, SPELL_FIELD, SPELL_JUMP, SPELL_SHIFT

_DIP_STEADY_KANG = const(273)   # 1.5 deg: a learning stretch restarts beyond this
_DIP_LEARN_US = const(500000)   # 0.5 s of steady, clean samples make the reference...
_DIP_MIN_SAMPLES = const(8)     # ...and at least 8 of them (the mean's noise < 0.1 deg)
_DIP_MAX_SAMPLES = const(2048)  # sums stay below 2**26
_KANG_PER_RAD = const(10430)    # 65536 / (2 pi): a fit error (1e-4 rad of direction) -> KANG
_JUMP_KANG = const(728)         # the jump limit: 4 deg at least...
_JUMP_MAX_KANG = const(1456)    # ...8 deg at most, else 3.5 x the heading's noise...
_JUMP_HALVES = const(7)         # ...(7 halves of it)...
_NOISE_SHIFT = const(6)         # ...its mean change of step over ~2**6 still steps
_TURN_KANG_PER_S = const(4551) # 25 deg/s: the turn two steps may add to the limit
_RATE_SHIFT = const(3)          # one step is judged against the mean of ~2**3 still steps
_RAMP_US = const(60000)         # three steps in less (above 50 Hz) are judged as one too
_TILT_STILL_KANG = const(182)   # 1 deg of pitch and of roll from one sample to the next
_LEVEL_KANG = const(8192)       # 45 deg: jumps are judged within this of level
_STEADY_SHIFT = const(3)        # short averages over ~2**3 samples
_STEADY_FIELD_PCT = const(4)
_STEADY_DIP_KANG = const(364)   # 2 deg
_RETURN_PCT = const(4)          # "back where it was": within 4 % of B...
_RETURN_TILT_KANG = const(364)  # ...and 2 deg of pitch and of roll
_RETURN_US = const(100000)      # ...for 0.1 s of clean samples
_CLEAN_US = const(2000000)      # 2 s of clean samples over a turn of B / 4...
_HOLD_MAX_US = const(10000000)  # ...or 10 s of clean samples end a spell
_LEARN_FIELD_PCT = const(3)     # the dip is learned from samples with |B| this close
_STALE_US = const(30000000)     # 30 s of interference: the calibration no longer fits the board
# check(app): what the app shows for a sample in a spell (0: the field is clean)
W_JUMP = const(1)               # "heading jumped" (else "interference")
W_FLAG = const(2)               # this sample raised a flag: counted in app.errors
W_KEEP = const(4)               # the collector may take the sample
_FIELD_TOL_MAX_PCT = const(50)  # use(): the compass's |B| window at most +-50 %


class DipCheck:
    # The dip check (docs/design.md, module notes). learn(dip, dt_us) on clean samples until
    # .armed (True on the sample that arms it); set(ref) arms it with a known dip; off(dip)
    # True when armed and the dip is more than .tol off .ref (KANG); reset() when another
    # calibration is put in force. Small ints only: dips are within +-16384 KANG and the sums
    # hold at most _DIP_MAX_SAMPLES of them.

    def __init__(self, tol=DIP_TOL_KANG):
        self.tol = tol
        self.ref = 0
        self.armed = False
        self._sum = 0
        self._n = 0
        self._us = 0

    def reset(self):
        self.armed = False
        self._n = 0
        self._sum = 0
        self._us = 0

    def set(self, ref):
        self.ref = ref
        self.armed = True

    def off(self, d):
        if not self.armed:
            return False
        d -= self.ref
        return d > self.tol or d < -self.tol

    def learn(self, d, dt):
        if self.armed:
            return False
        n = self._n
        if n >= _DIP_MAX_SAMPLES or not self._steady(d, n):
            self._restart(d)
            return False
        self._sum += d
        self._n = n + 1
        self._us += dt
        if self._us >= _DIP_LEARN_US and n >= _DIP_MIN_SAMPLES:
            self._arm()
            return True
        return False

    def _steady(self, d, n):
        # |d - mean| <= _DIP_STEADY_KANG, without a division
        d = d * n - self._sum
        n *= _DIP_STEADY_KANG
        return n > 0 and -n <= d <= n

    def _restart(self, d):
        self._sum = d
        self._n = 1
        self._us = 0

    def _arm(self):
        n = self._n
        self.ref = (2 * self._sum + n) // (2 * n)  # the mean, rounded
        self.armed = True


class FieldWatch:
    # The spells (docs/design.md, module notes), for one Compass `c` and the body-frame field
    # array `body` its update() used. use(cal) when a calibration is put in force (the same
    # one again keeps the state), restart() after a step without a sample or a gap: the next
    # sample starts the short averages afresh. sample(tilt, dt_us) after each compass update
    # returns the flag this sample raised (0, SPELL_JUMP, SPELL_SHIFT, SPELL_FIELD) and leaves
    # .spell (0 when the status may be ok), .learned (True on the sample that armed the dip
    # reference) and .dip (the DipCheck); check(app) is sample() for a CompassApp, returning
    # the W_* bits of what it shows. forget(run) ends a spell that began within the last
    # `run` samples (a run of stale repeats: not a field). A dip outside the DipCheck's
    # tolerance raises c.interference like the compass's own windows. Small ints only:
    # field differences are taken on body >> .shift (B >> shift < 2**11; a smaller B, such as
    # an AKM chip's ~330 counts, keeps every count) and held to 2**14.

    def __init__(self, c, body):
        self.c = c
        self.body = body
        self.dip = DipCheck()
        self.spell = 0
        self.learned = False
        self.n = 0                        # samples seen (wraps at 2**14)
        self.spell_at = 0
        self.clean_us = 0
        self.m0 = array("h", (0, 0, 0))   # body at the spell's last flag
        self.p0 = array("h", (0, 0, 0))   # body at a clean sample before the spell,
        self.p0_pitch = 0                 # and the tilt then
        self.p0_roll = 0
        self.p0_ok = False
        self.g0 = array("h", (0, 0, 0))   # the last clean sample: body, tilt
        self.g1 = array("h", (0, 0, 0))   # the two clean samples before it (a ramp caught
        self.g2 = array("h", (0, 0, 0))   # on its third step began before g0)
        self.g0_pitch = 0
        self.g0_roll = 0
        self.g0_ok = 0                    # how many of g0, g1, g2 hold a sample
        # the previous sample: heading (-1: none), tilt; the short averages of |b| and dip (x 8)
        self.prev_h, self.prev_tilt, self.prev_pitch, self.prev_roll = -1, False, 0, 0
        self.step_h = 0                   # the last still, clean step's heading change...
        self.step_us = 0                  # ...and its time
        self.step_h2 = self.step_us2 = 0  # the same of the two steps before this one
        self.noise = (_JUMP_KANG << (_NOISE_SHIFT + 1)) // _JUMP_HALVES  # 2**6 x that mean
        self.jump = _JUMP_KANG            # the jump limit (KANG)
        self.rate = 0                     # 2**3 x the mean still step: the turn per step
        self.dt = 0                       # this sample's time (sample())
        self.mag8, self.dip8 = 0, 0
        self.shift = 2
        self.turn2 = 0
        self.back2 = 0
        self.field_pct = _STEADY_FIELD_PCT
        self.dip_kang = _STEADY_DIP_KANG
        self.lo = 0
        self.hi = 0
        self.on = False
        self.cal = None
        self.flagged_us = 0               # check(): time flagged since the last clean sample
        room(self)  # a sample calls a dozen methods (firmware/compat.py room)

    def use(self, cal):
        # the compass's |B| window afresh: max(FIELD_TOL_PCT, 3 x the fit's RMS error, which
        # is no evidence of a magnet), at most _FIELD_TOL_MAX_PCT; the same calibration again
        # keeps the rest
        t = 3 * cal.fit_error // 100
        if t < FIELD_TOL_PCT:
            t = FIELD_TOL_PCT
        elif t > _FIELD_TOL_MAX_PCT:
            t = _FIELD_TOL_MAX_PCT
        self.c.set_field(cal.field_out if cal.model is not None else 0, t)
        if cal is self.cal:
            return
        self.cal = cal
        self.spell = 0
        self.prev_h = -1
        self.g0_ok = 0
        self.on = cal.model is not None
        self.dip.reset()
        fe = cal.fit_error
        self.dip.tol = _angle(3 * fe, DIP_TOL_KANG)
        if self.on and cal.dip_kang is not None:
            self.dip.set(cal.dip_kang)
        self.dip_kang = _angle(3 * fe, _STEADY_DIP_KANG)
        t = 3 * fe // 100
        self.field_pct = t if t > _STEADY_FIELD_PCT else _STEADY_FIELD_PCT
        f = cal.field_out
        t = fe // 100
        t = t if t > _LEARN_FIELD_PCT else _LEARN_FIELD_PCT
        self.lo = f - f * t // 100
        self.hi = f + f * t // 100
        s = 0
        while f >> s >= 1 << 11:
            s += 1
        self.shift = s
        f >>= s
        t = f // 4
        self.turn2 = t * t
        t = f * _RETURN_PCT // 100
        self.back2 = t * t

    def restart(self):
        self.prev_h = -1

    def forget(self, run):
        if self.spell and (self.n - self.spell_at) & 0x3FFF < run:
            self.spell = 0

    # --- one sample ------------------------------------------------------------------------
    def sample(self, tilt, dt):
        self.learned = False
        self.n = (self.n + 1) & 0x3FFF
        if not self.on:
            return 0
        self.dt = dt
        k = self._flags(tilt)
        if k:
            self._mark(k)
        elif self.spell:
            self._hold(dt)
        else:
            self._clean(tilt, dt)
        self._remember(tilt)
        return k

    def check(self, app):
        """The app's sample, after its compass update: 0 when the field is clean, else the
        W_* bits of the spell it shows (docs/design.md, app). A field outside its windows also
        has the chip's set read back (Health.cfg_due), and after _STALE_US the app relearns."""
        k = self.sample(app.health.tilt and app.accel is not None, app._dt)
        if k == SPELL_FIELD:
            app.health.cfg_due = True  # the chip's set read back at the next sample
            if app.relearning:  # the calibration in force is the one that does not fit
                return W_FLAG | W_KEEP
            self.flagged_us += app._dt
            if self.flagged_us < _STALE_US:
                return W_FLAG
            self.flagged_us = 0
            self.dip.reset()  # the dip too is learned afresh
            app.learning.relearn(app)  # the board's iron changed: relearn
            return W_FLAG
        if not self.spell:
            self.flagged_us = 0
            return 0
        r = W_JUMP if self.spell == SPELL_JUMP else 0
        if k:
            r |= W_FLAG
        if k == 0 or k == SPELL_JUMP or app.relearning:  # what the collector still takes
            r |= W_KEEP
        return r

    def _clean(self, tilt, dt):
        c = self.c
        self.g2, self.g1, self.g0 = self.g1, self.g0, self.g2  # (a rotation: no allocation)
        _copy(self.body, self.g0)
        self.g0_pitch = c.pitch_kang
        self.g0_roll = c.roll_kang
        if self.g0_ok < 3:
            self.g0_ok += 1
        if tilt and self.lo <= c.magnitude <= self.hi:
            self.learned = self.dip.learn(c.dip_kang, dt)

    def _flags(self, tilt):
        c = self.c
        k = 0
        if tilt and self.dip.off(c.dip_kang):
            c.mark_interference()
        if self.prev_h < 0 or tilt != self.prev_tilt:
            self.mag8 = c.magnitude << _STEADY_SHIFT  # after a gap, another calibration
            self.dip8 = c.dip_kang << _STEADY_SHIFT   # or tilt mode: start afresh
            self.step_h = 0
        elif self._field_moved() | self._dip_moved(tilt):  # both: each updates its average
            k = SPELL_SHIFT
            self.step_h = 0
        elif self._jumped(tilt):
            k = SPELL_JUMP
        if c.interference:
            self.step_h = 0
            return SPELL_FIELD
        return k

    def _field_moved(self):
        a = self.mag8
        d = (self.c.magnitude << _STEADY_SHIFT) - a
        self.mag8 = a + (d >> _STEADY_SHIFT)
        a *= self.field_pct
        d *= 100
        return d > a or d < -a

    def _dip_moved(self, tilt):
        a = self.dip8
        d = (self.c.dip_kang << _STEADY_SHIFT) - a
        self.dip8 = a + (d >> _STEADY_SHIFT)
        a = self.dip_kang << _STEADY_SHIFT
        return tilt and (d > a or d < -a)

    def _jumped(self, tilt):
        # a still step more than .jump off the recent turn per step (.rate), two more than
        # .jump plus a turn at _TURN_KANG_PER_S, or, above 50 Hz, three more than that off the
        # recent turn (a ramp of steps each under .jump: a magnet brought near); .step_h is
        # the last step's change (0 when that step was not still or raised a flag), .step_us
        # its time, .step_h2 and .step_us2 the same of the last two. No more locals: a larger
        # frame would go on MicroPython's heap (tests/scenarios/app_alloc.py)
        c = self.c
        if tilt and (_off(c.pitch_kang - self.prev_pitch, _TILT_STILL_KANG)
                     or _off(c.roll_kang - self.prev_roll, _TILT_STILL_KANG)
                     or _off(c.pitch_kang, _LEVEL_KANG) or _off(c.roll_kang, _LEVEL_KANG)):
            self.step_h = 0
            return False
        d = ((c.heading_kang - self.prev_h + 32768) & 0xFFFF) - 32768
        p = self.step_h
        self.step_h = 0
        if _off(d - (self.rate >> _RATE_SHIFT), self.jump) or \
                _off(p + d, self.jump + _turn(self.step_us + self.dt)) or \
                p and self.step_us2 + self.dt < _RAMP_US and \
                _off(self.step_h2 + d - 3 * (self.rate >> _RATE_SHIFT),
                     self.jump + _turn(self.step_us2 + self.dt)):
            return True
        if p:
            self._noise(d, p)
            self.step_h2 = p + d
            self.step_us2 = self.step_us + self.dt
        else:
            self.step_h2 = d
            self.step_us2 = self.dt
        self.step_h = d
        self.step_us = self.dt
        return False

    def _noise(self, d, p):
        # two still steps in a row, d after p: the turn per step (.rate) and the heading's
        # noise, from the change of step (a steady turn cancels); |d|, |p| <= 2**15, so
        # |.rate| < 2**18, .noise < 2**22 and the product below < 2**25
        r = self.rate
        self.rate = r + d - (r >> _RATE_SHIFT)
        e = d - p
        n = self.noise
        n += (e if e > 0 else -e) - (n >> _NOISE_SHIFT)
        self.noise = n
        n = n * _JUMP_HALVES >> (_NOISE_SHIFT + 1)
        self.jump = _JUMP_KANG if n < _JUMP_KANG else n if n < _JUMP_MAX_KANG else _JUMP_MAX_KANG

    def _mark(self, k):
        # a flag (re)starts the spell; the turn is measured from this sample's field
        self.clean_us = 0
        if not self.spell:
            self.spell_at = self.n
            self._before()
        if k > self.spell:
            self.spell = k
        _copy(self.body, self.m0)

    def _before(self):
        # where the field was before the spell: the clean sample before the steps that raised
        # the flag (three back, for a ramp caught on its third step), if there was one; the
        # tilt is g0's (a still step moves it < 1 deg)
        n = self.g0_ok
        self.p0_ok = n > 0
        _copy(self.g2 if n > 2 else self.g1 if n > 1 else self.g0, self.p0)
        self.p0_pitch = self.g0_pitch
        self.p0_roll = self.g0_roll

    def _hold(self, dt):
        u = self.clean_us + dt
        self.clean_us = u if u < _HOLD_MAX_US else _HOLD_MAX_US
        if u >= _HOLD_MAX_US or (u >= _CLEAN_US and self._d2(self.m0) >= self.turn2) \
                or (u >= _RETURN_US and self._back()):
            self.spell = 0

    def _back(self):
        c = self.c
        return (self.p0_ok and not _off(c.pitch_kang - self.p0_pitch, _RETURN_TILT_KANG)
                and not _off(c.roll_kang - self.p0_roll, _RETURN_TILT_KANG)
                and self._d2(self.p0) <= self.back2)

    def _d2(self, a):
        return self._sq(a, 0) + self._sq(a, 1) + self._sq(a, 2)

    def _sq(self, a, i):
        d = (self.body[i] - a[i]) >> self.shift
        if d > 16383 or d < -16383:  # past every limit compared (B >> shift < 2**11)
            d = 16383
        return d * d

    def _remember(self, tilt):
        c = self.c
        self.prev_h = c.heading_kang
        self.prev_tilt = tilt
        self.prev_pitch = c.pitch_kang
        self.prev_roll = c.roll_kang


room(FieldWatch)  # its methods' table too (firmware/compat.py room)


def _off(d, lim):
    # |d| > lim for an angle difference in KANG (wrapped to -32768..32767)
    d = ((d + 32768) & 0xFFFF) - 32768
    return d > lim or d < -lim


def _turn(us):
    # what steps lasting `us` (two, or three above 50 Hz) add to .jump: the turn at
    # _TURN_KANG_PER_S; `us` held to 8 s (two of the app's steps are at most 8 sample periods;
    # three are checked only within _RAMP_US), so the product
    # stays below 2**26
    if us > 8000000:
        us = 8000000
    return (us // 1000) * _TURN_KANG_PER_S // 1000


def _copy(a, b):
    b[0] = a[0]
    b[1] = a[1]
    b[2] = a[2]


def _angle(fe, floor):
    # a fit error (hundredths of a percent: 1e-4 rad of direction) as KANG, at least floor,
    # at most 90 deg
    if fe >= 15000:
        return 16384
    k = fe * _KANG_PER_RAD // 10000
    return k if k > floor else floor
