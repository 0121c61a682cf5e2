"""`python -m host_sim soak`: a seeded fault campaign against the simulated board (make soak).

    python -m host_sim soak [--sessions N] [--seconds S] [--seed K] [--clean C] [--only K]...
                            [--gyro] [--akm] [--json]

Each session boots CompassApp from a store holding a good calibration (a GY-271 + MPU6050 or
a GY-87: SETUPS; --akm: a GY-9250 (MPU-9250 and its AK8963) or an ICM-20948 module (and its
AK09916): AKM_SETUPS; strong hard and soft iron, the board turning slowly and tilting), and
injects
random field faults from every class below through the simulator's fault hooks, each held
for a random spell and then cleared; some sessions reboot the app half-way (same board and
filesystem, sometimes with the accelerometer absent at boot). Printed: steps, faults,
reboots, exceptions out of step(), calibrations lost (a store that no longer loads a
calibration at least as good as the good one), "wrong-but-ok" samples - status "ok", a
calibration in force, and a heading error above ACCURACY_DEG - and, per fault class, the
median and worst time from injection to the first non-ok status (docs/faults.md). Then C
fault-free sessions (default one in ten) on the next streams: the same boards and motions
with no fault and no reboot, whose non-ok samples are false alarms. Last, the goals (GOALS,
docs/faults.md): the exit status is 1 when one fails, and the line says which.

Each session is seeded on its own (stream k of the seed), so --only K runs session K of
the campaign alone, as the whole campaign runs it (K from --sessions on: a fault-free one):
`--seed 1 --sessions 600 --only 554` replays the one session of make soak that once held a
heading "ok" while a magnet moved in (tests/test_soak.py).

--gyro runs every app with the gyro-aided heading (CompassApp.use_gyro, docs/gyro.md) where
an MPU6050 answers at boot: a "gyro held" sample then claims a good heading as "ok" does, and
counts as wrong-but-ok (and as not ok in the fault-free sessions) the same way.

Fault classes: stale (output registers frozen), zeros (the chip returns 0 0 0), mag_reset
(brown-out), range (a glitch write to the range/gain register), accel_sleep (MPU6050 asleep:
frozen tilt), accel_ff (0xFF reads), free_fall, stall (the main loop blocked 2-60 s), magnet
(interference near the board), nack (a burst of bus errors), accel_absent (missing at the
next boot, back later).
"""
import json
import math

from host_sim import motion
from host_sim.boards import make_board
from host_sim.prng import Prng
from host_sim.world import World

from desktop.args import Parser, UsageError
from desktop.memfs import MemFs

from firmware.app import CompassApp
from firmware.calibration import Calibration
from firmware.store import CalStore

ACCURACY_DEG = 5.0      # documented accuracy of a calibrated "ok" heading (docs/faults.md)
HARD_IRON_UT = (45.0, -35.0, 30.0)
SOFT_IRON = ((1.18, 0.09, -0.06), (0.09, 0.88, 0.07), (-0.06, 0.07, 1.04))
SETUPS = (("gy271", True), ("gy87", None))
AKM_SETUPS = (("gy9250", None), ("icm20948", None))
# the other magnetometers, each on its module with a GY-521 (tests/test_soak.py runs each)
CHIP_SETUPS = (("hmc5883l", True), ("qmc5883p", True), ("lis3mdl", True), ("lis2mdl", True),
               ("mmc5603", True)) + AKM_SETUPS
CLASSES = ("stale", "zeros", "mag_reset", "range", "accel_sleep", "accel_ff", "free_fall",
           "stall", "magnet", "nack", "accel_absent")
# each board's maps (boards/breakouts.py: the magnetometer inside an IMU has its own axes)
AXES = {"gy271": ("x,-y,-z", "-x,y,z"), "gy87": ("x,-y,-z", "-x,y,z"),
        "gy9250": ("y,-x,z", "-x,y,z"), "icm20948": ("x,y,z", "-x,y,z"),
        "hmc5883l": ("x,-y,-z", "-x,y,z"), "qmc5883p": ("x,-y,-z", "-x,y,z"),
        "lis3mdl": ("x,-y,-z", "-x,y,z"), "lis2mdl": ("x,-y,z", "-x,y,z"),
        "mmc5603": ("x,-y,-z", "-x,y,z")}


