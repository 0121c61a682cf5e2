"""Motion scripts: the board's orientation as a function of simulated time.

A script is an object with `at(t_us) -> (yaw_deg, pitch_deg, roll_deg)` (AN4248 angles:
yaw psi clockwise from magnetic north, pitch theta, roll phi; the body rotation is
Rx(phi) Ry(theta) Rz(psi), AN4248 eqs. 1-3) and `duration_us` (None when it never ends).
Everything is a pure function of the integer time, so runs repeat bit for bit.

    from host_sim import motion
    motion.still(yaw=30)                         # a board lying still, heading 30 deg
    motion.flat_spin(period_s=8)                 # level, one turn every 8 s (planar data)
    motion.figure8(period_s=30)                  # waves through every field direction
    motion.arc(0, 90, duration_s=5)              # a partial turn, then holds
    motion.waypoints([(0, 0, 0, 0), (2, 90, 0, 0), (4, 90, 30, 0)])   # piecewise constant
    motion.sequence([(5, motion.still()), (30, motion.figure8())])   # one after the other
"""
import math

_TWO_PI = 6.283185307179586


def _s(t_us):
    return t_us / 1000000


class still:
    """A board at rest."""

    def __init__(self, yaw=0.0, pitch=0.0, roll=0.0):
        self.pose = (float(yaw), float(pitch), float(roll))
        self.duration_us = None

    def at(self, t_us):
        return self.pose


class flat_spin:
    """Constant pitch and roll (level by default), yaw turning at one turn per `period_s`.

    The field in the body frame only sweeps a cone: the planar, degenerate case for
    calibration (Judd; AN4246 needs rotation about more than one axis).
    """

    def __init__(self, period_s=10.0, yaw0=0.0, pitch=0.0, roll=0.0, clockwise=True):
        if period_s <= 0:
            raise ValueError("flat_spin: period_s must be > 0, got %r" % period_s)
        self.period_s = float(period_s)
        self.yaw0 = float(yaw0)
        self.pitch = float(pitch)
        self.roll = float(roll)
        self.sign = 1.0 if clockwise else -1.0
        self.duration_us = None

    def at(self, t_us):
        yaw = self.yaw0 + self.sign * 360.0 * _s(t_us) / self.period_s
        return (yaw % 360.0, self.pitch, self.roll)


class figure8:
    """The calibration gesture: figure-8s in roll/pitch while the yaw keeps turning.

    Over one period (u = t / period in [0, 1)) the board traces `lobes` figure-8s
    (roll:pitch frequency 1:2, a Lissajous figure 8) whose shape drifts `drift` times, so the
    down direction visits every part of the sphere, while the yaw turns `yaw_turns` times:
        roll  = roll_amp  * sin(2 pi lobes u)
        pitch = pitch_amp * sin(2 pi (2 lobes + drift) u)
        yaw   = yaw0 + 360 yaw_turns u
    With the defaults, one period sampled at 20 Hz puts the field direction in the body frame
    into at least 95 of 100 equal-area sphere regions for inclinations 0-75 deg
    (tests/test_sim_world.py counts it).
    """

    def __init__(self, period_s=30.0, lobes=8, drift=2, yaw_turns=9.5, pitch_amp=85.0,
                 roll_amp=180.0, yaw0=0.0):
        if period_s <= 0:
            raise ValueError("figure8: period_s must be > 0, got %r" % period_s)
        self.period_s = float(period_s)
        self.lobes = lobes
        self.drift = drift
        self.yaw_turns = float(yaw_turns)
        self.pitch_amp = float(pitch_amp)
        self.roll_amp = float(roll_amp)
        self.yaw0 = float(yaw0)
        self.duration_us = None

    def at(self, t_us):
        u = _s(t_us) / self.period_s
        roll = self.roll_amp * math.sin(_TWO_PI * self.lobes * u)
        pitch = self.pitch_amp * math.sin(_TWO_PI * (2 * self.lobes + self.drift) * u)
        yaw = (self.yaw0 + 360.0 * self.yaw_turns * u) % 360.0
        return (yaw, pitch, roll)


class arc:
    """Yaw moves linearly from `yaw_from` to `yaw_to` over `duration_s` (after `start_s`),
    then holds: a partial turn, the usual "not enough coverage" case."""

    def __init__(self, yaw_from, yaw_to, duration_s, pitch=0.0, roll=0.0, start_s=0.0):
        if duration_s <= 0:
            raise ValueError("arc: duration_s must be > 0, got %r" % duration_s)
        self.yaw_from = float(yaw_from)
        self.yaw_to = float(yaw_to)
        self.start_us = int(math.floor(start_s * 1000000 + 0.5))
        self.len_us = int(math.floor(duration_s * 1000000 + 0.5))
        self.pitch = float(pitch)
        self.roll = float(roll)
        self.duration_us = self.start_us + self.len_us

    def at(self, t_us):
        dt = t_us - self.start_us
        if dt <= 0:
            f = 0.0
        elif dt >= self.len_us:
            f = 1.0
        else:
            f = dt / self.len_us
        yaw = self.yaw_from + (self.yaw_to - self.yaw_from) * f
        return (yaw % 360.0, self.pitch, self.roll)


class waypoints:
    """Piecewise constant: [(t_s, yaw, pitch, roll), ...] sorted by time; each pose holds
    from its time until the next one (the first also before its time)."""

    def __init__(self, points):
        pts = []
        for p in points:
            if len(p) != 4:
                raise ValueError("waypoints: each point is (t_s, yaw, pitch, roll), got %r" % (p,))
            pts.append((int(math.floor(p[0] * 1000000 + 0.5)),
                        (float(p[1]), float(p[2]), float(p[3]))))
        if not pts:
            raise ValueError("waypoints: need at least one point")
        for i in range(1, len(pts)):
            if pts[i][0] < pts[i - 1][0]:
                raise ValueError("waypoints: times must not decrease (point %d)" % i)
        self.points = pts
        self.duration_us = pts[-1][0]

    def at(self, t_us):
        pose = self.points[0][1]
        for t, p in self.points:
            if t <= t_us:
                pose = p
            else:
                break
        return pose


class sequence:
    """Scripts one after another: [(duration_s, script), ...]; each script sees its own
    time starting at 0; the last one continues past its duration."""

    def __init__(self, parts):
        self.parts = []
        t = 0
        for d, m in parts:
            n = int(math.floor(d * 1000000 + 0.5))
            if n <= 0:
                raise ValueError("sequence: durations must be > 0, got %r" % d)
            self.parts.append((t, n, m))
            t += n
        if not self.parts:
            raise ValueError("sequence: need at least one part")
        self.duration_us = t

    def at(self, t_us):
        for start, n, m in self.parts:
            if t_us < start + n:
                return m.at(t_us - start if t_us > start else 0)
        start, n, m = self.parts[-1]
        return m.at(t_us - start)
