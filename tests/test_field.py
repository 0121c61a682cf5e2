"""firmware/field/wmm.py against the full float World Magnetic Model (pygeomag), plus its inputs,
validity window, table checks, heap and MicroPython parity, and the `field` / `wmm` commands.

Goals (docs/field_model.md): at |lat| <= 60 deg over 2025.0-2030.0, declination RMS <= 0.1 deg
and max <= 0.5 deg, inclination max <= 0.3 deg, total field within 0.5 %.
"""
import json
import os
import random
import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from firmware.field import wmm as field
from firmware.field.wmm import FieldModel, FieldTableError, decimal_year_e3
from desktop import wmm
from desktop.benchmarks import fieldacc
from tests import intcheck, mp

pygeomag = pytest.importorskip("pygeomag", reason="pygeomag not installed (requirements.txt: "
                               "make venv)")
ROOT = mp.ROOT
TABLE = os.path.join(ROOT, "firmware", "field", "wmm2025.bin")

DECL_RMS_DEG = fieldacc.GOALS["decl_rms_deg"]
DECL_MAX_DEG = fieldacc.GOALS["decl_max_deg"]
INCL_MAX_DEG = fieldacc.GOALS["incl_max_deg"]
FIELD_MAX_PCT = fieldacc.GOALS["field_max_pct"]


@pytest.fixture(scope="module")
def model():
    with FieldModel() as m:
        yield m


@pytest.fixture(scope="module")
def reference():
    return fieldacc.reference()


def test_accuracy_against_the_full_model_within_60_deg(model, reference):
    errs = fieldacc.errors(model, reference, fieldacc.points(random.Random(2025), 10000, 0, 60))
    s = fieldacc.summary(errs)
    print("\n|lat| <= 60: %s" % json.dumps({k: round(v, 4) for k, v in s.items()}))
    assert s["decl_rms_deg"] <= DECL_RMS_DEG
    assert s["decl_max_deg"] <= DECL_MAX_DEG
    assert s["incl_max_deg"] <= INCL_MAX_DEG
    assert s["field_max_pct"] <= FIELD_MAX_PCT


def test_polar_band_figures(model, reference):
    """|lat| > 60 deg: reported; declination is held to the goals only where WMM itself trusts
    a compass (H >= 6000 nT, outside its caution zone); inclination and field everywhere."""
    errs = fieldacc.errors(model, reference, fieldacc.points(random.Random(2030), 3000, 60, 90))
    s = fieldacc.summary(errs)
    usable = [e for e in errs if e[3] >= fieldacc.H_TRUSTED_NT]
    su = fieldacc.summary(usable)
    print("\n|lat| > 60: %s" % json.dumps({k: round(v, 4) for k, v in s.items()}))
    print("|lat| > 60, H >= 6000 nT: %s" % json.dumps({k: round(v, 4) for k, v in su.items()}))
    assert s["incl_max_deg"] <= INCL_MAX_DEG
    assert s["field_max_pct"] <= FIELD_MAX_PCT
    assert su["decl_rms_deg"] <= DECL_RMS_DEG
    assert su["decl_max_deg"] <= DECL_MAX_DEG


def test_status_marks_weak_horizontal_field(model, reference):
    # the north magnetic dip pole region and a point near the south one (WMM2025 report)
    for lat, lon in ((86.0, 139.0), (-64.0, 135.0)):
        d, i, f, status = model.at(int(lat * 1e7), int(lon * 1e7), 2026000)
        h = reference.calculate(glat=lat, glon=lon, alt=0, time=2026.0).h
        assert h < 6000
        assert status == (field.STATUS_BLACKOUT if h < 2000 else field.STATUS_CAUTION)
    assert model.at(515000000, -1300000, 2026000)[3] == field.STATUS_OK  # London


def test_components_match_the_reference_in_nt(model, reference):
    rng = random.Random(7)
    for lat_e7, lon_e7, year_e3 in fieldacc.points(rng, 200, 0, 60):
        model.at(lat_e7, lon_e7, year_e3)
        r = reference.calculate(glat=lat_e7 / 1e7, glon=lon_e7 / 1e7, alt=0, time=year_e3 / 1000)
        # 0.5 % of the field is >= 110 nT anywhere (F >= 22 uT at sea level)
        for got, want in ((model.north_nt, r.x), (model.east_nt, r.y), (model.down_nt, r.z),
                          (model.horizontal_nt, r.h)):
            assert abs(got - want) <= 110, (lat_e7, lon_e7, year_e3, got, want)


def test_longitude_wraps_and_both_poles_answer(model):
    assert model.at(0, 1800000000, 2026000) == model.at(0, -1800000000, 2026000)
    for lat in (-900000000, 900000000):
        d, i, f, status = model.at(lat, 0, 2026000)
        assert abs(i) > 7000 and 20000 < f < 70000