class Turning:
    """Yaw turning at `rate` deg/s, pitch and roll waving by up to 20 / 15 deg."""

    def __init__(self, yaw0, rate, phase):
        self.yaw0 = yaw0
        self.rate = rate
        self.phase = phase
        self.duration_us = None

    def at(self, t_us):
        t = t_us / 1e6
        return ((self.yaw0 + self.rate * t) % 360.0, 20.0 * math.sin(0.21 * t + self.phase),
                15.0 * math.sin(0.13 * t + 2 * self.phase))


def world(m):
    return World(field_ut=50.0, inclination_deg=60.0, declination_deg=4.0,
                 hard_iron_ut=HARD_IRON_UT, soft_iron=SOFT_IRON, motion=m)


GOOD = ("ok", "gyro held")  # statuses that present the heading as good


def app_on(b, store, gyro=False, **kw):
    mag_axes, accel_axes = AXES[b.chip]
    app = CompassApp(b.bus, mag_axes=mag_axes, accel_axes=accel_axes, declination_cdeg=400,
                     store=store, delay_us=b.sleep_us, ticks_us=b.clock.ticks_us, **kw)
    if gyro and app.accel is not None:
        app.use_gyro()
    return app


def good_calibration(setup, accel):
    """A 10-element calibration from a 40 s figure-8 session, then slow turning until the
    store holds it with the dip it measures (the app learns it and saves it once more): the
    calibration the store holds, the reference of 'lost'."""
    b = make_board(setup, world=world(motion.figure8()), seed=3, accel=accel)
    fs = MemFs()
    app = app_on(b, CalStore("/", fs=fs))
    while b.clock.now_us < 40000000:
        app.step()
    b.world.motion = Turning(0.0, 10.0, 0.0)
    cal = None
    while b.clock.now_us < 70000000 and (cal is None or cal.dip_kang is None):
        for _ in range(25):
            app.step()
        cal = Calibration.from_bytes(app.store.load())
    if cal.model != 10 or cal.dip_kang is None:
        raise RuntimeError("soak: no 10-element calibration with its dip for %s" % setup)
    return cal, app.mag.KIND, app.mag.range_code


def err_deg(app, b):
    true = b.world.true_heading_deg(b.clock.now_us)
    h = app.heading_kang * 360.0 / 65536
    return abs((h - true + 180.0) % 360.0 - 180.0)


def inject(b, cls, g):
    """Start fault `cls`; returns a function that clears it."""
    mag, acc, bus = b.mag, b.accel, b.bus
    if cls == "stale":
        mag.freeze(sticky=g.randrange(2) == 0)
        return mag.clear_fault
    if cls == "zeros":
        mag.constant(0, 0, 0, sticky=g.randrange(2) == 0)
        return mag.clear_fault
    if cls == "mag_reset":
        mag.brown_out()
        return lambda: None
    if cls == "range":
        if b.mag_address == 0x0D:
            mag.glitch(0x09, mag.ctrl1 ^ 0x10)
        elif b.mag_address == 0x0C:  # the AKM chips: their mode register (output width, rate)
            reg = mag.CNTL
            mag.glitch(reg, mag.regs[reg] ^ (0x10 if reg == 0x0A else 0x06))
        elif b.chip == "qmc5883p":  # CTRL2 RNG[3:2]
            mag.glitch(0x0B, mag.ctrl2 ^ (g.randrange(3) + 1) << 2)
        elif b.chip == "lis3mdl":  # CTRL_REG2 FS[6:5]
            mag.glitch(0x21, g.randrange(4) << 5)
        elif b.chip == "lis2mdl":  # one range: CFG_REG_A's ODR[3:2]
            mag.glitch(0x60, mag.cfg[0] ^ (g.randrange(3) + 1) << 2)
        elif b.chip == "mmc5603":  # the range is the driver's: Control 1's bandwidth
            mag.glitch(0x1C, g.randrange(4))
        else:
            mag.glitch(0x01, (g.randrange(8) << 5))
        return lambda: None
    if cls == "accel_sleep":
        acc.doze()
        return lambda: None
    if cls == "accel_ff":
        bus.stuck_high(b.accel_address)
        return lambda: bus.stuck_high(b.accel_address, False)
    if cls == "free_fall":
        acc.free_fall = True

        def land():
            acc.free_fall = False
        return land
    if cls == "magnet":
        t = b.clock.now_us / 1e6
        f = [(g.uniform() - 0.5) * 120.0 for _ in range(3)]
        b.world.add_magnet(f, t, t + 1 + g.randrange(20), ramp_s=0.2, frame="sensor")
        return lambda: None
    if cls == "nack":
        bus.inject_eio(after=0, count=1 + g.randrange(40))
        return bus.clear_faults
    return lambda: None


