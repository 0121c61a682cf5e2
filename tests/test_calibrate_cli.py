"""`python -m host_sim calibrate`: parsing, scaling into int16, JSON, refusals, MicroPython.
(tests/test_cli_robust.py: messy files, every option's validation, --force, --out.)"""
import json
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import given, strategies as st

from desktop import calibrate as cli
from tests import mp



@given(st.integers(-10 ** 12, 10 ** 12), st.integers(0, 9), st.integers(-3, 3))
def test_decimal_text_is_parsed_exactly(m, d, e):
    s = str(abs(m)).rjust(d + 1, "0")
    text = ("-" if m < 0 else "") + (s[:-d] + "." + s[-d:] if d else s)
    if e:
        text += "e%d" % e
    v, dec = cli.parse_decimal(text)
    assert Fr(v, 10 ** dec) == Fr(m, 10 ** d) * Fr(10) ** e


def test_parse_refuses_text():
    for bad in ("", "-", "1.2.3", "abc", "1e"):
        with pytest.raises(ValueError):
            cli.parse_decimal(bad)


def write_csv(path, rows, header="mx,my,mz", fmt="%.2f"):
    with open(path, "w") as f:
        f.write(header + "\n")
        for r in rows:
            f.write(",".join(fmt % v for v in r) + "\n")
    return str(path)


def test_decimals_are_scaled_by_the_largest_power_of_ten_that_fits(tmp_path):
    p = write_csv(tmp_path / "a.csv", [(59.73, -1.5, 0.01), (-3.2, 4.0, 12.0)])
    assert cli.choose_scale(p) == (2, 2)                   # 5973 fits, 59730 does not
    assert list(cli.scaled_rows(p, 2))[0] == [5973, -150, 1]
    p = write_csv(tmp_path / "b.csv", [(0.5, 0.25, -0.125)], fmt="%g")
    assert cli.choose_scale(p)[0] == 4                     # 5000, 2500, -1250
    p = write_csv(tmp_path / "c.csv", [(120, -7, 3)], fmt="%d")
    assert cli.choose_scale(p)[0] == 0                     # integer counts stay counts
    p = write_csv(tmp_path / "d.csv", [(40000, -7, 3)] * 3, fmt="%d")
    assert cli.choose_scale(p)[0] == -1                    # every row too large: 4000
    # one corrupt row among ordinary ones does not rescale the file (it is skipped later)
    p = write_csv(tmp_path / "e.csv", [(1200, -7, 3)] * 20 + [(40000, -7, 3)], fmt="%d")
    assert cli.choose_scale(p)[0] == 0
    p = write_csv(tmp_path / "f.csv", [(59.73, -1.5, 0.01)] * 20 + [(1e6, 1, 1)])
    assert cli.choose_scale(p)[0] == 2


