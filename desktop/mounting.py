"""The mounting check (firmware/calibrate/mounting.py, firmware/calibrate/mountcheck.py) on the desktop: the offline
check of a log with accelerometer columns, simulated calibration sessions, and the
no-false-alarm soak.

    python -m host_sim calibrate LOG.csv     # a log with ax, ay, az beside mx, my, mz: checked
    python -m desktop.mounting [--sessions N] [--seconds S] [--seed K] [--json]   # the soak

Offline (offline(), called by the calibrate command after a fit): the accelerometer columns
are found by their header names (ACCEL_PREFIXES: ax, ay, az / accX.. / acc_x.. / accel_x..),
scaled so that the median row reads 1 g (any units: counts, g, m/s^2), and each row with its
magnetometer row, both converted as the fit converted them, is offered to a
firmware.calibrate.mounting.Pairs; firmware.calibrate.mountcheck.check() then judges the fit's calibration with
the MAG_AXES / ACCEL_AXES given (--mag-axes, --accel-axes; default the breakouts' usual
"x,-y,-z" / "-x,y,z", boards/breakouts.py). The log's sample rate is not known: the pairs
take moves up to the slowest rate's (10 Hz), and each bin keeps the stillest row anyway.

Simulated sessions (session()): a board of host_sim.boards (QMC5883L, HMC5883L, QMC5883P with
an MPU6050 module, the GY-87 and its QMC5883L clone) with its chips mounted as asked, iron,
a figure-8 calibration dance (host_sim.motion.figure8) through CompassApp with the MAG_AXES /
ACCEL_AXES given. Every step with a plausible accelerometer offers (mag raw, accel raw) to a
firmware.calibrate.mounting.Pairs, and each calibration the app accepts is checked as the board checks
it: the verdicts in order, with the time of each.

The soak (soak(), the command above; make soak runs 600 sessions): seeded sessions, each a
random board, world (field 25-65 uT, inclination -75..75 deg), iron (host_sim.world.random_iron),
dance (period 24-36 s, pitch amplitude 60-85 deg, roll 120-180 deg, any start heading) and a
random one of the 24 mountings of each chip WITH its right MAG_AXES / ACCEL_AXES, and what a
real board and hand add (random_session's rough: accelerometer offsets, the chips 0-3 deg
apart, the hand's accelerations): a verdict "wrong" in any check of any session is a false
alarm, and so is the app's own check (firmware/calibrate/session.py) saying "wrong". Printed: sessions,
checks, false alarms, the verdicts of the last check of each session and of the app's own,
the largest spread (sigma) of a right setting.
"""
import json
import sys

from host_sim.world import World, mount_inverse

from firmware.calibrate import mountcheck
from firmware.calibrate import mounting

BOARDS = (("qmc5883l", True), ("hmc5883l", True), ("qmc5883p", True), ("gy87", None),
          ("gy87-qmc", None))
MOUNT = (1, -2, -3)   # host_sim.boards: every chip x forward, y left, z up
MAG_AXES = "x,-y,-z"  # ... and the maps that go with it (boards/breakouts.py)
ACCEL_AXES = "-x,y,z"
SECONDS = 40          # a normal dance: the bound, and test_app.py's session
_AXES = "xyz"


def _spec(m, neg=False):
    return ",".join(("-" if (a < 0) != neg else "") + _AXES[abs(a) - 1] for a in m)


def mag_axes(mount):
    """The MAG_AXES (firmware.axes spec) of a magnetometer mounted `mount` (host_sim.world: a
    body -> sensor signed permutation): its inverse, sensor -> body."""
    return _spec(mount_inverse(mount))


def accel_axes(mount):
    """The ACCEL_AXES of an accelerometer mounted `mount`: the inverse negated (AN4248 wants
    +1 g down, the chip reads +1 g on an axis pointing up)."""
    return _spec(mount_inverse(mount), neg=True)


