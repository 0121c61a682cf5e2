"""Glitch rows in a good log (desktop/glitches.py): an all-zero row, a row at the rails,
a row far off the ellipsoid and one far outside the others change the calibrate command's fit
by less than 0.5 % of B, and one line on stderr says how many of each kind were left out.

The good log is one the repository ships: datasets/qmc5883l_tomisuarez_filtered.csv without
its 3000 still rows, every 6th row (3291 rows; the command fits it at 2.87 %).
"""
import json
import os

import pytest
from hypothesis import given, settings, strategies as st

from desktop import calibrate, glitches

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LOG = os.path.join(ROOT, "datasets", "qmc5883l_tomisuarez_filtered.csv")
GOAL_PCT = 0.5
ZERO = (0, 0, 0)                # a failed read
RAIL = (32767, 1200, -400)      # an axis clipped at the int16 rail
OFF = (8200, 1500, 4700)        # inside the others' range, off the ellipsoid (2.5 B corrected)
FAR = (30000, 30000, 30000)     # far outside the others (alone: the fit was not an ellipsoid)


def good_rows():
    with open(LOG) as f:
        rows = [tuple(int(v) for v in line.split(",")) for line in f.read().splitlines()[1:]]
    return rows[3000::6]


def write(tmp_path, rows, name="log.csv"):
    p = tmp_path / name
    p.write_text("mx,my,mz\n" + "".join("%d,%d,%d\n" % r for r in rows))
    return str(p)


def fit(path, *extra):
    c, rej, info = calibrate.run(calibrate._parser().parse([path] + list(extra)))
    assert rej is None, rej
    return c, info


def change_pct(c0, c1, rows):
    """The largest difference between the two fits' corrected samples over the good rows,
    in percent of B (of the first fit's output field)."""
    a, b = [0, 0, 0], [0, 0, 0]
    worst = 0
    for r in rows:
        c0.correct(r, a)
        c1.correct(r, b)
        worst = max(worst, sum((a[i] - b[i]) ** 2 for i in range(3)) ** 0.5)
    return 100.0 * worst / c0.field_out


V = (6195, 248, 3483)           # the good log's hard iron (counts)


def scaled(r, k):
    """Row r moved k times as far from the hard iron: a row (k - 1) x 100 % off the fit."""
    return tuple(int(V[i] + k * (r[i] - V[i])) for i in range(3))


# (row index, glitch row, the kind the JSON's glitch_rows counts it as)
CASES = {
    "30 % off": [(1500, "30 % off", "off_ellipsoid")],
    "all-zero": [(1000, ZERO, "all_zero")],
    "rail": [(2000, RAIL, "rails")],
    "off the ellipsoid": [(3291, OFF, "off_ellipsoid")],
    "far outside": [(0, FAR, "outside_range")],
    "three": [(1000, ZERO, "all_zero"), (2000, RAIL, "rails"), (3291, OFF, "off_ellipsoid")],
    "four": [(0, FAR, "outside_range"), (1000, ZERO, "all_zero"), (2000, RAIL, "rails"),
             (3291, OFF, "off_ellipsoid")],
}


@pytest.mark.parametrize("extra", [(), ("--board-like",)])
@pytest.mark.parametrize("case", sorted(CASES))
def test_glitch_rows_move_the_fit_less_than_half_a_percent_and_are_reported(
        tmp_path, capsys, case, extra):
    rows = good_rows()
    assert len(rows) == 3291
    c0, _ = fit(write(tmp_path, rows, "good.csv"), *extra)
    bad = list(rows)
    for at, r, _ in sorted(CASES[case], reverse=True):
        bad.insert(at, scaled(rows[at], 1.3) if r == "30 % off" else r)
    path = write(tmp_path, bad)
    c1, info = fit(path, *extra)
    assert change_pct(c0, c1, rows) < GOAL_PCT
    capsys.readouterr()
    assert calibrate.main([path, "--json"] + list(extra)) == 0
    cap = capsys.readouterr()
    g = json.loads(cap.out)["glitch_rows"]
    kinds = [k for _, _, k in CASES[case]]
    assert g == dict((k, kinds.count(k)) for k in g)
    assert cap.err.count("\n") == 1 and "left out of the fit" in cap.err


