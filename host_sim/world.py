"""The world around the simulated board: Earth's field, gravity, orientation, iron, magnets.

    from host_sim.world import World
    from host_sim import motion
    w = World(field_ut=50.0, inclination_deg=60.0, declination_deg=2.0,
              hard_iron_ut=(20, -10, 5), soft_iron=((1.1, 0.05, 0), (0.05, 0.9, 0), (0, 0, 1)),
              motion=motion.figure8())
    w.field_body(t_us)                       # uT, body frame (AN4248: x fwd, y right, z down)
    w.sensor_field(t_us, (1, -2, -3))        # uT as a chip with that mounting senses it
    w.drift_iron((0.5, 0, 0), start_s=5)     # the hard iron drifts 0.5 uT/s from t = 5 s
    w.switch_iron((12, 8, -10), 5.0)         # ...or jumps by a vector every other 5 s

Frames (AN4248): world = magnetic NED; Br = B (cos delta, 0, sin delta) with inclination delta
positive down; Bp = Rx(phi) Ry(theta) Rz(psi) Br (eqs. 1-3); the AN4248 gravity vector
Gp = Rx Ry Rz (0, 0, 1) g, (0, 0, +1) for a level board. Yaw is the magnetic heading;
true heading = magnetic + declination.

Iron (AN4246 eq. 5) acts in the SENSOR frame of each chip:
    reading = W * (M * Bp) + V  (+ magnets),
with M the chip's mounting, a signed permutation written as a 3-tuple: sensor axis i reads
sign(m[i]) * body axis |m[i]| (1 = x, 2 = y, 3 = z). (1, -2, -3) is a chip with x forward,
y left, z up (the right-handed chip axes of a breakout lying component side up).
"""
import math

_DEG = 0.017453292519943295  # pi / 180
IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


UT_PER_GAUSS = 100.0  # 1 G = 100 uT


def check_mount(mount):
    """Validate a signed permutation (see module docstring); returns it as a tuple."""
    m = tuple(int(a) for a in mount)
    if len(m) != 3 or sorted([abs(a) for a in m]) != [1, 2, 3]:
        raise ValueError("mounting must be a signed permutation of (1, 2, 3), got %r" % (mount,))
    return m


def mount_apply(mount, v):
    """Body-frame vector -> sensor-frame vector for mounting `mount`."""
    out = [0.0, 0.0, 0.0]
    for i in range(3):
        a = mount[i]
        out[i] = v[a - 1] if a > 0 else -v[-a - 1]
    return out


def mount_inverse(mount):
    """The mounting that maps sensor-frame vectors back to the body frame."""
    inv = [0, 0, 0]
    for i in range(3):
        a = mount[i]
        inv[abs(a) - 1] = (i + 1) if a > 0 else -(i + 1)
    return tuple(inv)


def mat_vec(m, v):
    return [m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]]


def mat_mul(a, b):
    return [[a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] for j in range(3)]
            for i in range(3)]


def rotation(yaw_deg, pitch_deg, roll_deg):
    """R = Rx(phi) Ry(theta) Rz(psi): world (NED) -> body, AN4248 eqs. 1-3."""
    cps, sps = math.cos(yaw_deg * _DEG), math.sin(yaw_deg * _DEG)
    cth, sth = math.cos(pitch_deg * _DEG), math.sin(pitch_deg * _DEG)
    cph, sph = math.cos(roll_deg * _DEG), math.sin(roll_deg * _DEG)
    rz = ((cps, sps, 0.0), (-sps, cps, 0.0), (0.0, 0.0, 1.0))
    ry = ((cth, 0.0, -sth), (0.0, 1.0, 0.0), (sth, 0.0, cth))
    rx = ((1.0, 0.0, 0.0), (0.0, cph, sph), (0.0, -sph, cph))
    return mat_mul(rx, mat_mul(ry, rz))


