"""`python -m host_sim demo --chip CHIP --seed N [--json]`: the whole story (CHIP: one of
host_sim/chips.py DEMOS, e.g. qmc5883l, hmc5883l, gy87).

A simulated board with strong hard and soft iron, a user doing a figure-8 while the firmware's
CompassApp calibrates, the calibration it accepts (against the world's true iron), and the
heading accuracy at tilted orientations with three calibrations applied to the same raw
readings: none, min/max (the hobbyist one) and the accepted one. Also runs under
`micropython -m host_sim demo ...` (no plot) and prints the same calibration.

The world (seeded by --seed, so each seed is a different, reproducible world):
  Earth's field 50 uT, inclination 60 deg, declination +4.00 deg (east).
  Hard iron V: a random direction, |V| uniform in 1..3 x the Earth field.
  Soft iron W = R diag(e) R^T: eigenvalues e in 0.75..0.90, 0.90..1.10, 1.10..1.30 and a
  random rotation R, so W has large off-diagonal terms (symmetric, as AN4246 assumes:
  a rotation part of W would be indistinguishable from the chip's mounting).
The sensor range is the one an installer would pick: the most sensitive range whose datasheet
full scale holds max_i (|V_i| + B |row_i(W)|), the largest reading on any axis, with 10 %
margin (host_sim/chips.py ranges: QMC5883L +-2 or +-8 G; HMC5883L gain code 0..7; ...).

Heading accuracy is measured on a grid of still orientations (GRID_*), AVERAGE_N readings
each, the true heading from the world (magnetic yaw + declination). What limits it: on the
QMC5883L (12000 counts/G) the fit's own error, on the HMC5883L the integer-count offset V
(half a count at 820 counts/G is 0.06 uT, up to 0.2 deg of a 25 uT horizontal field), then
the accelerometer's tilt noise.
"""
import json
import math
import sys
from array import array

from host_sim import chips
from desktop.args import STATUS_REFUSED, Parser

# --chip: host_sim/chips.py DEMOS (make_board chip, accel argument, breakout for the
# magnetometer's axes, label)
CHIP_CHOICES = chips.DEMO_CHIPS
# GY-521 lies like the magnetometer breakouts (x forward, y left, z up): AN4248 gravity sign
# of a specific-force reading is (-x, y, z) (boards/breakouts.py derives the same for GY-87).
_GY521_ACCEL_AXES = "-x,y,z"

FIELD_UT = 50.0              # mid-latitude Earth field
INCLINATION_DEG = 60.0       # dip; heading noise grows as 1/cos(dip)
DECLINATION_CDEG = 400       # +4.00 deg east, applied by the app's Compass
HARD_IRON_MIN = 1.0          # |V| in Earth fields: "strong" iron
HARD_IRON_MAX = 3.0
SOFT_IRON_EIGS = ((0.75, 0.90), (0.90, 1.10), (1.10, 1.30))  # W eigenvalue ranges
RANGE_MARGIN = 1.10          # installer's margin over the largest expected reading
# (the HMC5883L runs at its fastest rate, 75 Hz, not its default 15 Hz: more samples per
# gesture and a 128-reading average in 1.7 s, not 8.5 s: chips.py demo_options)

MODEL = 10                   # the app's calibration model: AN4246's full 10 elements
SESSION_S = 30               # one figure8() period: waves through every field direction
TIME_LIMIT_FACTOR = 3        # keep going while nothing is accepted, up to 3 x the session
TICK_S = 2                   # progress line period when stdout is not a terminal
TTY_TICK_MS = 100            # on a terminal the line is rewritten in place this often
# Heading grid: every 30 deg of yaw, level and tilted 25 deg in pitch and roll at once.
GRID_YAWS = tuple(range(0, 360, 30))
GRID_TILTS = ((0, 0), (25, 25), (25, -25), (-25, 25), (-25, -25))  # (pitch, roll) deg
# Readings averaged per orientation (2.6 s at the QMC5883L's 50 Hz, 1.7 s at 75 Hz): the
# grid measures the calibration, so its own noise must stay well below 0.5 deg. One MPU6050
# reading has 6.4 mg of noise at its power-on filter setting, a 0.37 deg tilt error, worth up
# to tan(60 deg) x 0.37 = 0.64 deg of heading at 60 deg dip, and one magnetometer reading
# 2 mG / 25 uT horizontal = 0.46 deg; over 60 orientations the largest error is ~2.5 sigma.
# Measured with the world's exact iron (tests/test_demo.py's perfect_calibration), seeds
# 1-12, worst max error: QMC5883L 0.46 / 0.33 / 0.27 deg with 32 / 64 / 128 readings;
# HMC5883L 0.44 / 0.49 / 0.47 (a floor of 12-bit counts and integer offsets, not noise).
AVERAGE_N = 128
SETTLE_N = 2                 # readings dropped after each move (the chip's latched old set)
DEFAULT_PLOT = "build/calibration.png"