def test_without_the_glitch_rules_one_row_decides_the_fit(tmp_path):
    # what the rules are for: the all-zero row fed to the Calibrator with the others gives a
    # fit error of 19.5 % (refused), the row far outside a quadric that is no ellipsoid
    from firmware.calibrate.calibrator import Calibrator
    from firmware.errors import CalibrationRejected
    rows = good_rows()
    for r, reason in ((ZERO, "fit_error_high"), (FAR, "singular")):
        cal = Calibrator(model=10, capacity=len(rows) + 1, separation=1)
        for x in rows + [r]:
            cal.add(*x)
        with pytest.raises(CalibrationRejected) as e:
            cal.solve()
        assert e.value.reason == reason


def test_a_clean_log_loses_no_row(tmp_path, capsys):
    path = write(tmp_path, good_rows())
    assert calibrate.main([path, "--json"]) == 0
    cap = capsys.readouterr()
    assert cap.err == "" and set(json.loads(cap.out)["glitch_rows"].values()) == {0}


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 10 ** 6), st.sampled_from([0.002, 0.01, 0.03]))
def test_gaussian_noise_alone_is_never_left_out(seed, noise):
    # rows on an ellipsoid with Gaussian noise of up to 3 % of B: no row is SPREADS robust
    # spreads off (once in 500 million rows), none is far outside the others
    import random
    rng = random.Random(seed)
    pts, keep = [], bytearray(b"\x01" * 400)
    for _ in range(400):
        d = [rng.gauss(0, 1) for _ in range(3)]
        n = sum(v * v for v in d) ** 0.5
        r = 1000 * (1 + rng.gauss(0, noise))
        pts += [int(1500 + 1.3 * r * d[0] / n), int(-800 + r * d[1] / n),
                int(300 + 0.8 * r * d[2] / n)]
    assert glitches.box_outliers(pts, keep) == []
    c, rej, _ = calibrate._solve(_filled(pts), 10)
    assert glitches.radius_outliers(c, pts, keep) == []


def _filled(pts):
    from firmware.calibrate.calibrator import Calibrator
    cal = Calibrator(model=10, capacity=len(pts) // 3, separation=1)
    for i in range(0, len(pts), 3):
        cal.add(pts[i], pts[i + 1], pts[i + 2])
    return cal


def test_the_same_rows_are_left_out_under_micropython(tmp_path):
    # the calibrate command also runs on MicroPython (a log of 20000 rows within its heap:
    # glitches.kth counts instead of sorting copies); the same rows out, the same fit
    from tests.test_cli_robust import mp_call
    rows = good_rows()
    bad = rows[:1000] + [ZERO] + rows[1000:2000] + [RAIL] + rows[2000:] + [OFF, FAR]
    path = write(tmp_path, bad)
    keys = ("offset_counts", "invw_q15", "field_counts", "fit_error_x100", "glitch_rows")
    res = [mp_call([path, "--json"], micro) for micro in (False, True)]
    for rc, out, err in res:
        assert rc == 0 and err.count("\n") == 1, err
    cp, mpy = json.loads(res[0][1]), json.loads(res[1][1])
    assert [cp[k] for k in keys] == [mpy[k] for k in keys]
    assert cp["glitch_rows"] == {"all_zero": 1, "rails": 1, "outside_range": 1,
                                 "off_ellipsoid": 1}
    rc, out, err = mp_call([LOG, "--json"], True)   # the whole shipped log, 22745 rows
    assert rc == 0 and json.loads(out)["model"] == 10, err
