"""Accuracy against a float64 fit of the same model (CPython: numpy).

The firmware's results are the same bits on MicroPython (tests/scenarios/calibrator_parity.py,
compass_parity.py), so CPython runs it here next to numpy.

Logs (datasets/, and build/datasets after `make datasets`): for each log and model, sphericity
std(|out|) / mean(|out|) of our calibration against the float64 fit of the same model on the
same rows - the reading, scaling and reference of desktop/benchmarks/reference.py
(shared with the tests). And `python -m host_sim calibrate LOG` at its default settings
against a float64 fit of every row (reference.default_command): the table of
docs/calibration.md between LOGS_BEGIN and LOGS_END (command_section), which `make bench`
writes and tests/test_datasets.py checks against a fresh run.

Simulated headings: a simulated GY-271 + GY-521 with known hard and soft iron does one
noisy 30 s figure-8 at 200 Hz; our Calibrator (board defaults: 300 samples, QMC5883L
counts/G) keeps its samples; on exactly those held samples the float64 fit of each model
is computed (tests/test_solve.numpy_fit), and the heading guide's min/max (float offset and scale)
on every raw sample of the session. Then the board is held still, noise off (only
quantisation), on a grid of yaw x pitch x roll, and each calibration's heading error
against the true yaw is measured: ours with the firmware's integer path (correct, AxisMap,
Compass), the float64 fit and min/max with the heading guide's float tilt heading.
"""
import math
import sys

from desktop.benchmarks import common, floatpath

MODELS = ("minmax", 4, 7, 10)
SCENARIOS = {
    "rotated_soft_iron": (common.HARD_IRON_UT, common.SOFT_IRON),
    "axis_soft_iron": ((30.0, -45.0, 20.0), ((1.15, 0.0, 0.0), (0.0, 0.9, 0.0),
                                              (0.0, 0.0, 1.0))),
}


def logs(smoke):
    from desktop.benchmarks import reference as td
    from firmware.errors import CalibrationRejected
    names = [n for n in td.LOGS]
    if smoke:
        names = [n for n in names if n == SMOKE_LOG] or names[:1]
    out = {}
    for name in names:
        row = {}
        for model in MODELS:
            try:
                s_ours, c = td.ours(name, model)
            except CalibrationRejected as e:
                row[str(model)] = {"refused": e.reason}
                continue
            s_ref = td.reference(name, model)
            row[str(model)] = {"ours": s_ours, "float64": s_ref, "ratio": s_ours / s_ref}
        out[name] = row
    return out


def commands(smoke):
    from desktop.benchmarks import reference as td
    names = [n for n in td.LOGS if not smoke or n == SMOKE_LOG]
    return {name: td.default_command(name) for name in names}


SMOKE_LOG = "unknown_ellipsoid_fit_python_bazhin"   # small, and shipped
LOGS_BEGIN = "<!-- logs:begin -->"
LOGS_END = "<!-- logs:end -->"
COMMAND_GOAL = 1.05   # the default fit's spread at most 5 % above the float64 fit's


def command_row(name, e, shipped):
    """One line of command_section's table."""
    where = "datasets/" if shipped else "`make datasets`"
    if e.get("ours") is None:
        return "| %s | %s | refused: %s, even with --force | | | | |" % (
            name, where, e.get("refused"))
    note = "" if "refused" not in e else " (refused: %s; the fit --force gives)" % e["refused"]
    return "| %s%s | %s | %d | %d | %.3f %% | %.3f %% | %.3f |" % (
        name, note, where, e["rows"], e["held"], 100 * e["ours"], 100 * e["float64"],
        e["ratio"])


def command_section(cmd, shipped):
    """docs/calibration.md's table of the default fit on every log (`cmd`: commands())."""
    out = [LOGS_BEGIN,
           "| log | where | rows | samples held | spread, default fit | spread, float64 fit "
           "| ratio |", "|---|---|---|---|---|---|---|"]
    out += [command_row(n, cmd[n], n in shipped) for n in sorted(cmd)]
    out += ["", "*Written by `make bench` (desktop/benchmarks/accuracy.py) from the logs "
            "here when it ran; tests/test_datasets.py runs each log again and compares. Spread: "
            "std(|corrected|) / mean(|corrected|) over every row of the file; float64 fit: "
            "the same 10-element model fitted to every row in float64 "
            "(desktop/benchmarks/reference.py).*", LOGS_END]
    return "\n".join(out)


def grid(smoke):
    step = 45 if smoke else 15
    tilts = (-20, 0, 20) if smoke else (-30, -15, 0, 15, 30)
    return [(yaw, p, r) for yaw in range(0, 360, step) for p in tilts for r in tilts]