def rotations():
    """The 24 mountings that are rotations (det +1), the boards' own first."""
    out = [MOUNT]
    for p in ((1, 2, 3), (1, 3, 2), (2, 1, 3), (2, 3, 1), (3, 1, 2), (3, 2, 1)):
        for s in ((1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1), (-1, 1, 1), (-1, 1, -1),
                  (-1, -1, 1), (-1, -1, -1)):
            m = (p[0] * s[0], p[1] * s[1], p[2] * s[2])
            inv = (p[0] > p[1]) + (p[0] > p[2]) + (p[1] > p[2])
            if s[0] * s[1] * s[2] * (-1 if inv & 1 else 1) == 1 and m != MOUNT:
                out.append(m)
    return out


class Session:
    """One simulated calibration session with the mounting check (see the module docstring).
    .checks: (t_s, verdict, axes, sigma, best, bins) after each accepted calibration, and
    once more at the end when the last said nothing (spread or unsteady);
    .app, .pairs, .board; .rows with record=True, .statuses with statuses=True (the app
    runs the check itself too, firmware/calibrate/session.py: .app.mounting)."""

    def __init__(self, chip="qmc5883l", accel=True, mount=MOUNT, accel_mount=MOUNT,
                 mag_axes=MAG_AXES, accel_axes=ACCEL_AXES, world=None, seed=3,
                 seconds=SECONDS, record=False, accel_bias=None, statuses=False):
        from host_sim import motion
        from host_sim.boards import make_board
        from firmware.app import CompassApp
        if world is None:
            world = World(field_ut=50.0, inclination_deg=60.0, declination_deg=4.0,
                          hard_iron_ut=(45.0, -35.0, 30.0),
                          soft_iron=((1.18, 0.09, -0.06), (0.09, 0.88, 0.07),
                                     (-0.06, 0.07, 1.04)), motion=motion.figure8())
        b = make_board(chip, world=world, seed=seed, accel=accel, mount=mount,
                       accel_mount=accel_mount)
        if accel_bias is not None:  # the MPU6050's zero-g offsets, g per chip axis
            b.accel.bias_g = tuple(accel_bias)
        self.board = b
        self.mag_axes = mag_axes
        self.accel_axes = accel_axes
        app = CompassApp(b.bus, mag_axes=mag_axes, accel_axes=accel_axes, store=None,
                         delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)
        self.app = app
        self.pairs = mounting.Pairs(app.accel.counts_per_g,
                                    getattr(app.mag, "period_us", 20000))
        self.checks = []
        accepted = 0
        end = int(seconds * 1000000)
        self.rows = []  # record=True: (accel x, y, z, mag x, y, z) raw, per step with both
        self.statuses = []  # statuses=True: app.status after every step
        while b.clock.now_us < end:
            if app.step() and app.tilt:
                self.pairs.feed(app.raw, app._acc)
                if record:
                    self.rows.append(tuple(app._acc) + tuple(app.raw))
            if statuses:
                self.statuses.append(app.status)
            if app.accepted > accepted:
                accepted = app.accepted
                self.check(app.calibration)
        if self.checks and self.checks[-1][1] in (mountcheck.SPREAD, mountcheck.UNSTEADY):
            self.check(app.calibration)  # the session's end: with every pair it kept

    def check(self, cal):
        r = mountcheck.check(self.pairs, cal, self.mag_axes, self.accel_axes)
        self.checks.append((self.board.clock.now_us // 1000000,) + r + (self.pairs.count,))
        return r[0]

    @property
    def verdict(self):
        """The last check's verdict and MAG_AXES, or (None, None) when no fit was accepted."""
        return self.checks[-1][1:3] if self.checks else (None, None)


def random_session(seed, seconds=SECONDS, wrong=False, rough=False):
    """The soak's session `seed`: a random board, world, iron, dance and mounting, with the
    right MAG_AXES; wrong=True: with the MAG_AXES of another rotation (.right: the right one).
    rough=True adds what a real board and hand add: the accelerometer's zero-g offsets (up to
    the MPU6050's +-50 mg on x and y, +-80 mg on z), the magnetometer turned up to 3 deg
    against the accelerometer (a soft iron that is no longer symmetric: the fit cannot take
    the turn out), and the hand's accelerations (0.05-0.3 g for 0.3-1 s every 1.5-4 s)."""
    from host_sim import motion
    from host_sim.prng import Prng
    from host_sim.world import random_iron
    g = Prng(seed, stream=0x3A7)

    def u(lo, hi):
        return lo + (hi - lo) * g.uniform()

    chip, accel = BOARDS[g.randrange(len(BOARDS))]
    rots = rotations()
    mount = rots[g.randrange(24)]
    accel_mount = rots[g.randrange(24)]
    v, w = random_iron(seed)
    m = motion.figure8(period_s=u(24.0, 36.0), pitch_amp=u(60.0, 85.0),
                       roll_amp=u(120.0, 180.0), yaw0=u(0.0, 360.0))
    world = World(field_ut=u(25.0, 65.0), inclination_deg=u(-75.0, 75.0),
                  declination_deg=u(-20.0, 20.0), hard_iron_ut=v, soft_iron=w, motion=m,
                  seed=seed)
    setting = mag_axes(mount)
    if wrong:
        other = rots[g.randrange(23)]
        setting = mag_axes(rots[23] if other == mount else other)
    bias = None
    if rough is True:
        rough = "bias,turn,hand"
    if rough:
        bias = (u(-0.05, 0.05), u(-0.05, 0.05), u(-0.08, 0.08))
        turned = _turned(w, u(0.0, 3.0), (u(-1, 1), u(-1, 1), u(-1, 1)))
        if "bias" not in rough:
            bias = None
        if "turn" in rough:
            world.set_iron(v, turned)
        t = u(0.5, 2.0) if "hand" in rough else seconds
        while t < seconds:
            d = u(0.3, 1.0)
            a = u(0.05, 0.3)
            e = (u(-1, 1), u(-1, 1), u(-1, 1))
            n = (e[0] ** 2 + e[1] ** 2 + e[2] ** 2) ** 0.5 or 1.0
            world.add_acceleration((a * e[0] / n, a * e[1] / n, a * e[2] / n), t, t + d,
                                   ramp_s=0.15)
            t += d + u(1.5, 4.0)
    s = Session(chip, accel, mount, accel_mount, setting, accel_axes(accel_mount), world,
                seed=seed, seconds=seconds, accel_bias=bias)
    s.right = mag_axes(mount)
    return s


def _turned(w, deg, axis):
    # the soft-iron matrix w followed by a turn of `deg` about `axis` (Rodrigues' formula)
    import math
    n = math.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2) or 1.0
    x, y, z = axis[0] / n, axis[1] / n, axis[2] / n
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    r = ((c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s),
         (y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s),
         (z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)))
    return tuple(tuple(sum(w[i][k] * r[k][j] for k in range(3)) for j in range(3))
                 for i in range(3))