def session(k, seed, seconds, goods, stats, trace=None, faults=True, gyro=False,
            setups=SETUPS):
    """One session (stream k of the seed) on one of `setups`; faults=False: the same board
    and motion with no fault and no reboot, counting its non-ok samples in stats["clean"]
    (false alarms). trace(k, board, app, last_class) is called after every step when given."""
    g = Prng(seed, stream=k)
    si = g.randrange(len(setups))
    setup, accel = setups[si]
    cal, kind, rng = goods[si]
    m = Turning(g.randrange(360), 3.0 + g.randrange(20), g.uniform() * 6.0)
    b = make_board(setup, world=world(m), seed=1000 + k, accel=accel)
    fs = MemFs()
    CalStore("/", sensor=kind, range_code=rng, fs=fs).save(cal.to_bytes())
    app = app_on(b, CalStore("/", fs=fs), gyro)
    reboot_at = seconds * 1e6 / 2 if g.randrange(3) == 0 and faults else None
    end = seconds * 1e6
    next_fault = 2e6 + g.randrange(8) * 1e6 if faults else 2 * end
    clear = None
    clear_at = 0
    pending = None          # (class, injected at us) awaiting detection
    last = "none"           # the class of the last fault (wrong-but-ok samples are charged to it)
    while b.clock.now_us < end:
        now = b.clock.now_us
        if clear is None and now >= next_fault:
            cls = CLASSES[g.randrange(len(CLASSES))]
            last = cls
            stats["faults"][cls] = stats["faults"].get(cls, 0) + 1
            if cls == "stall":
                b.clock.advance(2000000 + g.randrange(58) * 1000000)
            elif cls == "accel_absent" and accel:  # a GY-521 module beside the magnetometer
                b.bus.kill(b.accel_address)
                app = reboot(app, b, fs, stats, gyro)
                revive_at = b.clock.now_us + 1e6 * (1 + g.randrange(10))
                clear = lambda: b.bus.revive(b.accel_address)  # noqa: E731
                clear_at = revive_at
            else:
                clear = inject(b, cls, g)
                clear_at = now + 1e6 * (1 + g.randrange(15))
                # (an IMU that carries the magnetometer is not taken away: nothing to detect)
                pending = None if cls == "accel_absent" else (cls, now)
            if clear is None:
                next_fault = b.clock.now_us + 1e6 * (3 + g.randrange(15))
        elif clear is not None and now >= clear_at:
            clear()
            clear = None
            pending = None
            next_fault = b.clock.now_us + 1e6 * (3 + g.randrange(15))
        if reboot_at is not None and now >= reboot_at:
            reboot_at = None
            app = reboot(app, b, fs, stats, gyro)
            if pending is not None:  # the reboot re-initialised the chips before any step saw
                c = stats["reboot_cleared"]  # the fault (an MPU6050 put to sleep, woken)
                c[pending[0]] = c.get(pending[0], 0) + 1
                pending = None
        try:
            app.step()
        except Exception as e:  # noqa: BLE001 - counted: step() must never raise
            stats["exceptions"] += 1
            stats["last_exception"] = repr(e)
        if trace is not None:
            trace(k, b, app, last)
        if not faults:
            clean_step(app, b, stats["clean"])
            continue
        pending = faulted_step(app, b, stats, pending, last)
    if clear is not None:
        clear()
    if not stored_as_good(fs, kind, rng, cal):
        stats["lost"] += 1


