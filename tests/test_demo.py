"""`python -m host_sim demo` / `run` (make run): the world it builds, the heading-accuracy
machinery (calibrated heading within 0.5 deg on the tilted grid, for
each chip), MicroPython parity of the calibration, the human-readable run and the plot."""
import contextlib
import io
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, strategies as st

from desktop import demo
from tests import mp

GOAL_DEG = 0.5  # calibrated max error on the tilted grid, every chip but the AKM ones:
# their count is 0.15 uT, 1/167 of a 25 uT horizontal field (an AK8963's raw count, before
# its fuse-ROM trim, up to 0.22 uT): with the world's own iron and no noise the grid's worst
# is 0.71 deg (AK8963) and 0.46 deg (AK09916), half-count rounding on two axes, so 0.75
GOAL_AKM_DEG = 0.75
# the LIS3MDL's noise, 3.2 mG RMS on x and y and 4.1 mG on z (its datasheet, section 2.1;
# the QMC5883L's and MMC5603's are ~2 mG) enters the fit through the samples: fit error
# 0.7 % (QMC5883L 0.4 %), grid worst 0.35-0.67 deg over seeds 1-3, rms 0.16-0.30 deg
GOAL_NOISY_DEG = 0.75
# Seeds 1-12 measured 0.14-0.35 deg (HMC5883L boards) and 0.16-0.29 deg (QMC5883L). The
# HMC5883L's floor is the calibration's integer-count offset V: at the gain strong hard iron
# forces (820 counts/G) half a count is 0.06 uT, up to 0.2 deg of a 25 uT horizontal field.


def run_demo(*argv):
    """demo.main in-process; returns (exit code, stdout)."""
    f = io.StringIO()
    with contextlib.redirect_stdout(f):
        rc = demo.main(list(argv))
    return rc, f.getvalue()


_CACHE = {}


def demo_json(chip, seed=1):
    key = (chip, seed)
    if key not in _CACHE:
        rc, out = run_demo("--chip", chip, "--seed", str(seed), "--json")
        assert rc == 0, out
        _CACHE[key] = json.loads(out)
    return _CACHE[key]


# --- the world ------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(1, 41))
def test_iron_is_strong_rotated_symmetric_and_reproducible(seed):
    v, w, eigs = demo.demo_iron(seed)
    assert demo.demo_iron(seed) == (v, w, eigs)
    vn = np.linalg.norm(v)
    assert demo.HARD_IRON_MIN * demo.FIELD_UT <= vn <= demo.HARD_IRON_MAX * demo.FIELD_UT
    w = np.array(w)
    assert np.array_equal(w, w.T)
    ev = np.sort(np.linalg.eigvalsh(w))
    assert np.allclose(ev, np.sort(eigs), atol=1e-12)
    for (lo, hi), e in zip(demo.SOFT_IRON_EIGS, ev):
        assert lo <= e <= hi
    # rotated principal axes: W is far from diagonal
    assert np.max(np.abs(w - np.diag(np.diag(w)))) > 0.01


def test_different_seeds_give_different_worlds():
    worlds = {tuple(demo.demo_iron(s)[0]) for s in range(1, 21)}
    assert len(worlds) == 20


@given(st.lists(st.floats(-150, 150), min_size=3, max_size=3),
       st.lists(st.floats(-1.5, 1.5), min_size=9, max_size=9))