class Pulse:
    """A vector switched on over [start, end] with linear ramps of `ramp_s` at both ends, in a
    frame: what Magnet and Acceleration share."""

    FRAMES = ("sensor", "body", "world")

    def __init__(self, vec, start_s, end_s, ramp_s, frame):
        kind = type(self).__name__
        if frame not in self.FRAMES:
            raise ValueError("%s: frame must be one of %s, got %r"
                             % (kind, ", ".join(repr(f) for f in self.FRAMES), frame))
        self.vec = (float(vec[0]), float(vec[1]), float(vec[2]))
        self.start_us = int(math.floor(start_s * 1000000 + 0.5))
        self.end_us = int(math.floor(end_s * 1000000 + 0.5))
        self.ramp_us = int(math.floor(ramp_s * 1000000 + 0.5))
        if self.end_us < self.start_us:
            raise ValueError("%s: end_s before start_s" % kind)
        self.frame = frame

    def envelope(self, t_us):
        """0..1: how much of the magnet's field is present at t_us."""
        if t_us <= self.start_us or t_us >= self.end_us:
            return 0.0
        r = self.ramp_us
        if r <= 0:
            return 1.0
        a = (t_us - self.start_us) / r
        b = (self.end_us - t_us) / r
        e = a if a < b else b
        return 1.0 if e > 1.0 else e


class Magnet(Pulse):
    """Interference: an extra field `field_ut` (3-vector) switched on over [start, end] with
    linear ramps of `ramp_s` at both ends. `frame` is 'sensor' (added as the chip reads it,
    like a magnet carried with the board), 'body' (through the chip's mounting) or 'world'
    (fixed in NED, so it rotates with the board's orientation, like a magnet on the table)."""

    def __init__(self, field_ut, start_s, end_s, ramp_s=0.5, frame="sensor"):
        Pulse.__init__(self, field_ut, start_s, end_s, ramp_s, frame)
        self.field_ut = self.vec


class Acceleration(Pulse):
    """The board's own acceleration `accel_g` (g, a 3-vector) over [start, end] with linear
    ramps: 'world' (NED: a car braking while heading north is (-0.5, 0, 0)) or 'body'."""

    FRAMES = ("body", "world")

    def __init__(self, accel_g, start_s, end_s, ramp_s=0.2, frame="world"):
        Pulse.__init__(self, accel_g, start_s, end_s, ramp_s, frame)