def soak(sessions=60, seed=1, seconds=SECONDS):
    """Run `sessions` random sessions with right settings (see the module docstring)."""
    out = {"sessions": sessions, "seed": seed, "seconds": seconds, "checks": 0,
           "false_alarms": 0, "alarms": [], "last": {}, "board": {}, "worst_sigma_q10": 0}
    for i in range(sessions):
        s = random_session(seed * 100003 + i, seconds, rough=True)
        for c in s.checks:
            out["checks"] += 1
            if c[1] == mountcheck.WRONG:
                out["false_alarms"] += 1
                out["alarms"].append([seed * 100003 + i, s.board.chip] + list(c))
            elif c[1] == mountcheck.OK and c[3] > out["worst_sigma_q10"]:
                out["worst_sigma_q10"] = c[3]
        last = s.verdict[0] or "no fit"
        out["last"][last] = out["last"].get(last, 0) + 1
        board = s.app.mounting  # the app's own check (firmware/calibrate/session.py)
        out["board"][board[0] if board else "none"] = out["board"].get(
            board[0] if board else "none", 0) + 1
        if board is not None and board[0] == mountcheck.WRONG:
            out["false_alarms"] += 1
            out["alarms"].append([seed * 100003 + i, s.board.chip, "board"] + list(board))
    return out


