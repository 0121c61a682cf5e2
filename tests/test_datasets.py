"""Real logs (shared/datasets): the firmware's calibration makes them as spherical as a float64
fit of the same model does, and the planar log is refused.

Sphericity = std(|corrected|) / mean(|corrected|) over every row of the file (the QMC5883L
logs without their first 3000 still samples). Ours: the Calibrator fed with every row, as the
offline tool does (desktop capacity, separation from the data's range), then Q15 correct().
Reference: the same model fitted in float64 to every evaluated row (test_solve.numpy_fit;
min/max over the rows), applied in float64.
"""
import os

import numpy as np
import pytest

from firmware.errors import CalibrationRejected
from firmware.magcal import Calibrator
from host_sim.cli.calibrate import DESKTOP_CAPACITY, choose_scale, scaled_rows
from tests.test_solve import numpy_fit

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATASETS = os.path.normpath(os.path.join(ROOT, "..", "shared", "datasets"))
HAVE = os.path.isdir(DATASETS)
LOGS = sorted(f[:-4] for f in os.listdir(DATASETS) if f.endswith(".csv")) if HAVE else []
PLANAR = "hmc5883l_nliaudat_windvane_planar"
STILL_ROWS = {"qmc5883l_tomisuarez_filtered": 3000, "qmc5883l_tomisuarez_noisy": 3000}
MODELS = ("minmax", 4, 7, 10)
TOLERANCE = 1.10   # ours may be at most 10 % less spherical than the reference
pytestmark = pytest.mark.skipif(not HAVE, reason="no datasets directory at %s" % DATASETS)

_cache = {}


def sphericity(m):
    r = np.sqrt((m.astype(float) ** 2).sum(axis=1))
    return r.std() / r.mean()


def load(name):
    """(calibrator filled with every row, int rows, evaluated float rows, scale power)."""
    if name not in _cache:
        path = os.path.join(DATASETS, name + ".csv")
        p, _ = choose_scale(path)
        rows = np.array(list(scaled_rows(path, p)), dtype=np.int64)
        cal = Calibrator(model=10, capacity=DESKTOP_CAPACITY, max_fit_error=10000)
        for x, y, z in rows.tolist():
            cal.add(x, y, z)
        data = np.genfromtxt(path, delimiter=",", names=True)
        floats = np.c_[data["mx"], data["my"], data["mz"]]
        skip = STILL_ROWS.get(name, 0)
        _cache[name] = (cal, rows[skip:], floats[skip:], p)
    return _cache[name]


def ours(name, model):
    cal, rows, _, _ = load(name)
    c = cal.solve(model=model, accept=False)
    out = np.zeros_like(rows)
    buf = [0, 0, 0]
    for i, r in enumerate(rows.tolist()):
        c.correct(r, buf)
        out[i] = buf
    return sphericity(out), c


def reference(name, model):
    _, _, f, _ = load(name)
    if model == "minmax":
        lo, hi = f.min(axis=0), f.max(axis=0)
        h = (hi - lo) / 2
        return sphericity((f - (hi + lo) / 2) * (h.mean() / h))    # seed 002
    v, invw, _ = numpy_fit(f, model)
    return sphericity((f - v) @ invw.T)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("name", [n for n in LOGS if n != PLANAR])
def test_log_is_as_spherical_as_the_float64_fit(name, model):
    s_ours, c = ours(name, model)
    s_ref = reference(name, model)
    assert s_ours <= TOLERANCE * s_ref, "%s model %s: ours %.4f vs float64 %.4f (%s)" % (
        name, model, s_ours, s_ref, c)


@pytest.mark.parametrize("model", [7, 10])
def test_planar_log_is_refused_with_a_reason(model):
    cal, _, _, _ = load(PLANAR)
    strict = Calibrator(model=model, capacity=DESKTOP_CAPACITY)   # the default limits
    held = cal.buffer
    for i in range(held.count):
        strict.add(*held.data[3 * i:3 * i + 3])
    with pytest.raises(CalibrationRejected) as e:
        strict.solve()
    assert e.value.reason == "planar", e.value


def test_qmc_logs_default_limits_refuse_only_the_sphere_fit():
    # a 2:1 ellipsoid: the 4-element (sphere) fit is refused for its fit error, the
    # ellipsoid fits pass at NXP's 15 %
    for name in STILL_ROWS:
        if name not in LOGS:
            continue
        cal, _, _, _ = load(name)
        cal.max_fit_error = 1500
        with pytest.raises(CalibrationRejected) as e:
            cal.solve(model=4, accept=False)
        assert e.value.reason == "fit_error_high"
        assert cal.solve(model=10, accept=False).fit_error < 1500
        cal.max_fit_error = 10000


def published_centre(name):
    import json
    with open(os.path.join(DATASETS, name + ".json")) as f:
        meta = json.load(f)
    return meta.get("sanity_summary", {}).get("ref_center")


@pytest.mark.parametrize("name", [n for n in LOGS if n != PLANAR])
def test_ten_element_centre_agrees_with_the_authors_published_calibration(name):
    # independent evidence: the hard iron their own tools (Magneto, Dorveaux LS, ellipsoid
    # fits) published for the same file, within 1.5 % of the field
    ref = published_centre(name)
    if ref is None:
        pytest.skip("%s: no published reference" % name)
    # The noisy QMC log (6 % scatter) gets 3 %: distance selection keeps the samples that
    # stand out of the shell, i.e. the noisiest, and moves V by ~2 % of B there; holding the
    # whole session (--capacity 8000) gives 0.9 %, as the float64 fit of all rows does.
    tol = 0.03 if name == "qmc5883l_tomisuarez_noisy" else 0.015
    cal, _, _, p = load(name)
    c = cal.solve(model=10, accept=False)
    ours = np.array(c.offset, dtype=float) / 10 ** p
    assert np.abs(ours - np.array(ref)).max() < tol * c.field / 10 ** p
