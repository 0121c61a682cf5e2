"""Simulated boards whose world is the field model's at a place: the world's field, dip and
declination are the table's, so the heading the app reports can be compared with the truth.
Shared by tests/test_location.py and tests/test_quickcal.py (host only: floats)."""
import math
import random
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from host_sim import motion  # noqa: E402
from host_sim.boards import make_board  # noqa: E402
from host_sim.world import World  # noqa: E402

from firmware.location import Location  # noqa: E402

ZURICH = (473977000, 85000000)      # dip 63.5 deg, |B| 48 uT, declination 3.6 deg E
SAO_PAULO = (-235505000, -466333000)  # dip -38 deg, |B| 23 uT (South Atlantic Anomaly)
SYDNEY = (-338688000, 1512093000)   # dip -64 deg, declination 12.9 deg E
YEAR_E3 = 2026500


def soft_iron(rng, dev):
    """W = Q diag(1 + u_i) Q^T with |u_i| <= dev and Q a random rotation: eigenvalues within
    1 +- dev ("soft iron dev"), axes in a random direction."""
    a = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(x * x for x in a))
    w, x, y, z = [v / n for v in a]
    q = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    d = [1 + rng.uniform(-dev, dev) for _ in range(3)]
    return tuple(tuple(sum(q[i][k] * d[k] * q[j][k] for k in range(3)) for j in range(3))
                 for i in range(3))


def world_at(place, hard_iron_ut=(0.0, 0.0, 0.0), soft=None, year_e3=YEAR_E3, scale=1.0):
    """A still World with the field model's field at `place` (times `scale`: a sensor whose
    gain is off by that factor senses the same)."""
    loc = Location(place[0], place[1], year_e3)
    kw = {} if soft is None else {"soft_iron": soft}
    return World(field_ut=loc.field_nt / 1000 * scale, inclination_deg=loc.inclination_cdeg / 100,
                 declination_deg=loc.declination_cdeg / 100, hard_iron_ut=hard_iron_ut, **kw)


def board(world, chip="qmc5883l", accel=True, seed=1):
    return make_board(chip, world=world, seed=seed, accel=accel)


def app_on(b, accel=True, **kw):
    if accel is False:
        kw["accel"] = False
    return W.make_app(b, **kw)


def hold(b, yaw, pitch=0.0, roll=0.0):
    b.world.motion = motion.still(yaw, pitch, roll)


def true_heading_cdeg(b):
    return int(round(b.world.true_heading_deg(b.clock.now_us) * 100)) % 36000


def mean_error_deg(app, b, n=8):
    """The app's heading minus the truth, degrees, averaged over n steps."""
    e = 0
    for _ in range(n):
        app.step()
        e += W.heading_error_cdeg(app, b)
    return e / n / 100


def quick_cal_errors(seed, dev, chip="qmc5883l", accel=True, tilt=0.0, poses=1,
                     place=ZURICH, headings=12):
    """One seed of the quick-calibration measurement: random hard iron (+-40 uT per axis) and
    soft iron (eigenvalues within 1 +- dev), a quick calibration at `poses` poses (a random
    heading, then 180 deg from it), then the heading error at `headings` other headings,
    each with a random tilt within +-tilt deg. Returns the errors in degrees."""
    rng = random.Random(seed)
    hi = tuple(rng.uniform(-40, 40) for _ in range(3))
    b = board(world_at(place, hi, soft_iron(rng, dev)), chip, accel, seed)
    app = app_on(b, accel, learn=False)
    app.set_location(place[0], place[1], YEAR_E3)
    yaw0 = rng.uniform(0, 360)
    for p in range(poses):
        hold(b, yaw0 + 180.0 * p, rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt))
        W.run_until(app, b, b.clock.now_us / 1e6 + 0.1)
        app.quick_calibrate(true_heading_cdeg(b), refine=p > 0)
    out = []
    for k in range(headings):
        hold(b, yaw0 + 360.0 * k / headings + rng.uniform(-10, 10), rng.uniform(-tilt, tilt),
             rng.uniform(-tilt, tilt))
        out.append(mean_error_deg(app, b))
    return out