def still_readings(hard, soft, poses):
    """Raw (mag, accel) counts at each pose, noise off: one board, one pose per second."""
    from host_sim import motion
    from host_sim.boards import make_board
    from host_sim.world import World
    pts = [(i, float(y), float(p), float(r)) for i, (y, p, r) in enumerate(poses)]
    w = World(field_ut=50.0, inclination_deg=60.0, hard_iron_ut=hard, soft_iron=soft,
              motion=motion.waypoints(pts))
    b = make_board("qmc5883l", world=w, seed=9, noise=False, accel=True)
    b.bus.writeto_mem(common.QMC_ADDR, 0x0B, b"\x01")
    b.bus.writeto_mem(common.QMC_ADDR, 0x09, b"\x0d")
    b.bus.writeto_mem(common.MPU_ADDR, 0x6B, b"\x01")
    b.bus.writeto_mem(common.MPU_ADDR, 0x1C, b"\x00")
    out = []
    for i in range(len(poses)):
        b.clock.advance(i * 1000000 + 500000 - b.clock.now_us)
        # the QMC5883L holds a latched set until it is read: release the one from the last
        # pose, then take a fresh one a period later
        b.bus.readfrom_mem(common.QMC_ADDR, common.QMC_DATA, 6)
        b.clock.advance(10000)
        m = b.bus.readfrom_mem(common.QMC_ADDR, common.QMC_DATA, 6)
        a = b.bus.readfrom_mem(common.MPU_ADDR, common.MPU_ACCEL, 6)
        out.append(((common.le16(m, 0), common.le16(m, 2), common.le16(m, 4)),
                    (common.be16(a, 0), common.be16(a, 2), common.be16(a, 4))))
    return out


def _err(h, yaw):
    return (h - yaw + 180.0) % 360.0 - 180.0


def _stats(errs):
    rms = math.sqrt(sum(e * e for e in errs) / len(errs))
    return {"rms_deg": rms, "max_deg": max(abs(e) for e in errs)}


def float_heading(body_m, acc):
    # the heading guide's compute_heading on body-frame vectors (accel in g, AN4248 sign)
    g = (-acc[0] / 16384.0, acc[1] / 16384.0, acc[2] / 16384.0)
    return floatpath.compute_heading(g[0], g[1], g[2], body_m[0], -body_m[1], -body_m[2],
                                     0.0)


def headings(smoke):
    import numpy as np
    from desktop.benchmarks.reference import numpy_fit

    from firmware.axes import AxisMap
    from firmware.compass import Compass
    from firmware.calibrate.calibrator import Calibrator
    mmap = AxisMap("x,-y,-z")
    amap = AxisMap("-x,y,z")
    res = {}
    for name, (hard, soft) in SCENARIOS.items():
        n = 1500 if smoke else 6000
        mag, _ = common.session(n, dt_us=20000 if smoke else 5000, hard_iron_ut=hard,
                                soft_iron=soft, accel=False, seed=7)
        raw = common.raw_triples(mag)
        cal = Calibrator(model=10, counts_per_gauss=common.QMC_CPG)
        mm = floatpath.MinMaxCollector()
        for x, y, z in raw:
            cal.add(x, y, z)
            mm.collect(x, y, z)
        held = [tuple(cal.buffer.data[3 * i:3 * i + 3]) for i in range(cal.count)]
        mmcal = mm.compute()
        poses = grid(smoke)
        reads = still_readings(hard, soft, poses)
        row = {"held": cal.count, "poses": len(poses)}
        # the heading guide min/max, float
        errs = []
        for (yaw, _, _), (m, a) in zip(poses, reads):
            f = [0.0, 0.0, 0.0]
            floatpath.mag_apply_cal(mmcal, m, f)
            errs.append(_err(float_heading(f, a), yaw))
        row["minmax_seed004_float"] = _stats(errs)
        for model in MODELS:
            c = cal.solve(model=model, accept=False)
            comp = Compass()
            out = [0, 0, 0]
            b = [0, 0, 0]
            g = [0, 0, 0]
            errs = []
            for (yaw, _, _), (m, a) in zip(poses, reads):
                c.correct(m, out)
                mmap.apply(out, b)
                amap.apply(a, g)
                errs.append(_err(comp.update(b, g) * 360.0 / 65536.0, yaw))
            entry = {"ours": _stats(errs), "fit_error_x100": c.fit_error}
            if model != "minmax":
                v, invw, _ = numpy_fit(held, model)
                errs = []
                for (yaw, _, _), (m, a) in zip(poses, reads):
                    f = invw @ (np.array(m, dtype=float) - v)
                    errs.append(_err(float_heading(f, a), yaw))
                entry["float64"] = _stats(errs)
                entry["ratio_rms"] = entry["ours"]["rms_deg"] / entry["float64"]["rms_deg"]
            row[str(model)] = entry
        res[name] = row
    return res


def main():
    smoke = common.smoke()
    res = {"interpreter": common.interpreter()}
    try:
        res["logs"] = logs(smoke)
        res["commands"] = commands(smoke)
    except ImportError as e:  # no numpy
        res["logs"] = {"skipped": str(e)}
    res["headings"] = headings(smoke)
    common.emit(res)


if __name__ == "__main__":
    sys.exit(main())
