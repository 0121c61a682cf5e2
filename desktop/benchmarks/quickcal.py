"""Quick calibration (firmware/field/quickcal.py, CompassApp.quick_calibrate) in the simulator: the
heading error at other headings after a calibration from one pose (or two opposite poses) and
a known true heading, over many seeds (docs/quick_calibration.md).

Each seed: the board in Zurich (the field model's field there: dip 63.5 deg, 48 uT), random
hard iron up to 40 uT per axis, soft iron W = Q diag(1 + u) Q^T with |u_i| <= `dev` along random
axes ("soft iron dev": W's eigenvalues within 1 +- dev), sensor noise on; a quick calibration at
a random heading (and, for two poses, a second one 180 deg away); then the heading error at 12
other headings, each averaged over 8 samples.

The limit of one pose (tests/test_quickcal.py shows it on two simulated boards): two boards with
soft iron I + E and I - E (E symmetric with eigenvalues +-dev in the horizontal plane) and hard
irons that differ by 2 E B0 read the same at the calibration pose B0, so no method that sees
only that pose can tell them apart; at the opposite heading their readings differ by 4 dev H
across the field, so one of the two is wrong by at least 2 dev radians (3.4 deg at dev 3 %).

python -m desktop.benchmarks.quickcal [--smoke]   (one JSON line; host only: floats)
"""
import math
import random
import sys

from host_sim import motion
from host_sim.boards import make_board
from desktop.benchmarks import common
from host_sim.world import World

ZURICH = (473977000, 85000000)      # dip 63.5 deg, |B| 48 uT, declination 3.6 deg E
SAO_PAULO = (-235505000, -466333000)  # dip -38 deg, |B| 23 uT (South Atlantic Anomaly)
SYDNEY = (-338688000, 1512093000)   # dip -64 deg, declination 12.9 deg E
YEAR_E3 = 2026500
# host_sim.boards mounts every chip x forward, y left, z up (boards/breakouts.py: gy271, gy87)
MAG_AXES = "x,-y,-z"
ACCEL_AXES = "-x,y,z"
SETUPS = (("QMC5883L + MPU6050, level", "qmc5883l", True, 0.0),
          ("QMC5883L + MPU6050, tilt +-20 deg", "qmc5883l", True, 20.0),
          ("QMC5883L alone, level", "qmc5883l", False, 0.0),
          ("GY-87 (HMC5883L + MPU6050), tilt +-20 deg", "gy87", None, 20.0))
DEVS = (0.0, 0.015, 0.02, 0.03)
GOAL_DEG = 2.0


def soft_iron(rng, dev):
    """W = Q diag(1 + u_i) Q^T with |u_i| <= dev and Q a random rotation."""
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
    from firmware.field.location import Location
    loc = Location(place[0], place[1], year_e3)
    kw = {} if soft is None else {"soft_iron": soft}
    return World(field_ut=loc.field_nt / 1000 * scale, inclination_deg=loc.inclination_cdeg / 100,
                 declination_deg=loc.declination_cdeg / 100, hard_iron_ut=hard_iron_ut, **kw)


def board(world, chip="qmc5883l", accel=True, seed=1):
    return make_board(chip, world=world, seed=seed, accel=accel)


def app_on(b, accel=True, **kw):
    """A CompassApp on simulated board b (no store unless given; accel=False: none)."""
    from firmware.app import CompassApp
    if accel is False:
        kw["accel"] = False
    kw.setdefault("declination_cdeg", 0)
    return CompassApp(b.bus, mag_axes=MAG_AXES, accel_axes=ACCEL_AXES, delay_us=b.sleep_us,
                      ticks_us=b.clock.ticks_us, **kw)


def hold(b, yaw, pitch=0.0, roll=0.0):
    b.world.motion = motion.still(yaw, pitch, roll)


def settle(app, b, seconds=0.1):
    end = b.clock.now_us + int(seconds * 1000000)
    while b.clock.now_us < end:
        app.step()


def true_heading_cdeg(b):
    return int(round(b.world.true_heading_deg(b.clock.now_us) * 100)) % 36000


def error_cdeg(app, b):
    """The app's heading minus the world's true heading, centidegrees in -18000..17999."""
    true_cdeg = int(b.world.true_heading_deg(b.clock.now_us) * 100 + 0.5)
    h = app.heading_kang * 36000 // 65536
    return (h - true_cdeg + 18000) % 36000 - 18000


def mean_error_deg(app, b, n=8):
    """The app's heading minus the truth, degrees, averaged over n steps."""
    e = 0
    for _ in range(n):
        app.step()
        e += error_cdeg(app, b)
    return e / n / 100


def quick_cal_errors(seed, dev, chip="qmc5883l", accel=True, tilt=0.0, poses=1,
                     place=ZURICH, headings=12):
    """One seed of the measurement (module docstring). Returns the errors in degrees."""
    rng = random.Random(seed)
    hi = tuple(rng.uniform(-40, 40) for _ in range(3))
    b = board(world_at(place, hi, soft_iron(rng, dev)), chip, accel, seed)
    app = app_on(b, accel, learn=False)
    app.set_location(place[0], place[1], YEAR_E3)
    yaw0 = rng.uniform(0, 360)
    for p in range(poses):
        hold(b, yaw0 + 180.0 * p, rng.uniform(-tilt, tilt), rng.uniform(-tilt, tilt))
        settle(app, b)
        app.quick_calibrate(true_heading_cdeg(b), refine=p > 0)
    out = []
    for k in range(headings):
        hold(b, yaw0 + 360.0 * k / headings + rng.uniform(-10, 10), rng.uniform(-tilt, tilt),
             rng.uniform(-tilt, tilt))
        out.append(mean_error_deg(app, b))
    return out


def row(chip, accel, tilt, poses, dev, seeds):
    """RMS over every heading, the per-seed worst that 95 % of seeds stay within, and the max."""
    worst = []
    every = []
    for s in range(seeds):
        e = quick_cal_errors(s, dev, chip, accel, tilt, poses)
        worst.append(max(abs(x) for x in e))
        every += e
    worst.sort()
    return {"rms_deg": math.sqrt(sum(x * x for x in every) / len(every)),
            "p95_deg": worst[max(0, int(0.95 * seeds) - 1)], "max_deg": worst[-1],
            "seeds": seeds}


def measure(seeds, setups=SETUPS, devs=DEVS):
    out = []
    for name, chip, accel, tilt in setups:
        for poses in (1, 2):
            for dev in devs:
                r = row(chip, accel, tilt, poses, dev, seeds)
                r.update(setup=name, poses=poses, soft_iron_pct=dev * 100)
                out.append(r)
    return out


def markdown(rows):
    """The table of docs/quick_calibration.md."""
    lines = ["| setup | poses | soft iron | RMS deg | 95 % of seeds within deg | max deg |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %d | +-%.1f %% | %.2f | %.2f | %.2f |" % (
            r["setup"], r["poses"], r["soft_iron_pct"], r["rms_deg"], r["p95_deg"],
            r["max_deg"]))
    return "\n".join(lines)


def main():
    smoke = common.smoke()
    if smoke:
        rows = measure(4, SETUPS[:1], (0.015, 0.03))
    else:
        rows = measure(50)
    if "--markdown" in sys.argv:
        print(markdown(rows))
    common.emit({"interpreter": common.interpreter(), "rows": rows})


if __name__ == "__main__":
    sys.exit(main())