def test_largest_reading_bounds_every_field_direction_and_is_reached(v, wf):
    w = np.array(wf).reshape(3, 3)
    need = demo.largest_reading_ut(v, w.tolist())
    rng = np.random.default_rng(0)
    u = rng.normal(size=(2000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    reads = np.abs(u @ w.T * demo.FIELD_UT + np.array(v))
    assert reads.max() <= need + 1e-9
    # the bound is attained along each row's own direction
    best = max(abs(v[i]) + demo.FIELD_UT * np.linalg.norm(w[i]) for i in range(3))
    assert need == pytest.approx(best)


@given(st.floats(1, 900))
def test_range_is_the_most_sensitive_one_that_holds_the_field(need_ut):
    from host_sim import chips
    assert [fs for fs, _ in demo.full_scales("qmc5883l")] == [2, 8]
    assert [fs for fs, _ in demo.full_scales("qmc5883p")] == [2, 8, 12, 30]
    assert demo.full_scales("hmc5883l")[0] == (0.88, 0)
    for kind in chips.MAG_KINDS:
        table = [fs for fs, _ in demo.full_scales(kind)]
        opt, code, fs = demo.pick_range(kind, need_ut)
        assert opt == chips.mag(kind)["range_option"]
        assert dict(demo.full_scales(kind))[fs] == code
        i = table.index(fs)
        need_g = need_ut * demo.RANGE_MARGIN / 100
        if need_g <= table[-1]:
            assert need_g <= fs                          # holds it
            assert i == 0 or need_g > table[i - 1]       # and nothing more sensitive does
        else:
            assert fs == table[-1]


def test_stage_keeps_the_past_and_switches_the_future():
    from host_sim import motion
    st_ = demo.Stage(motion.flat_spin(period_s=10))
    st_.switch(5000000, motion.still(30, 20, -10))
    assert st_.at(2500000) == motion.flat_spin(period_s=10).at(2500000)
    assert st_.at(5000000) == (30.0, 20.0, -10.0)
    assert st_.at(9000000) == (30.0, 20.0, -10.0)


@given(st.floats(-1e4, 1e4))
def test_wrap180_is_in_range_and_congruent(d):
    w = demo.wrap180(d)
    assert -180.0 <= w < 180.0
    k = (d - w) / 360.0
    assert abs(k - round(k)) < 1e-9


# --- the heading machinery, independent of any fit --------------------------------------
def perfect_calibration(setup):
    """The world's own V and W^-1 as a Calibration (rounded to the format's integers)."""
    from firmware.calibration import Calibration
    v, b_eff, wi = setup.true_effective()
    k = 32700 / max(sum(abs(x) for x in row) for row in wi)  # rounding stays <= 32767
    q = [int(np.rint(wi[i][j] * k)) for i in range(3) for j in range(3)]
    field = int(np.rint(b_eff * setup.cpg / 100))
    return Calibration(model=10, offset=[int(np.rint(x)) for x in v], invw=q, field=field,
                       field_out=int(np.rint(field * k / 32768)))


def test_grid_heading_with_the_true_iron_and_no_noise_matches_the_true_heading():
    # Checks frames, axis maps, declination and the true heading without the calibrator:
    # on a noise-free QMC5883L (1 count = 0.0083 uT at +-2 G) the only errors left are
    # integer rounding, far below 0.05 deg.
    from firmware.trig import cdeg_to_kang
    from firmware.calibration import UNCALIBRATED
    s = demo.Setup("qmc5883l", 1, 30, noise=False)
    rows = demo.measure_grid(s, [perfect_calibration(s), UNCALIBRATED],
                             cdeg_to_kang(demo.DECLINATION_CDEG), n=2)
    assert len(rows) == len(demo.GRID_YAWS) * len(demo.GRID_TILTS)
    assert demo.error_stats(rows, 0)["max"] < 0.05
    # the true heading includes the declination
    assert {round(r[3] - r[0], 6) for r in rows} == {demo.DECLINATION_CDEG / 100}
    # and without calibration the strong hard iron ruins the heading
    assert demo.error_stats(rows, 1)["max"] > 30


# --- the demo: the accuracy goal, on CPython -----------------------------------------------
@pytest.mark.parametrize("seed", (1, 2, 3))
@pytest.mark.parametrize("chip", demo.CHIP_CHOICES)
def test_calibrated_heading_meets_the_goal_and_beats_minmax_and_none(chip, seed):
    # the accuracy goal on the demo's world (seed 1) and two more seeds, for every chip
    bound = (GOAL_AKM_DEG if chip in ("ak8963", "ak09916") else
             GOAL_NOISY_DEG if chip == "lis3mdl" else GOAL_DEG)
    r = demo_json(chip, seed)
    e = r["heading_error_deg"]
    assert set(e) >= {"uncalibrated", "minmax", "calibrated"}
    for m in ("uncalibrated", "minmax", "calibrated"):
        assert set(e[m]) >= {"max", "rms"}
        assert 0 <= e[m]["rms"] <= e[m]["max"]
    assert e["calibrated"]["max"] <= bound
    assert r["calibration"]["model"] == 10 and e["calibrated"]["rms"] <= 1.0  # issue goal
    print("%s seed %d: 10-element fit error %d.%02d %%, heading error rms %.2f deg, max %.2f"
          % (chip, seed, r["calibration"]["fit_error"] // 100, r["calibration"]["fit_error"] % 100,
             e["calibrated"]["rms"], e["calibrated"]["max"]))
    assert e["calibrated"]["max"] < e["minmax"]["max"] < e["uncalibrated"]["max"]
    assert e["calibrated"]["rms"] < e["minmax"]["rms"] < e["uncalibrated"]["rms"]


@pytest.mark.parametrize("chip", demo.CHIP_CHOICES)
def test_accepted_calibration_finds_the_worlds_iron(chip):
    r = demo_json(chip)
    c = r["calibration"]
    assert c["model"] == 10
    assert len(c["offset"]) == 3 and len(c["invw_q15"]) == 9
    assert all(isinstance(x, int) for x in c["offset"] + c["invw_q15"])
    for k in ("field", "field_out", "fit_error", "samples", "coverage", "counts_per_gauss"):
        assert isinstance(c[k], int)
    # against the world's truth (not the code's own output): V within 0.3 uT of |V| = 50..150
    # uT, W^-1 within 0.5 %, B within 0.3 uT
    v_true = np.array(r["world"]["hard_iron_ut"])
    v_fit = np.array(c["offset"]) * 100 / c["counts_per_gauss"]
    assert np.linalg.norm(v_fit - v_true) < 0.3
    w = np.array(r["world"]["soft_iron"])
    s = np.linalg.det(w) ** (1 / 3)
    wi_true = np.linalg.inv(w) * s
    wi_fit = np.array(c["invw_q15"]).reshape(3, 3) / 32768 * c["field"] / c["field_out"]
    assert np.max(np.abs(wi_fit - wi_true)) < 0.005
    assert abs(c["field"] * 100 / c["counts_per_gauss"] - demo.FIELD_UT * s) < 0.3


def test_every_chip_the_simulator_models_is_a_demo_choice():
    # host_sim/boards.py's magnetometers, each by its chip's name (the GY-271 / GY-87 are
    # breakouts of those chips, gy87 the demo's one-board choice)
    from host_sim.boards import CHIPS
    assert {c for c in CHIPS if c[:2] in ("qm", "hm", "li", "mm")} <= set(demo.CHIP_CHOICES)
    r = demo_json("qmc5883p")
    assert r["chip"] == "qmc5883p" and r["calibration"]["counts_per_gauss"] in (
        1000, 2500, 3750, 15000)                       # the QMC5883P's, not the QMC5883L's


def test_the_same_seed_repeats_and_another_seed_differs():
    a = demo_json("qmc5883l", 1)
    rc, out = run_demo("--chip", "qmc5883l", "--seed", "1", "--json")
    assert rc == 0 and json.loads(out) == a
    assert demo_json("qmc5883l", 2)["calibration"] != a["calibration"]


# --- MicroPython parity -----------------------------------------------------------------
def test_micropython_run_prints_what_cpython_prints():
    # the whole human-readable story, bit for bit, except the plot (CPython only)
    cp = mp.run(["-m", "host_sim", "run", "--no-plot"], micro=False)
    mpy = mp.run(["-m", "host_sim", "run"], micro=True)
    assert mpy == cp + "\nplot skipped: matplotlib runs on CPython only\n"


@pytest.mark.parametrize("chip", demo.CHIP_CHOICES)
def test_micropython_demo_prints_the_same_calibration(chip):
    argv = ["-m", "host_sim", "demo", "--chip", chip, "--seed", "1", "--json"]
    mpy = json.loads(mp.run(argv, micro=True))
    cp = demo_json(chip)
    assert mpy["calibration"] == cp["calibration"]
    # the same bits all the way: the heading errors too (json.loads makes floats comparable)
    assert mpy["heading_error_deg"] == cp["heading_error_deg"]
    assert "plot" not in mpy


def test_cpython_subprocess_demo_matches_in_process():
    argv = ["-m", "host_sim", "demo", "--chip", "qmc5883l", "--seed", "1", "--json"]
    assert json.loads(mp.run(argv, micro=False)) == demo_json("qmc5883l")


# --- the human-readable run and the plot ------------------------------------------------
def test_run_exits_0_and_tells_the_story():
    p = subprocess.run([sys.executable, "-m", "host_sim", "run", "--no-plot"], cwd=mp.ROOT,
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    out = p.stdout
    for section in ("QMC5883L", "hard iron V", "soft iron W", "figure-8", "coverage",
                    "Accepted calibration", "V (uT)", "B (uT)", "InvW (Q15)", "fit error",
                    "Heading accuracy", "uncalibrated", "min/max", "calibrated", "max / rms"):
        assert section in out, section
    assert "Plot:" not in out


def test_plot_is_written_when_matplotlib_is_present(tmp_path):
    pytest.importorskip("matplotlib", reason="matplotlib not installed (requirements.txt: make "
                        "venv)")
    path = tmp_path / "sub" / "cal.png"
    rc, out = run_demo("--chip", "qmc5883l", "--seed", "1", "--plot", str(path))
    assert rc == 0
    assert "Plot: %s" % path in out
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 50000


def test_json_mode_prints_one_object_and_no_plot_unless_asked(tmp_path):
    rc, out = run_demo("--chip", "qmc5883l", "--seed", "1", "--json")
    assert rc == 0
    assert len(out.strip().splitlines()) == 1
    assert "plot" not in json.loads(out)


def test_no_10_element_calibration_exits_1_and_says_why(monkeypatch):
    # 1 s of 50 Hz readings is 50 samples: a 10-element fit needs 100 (firmware/magcal.py)
    monkeypatch.setattr(demo, "TIME_LIMIT_FACTOR", 1)
    rc, out = run_demo("--chip", "qmc5883l", "--seconds", "1", "--json")
    assert rc == 1
    r = json.loads(out)
    assert r["rejected"] and "heading_error_deg" not in r and "calibration" not in r
    rc, out = run_demo("--chip", "qmc5883l", "--seconds", "1", "--no-plot")
    assert rc == 1 and "no 10-element calibration accepted" in out


def test_bad_usage_exits_2_with_one_line_on_stderr(capsys):
    for argv, word in ((["--chip", "bmm150"], "--chip"), (["--seed"], "--seed"),
                       (["--seconds", "0"], "--seconds"), (["--frob"], "--frob"),
                       (["--samples", "x"], "--samples")):
        assert demo.main(argv) == 2
        cap = capsys.readouterr()
        assert cap.out == ""
        lines = cap.err.splitlines()
        assert len(lines) == 1 and lines[0].startswith("host_sim demo: error: ") \
            and word in lines[0], cap.err
    rc, out = run_demo("--help")
    assert rc == 0 and "--chip" in out


# ---- docs/design.md quotes `make run`: written by it, checked here ---------------------------

def test_design_md_quotes_what_make_run_prints():
    from desktop import run
    p = subprocess.run([sys.executable, "-m", "host_sim", "run", "--no-plot"], cwd=mp.ROOT,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    doc = open(run.DOC, encoding="utf-8").read()
    i, j = doc.index(run.BEGIN), doc.index(run.END) + len(run.END)
    assert doc[i:j] == run.excerpt(p.stdout), "make run rewrites it: python -m host_sim run " \
                                              "--update-doc"
    assert "error max / rms" in doc[i:j] and "Accepted calibration: model 10" in doc[i:j]


def test_update_doc_rewrites_the_excerpt_only_for_the_default_world(tmp_path, monkeypatch,
                                                                    capsys):
    from desktop import run
    doc = tmp_path / "design.md"
    doc.write_text("intro\n%s\n```\nold figures\n```\n%s\nafter\n" % (run.BEGIN, run.END))
    monkeypatch.setattr(run, "DOC", str(doc))
    assert run.main(["--no-plot", "--seed", "2", "--update-doc"]) == 0
    err = capsys.readouterr().err
    assert "old figures" in doc.read_text() and "not written" in err and "--seed" in err
    assert run.main(["--no-plot", "--update-doc"]) == 0
    out = capsys.readouterr().out
    text = doc.read_text()
    assert "old figures" not in text and text.startswith("intro\n") and text.endswith("after\n")
    assert run.excerpt(out) in text and "excerpt of this run rewritten" in out