def faulted_step(app, b, stats, pending, last):
    """Count one step of a session with faults: a status not ok detects the `pending`
    fault (None returned then, else `pending`); an ok heading off by more than ACCURACY_DEG
    is charged to the `last` fault's class."""
    stats["steps"] += 1
    if app.status not in GOOD:
        if pending is not None:
            d = (b.clock.now_us - pending[1]) / 1e3
            stats["detect_ms"].setdefault(pending[0], []).append(d)
            pending = None
    elif app.calibration.model is not None and err_deg(app, b) > ACCURACY_DEG:
        stats["wrong_but_ok"] += 1
        stats["wrong_by_class"][last] = stats["wrong_by_class"].get(last, 0) + 1
    return pending


def stored_as_good(fs, kind, rng, cal):
    """Not lost: the store still boots a calibration at least as good as the good one."""
    try:
        st = CalStore("/", sensor=kind, range_code=rng, fs=fs)
        got = Calibration.from_bytes(st.load())
        return got.model is not None and got.fit_error <= cal.fit_error
    except Exception:  # noqa: BLE001
        return False


def clean_step(app, b, st):
    st["steps"] += 1
    if app.status not in GOOD:
        st["not_ok"] += 1
        st["by_status"][app.status] = st["by_status"].get(app.status, 0) + 1
    elif err_deg(app, b) > ACCURACY_DEG:
        st["wrong_but_ok"] += 1


def reboot(app, b, fs, stats, gyro=False):
    stats["reboots"] += 1
    return app_on(b, CalStore("/", fs=fs), gyro)