def test_validity_window_is_not_extrapolated(model):
    assert model.at(0, 0, 2025000)[3] == field.STATUS_OK
    assert model.at(0, 0, 2030000)[3] == field.STATUS_OK
    for y in (2024999, 2030001, 2031000, 0):
        assert model.at(0, 0, y) == (None, None, None, field.STATUS_OUTSIDE)
        assert model.declination_kang is None and model.field_nt is None
    d, i, f, status = model.at(0, 0, None)
    assert status == field.STATUS_NO_DATE
    assert (d, i, f) == model.at(0, 0, 2027500)[:3]


@pytest.mark.parametrize("args, exc, words", [
    ((45.0, 0, 2026000), TypeError, ("lat_e7", "1e-7 deg", "float")),
    ((0, 10.5, 2026000), TypeError, ("lon_e7", "1e-7 deg")),
    ((0, 0, 2026.5), TypeError, ("year_e3", "decimal years * 1000")),
    ((True, 0, 2026000), TypeError, ("lat_e7",)),
    (("45", 0, 2026000), TypeError, ("lat_e7",)),
    ((900000001, 0, 2026000), ValueError, ("lat_e7", "1e-7 deg")),
    ((-900000001, 0, 2026000), ValueError, ("lat_e7",)),
    ((0, 1800000001, 2026000), ValueError, ("lon_e7", "1e-7 deg")),
    ((0, -1800000001, 2026000), ValueError, ("lon_e7",)),
])
def test_bad_arguments_name_the_argument_and_unit(model, args, exc, words):
    with pytest.raises(exc) as e:
        model.at(*args)
    for w in words:
        assert w in str(e.value)


def test_decimal_year_matches_pygeomag():
    import datetime
    day = datetime.date(2024, 1, 1)
    while day < datetime.date(2031, 1, 1):
        want = pygeomag.decimal_year_from_date(day)
        got = decimal_year_e3(day.year, day.month, day.day)
        assert abs(got - want * 1000) <= 0.5, day
        day += datetime.timedelta(days=1)
    for bad in ((2026, 13, 1), (2026, 2, 29), (2026, 4, 31), (2026, 0, 1), (2026, 1, 0)):
        with pytest.raises(ValueError):
            decimal_year_e3(*bad)
    with pytest.raises(TypeError):
        decimal_year_e3(2026.0, 1, 1)


def test_weights_are_the_cubic_lagrange_weights_and_sum_to_one():
    w = [0] * 4
    for t in range(4097):
        field._weights(t, w)
        x = t / 4096
        exact = (-x * (x - 1) * (x - 2) / 6, (x + 1) * (x - 1) * (x - 2) / 2,
                 -(x + 1) * x * (x - 2) / 2, (x + 1) * x * (x - 1) / 6)
        assert sum(w) == 4096
        for k in range(4):
            assert abs(w[k] - exact[k] * 4096) <= 1.5, (t, k, w, exact)


# -- the table file ------------------------------------------------------------------------

def test_committed_table_is_what_make_wmm_writes():
    with open(TABLE, "rb") as f:
        committed = f.read()
    assert committed == wmm.build(), "firmware/field/wmm2025.bin is stale: run `make wmm`"
    assert len(committed) <= 16 * 1024


def _corrupt(tmp_path, edit):
    data = bytearray(open(TABLE, "rb").read())
    data = edit(data)
    p = tmp_path / "t.bin"
    p.write_bytes(bytes(data))
    return str(p)


def _flip(k):
    def edit(d):
        d[k] ^= 0x10
        return d
    return edit


@pytest.mark.parametrize("edit, reason", [
    (lambda d: d[:-1], field.REASON_TRUNCATED),
    (lambda d: d[:20], field.REASON_TRUNCATED),
    (lambda d: bytearray(), field.REASON_TRUNCATED),
    (lambda d: d + b"\0", field.REASON_BAD_HEADER),
    (_flip(0), field.REASON_BAD_MAGIC),
    (_flip(4), field.REASON_UNKNOWN_VERSION),
    (_flip(6), field.REASON_BAD_HEADER),  # n_lat
    (_flip(20), field.REASON_BAD_HEADER),  # units
    (_flip(32 + 5000), field.REASON_BAD_CRC),
    (_flip(-1), field.REASON_BAD_CRC),
])
def test_a_corrupt_table_is_refused_with_a_reason(tmp_path, edit, reason):
    path = _corrupt(tmp_path, edit)
    with pytest.raises(FieldTableError) as e:
        FieldModel(path)
    assert e.value.reason == reason
    assert path in str(e.value)


def test_a_missing_table_is_refused(tmp_path):
    with pytest.raises(FieldTableError) as e:
        FieldModel(str(tmp_path / "none.bin"))
    assert e.value.reason == field.REASON_MISSING