def report(st):
    """The soak's lines."""
    return ["mounting check soak: %d sessions x %d s, seed %d, right settings on random boards, "
            "worlds and mountings, offsets, misalignment and the hand's accelerations"
            % (st["sessions"], st["seconds"], st["seed"]),
            "checks %d (after each accepted fit, and at the end)  false alarms %d  last verdicts "
            "%s  worst sigma with ok %.3f" % (st["checks"], st["false_alarms"],
                              ", ".join("%s %d" % kv for kv in sorted(st["last"].items())),
                              st["worst_sigma_q10"] / 1024.0),
            "the board's own check (app.mounting at the end): %s"
            % ", ".join("%s %d" % kv for kv in sorted(st["board"].items())),
            "goal: no false alarm: %s" % ("FAILED, %d (%s)" % (
                st["false_alarms"], "; ".join(" ".join(str(v) for v in a[:4])
                                              for a in st["alarms"][:5]))
                                          if st["false_alarms"] else "met")]


# ---- offline: a log with accelerometer columns (the calibrate command) ----------------------

ACCEL_PREFIXES = ("a", "acc", "accel", "accelerometer", "acceleration", "rawa", "rawacc",
                  "accraw", "accelraw")
ACCEL_SUFFIXES = ("", "g", "ms2", "mss", "raw", "lsb", "counts")
OFFLINE_CPG = 16384       # the accelerometer rows are scaled to the MPU6050's +-2 g counts
OFFLINE_PERIOD_US = 100000  # the log's rate is not known: the slowest a driver sets


def accel_columns(names):
    """The 0-based indices of the accelerometer's x, y, z columns among header `names`, or
    None."""
    from desktop.logfile import normalise_name
    norm = [normalise_name(n) for n in names]
    for p in ACCEL_PREFIXES:
        for u in ACCEL_SUFFIXES:
            keys = [p + a + u for a in "xyz"]
            if all(k in norm for k in keys):
                return tuple(norm.index(k) for k in keys)
    return None


def _axes(text, accel=False):
    # a magnetometer's map of either handedness here: which one its chip needs is known once
    # --sensor is (handedness() below)
    from firmware.axes import AxisMap
    try:
        m = AxisMap(text)
    except ValueError as e:
        raise ValueError(str(e))
    if accel and m.det != -1:
        raise ValueError("%r is a rotation: an accelerometer's map to AN4248 is a rotation "
                         "then a negation (e.g. -x,y,z)" % text)
    return m.spec


def handedness(mag_axes, sensor):
    """None when the MAG_AXES spec `mag_axes` has the handedness of the magnetometer `sensor`
    (host_sim/chips.py: a rotation, a mirror where the datasheet draws the chip's axes as a
    mirror of its accelerometer's; any for a chip not named, None), else what is wrong."""
    from firmware.axes import AxisMap
    from host_sim import chips
    if mag_axes is None or sensor is None:
        return None
    want = -1 if chips.mag(sensor)["mirror"] else 1
    det = AxisMap(mag_axes).det
    if det == want:
        return None
    return ("%r is a %s: the %s's axes are %s (its datasheet), so is its map (e.g. %s)" % (
        mag_axes, "mirror image" if det < 0 else "rotation", sensor,
        "right-handed as the body frame" if want > 0 else "a mirror of its accelerometer's",
        "x,-y,-z" if want > 0 else "x,y,-z"))


def mag_axes_opt(text):
    return _axes(text)


def accel_axes_opt(text):
    return _axes(text, accel=True)


def options(p):
    """The calibrate command's options for the check (desktop/calibrate.py)."""
    p.option("--mag-axes", mag_axes_opt, metavar="SPEC",
             help="the board's MAG_AXES, for the mounting check of a log with\n"
                  "accelerometer columns (default %s)" % MAG_AXES)
    p.option("--accel-axes", accel_axes_opt, metavar="SPEC",
             help="the board's ACCEL_AXES (default %s)" % ACCEL_AXES)