def sphere_csv(tmp_path, name="s.csv", n=3000, centre=(20.0, -35.5, 12.25), radius=48.0,
               axes=(1.0, 1.0, 1.0), flat=False, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    if flat:
        u[:, 2] = 0.01 * u[:, 2]
    u /= np.linalg.norm(u, axis=1)[:, None]
    pts = u * np.array(axes) * radius + np.array(centre) + rng.normal(scale=0.1, size=u.shape)
    return write_csv(tmp_path / name, pts)


def test_json_reports_the_calibration_in_the_files_units(tmp_path, capsys):
    p = sphere_csv(tmp_path)
    assert cli.main([p, "--model", "10", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert set(r) >= {"model", "offset", "invw", "invw_q15", "field", "fit_error_percent",
                      "samples_used", "coverage_percent"}
    assert r["model"] == 10 and len(r["invw_q15"]) == 9
    assert np.allclose(r["offset"], (20.0, -35.5, 12.25), atol=0.05)
    assert abs(r["field"] - 48.0) < 0.05
    assert np.allclose(r["invw"], np.eye(3), atol=0.005)
    assert r["fit_error_percent"] < 1 and r["coverage_percent"] > 90
    assert 100 <= r["samples_used"] <= cli.DESKTOP_CAPACITY


def test_invw_in_json_maps_the_ellipsoid_onto_a_sphere_of_radius_field(tmp_path, capsys):
    p = sphere_csv(tmp_path, axes=(1.3, 1.0, 0.8))
    assert cli.main([p, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    data = np.genfromtxt(p, delimiter=",", names=True)
    f = np.c_[data["mx"], data["my"], data["mz"]]
    mags = np.linalg.norm((f - r["offset"]) @ np.array(r["invw"]).T, axis=1)
    assert abs(mags.mean() / r["field"] - 1) < 0.002 and mags.std() / mags.mean() < 0.005


def test_refusal_exits_1_with_the_reason_and_what_to_try(tmp_path, capsys):
    p = sphere_csv(tmp_path, flat=True)
    assert cli.main([p, "--json"]) == 1
    cap = capsys.readouterr()
    r = json.loads(cap.out)
    assert r["rejected"] == "planar" and r["detail"] and "--force" in r["hint"]
    assert cap.err.count("\n") == 1 and "refused (planar)" in cap.err
    assert cli.main([p]) == 1
    # without --json: the refusal once, on stderr, with what to try; nothing on stdout
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1 and cap.err.count("planar") == 1
    assert cap.err.startswith("host_sim calibrate: calibration refused (planar): ")
    assert "try: " in cap.err and "--force" in cap.err


def test_bad_usage_exits_2(tmp_path, capsys):
    assert cli.main([]) == 2
    assert cli.main(["x.csv", "--model", "5"]) == 2
    assert cli.main(["x.csv", "--bogus"]) == 2
    assert cli.main([str(tmp_path / "missing.csv")]) == 2
    p = tmp_path / "nohead.csv"
    p.write_text("1,2,3\n")
    assert cli.main([str(p)]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and "mx,my,mz" in cap.err and "--columns" in cap.err
    assert cli.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "--capacity" in out and "300" in out and "exit status" in out


def test_skip_drops_leading_rows(tmp_path, capsys):
    p = sphere_csv(tmp_path)
    assert cli.main([p, "--json", "--skip", "1000"]) == 0
    with_skip = json.loads(capsys.readouterr().out)
    assert cli.main([p, "--json"]) == 0
    assert with_skip != json.loads(capsys.readouterr().out)


def test_counts_per_gauss_enables_the_field_check(tmp_path, capsys):
    p = sphere_csv(tmp_path, centre=(100, 200, 300), radius=9000)  # "counts"
    # 9000 counts at 1090 counts/G is 826 uT: refused
    assert cli.main([p, "--json", "--counts-per-gauss", "1090", "--units", "counts"]) == 1
    assert json.loads(capsys.readouterr().out)["rejected"] == "field_out_of_range"
    assert cli.main([p, "--json", "--counts-per-gauss", "12000", "--units", "counts"]) == 0
    assert abs(json.loads(capsys.readouterr().out)["field_ut"] - 75) < 0.1


def test_runs_under_micropython_with_the_same_result(tmp_path):
    p = sphere_csv(tmp_path, axes=(1.2, 1.0, 0.9))
    cp = json.loads(mp.run(["-m", "host_sim", "calibrate", p, "--json"], micro=False))
    mpy = json.loads(mp.run(["-m", "host_sim", "calibrate", p, "--json"], micro=True))
    assert cp["invw_q15"] == mpy["invw_q15"] and cp["samples_used"] == mpy["samples_used"]
    assert np.allclose(cp["offset"], mpy["offset"]) and cp["field"] == mpy["field"]


def _clipped_csv(tmp_path, name, centre, radius, rail_lo, rail_hi, markers=0, marker=-4096):
    rng = np.random.default_rng(7)
    u = rng.normal(size=(4000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    pts = np.round(u * radius + np.array(centre) + rng.normal(scale=2.0, size=u.shape))
    pts = np.clip(pts, rail_lo, rail_hi)  # the chip clips at its rails
    rows = [list(map(int, p)) for p in pts]
    for k in range(markers):  # overflow markers on a whole sample, as the HMC5883L writes them
        rows[k * 37] = [marker, marker, marker]
    return write_csv(tmp_path / name, rows, fmt="%d"), int((np.abs(pts) >= 32767).any(axis=1).sum())


def test_samples_at_the_int16_rails_never_enter_the_fit_and_are_counted(tmp_path, capsys):
    # a QMC5883L at +-2 G clipping: the centre 27000 counts + 6000 reaches past 32767
    p, n_rail = _clipped_csv(tmp_path, "clip.csv", (27000, 0, 0), 6000, -32768, 32767)
    assert n_rail > 30
    assert cli.main([p, "--json", "--sensor", "qmc5883l", "--units", "counts"]) == 0
    out, err = capsys.readouterr()
    r = json.loads(out)
    assert abs(r["offset"][0] - 27000) < 0.005 * 6000 and abs(r["field"] - 6000) < 30
    assert "sample(s) at the sensor's rails dropped" in err
    n = int(err.split(" sample(s) at the sensor's rails")[0].split()[-1])
    assert n >= n_rail  # every clipped row, one reading 32767 counted


def test_hmc5883l_overflow_markers_are_dropped_not_a_singular_fit(tmp_path, capsys):
    p, _ = _clipped_csv(tmp_path, "hmc.csv", (120, -80, 40), 600, -2048, 2047, markers=40)
    assert cli.main([p, "--json", "--sensor", "hmc5883l", "--units", "counts"]) == 0
    out, err = capsys.readouterr()
    r = json.loads(out)
    assert abs(r["offset"][0] - 120) < 5 and "40 sample(s) at the sensor's rails dropped" in err


# ---- what a newcomer types: one line on stderr saying what to do, the documented status -----
# Subprocesses, as a user runs them: no traceback ever, errors on one line.

import os
import subprocess
import sys


def cli_run(*argv, micro=False):
    exe = [mp.MICROPYTHON] if micro else [sys.executable]
    p = subprocess.run(exe + ["-m", "host_sim"] + [str(a) for a in argv], cwd=mp.ROOT,
                       env=mp._env(micro), capture_output=True, text=True, timeout=300)
    assert "Traceback" not in p.stderr and "Traceback" not in p.stdout, p.stderr
    return p.returncode, p.stdout, p.stderr


def one_error_line(err):
    lines = err.splitlines()
    assert len(lines) == 1 and ": error: " in lines[0], err
    return lines[0]


def qmc_log(tmp_path, n=600, name="qmc.csv", comment=True):
    """A QMC5883L log at 2 G: 12000 counts/G, 50 uT = 6000 counts around hard iron of 4800,
    -3600, 3000 counts (the simulated GY-271's), as examples/log_csv.py writes it."""
    rng = np.random.default_rng(5)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    pts = np.round(u * 6000 + (4800, -3600, 3000) + rng.normal(scale=3, size=u.shape))
    p = tmp_path / name
    head = "# qmc5883l range_code 0 counts_per_gauss 12000\n" if comment else ""
    p.write_text(head + "mx,my,mz\n" + "".join("%d,%d,%d\n" % tuple(r) for r in pts))
    return str(p)


def test_the_loggers_sensor_line_states_the_board(tmp_path, capsys):
    # examples/log_csv.py writes '# qmc5883l range_code 0 counts_per_gauss 12000' above the
    # header: calibrate --out needs no --sensor then, and the field check is on
    from desktop import calfile
    p = qmc_log(tmp_path)
    out = str(tmp_path / "cal.json")
    assert cli.main([p, "--out", out, "--json"]) == 0
    cap = capsys.readouterr()
    r = json.loads(cap.out)
    assert cap.err == "" and r["sensor"] == "qmc5883l" and r["range_code"] == 0
    assert abs(r["field_ut"] - 50) < 0.5 and calfile.read(out)["counts_per_gauss"] == 12000
    # the same counts logged at 8 G (range code 1): 3000 counts/G, 6000 counts is 200 uT
    text = open(p).read().replace("range_code 0 counts_per_gauss 12000",
                                  "range_code 1 counts_per_gauss 3000")
    p8 = tmp_path / "q8.csv"
    p8.write_text(text)
    assert cli.main([str(p8), "--json"]) == 1
    r = json.loads(capsys.readouterr().out)
    assert r["rejected"] == "field_out_of_range" and "3000 counts/G" in r["detail"]
    # a bare log fits in its own counts, without the board's field check
    assert cli.main([qmc_log(tmp_path, name="bare.csv", comment=False), "--json"]) == 0
    assert "field_ut" not in json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("argv, said", [
    (["--range", "8"], "--range 8 differs"),
    (["--sensor", "qmc5883l", "--range", "8"], "--sensor qmc5883l --range 8 differs"),
    (["--counts-per-gauss", "3000"], "--counts-per-gauss 3000 differs"),
    (["--units", "uT"], "--units uT differs"),
])
def test_options_that_differ_from_the_loggers_line_win_with_one_warning(tmp_path, capsys,
                                                                         argv, said):
    p = qmc_log(tmp_path)
    cli.main([p, "--json", "--force"] + argv)
    cap = capsys.readouterr()
    lines = [ln for ln in cap.err.splitlines() if "the log's line" in ln]
    assert len(lines) == 1 and said in lines[0] and "(the options win)" in lines[0], cap.err
    assert lines[0].startswith("host_sim calibrate: warning: ")
    assert any(said in w for w in json.loads(cap.out)["warnings"])


def test_a_loggers_line_naming_a_range_the_chip_lacks_is_refused_in_one_line(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text(open(qmc_log(tmp_path)).read().replace("range_code 0", "range_code 7"))
    rc, out, err = cli_run("calibrate", p)
    line = one_error_line(err)
    assert rc == 2 and out == "" and "qmc5883l has no range code 7" in line and "1: 8 G" in line


def test_capacity_is_bounded_by_what_the_calibrator_holds(tmp_path):
    from firmware.calibrate.samples import MAX_CAPACITY
    p = qmc_log(tmp_path)
    rc, out, err = cli_run("calibrate", p, "--capacity", MAX_CAPACITY + 1)
    line = one_error_line(err)
    assert rc == 2 and out == "" and "--capacity" in line and "..%d" % MAX_CAPACITY in line
    rc, out, err = cli_run("calibrate", p, "--capacity", MAX_CAPACITY, "--json")
    assert rc == 0, err


def test_a_log_of_another_chip_is_counted_once_and_the_warning_says_which(tmp_path):
    p = qmc_log(tmp_path)
    rc, out, err = cli_run("calibrate", p, "--sensor", "hmc5883l", "--json")
    r = json.loads(out)
    assert rc == 1 and r["rows"] == 600 and r["skipped_rows"] > 500   # not 1176 rows
    note = [w for w in r["warnings"] if "outside hmc5883l's output" in w]
    assert len(note) == 1 and "--sensor qmc5883l" in note[0], r["warnings"]
    assert "log more samples" not in r["hint"] and "--sensor" in r["hint"]
    assert "outside hmc5883l's output" in err and "refused" in err.splitlines()[-1]
    rc, out, err = cli_run("calibrate", p, "--sensor", "hmc5883l")
    assert rc == 1 and out == "" and "(600 rows, %d skipped;" % r["skipped_rows"] in err
    # no comment naming the chip: the int16 counts still point at the QMC chips
    p = qmc_log(tmp_path, name="bare.csv", comment=False)
    rc, out, _ = cli_run("calibrate", p, "--sensor", "hmc5883l", "--json")
    assert rc == 1 and any("--sensor qmc5883l or qmc5883p" in w
                           for w in json.loads(out)["warnings"])
    # what the warning says works
    rc, out, err = cli_run("calibrate", p, "--sensor", "qmc5883l", "--json")
    assert rc == 0 and json.loads(out)["warnings"] == [] and err == ""


def test_every_row_outside_the_chip_is_one_line_saying_what_to_give(tmp_path):
    p = tmp_path / "far.csv"
    p.write_text("mx,my,mz\n" + "".join("%d,%d,%d\n" % (9000 + k, 5000, -4000)
                                        for k in range(50)))
    rc, out, err = cli_run("calibrate", str(p), "--sensor", "hmc5883l")
    line = one_error_line(err)
    assert rc == 2 and "no row within -2048..2047" in line and "--sensor qmc5883l" in line


def test_a_labelled_log_is_read_with_the_columns_the_error_names(tmp_path):
    rng = np.random.default_rng(2)
    u = rng.normal(size=(400, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    pts = np.round(u * 500 + (34, -292, 420))
    p = tmp_path / "labelled.txt"
    p.write_text("".join("Mx %d My %d Mz %d\n" % tuple(r) for r in pts))
    rc, out, err = cli_run("calibrate", str(p))
    line = one_error_line(err)
    assert rc == 2 and "--columns 2,4,6" in line
    rc, out, err = cli_run("calibrate", str(p), "--columns", "2,4,6", "--json")
    r = json.loads(out)
    assert rc == 0 and r["rows"] == 400 and np.allclose(r["offset"], (34, -292, 420), atol=3)


def test_values_glued_to_their_labels_are_refused_with_how_to_strip_them(tmp_path):
    rng = np.random.default_rng(4)
    u = rng.normal(size=(300, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    pts = np.round(u * 500 + (34, -292, 420))
    p = tmp_path / "glued.txt"
    p.write_text("".join("Mx:%d,My:%d,Mz:%d\n" % tuple(r) for r in pts))
    rc, out, err = cli_run("calibrate", str(p))
    line = one_error_line(err)
    assert rc == 2 and "carry their labels" in line and "--columns 1,2,3" in line
    sed = line.split("e.g. ")[1].split(" %s" % p)[0]          # sed -E 's/.../g'
    assert sed.startswith("sed -E '")
    clean = tmp_path / "clean.csv"                              # what the sed does
    import re as _re
    expr = sed.split("'")[1].split("/")
    clean.write_text(_re.sub(expr[1], expr[2], p.read_text()))
    rc, out, err = cli_run("calibrate", str(clean), "--columns", "1,2,3", "--json")
    assert rc == 0 and json.loads(out)["rows"] == 300, err


UNIT_SPELLINGS = {"uT": ("uT", "\u00b5T", "\u03bcT", "ut", "UT", "microtesla", "Microtesla"),
                  "mG": ("mG", "mg", "milligauss"), "G": ("G", "g", "gauss", "Gauss"),
                  "nT": ("nT", "nt", "nanotesla"), "counts": ("counts", "COUNTS", "raw")}


@pytest.mark.parametrize("unit", sorted(UNIT_SPELLINGS))
def test_units_are_read_in_every_spelling_the_docs_use(tmp_path, unit):
    p = sphere_csv(tmp_path, n=500)          # decimal values around 48
    res = set()
    for spelling in UNIT_SPELLINGS[unit]:
        rc, out, err = cli_run("calibrate", p, "--units", spelling, "--json", "--force",
                               "--date", "2025-01-02T03:04:05Z")
        assert rc == 0, (spelling, err)
        r = json.loads(out)
        res.add(json.dumps([r["invw_q15"], r["offset_counts"], r.get("field_ut")]))
    assert len(res) == 1
    rc, out, err = cli_run("calibrate", p, "--units", "furlongs")
    line = one_error_line(err)
    assert rc == 2 and "microtesla" in line and "gauss" in line


def test_sensor_names_in_any_case_and_breakouts_by_their_name(tmp_path):
    from boards.breakouts import BREAKOUTS
    p = qmc_log(tmp_path)
    base = ["calibrate", p, "--json", "--date", "2025-01-02T03:04:05Z"]
    rc, out, _ = cli_run(*(base + ["--sensor", "qmc5883l"]))
    ref = json.loads(out)
    for name in ("QMC5883L", "Qmc5883l", "qmc-5883l", "gy271", "GY-271", "gy_271"):
        rc, out, err = cli_run(*(base + ["--sensor", name]))
        r = json.loads(out)
        assert rc == 0 and r["sensor"] == "qmc5883l" and r["invw_q15"] == ref["invw_q15"], name
        if name.lower().startswith("gy"):  # the breakout's other chip is named
            assert "qmc5883p" in err and any("qmc5883p" in w for w in r["warnings"])
        else:
            assert err == ""
    for name in BREAKOUTS:                 # every breakout boards/breakouts.py knows
        for spelling in (name, name.upper(), name[:2] + "-" + name[2:]):
            rc, out, err = cli_run("calibrate", p, "--sensor", spelling, "--json")
            assert rc in (0, 1) and json.loads(out), (spelling, err)
    for name, chip in (("gy273", "hmc5883l"), ("GY-87", "hmc5883l")):
        rc, out, err = cli_run(*(base + ["--sensor", name]))
        assert '"sensor": "%s"' % chip in out or "%s's output" % chip in out, (name, out)


@pytest.mark.parametrize("chip", ["lsm303", "IST8310", "lsm9ds1", "bmm150", "mmc5883"])
def test_an_unsupported_chip_points_at_the_generic_path_which_fits_it(tmp_path, chip):
    p = sphere_csv(tmp_path, n=600)          # a log in uT of some chip
    rc, out, err = cli_run("calibrate", p, "--sensor", chip)
    line = one_error_line(err)
    assert rc == 2 and out == "" and "leave out --sensor" in line and "--units" in line
    rc, out, err = cli_run("calibrate", p, "--units", "uT", "--json")   # what it says
    r = json.loads(out)
    assert rc == 0 and abs(r["field"] - 48.0) < 0.1 and r["field_ut"] > 40


def test_an_accelerometer_breakout_is_no_magnetometer(tmp_path):
    rc, out, err = cli_run("calibrate", qmc_log(tmp_path), "--sensor", "GY-521")
    line = one_error_line(err)
    assert rc == 2 and "MPU6050" in line and "no magnetometer" in line


def test_the_new_spellings_under_micropython(tmp_path):
    p = qmc_log(tmp_path)
    for argv in (["--sensor", "GY-271"], ["--units", "\u00b5T", "--force"]):
        rc, out, err = cli_run("calibrate", p, "--json", *argv, micro=True)
        assert rc == 0, err
    rc, out, err = cli_run("calibrate", p, "--sensor", "lsm303", micro=True)
    assert rc == 2 and "leave out --sensor" in one_error_line(err)


# ---- the runner: --help describes each command; nothing escapes as a traceback ---------------

def test_top_level_help_describes_every_command_in_a_line():
    from desktop import __main__ as runner
    rc, out, err = cli_run("--help")
    assert rc == 0 and err == ""
    lines = out.splitlines()
    described = {}
    for cmd in runner._COMMANDS:
        mine = [ln for ln in lines if ln.split()[:1] == [cmd]]
        assert len(mine) == 1 and len(mine[0].split()) >= 5, (cmd, out)
        described[cmd] = mine[0]
    assert described["run"] != described["demo"]
    assert "make run" in described["run"] and "--chip" in described["demo"]
    assert "exit status" in out and "3 internal error" in out
    rc, out, err = cli_run()
    assert rc == 2 and out == "" and "no command" in one_error_line(err) and "--help" in err


def _commands():
    from desktop import __main__ as runner
    return list(runner._COMMANDS)


@pytest.mark.parametrize("cmd", _commands())
def test_bad_usage_of_every_command_is_one_line_exit_2(cmd):
    rc, out, err = cli_run(cmd, "--no-such-option")
    line = one_error_line(err)
    assert rc == 2 and line.startswith("host_sim %s: error: " % cmd) and out == ""


def test_the_last_resort_names_the_problem_in_one_line(monkeypatch, capsys):
    from desktop import __main__ as runner
    from desktop import calibrate

    def boom(opts):
        raise RuntimeError("an invariant broke\nsecond line")
    monkeypatch.setattr(calibrate, "body", boom)
    assert runner.main(["calibrate", "x.csv"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "host_sim calibrate: internal error: RuntimeError: an " \
                                   "invariant broke second line" in err

    def unreadable(opts):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(calibrate, "body", unreadable)
    assert runner.main(["calibrate", "x.csv"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("host_sim calibrate: error: ")
    assert runner.main(["nonsense"]) == 2 and capsys.readouterr().err.count("\n") == 1