def test_crc_without_binascii_gives_the_same_check(monkeypatch, tmp_path):
    monkeypatch.setattr(field, "_crc32", None)
    FieldModel().close()
    with pytest.raises(FieldTableError) as e:
        FieldModel(_corrupt(tmp_path, _flip(32 + 77)))
    assert e.value.reason == field.REASON_BAD_CRC


# -- integers, heap, MicroPython ----------------------------------------------------------

CHECKED, STATS = intcheck.load("field.wmm")
_CHECKED_MODEL = CHECKED.FieldModel(TABLE)


@given(st.integers(-900000000, 900000000), st.integers(-1800000000, 1800000000),
       st.one_of(st.none(), st.integers(2025000, 2030000)))
def test_query_intermediates_stay_small_ints(lat_e7, lon_e7, year_e3):
    _CHECKED_MODEL.at(lat_e7, lon_e7, year_e3)


def test_interpolation_headroom_is_reported():
    """The largest intermediate of the interpolation and the derived angles (the range checks
    compare with 90 deg = 9e8 in 1e-7 deg, which is no computation), at every cell centre."""
    m = _CHECKED_MODEL
    STATS.max_abs = 0
    for i in range(24):
        for j in range(48):
            for dt in (0, 5000):
                m._cell(-900000 + 37500 + 75000 * i, -1800000 + 37500 + 75000 * j)
                m._interpolate(dt)
                m._derive(field.STATUS_OK)
    print("\nlargest interpolation intermediate %d (%.3f of 2**30), field.py line %s"
          % (STATS.max_abs, STATS.max_abs / 2 ** 30, STATS.where))
    assert 0 < STATS.max_abs < 2 ** 30


def test_micropython_heap_per_query_and_import():
    out = mp.json_lines(mp.run(["-m", "desktop.benchmarks.fieldheap"], micro=True))[0]
    print("\nMicroPython heap: %s" % json.dumps(out))
    assert out["query_bytes"] <= 1024
    assert out["first_bytes"] <= 1024 + 512  # + one-time cost of the first atan2 call
    assert out["model_bytes"] <= 1024
    assert out["import_bytes"] <= 16 * 1024


def test_cpython_and_micropython_give_identical_integers():
    lines = mp.json_lines(mp.parity(["tests/scenarios/field_parity.py"]))
    assert len(lines) == 301
    assert {ln[6] for ln in lines[:-1]} >= {field.STATUS_OK}


# -- the commands --------------------------------------------------------------------------

def _cli(args, stdin=None):
    return subprocess.run([sys.executable, "-m", "host_sim", "field"] + args, cwd=ROOT,
                          capture_output=True, text=True, input=stdin, timeout=60)


def test_field_command_prints_the_boards_figures(model):
    r = _cli(["--date", "2026-03-01", "--json", "-33.9,151.2", "51.5,-0.13"])
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    y = decimal_year_e3(2026, 3, 1)
    for row, (lat, lon) in zip(out, ((-339000000, 1512000000), (515000000, -1300000))):
        d, i, f, status = model.at(lat, lon, y)
        assert (row["declination_deg"], row["inclination_deg"], row["field_nt"],
                row["status"]) == (d / 100, i / 100, f, status)
    r2 = _cli(["--date", "2026-03-01", "--json"], stdin="# Sydney\n-33.9,151.2\n\n51.5,-0.13\n")
    assert r2.returncode == 0 and json.loads(r2.stdout) == out


@pytest.mark.parametrize("args, stdin, code, words", [
    (["--date", "2031-01-01", "1,2"], None, 1, "outside model validity"),
    (["--date", "2026-13-01", "1,2"], None, 2, "month"),
    (["--date", "2026/01/01", "1,2"], None, 2, "YYYY-MM-DD"),
    (["--date", "2026-01-01", "91,2"], None, 2, "latitude"),
    (["--date", "2026-01-01", "1,-181"], None, 2, "longitude"),
    (["--date", "2026-01-01", "-x"], None, 2, "unknown option"),
    (["--date", "2026-01-01"], "1,2\nabc\n", 2, "line 2"),
    (["--date", "2026-01-01", "--table", "/nonexistent.bin", "1,2"], None, 2, "missing"),
])
def test_field_command_bad_input_is_one_line(args, stdin, code, words):
    r = _cli(args, stdin)
    assert r.returncode == code
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert words in r.stderr


def test_wmm_command_writes_the_table(tmp_path):
    out = tmp_path / "t.bin"
    r = subprocess.run([sys.executable, "-m", "host_sim", "wmm", "--out", str(out)], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes() == open(TABLE, "rb").read()
    bad = subprocess.run([sys.executable, "-m", "host_sim", "wmm", "--step", "7"], cwd=ROOT,
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "--step" in bad.stderr
