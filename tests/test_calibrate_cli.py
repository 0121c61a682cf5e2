"""`python -m host_sim calibrate`: parsing, scaling into int16, JSON, refusals, MicroPython.
(tests/test_cli_robust.py: messy files, every option's validation, --force, --out.)"""
import json
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import given, strategies as st

from host_sim.cli import calibrate as cli
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
    assert "refused: planar" in capsys.readouterr().out


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