def campaign(sessions, seconds, seed, clean=None, gyro=False, only=None, setups=SETUPS):
    """The campaign: `sessions` sessions with faults, then `clean` fault-free ones (None:
    one in ten, at least 2) on streams after them, whose non-ok samples are false alarms;
    gyro: every app with use_gyro() where it has an MPU6050; only: run just these sessions
    of it (stream numbers; from `sessions` on, fault-free ones); setups: the boards drawn
    from."""
    goods = [good_calibration(s, a) for s, a in setups]
    if clean is None:
        clean = max(2, sessions // 10)
    ks = range(sessions + clean) if only is None else sorted(set(only))
    if ks and not 0 <= ks[0] <= ks[-1] < sessions + clean:
        raise ValueError("only: sessions 0..%d" % (sessions + clean - 1))
    stats = {"sessions": sessions, "seconds_per_session": seconds, "seed": seed, "steps": 0,
             "gyro": gyro, "only": None if only is None else list(ks),
             "faults": {}, "reboots": 0, "exceptions": 0, "lost": 0, "wrong_but_ok": 0,
             "wrong_by_class": {}, "detect_ms": {}, "reboot_cleared": {},
             "accuracy_deg": ACCURACY_DEG,
             "clean": {"sessions": sum(1 for k in ks if k >= sessions), "steps": 0,
                       "not_ok": 0, "by_status": {}, "wrong_but_ok": 0}}
    for k in ks:
        session(k, seed, seconds, goods, stats, faults=k < sessions, gyro=gyro, setups=setups)
    det = {}
    for cls, v in sorted(stats["detect_ms"].items()):
        v = sorted(v)
        det[cls] = {"n": len(v), "median_ms": round(v[len(v) // 2], 1), "max_ms": round(v[-1], 1)}
    stats["detect_ms"] = det
    stats["total_faults"] = sum(stats["faults"].values())
    stats["goals_failed"] = failed_goals(stats)
    return stats


# The campaign's goals (docs/faults.md): make soak exits 1 when one fails. Faults that need
# no detection: a stall (a pause), an accelerometer found missing at boot (the app runs
# without it), a range glitch (one to the same sensitivity changes nothing).
NEED_NO_DETECTION = ("stall", "accel_absent", "range")
DETECT_MS = 1000.0
GOALS = ("no exception out of step()",
         "no calibration lost",
         "wrong-but-ok 0 (status ok, heading more than %.0f deg off)" % ACCURACY_DEG,
         "fault-free sessions: wrong-but-ok 0, at most 1 in 1000 samples not ok",
         "every fault that needs it detected while it lasts, within %.0f ms\n"
         "    (not with --gyro: 'gyro held' vouches for the heading instead)" % DETECT_MS)


def failed_goals(st):
    """The goals `st` (campaign()'s figures) misses, one text each naming the figure."""
    out = []
    if st["exceptions"]:
        out.append("exceptions out of step() %d (goal 0; last %s)"
                   % (st["exceptions"], st.get("last_exception")))
    if st["lost"]:
        out.append("calibrations lost %d (goal 0)" % st["lost"])
    if st["wrong_but_ok"]:
        out.append("wrong-but-ok %d (goal 0; by class %s)"
                   % (st["wrong_but_ok"], st["wrong_by_class"]))
    c = st["clean"]
    if c["wrong_but_ok"]:
        out.append("fault-free wrong-but-ok %d (goal 0)" % c["wrong_but_ok"])
    if c["not_ok"] * 1000 > c["steps"]:
        out.append("fault-free not ok %d of %d samples (goal at most 1 in 1000)"
                   % (c["not_ok"], c["steps"]))
    if st.get("gyro"):
        return out
    for cls in CLASSES:
        d = st["detect_ms"].get(cls)
        if d is not None and d["max_ms"] >= DETECT_MS:
            out.append("%s detected after %.1f ms (goal under %.0f)" % (cls, d["max_ms"],
                                                                       DETECT_MS))
        n = st["faults"].get(cls, 0)
        seen = (d["n"] if d else 0) + st["reboot_cleared"].get(cls, 0)
        if cls not in NEED_NO_DETECTION and seen < n:
            out.append("%s detected %d of %d (goal all)" % (cls, seen, n))
    return out


def parser():
    p = Parser("soak", "[--sessions N] [--seconds S] [--seed K] [--clean C] [--only K]... "
               "[--gyro] [--akm] [--json]",
               "A seeded fault campaign against the simulated board (docs/faults.md).")
    p.option("--sessions", "int", default=40, lo=1, hi=100000, metavar="N",
             help="sessions with faults (default 40; make soak: 600)")
    p.option("--seconds", "int", default=60, lo=5, hi=100000, metavar="S",
             help="simulated seconds per session (default 60)")
    p.option("--seed", "int", default=1, lo=0, hi=2 ** 31 - 1, metavar="K",
             help="campaign seed (default 1)")
    p.option("--clean", "int", lo=0, hi=100000, metavar="C",
             help="fault-free sessions (default one in ten, at least 2)")
    p.option("--only", "int", lo=0, hi=200000, metavar="K", repeat=True,
             help="run only session K of the campaign (each is seeded on its own, so it runs\n"
                  "as in the whole campaign; K >= N: a fault-free one); may be repeated")
    p.option("--gyro", "flag", help="the apps run the gyro-aided heading (use_gyro)")
    p.option("--akm", "flag", help="the boards with an AKM magnetometer (AKM_SETUPS)")
    p.option("--json", "flag", help="the figures as one JSON object")
    p.option("--doc", "path", metavar="PAGE",
             help="also write the report into PAGE between its soak-run markers\n"
                  "(make soak: docs/faults.md, so the page quotes this run)")
    p.epilog = ("goals (docs/faults.md), checked on the sessions run:\n"
                + "".join("  - %s\n" % g for g in GOALS)
                + "exit status: 0 every goal met; 1 a goal failed (the report's last line, or\n"
                  "goals_failed with --json, says which); 2 bad usage.")
    return p


def body(opts):
    n = opts["sessions"]
    clean = opts["clean"] if opts["clean"] is not None else max(2, n // 10)
    only = opts["only"] or None
    if only is not None and max(only) >= n + clean:
        raise UsageError("--only %d: this campaign's sessions are 0..%d (%d with faults, then "
                         "%d fault-free)" % (max(only), n + clean - 1, n, clean))
    if opts["doc"]:
        write_doc(opts["doc"], None)  # the markers are there before minutes of campaign
    st = campaign(n, opts["seconds"], opts["seed"], clean, opts["gyro"], only,
                  AKM_SETUPS if opts["akm"] else SETUPS)
    if opts["json"]:
        print(json.dumps(st, sort_keys=True))
    else:
        for line in report(st):
            print(line)
    if opts["doc"]:
        write_doc(opts["doc"], report(st))
    return 1 if st["goals_failed"] else 0


DOC_BEGIN, DOC_END = "<!-- soak-run:begin -->", "<!-- soak-run:end -->"


def write_doc(path, lines):
    """Put the report's lines, indented as a block, between the page's soak-run markers
    (lines None: only check that the page has them)."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise UsageError("--doc %s: %s" % (path, e.strerror))
    if DOC_BEGIN not in text or DOC_END not in text:
        raise UsageError("--doc %s: the page has no %s ... %s markers" % (path, DOC_BEGIN,
                                                                          DOC_END))
    if lines is None:
        return
    a, b = text.index(DOC_BEGIN) + len(DOC_BEGIN), text.index(DOC_END)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text[:a] + "\n\n" + "".join("    %s\n" % ln for ln in lines) + "\n" + text[b:])


def main(argv):
    return parser().main(argv, body)


def report(st):
    """The campaign's table as lines (make soak prints them; make bench puts them in
    docs/benchmarks.md)."""
    only = st.get("only")
    out = ["soak: %d sessions x %d s, seed %d%s%s" % (
               st["sessions"], st["seconds_per_session"], st["seed"],
               ", gyro-aided heading (ok or gyro held count as good)" if st.get("gyro") else "",
               ", only session%s %s of them" % ("s" if len(only) > 1 else "",
                                                ", ".join(str(k) for k in only))
               if only else ""),
           "steps %d  faults %d  reboots %d  exceptions %d  calibrations lost %d  "
           "wrong-but-ok %d (ok and > %.0f deg)" % (st["steps"], st["total_faults"],
                                                     st["reboots"], st["exceptions"],
                                                     st["lost"], st["wrong_but_ok"],
                                                     st["accuracy_deg"]),
           "%-13s %7s %9s %10s %10s" % ("fault", "count", "detected", "median ms", "max ms")]
    for cls in CLASSES:
        d = st["detect_ms"].get(cls)
        out.append("%-13s %7d %9s %10s %10s" % (cls, st["faults"].get(cls, 0),
                                                d["n"] if d else "-", d["median_ms"] if d else "-",
                                                d["max_ms"] if d else "-"))
    if st["wrong_by_class"]:
        out.append("wrong-but-ok by class: %s" % st["wrong_by_class"])
    if st.get("reboot_cleared"):
        out.append("cleared by a reboot before any step read them: %s" % st["reboot_cleared"])
    out.append(false_alarms(st["clean"], st["seconds_per_session"]))
    if "goals_failed" in st:
        failed = st["goals_failed"]
        out.append("goals: FAILED: %s" % "; ".join(failed) if failed else "goals: all met")
    return out


def false_alarms(c, seconds):
    """The fault-free sessions' line: their non-ok samples are false alarms."""
    n = c["steps"]
    return ("fault-free: %d sessions x %d s, %d steps, %d not ok (%.3f %%%s), wrong-but-ok %d"
            % (c["sessions"], seconds, n, c["not_ok"], 100.0 * c["not_ok"] / n if n else 0.0,
               (": " + ", ".join("%s %d" % kv for kv in sorted(c["by_status"].items())))
               if c["by_status"] else "", c["wrong_but_ok"]))