class World:
    """Earth's field, gravity, the board's motion, hard/soft iron and magnets.

    `seed` is kept for world-level randomness a script wants (e.g. random_iron(world.seed));
    the chips' noise is seeded separately (make_board's seed)."""

    def __init__(self, field_ut=50.0, inclination_deg=60.0, declination_deg=0.0,
                 hard_iron_ut=(0, 0, 0), soft_iron=IDENTITY, motion=None, seed=1,
                 temperature_c=25.0):
        if motion is None:
            from host_sim.motion import still
            motion = still()
        self.field_ut = float(field_ut)
        self.inclination_deg = float(inclination_deg)
        self.declination_deg = float(declination_deg)
        self.motion = motion
        self.seed = seed
        self.temperature_c = float(temperature_c)
        self.magnets = []
        self.accelerations = []
        self.drift = None       # (rate uT/s, start us, end us or None): drift_iron()
        self.switch = None      # (delta uT, period us, start us, end us or None): switch_iron()
        self.set_iron(hard_iron_ut, soft_iron)
        self._rot_t = None
        self._rot = None

    def set_iron(self, hard_iron_ut=(0, 0, 0), soft_iron=IDENTITY):
        """V (uT, sensor frame) and the full 3x3 soft-iron matrix W (AN4246 eq. 5)."""
        if len(hard_iron_ut) != 3 or [len(r) for r in soft_iron] != [3, 3, 3]:
            raise ValueError("World: hard_iron_ut is a 3-vector and soft_iron a 3x3 matrix")
        self.hard_iron_ut = (float(hard_iron_ut[0]), float(hard_iron_ut[1]), float(hard_iron_ut[2]))
        self.soft_iron = tuple(tuple(float(x) for x in row) for row in soft_iron)

    def drift_iron(self, rate_ut_per_s, start_s=0.0, end_s=None):
        """The hard iron drifts (a warming board, a slowly magnetised part): V + rate x
        (t - start) in the sensor frame from start_s, held at its end value after end_s.
        None stops it."""
        if rate_ut_per_s is None:
            self.drift = None
            return
        self.drift = (tuple(float(x) for x in rate_ut_per_s), int(start_s * 1000000),
                      None if end_s is None else int(end_s * 1000000))

    def switch_iron(self, delta_ut, period_s, start_s=0.0, end_s=None):
        """Two hard-iron states (a relay, a motor, a magnetised part switched on and off):
        V + delta during the second half of every period from start_s until end_s, V
        otherwise. None stops it."""
        if delta_ut is None:
            self.switch = None
            return
        if period_s <= 0:
            raise ValueError("switch_iron: period_s must be > 0")
        self.switch = (tuple(float(x) for x in delta_ut), int(period_s * 1000000),
                       int(start_s * 1000000), None if end_s is None else int(end_s * 1000000))

    def hard_iron_at(self, t_us):
        """V at t_us (uT, sensor frame), drift and switching included."""
        v = self.hard_iron_ut
        d = self.drift
        if d is not None and t_us > d[1]:
            t = (t_us if d[2] is None or t_us < d[2] else d[2]) - d[1]
            v = (v[0] + d[0][0] * t / 1e6, v[1] + d[0][1] * t / 1e6, v[2] + d[0][2] * t / 1e6)
        sw = self.switch
        if sw is not None and t_us >= sw[2] and (sw[3] is None or t_us < sw[3]):
            if (t_us - sw[2]) % sw[1] >= sw[1] // 2:
                v = (v[0] + sw[0][0], v[1] + sw[0][1], v[2] + sw[0][2])
        return v

    def add_magnet(self, field_ut, start_s, end_s, ramp_s=0.5, frame="sensor"):
        m = Magnet(field_ut, start_s, end_s, ramp_s, frame)
        self.magnets.append(m)
        return m

    def add_acceleration(self, accel_g, start_s, end_s, ramp_s=0.2, frame="world"):
        """The board accelerates (braking, a bump): the accelerometer senses it on top of
        gravity (specific_force)."""
        a = Acceleration(accel_g, start_s, end_s, ramp_s, frame)
        self.accelerations.append(a)
        return a

    # --- geometry ---------------------------------------------------------------------
    def earth_field_ned(self):
        """Br in uT, magnetic NED (AN4248: B (cos delta, 0, sin delta))."""
        d = self.inclination_deg * _DEG
        return (self.field_ut * math.cos(d), 0.0, self.field_ut * math.sin(d))

    def orientation(self, t_us):
        """(yaw_deg, pitch_deg, roll_deg); yaw is the magnetic heading."""
        return self.motion.at(t_us)

    def rotation(self, t_us):
        """World (NED) -> body rotation at t_us (cached for the last time asked)."""
        if t_us != self._rot_t:
            yaw, pitch, roll = self.motion.at(t_us)
            self._rot = rotation(yaw, pitch, roll)
            self._rot_t = t_us
        return self._rot

    def angular_rate_body(self, t_us, half_us=500):
        """The board's rotation rate in its own frame, deg/s (p, q, r about body x, y, z,
        right-handed; a level board turning clockwise seen from above has r > 0): from the
        rotation matrices 2 x half_us apart, [w]x = -(dR/dt) R^T (R world -> body), so a
        heading that wraps through 360 deg is no jump."""
        a = rotation(*self.motion.at(t_us - half_us))
        b = rotation(*self.motion.at(t_us + half_us))
        r = rotation(*self.motion.at(t_us))
        dt = 2 * half_us / 1e6
        d = [[(b[i][j] - a[i][j]) / dt for j in range(3)] for i in range(3)]
        # W = -D R^T; w = (W32, W13, W21), averaged with the antisymmetric partner
        w = [[-sum(d[i][k] * r[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
        k = 180.0 / math.pi
        return [k * (w[2][1] - w[1][2]) / 2, k * (w[0][2] - w[2][0]) / 2,
                k * (w[1][0] - w[0][1]) / 2]

    def linear_accel_body(self, t_us):
        """The board's own acceleration in its frame, g (the sum of add_acceleration's)."""
        return self._pulses(self.accelerations, t_us, None)

    def _pulses(self, pulses, t_us, mount):
        # the sum of the pulses present at t_us: world-frame ones rotated into the body, then
        # (mount given) body-frame ones through the chip's mounting; sensor-frame ones as is
        out = [0.0, 0.0, 0.0]
        for p in pulses:
            e = p.envelope(t_us)
            if e == 0.0:
                continue
            v = p.vec
            if p.frame == "world":
                v = mat_vec(self.rotation(t_us), v)
            if mount is not None and p.frame != "sensor":
                v = mount_apply(mount, v)
            out[0] += e * v[0]
            out[1] += e * v[1]
            out[2] += e * v[2]
        return out

    def field_body(self, t_us):
        """Earth's field in the body frame, uT, no iron, no magnets (AN4248 Bp)."""
        return mat_vec(self.rotation(t_us), self.earth_field_ned())

    def gravity_body(self, t_us):
        """AN4248 Gp in g: (0, 0, +1) level. A physical accelerometer reads -Gp (specific force)."""
        r = self.rotation(t_us)
        return [r[0][2], r[1][2], r[2][2]]

    def magnetic_heading_deg(self, t_us):
        return self.motion.at(t_us)[0] % 360.0

    def true_heading_deg(self, t_us):
        """True heading = magnetic heading + declination (east positive), in [0, 360)."""
        return (self.motion.at(t_us)[0] + self.declination_deg) % 360.0

    # --- what a chip senses -----------------------------------------------------------
    def interference(self, t_us, mount):
        """Sum of the magnets' fields in the sensor frame of a chip mounted `mount`, uT."""
        return self._pulses(self.magnets, t_us, mount)

    def sensor_field(self, t_us, mount):
        """W * (M * Bp) + V + magnets, uT, in the sensor frame (AN4246 eq. 5)."""
        b = mat_vec(self.soft_iron, mount_apply(mount, self.field_body(t_us)))
        v = self.hard_iron_at(t_us)
        out = [b[0] + v[0], b[1] + v[1], b[2] + v[2]]
        if self.magnets:
            m = self.interference(t_us, mount)
            out[0] += m[0]
            out[1] += m[1]
            out[2] += m[2]
        return out

    def specific_force(self, t_us, mount):
        """What an accelerometer mounted `mount` senses, in g: M * (a - Gp), the board's own
        acceleration a (add_acceleration; none by default: slow hand motion) minus gravity
        (+1 g on an axis pointing up)."""
        g = self.gravity_body(t_us)
        if self.accelerations:
            a = self.linear_accel_body(t_us)
            return mount_apply(mount, [a[0] - g[0], a[1] - g[1], a[2] - g[2]])
        return mount_apply(mount, [-g[0], -g[1], -g[2]])


def sensor_counts(world, t_us, mount, counts_per_gauss, sigma_counts, g, bias_g=None):
    """The three float counts a magnetometer converts at t_us: the sensor-frame field (zero
    without a world) plus an optional bias field in gauss, times the sensitivity, plus
    Gaussian noise of sigma_counts from Prng g (None: noise-free). The chip models round,
    clip and flag these their own way."""
    f = (0.0, 0.0, 0.0) if world is None else world.sensor_field(t_us, mount)
    out = [0.0, 0.0, 0.0]
    for i in range(3):
        v = f[i] / UT_PER_GAUSS
        if bias_g is not None:
            v += bias_g[i]
        v *= counts_per_gauss
        if g is not None:
            v += g.gauss(sigma_counts)
        out[i] = v
    return out


def random_iron(seed, hard_max_ut=60.0, soft_dev=0.15):
    """A reproducible hard-iron vector and symmetric, well-conditioned soft-iron matrix:
    V uniform in [-hard_max_ut, hard_max_ut]^3, W = I + a symmetric perturbation with entries
    within +-soft_dev (diagonal) and +-soft_dev/2 (off-diagonal). Returns (V, W)."""
    from host_sim.prng import Prng
    g = Prng(seed, stream=0x1205)

    def u(a):
        return (2.0 * g.uniform() - 1.0) * a

    v = (u(hard_max_ut), u(hard_max_ut), u(hard_max_ut))
    d = (1.0 + u(soft_dev), 1.0 + u(soft_dev), 1.0 + u(soft_dev))
    xy, xz, yz = u(soft_dev / 2), u(soft_dev / 2), u(soft_dev / 2)
    w = ((d[0], xy, xz), (xy, d[1], yz), (xz, yz, d[2]))
    return v, w