def parser(command="demo", description=None):
    """The demo's options (run.py shows the same ones under its own name)."""
    p = Parser(command, "[--chip CHIP] [--seed N] [options]", description or
               "The simulated board calibrates during a figure-8 and reports its heading "
               "accuracy.")
    p.option("--chip", "choice", default="qmc5883l", choices=CHIP_CHOICES, metavar="CHIP",
             help="%s;\ndefault qmc5883l" % ",\n".join(
                 "%s (%s)" % (c, chips.demo(c)[3]) for c in CHIP_CHOICES))
    p.option("--seed", "int", default=1, metavar="N",
             help="the world (iron) and the sensors' noise; default 1")
    p.option("--seconds", "int", default=SESSION_S, lo=1, hi=100000, metavar="S",
             help="the figure-8 session, simulated seconds (default %d); it\n"
                  "goes on, up to %d x S, until a 10-element calibration is in\n"
                  "force" % (SESSION_S, TIME_LIMIT_FACTOR))
    p.option("--samples", "int", default=AVERAGE_N, lo=1, hi=100000, metavar="N",
             help="readings averaged per orientation of the heading grid\n"
                  "(default %d)" % AVERAGE_N)
    p.option("--json", "flag",
             help="print one JSON object (heading_error_deg, calibration, ...)\n"
                  "and nothing else")
    p.option("--plot", "path", metavar="PATH",
             help="write the PNG there (default %s; CPython with\n"
                  "matplotlib only)" % DEFAULT_PLOT)
    p.option("--no-plot", "flag", help="no PNG")
    p.epilog = ("exit status: 0 a 10-element calibration was accepted; 1 none was (the last "
                "refusal is\nprinted); 2 bad usage.")
    return p


# --- small float linear algebra (host side) ---------------------------------------------
def _mat_t(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def _det(a):
    return (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))


def _inv(a):
    d = _det(a)
    c = [[a[(j + 1) % 3][(i + 1) % 3] * a[(j + 2) % 3][(i + 2) % 3]
          - a[(j + 1) % 3][(i + 2) % 3] * a[(j + 2) % 3][(i + 1) % 3] for j in range(3)]
         for i in range(3)]
    return [[c[i][j] / d for j in range(3)] for i in range(3)]