def offline(opts, cal, info):
    """The mounting check of the log the calibrate command fitted (see the module docstring):
    a dict for its JSON (verdict, mag_axes: what the data say, mag_axes_given, accel_axes,
    sigma, best: spreads of the dip's sine, pairs: directions held of mounting.BINS, rows),
    or None when the log has no accelerometer columns."""
    from desktop import logfile
    log = info["log"]
    cols = accel_columns(log.names) if log.names else None
    if cols is None:
        return None
    acc = logfile.Log(log.path, cols, opts["skip"])
    rows = []
    for lineno, row in acc.rows():
        rows.append((lineno, [m / 10 ** d for m, d in row]))
    if not rows:
        return None
    mags = sorted((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) ** 0.5 for _, a in rows)
    one_g = mags[len(mags) // 2]
    if one_g <= 0:
        return None
    k = OFFLINE_CPG / one_g
    accel = dict((ln, [int(round(v * k)) for v in a]) for ln, a in rows)
    pairs = mounting.Pairs(OFFLINE_CPG, OFFLINE_PERIOD_US)
    from array import array
    raw = array("h", (0, 0, 0))
    a16 = array("h", (0, 0, 0))
    num, den = info["num"], info["den"]
    used = 0
    for lineno, row in logfile.Log(log.path, log.columns, opts["skip"]).rows():
        a = accel.get(lineno)
        if a is None:
            continue
        v = [logfile.convert(m, d, num, den) for m, d in row]
        if not all(-32768 <= x <= 32767 for x in v + a):
            continue
        for i in range(3):
            raw[i] = v[i]
            a16[i] = a[i]
        pairs.feed(raw, a16)
        used += 1
    mag_axes = opts.get("mag_axes") or MAG_AXES
    accel_axes = opts.get("accel_axes") or ACCEL_AXES
    v, axes, sigma, best = mountcheck.check(pairs, cal, mag_axes, accel_axes)
    return {"verdict": v, "mag_axes": axes, "mag_axes_given": mag_axes,
            "accel_axes": accel_axes, "sigma": sigma / 1024.0, "best": best / 1024.0,
            "pairs": pairs.count, "bins": mounting.BINS, "rows": used,
            "accel_columns": [log.names[c] for c in cols]}


def offline_lines(r):
    """The calibrate command's text lines for offline()'s result."""
    given, axes, acc = r["mag_axes_given"], r["mag_axes"], r["accel_axes"]
    spread = "%d of %d directions of gravity" % (r["pairs"], r["bins"])
    v = r["verdict"]
    if v == mountcheck.OK:
        return ['mounting       ok: MAG_AXES "%s" agrees with ACCEL_AXES "%s" (the dip steady: '
                'its sine within %.3f RMS over %s)' % (given, acc, r["sigma"], spread)]
    if v == mountcheck.WRONG:
        return ['mounting       WRONG: with ACCEL_AXES "%s" the data say MAG_AXES = "%s" (with '
                '"%s" the dip swings: its sine by %.2f RMS; %.3f with "%s")'
                % (acc, axes, given, r["sigma"], r["best"], axes),
                "               put it in boards/<board>/board.py; examples/check_axes.py "
                "checks ACCEL_AXES (docs/calibration.md, troubleshooting)"]
    if v == mountcheck.SPREAD:
        return ["mounting       not enough spread: %s, or two mappings fit as well (turn the "
                "board over, not only around)" % spread]
    return ["mounting       unsteady: no mapping keeps the dip steady (best %.2f RMS): a magnet, "
            "a shaking hand, or columns that are not the accelerometer" % r["best"]]


def main(argv):
    from desktop.args import Parser
    p = Parser("mounting", "[options]", "The mounting check's no-false-alarm soak.")
    p.option("--sessions", "int", default=600, lo=1, metavar="N", help="sessions")
    p.option("--seconds", "int", default=SECONDS, lo=5, hi=600, metavar="S",
             help="seconds of dance per session")
    p.option("--seed", "int", default=1, lo=0, metavar="K", help="the campaign's seed")
    p.option("--json", "flag", help="one JSON object")
    p.epilog = ("goal: no false alarm (no check says \"wrong\" with the right settings).\n"
                "exit status: 0 the goal met; 1 a false alarm (the report's last line, or\n"
                "false_alarms and alarms with --json, says which); 2 bad usage.")

    def body(o):
        st = soak(o["sessions"], o["seed"], o["seconds"])
        if o["json"]:
            print(json.dumps(st, sort_keys=True))
        else:
            print("\n".join(report(st)))
        return 1 if st["false_alarms"] else 0
    return p.main(argv, body)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