def _norm(v):
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _rotation_from_quaternion(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def _fmt(x, nd=2):
    """%.Nf that prints -0.00 as 0.00 (MicroPython and CPython alike)."""
    s = "%.*f" % (nd, x)
    if s.startswith("-") and float(s) == 0:
        s = s[1:]
    return s


def _round(x, nd):
    k = 10 ** nd
    return math.floor(x * k + 0.5) / k


# --- the world ----------------------------------------------------------------------------
def demo_iron(seed):
    """(V in uT, W) for a seed: see the module docstring."""
    from host_sim.prng import Prng
    from host_sim.world import mat_mul
    g = Prng(seed, stream=0xDE30)
    d = [g.gauss(), g.gauss(), g.gauss()]
    n = _norm(d)
    mag = FIELD_UT * (HARD_IRON_MIN + (HARD_IRON_MAX - HARD_IRON_MIN) * g.uniform())
    v = [mag * d[i] / n for i in range(3)]
    q = [g.gauss(), g.gauss(), g.gauss(), g.gauss()]  # uniform random rotation
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    r = _rotation_from_quaternion([c / n for c in q])
    e = [lo + (hi - lo) * g.uniform() for lo, hi in SOFT_IRON_EIGS]
    w = mat_mul(mat_mul(r, [[e[0], 0, 0], [0, e[1], 0], [0, 0, e[2]]]), _mat_t(r))
    for i in range(3):  # exactly symmetric
        for j in range(i):
            w[i][j] = w[j][i]
    return v, w, e


def largest_reading_ut(v, w, field_ut=FIELD_UT):
    """max over axes and field directions of |(W b + V)_i| for |b| = field_ut."""
    return max(abs(v[i]) + field_ut * _norm(w[i]) for i in range(3))


def full_scales(kind):
    """(full scale in G, the driver's range option value) of each range of `kind`, most
    sensitive first (host_sim/chips.py ranges: "2" -> 2, "1.3" -> 1.3)."""
    out = [(float(r[0]) if "." in r[0] else int(r[0]), r[3]) for r in chips.mag(kind)["ranges"]]
    return sorted(out, key=lambda t: t[0])


def pick_range(kind, need_ut):
    """The most sensitive range holding need_ut x RANGE_MARGIN: (the driver's range option,
    e.g. 'range' for the QMC5883L, 'gain' for the HMC5883L, None for a chip with one range;
    its value; the full scale in G)."""
    need_g = need_ut * RANGE_MARGIN / 100
    opt = chips.mag(kind)["range_option"]
    table = full_scales(kind)
    for fs, value in table:
        if need_g <= fs:
            return opt, value, fs
    return opt, table[-1][1], table[-1][0]


class Stage:
    """A motion script whose part can be replaced from a given time on: the figure-8 first,
    then each pose of the grid held from the moment the board is put there."""

    def __init__(self, script):
        self.parts = [(0, script)]
        self.duration_us = None

    def switch(self, t_us, script):
        # the chips compute samples lazily, so times before t_us may still be asked for
        self.parts = [(0, script)] if t_us <= 0 else [self.parts[-1], (t_us, script)]

    def at(self, t_us):
        start, script = self.parts[0]
        for s, m in self.parts:
            if s <= t_us:
                start, script = s, m
        return script.at(t_us - start)


class Setup:
    """The simulated board, its world and the firmware drivers on it."""

    def __init__(self, chip, seed, seconds, noise=True):
        from firmware import detect
        from host_sim import motion
        from host_sim.boards import make_board
        from host_sim.world import World
        from boards.breakouts import breakout

        board_chip, accel, axes_name, label = chips.demo(chip)
        self.chip = chip
        self.seed = seed
        self.label = label
        self.kind = chips.board(board_chip)[0]  # the magnetometer's KIND
        self.hard_iron_ut, self.soft_iron, self.soft_eigs = demo_iron(seed)
        self.stage = Stage(motion.figure8(period_s=seconds))
        self.world = World(field_ut=FIELD_UT, inclination_deg=INCLINATION_DEG,
                           declination_deg=DECLINATION_CDEG / 100, hard_iron_ut=self.hard_iron_ut,
                           soft_iron=self.soft_iron, motion=self.stage, seed=seed)
        self.board = make_board(board_chip, world=self.world, seed=seed, accel=accel,
                                noise=noise)
        self.need_ut = largest_reading_ut(self.hard_iron_ut, self.soft_iron)
        opt, val, self.full_scale_g = pick_range(self.kind, self.need_ut)
        b = self.board
        opts = dict(chips.mag(self.kind)["demo_options"])
        if opt is not None:
            opts[opt] = val
        self.mag = detect.detect(b.bus, delay_us=b.sleep_us, **opts)
        self.accel = detect.detect_accel(b.bus)
        if self.accel is None:
            raise RuntimeError("demo: no MPU6050 on the simulated %s board" % chip)
        self.mag_axes = breakout(axes_name)["mag"]
        self.accel_axes = breakout(axes_name).get("accel", _GY521_ACCEL_AXES)
        self.cpg = self.mag.counts_per_gauss

    def ut(self, counts):
        """Counts -> uT (1 G = 100 uT)."""
        return counts * 100.0 / self.cpg

    def true_effective(self):
        """What a perfect fit finds (AN4246: B and W share a scale factor, fixed by
        det(W^-1) = 1): V in counts, B_eff = B det(W)^1/3 in uT, W^-1 normalised to det 1."""
        w = self.soft_iron
        s = _det(w) ** (1.0 / 3)
        wi = _inv(w)
        return ([v * self.cpg / 100 for v in self.hard_iron_ut], FIELD_UT * s,
                [[wi[i][j] * s for j in range(3)] for i in range(3)])


# --- calibration figures ---------------------------------------------------------------
def invw_float(c):
    """W^-1 of a Calibration as floats, scaled so that it maps raw - V onto a sphere of
    radius B (c.field): InvW / 32768 x field / field_out (det 1 for a fitted one)."""
    k = c.field / c.field_out if c.field_out else 1.0
    return [[c.invw[3 * i + j] / 32768 * k for j in range(3)] for i in range(3)]


def calibration_json(c, cpg):
    """The accepted calibration's integers (identical on both interpreters)."""
    return {"model": c.model, "offset": list(c.offset), "invw_q15": list(c.invw),
            "field": c.field, "field_out": c.field_out, "fit_error": c.fit_error,
            "samples": c.samples, "coverage": c.coverage, "counts_per_gauss": cpg}


def calibration_errors(setup, c):
    """The accepted calibration against the world's truth: |V error| uT, B error uT,
    largest |W^-1 element error| (det-1 normalisation)."""
    v_true, b_true, wi_true = setup.true_effective()
    dv = [setup.ut(c.offset[i] - v_true[i]) for i in range(3)]
    wi = invw_float(c)
    dw = max(abs(wi[i][j] - wi_true[i][j]) for i in range(3) for j in range(3))
    return {"offset_ut": _norm(dv), "field_ut": setup.ut(c.field) - b_true, "invw_max": dw}


# --- the session ----------------------------------------------------------------------
def _isatty():
    try:
        return sys.stdout.isatty()
    except AttributeError:  # MicroPython's stdout has no isatty
        return False


def _columns():
    try:
        import shutil
        return shutil.get_terminal_size().columns
    except (ImportError, AttributeError):  # MicroPython
        return 80


def _show(line, tty):
    line = "  " + line
    if tty:  # rewrite the same line; a wrapped line could not be rewritten
        w = _columns() - 1
        print(line[:w] + " " * (w - len(line)), end="\r")
    else:
        print(line)


def progress_line(app, t_s):
    """coverage, samples held, model in force, its fit error, the last refusal, accepted."""
    p = app.progress()
    fe = p["fit_error"]
    parts = ["t %4.1f s" % t_s, "coverage %2d %%" % p["coverage"], "samples %3d" % p["samples"],
             "model %s" % ("-" if p["model"] is None else p["model"]),
             "fit error %s" % ("-" if fe is None else "%d.%02d %%" % (fe // 100, fe % 100))]
    if p["last_reason"]:
        parts.append("last refusal: %s" % p["last_reason"])
    parts.append("accepted %d" % p["accepted"])
    return "  ".join(parts)


def run_session(setup, seconds, quiet=False):
    """The figure-8 while CompassApp runs. Returns (app, minmax Calibrator, raw samples
    as a flat array('h') x0 y0 z0 x1 ..., info). Feeds every raw sample the app read to a
    min/max Calibrator too."""
    from firmware.app import CompassApp
    from firmware.calibration import MINMAX
    from firmware.calibrate.calibrator import Calibrator

    b = setup.board
    app = CompassApp(b.bus, mag=setup.mag, accel=setup.accel, mag_axes=setup.mag_axes,
                     accel_axes=setup.accel_axes, model=MODEL, declination_cdeg=DECLINATION_CDEG,
                     store=None, delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)
    minmax = Calibrator(model=MINMAX, counts_per_gauss=setup.cpg)
    raws = array("h")  # every raw sample, x y z flat: 6 bytes each (MicroPython's heap)
    end_us = seconds * 1000000
    limit_us = TIME_LIMIT_FACTOR * end_us
    tty = _isatty() and not quiet
    tick_us = (TTY_TICK_MS * 1000) if tty else (TICK_S * 1000000)
    next_tick = 0
    shown = None  # the simulated time of the last progress line
    steps = 0
    while True:
        got = app.step()  # True: a sample was read and made a heading
        steps += 1
        now = b.clock.now_us
        if got:
            r = app.raw
            raws.append(r[0])
            raws.append(r[1])
            raws.append(r[2])
            minmax.add(r[0], r[1], r[2])
        if not quiet and now >= next_tick:
            _show(progress_line(app, now / 1000000), tty)
            shown = now
            next_tick += tick_us
        # done when the gesture is over and the configured model is in force (the app
        # may first accept a quick 4-element fit: a user watching the line keeps going)
        if now >= end_us and app.calibration.model == MODEL and not app.progress()["solving"]:
            break
        if now >= limit_us:
            break
    if not quiet:
        if shown != b.clock.now_us:
            _show(progress_line(app, b.clock.now_us / 1000000), tty)
        if tty:
            print("")
    info = {"seconds": _round(b.clock.now_us / 1000000, 3), "steps": steps,
            "samples_read": len(raws) // 3, "accepted": app.accepted,
            "last_reason": app.last_reason, "errors": dict(app.errors)}
    return app, minmax, raws, info


# --- heading accuracy -----------------------------------------------------------------
def wrap180(d):
    d = math.fmod(d, 360.0)
    if d >= 180.0:
        d -= 360.0
    elif d < -180.0:
        d += 360.0
    return d


def _mean(s, n):
    """The mean of n vectors from their sum, with as many fractional bits as keep every
    component within 14 bits (heading.Compass takes any scale). Rounding the mean to whole
    counts would throw away what averaging gained: an HMC5883L's corrected field is only
    ~300 counts, so half a count is 0.1-0.2 deg of heading."""
    from firmware.fixedpoint import bit_length, rdiv
    m = max(abs(s[0]), abs(s[1]), abs(s[2])) // n
    k = 14 - bit_length(m)
    if k < 0:
        k = 0
    return [rdiv(s[i] << k, n) for i in range(3)]


def measure_grid(setup, cals, declination_kang, n=AVERAGE_N):
    """Hold the board still at every grid orientation, read n samples through the drivers
    and compute the heading with each Calibration in `cals` from the same readings:
    mean of the corrected body-frame fields and of the accelerometer, then heading.Compass.
    A None calibration is skipped (its headings are None).
    Returns rows (yaw, pitch, roll, true_deg, [heading_deg per calibration])."""
    from firmware.axes import AxisMap
    from firmware.compass import Compass
    from host_sim import motion

    b = setup.board
    mmap = AxisMap(setup.mag_axes)
    amap = AxisMap(setup.accel_axes)
    # no reference field: the scaled means would only raise the interference flag
    compasses = [None if c is None else Compass(declination_kang=declination_kang)
                 for c in cals]
    raw = [0, 0, 0]
    acc = [0, 0, 0]
    out = [0, 0, 0]
    body = [0, 0, 0]
    rows = []
    for pitch, roll in GRID_TILTS:
        for yaw in GRID_YAWS:
            setup.stage.switch(b.clock.now_us, motion.still(yaw, pitch, roll))
            for _ in range(SETTLE_N):
                setup.mag.read_into(raw)
            sb = [[0, 0, 0] for _ in cals]
            sg = [0, 0, 0]
            for _ in range(n):
                setup.mag.read_into(raw)
                setup.accel.read_accel_into(acc)
                amap.apply(acc, body)
                for i in range(3):
                    sg[i] += body[i]
                for k in range(len(cals)):
                    if cals[k] is None:
                        continue
                    cals[k].correct(raw, out)
                    mmap.apply(out, body)
                    s = sb[k]
                    for i in range(3):
                        s[i] += body[i]
            g = _mean(sg, n)
            heads = []
            for k in range(len(cals)):
                if cals[k] is None:
                    heads.append(None)
                    continue
                bm = _mean(sb[k], n)
                h = compasses[k].update(bm, g)
                heads.append(None if h < 0 else h * 360.0 / 65536)
            rows.append((yaw, pitch, roll, setup.world.true_heading_deg(b.clock.now_us), heads))
    return rows


def error_stats(rows, k):
    """max |error| and rms error (degrees) of calibration k over the grid; a missing
    heading counts as 180 deg. None when calibration k was skipped altogether."""
    if all(row[4][k] is None for row in rows):
        return None
    worst = 0.0
    ss = 0.0
    for row in rows:
        h = row[4][k]
        e = 180.0 if h is None else abs(wrap180(h - row[3]))
        worst = e if e > worst else worst
        ss += e * e
    return {"max": _round(worst, 4), "rms": _round(math.sqrt(ss / len(rows)), 4)}


# --- output ---------------------------------------------------------------------------
METHODS = ("uncalibrated", "minmax", "calibrated")


def print_world(setup, seconds):
    w = setup.soft_iron
    v = setup.hard_iron_ut
    print("eCompass demo: simulated %s, seed %d" % (setup.label, setup.seed))
    print("World: B %s uT, inclination %s deg, declination %+.2f deg"
          % (_fmt(FIELD_UT, 1), _fmt(INCLINATION_DEG, 1), DECLINATION_CDEG / 100))
    print("  hard iron V  (%s, %s, %s) uT   |V| = %s uT = %s x B"
          % (_fmt(v[0], 1), _fmt(v[1], 1), _fmt(v[2], 1), _fmt(_norm(v), 1),
             _fmt(_norm(v) / FIELD_UT, 2)))
    print("  soft iron W  [%s]"
          % "; ".join(" ".join("%6.3f" % w[i][j] for j in range(3)) for i in range(3)))
    print("               eigenvalues %s, principal axes rotated"
          % " ".join("%.3f" % e for e in setup.soft_eigs))
    if chips.mag(setup.kind)["range_option"] == "gain":
        rng = "+-%s G (gain code %d)" % (setup.full_scale_g, setup.mag.range_code)
    else:
        rng = "+-%s G" % setup.full_scale_g
    print("  range %s, %d counts/G: readings reach %s uT on one axis"
          % (rng, setup.cpg, _fmt(setup.need_ut, 0)))
    print("User: figure-8 for %d s (host_sim.motion.figure8) while CompassApp calibrates" % seconds)


def print_calibration(setup, c, info):
    v_true, b_true, wi_true = setup.true_effective()
    wi = invw_float(c)
    err = calibration_errors(setup, c)
    print("")
    print("Accepted calibration: model %s, fit error %d.%02d %%, %d samples, coverage %d %% "
          "(%d accepted in %s s)" % (c.model, c.fit_error // 100, c.fit_error % 100, c.samples,
                                     c.coverage, info["accepted"], _fmt(info["seconds"], 1)))
    print("                fitted                          true")
    print("  V (uT)        %-31s %s   |error| %s uT" % (
        " ".join("%8s" % _fmt(setup.ut(x)) for x in c.offset),
        " ".join("%8s" % _fmt(setup.ut(x)) for x in v_true), _fmt(err["offset_ut"], 3)))
    print("  B (uT)        %-31s %8s   error %s uT   (B det(W)^1/3)" % (
        "%8s" % _fmt(setup.ut(c.field)), _fmt(b_true), _fmt(err["field_ut"], 3)))
    for i in range(3):
        print("  %-13s %-31s %s%s" % (
            "InvW" if i == 0 else "", " ".join("%8.5f" % wi[i][j] for j in range(3)),
            " ".join("%8.5f" % wi_true[i][j] for j in range(3)),
            "   max error %.5f" % err["invw_max"] if i == 0 else ""))
    print("  InvW (Q15)    %s   x B/B_out = %d/%d counts"
          % (" ".join("%d" % q for q in c.invw), c.field, c.field_out))


def print_grid(rows, stats, n, refused=None):
    print("")
    print("Heading accuracy: the board held still at %d orientations, yaw every 30 deg x"
          % len(rows))
    print("(pitch, roll) in %s deg," % ", ".join("(%d, %d)" % t for t in GRID_TILTS))
    print("%d readings averaged at each, the same readings through three calibrations."
          % n)
    print("Heading (error) in deg:")
    print("  pitch  roll   true | %-16s | %-16s | %s" % ("uncalibrated", "min/max", "calibrated"))
    for yaw, pitch, roll, true, heads in rows:
        cells = []
        for h in heads:
            if h is None:
                cells.append("%-16s" % "  -")
            else:
                cells.append("%6s (%7s)" % (_fmt(h, 1), _fmt(wrap180(h - true), 2)))
        print("  %5d %5d  %5s | %s" % (pitch, roll, _fmt(true, 1), " | ".join(cells)))
    cells = []
    for m in METHODS:
        st = stats[m]
        cells.append("%-16s" % ("refused" if st is None else "%s / %s" % (_fmt(st["max"], 2),
                                                                           _fmt(st["rms"], 2))))
    print("  error max / rms    | %s" % " | ".join(cells))
    if refused:
        print("  (min/max calibration refused: %s)" % refused)


def main(argv):
    return parser().main(argv, body)


def body(opts):
    """The demo for parsed options; the exit status."""
    from firmware.trig import cdeg_to_kang
    from firmware.calibration import UNCALIBRATED
    from firmware.errors import CalibrationRejected

    quiet = opts["json"]
    setup = Setup(opts["chip"], opts["seed"], opts["seconds"])
    if not quiet:
        print_world(setup, opts["seconds"])
    app, minmax, raws, info = run_session(setup, opts["seconds"], quiet)
    result = {"chip": setup.chip, "seed": setup.seed, "session": info,
              "world": {"field_ut": FIELD_UT, "inclination_deg": INCLINATION_DEG,
                        "declination_deg": DECLINATION_CDEG / 100,
                        "hard_iron_ut": setup.hard_iron_ut, "soft_iron": setup.soft_iron,
                        "counts_per_gauss": setup.cpg, "full_scale_g": setup.full_scale_g}}
    c = app.calibration
    if c.model != MODEL:
        # the last refusal, or "time_limit" when the time ran out before any solve refused
        result["rejected"] = info["last_reason"] or "time_limit"
        result["in_force"] = c.model
        if quiet:
            print(json.dumps(result))
        else:
            print("no %d-element calibration accepted in %s s (in force: %s); last refusal: %s"
                  % (MODEL, _fmt(info["seconds"], 1), c.model, result["rejected"]))
        return STATUS_REFUSED
    try:
        mm = minmax.solve()
    except CalibrationRejected as e:
        mm = None
        result["minmax_rejected"] = e.reason
    cals = [UNCALIBRATED, mm, c]
    decl = getattr(getattr(app, "compass", None), "declination_kang", None)
    if decl is None:
        decl = cdeg_to_kang(DECLINATION_CDEG)
    setup.mag = app.mag  # the app's drivers (it re-creates them after a chip reset)
    setup.accel = app.accel
    rows = measure_grid(setup, cals, decl, opts["samples"])
    stats = {}
    for k in range(3):
        stats[METHODS[k]] = error_stats(rows, k)
    result["calibration"] = calibration_json(c, setup.cpg)
    if mm is not None:
        result["minmax_calibration"] = calibration_json(mm, setup.cpg)
    err = calibration_errors(setup, c)
    result["calibration_error"] = {"offset_ut": _round(err["offset_ut"], 4),
                                   "field_ut": _round(err["field_ut"], 4),
                                   "invw_max": _round(err["invw_max"], 6)}
    result["heading_error_deg"] = stats
    result["grid"] = {"yaws_deg": list(GRID_YAWS), "tilts_deg": [list(t) for t in GRID_TILTS],
                      "samples_per_orientation": opts["samples"]}
    plot_path = opts["plot"]
    if plot_path is None and not quiet:
        plot_path = DEFAULT_PLOT
    if opts["no_plot"]:
        plot_path = None
    if not quiet:
        print_calibration(setup, c, info)
        print_grid(rows, stats, opts["samples"], result.get("minmax_rejected"))
    if plot_path is not None:
        written = _plot(plot_path, setup, c, raws, quiet)
        if written:
            result["plot"] = plot_path
    if quiet:
        print(json.dumps(result))
    return 0


def _plot(path, setup, c, raws, quiet):
    if sys.implementation.name != "cpython":
        if not quiet:
            print("\nplot skipped: matplotlib runs on CPython only")
        return False
    try:
        from desktop import plot
        plot.calibration_png(path, setup, c, raws)
    except ImportError as e:
        if not quiet:
            print("\nplot skipped: %s" % e)
        return False
    if not quiet:
        print("\nPlot: %s (raw samples on their ellipsoid, hard iron removed, corrected on "
              "the sphere)" % path)
    return True
