"""Real logs (shared/datasets): the firmware's calibration makes them as spherical as a float64
fit of the same model does, and the planar log is refused.

Sphericity = std(|corrected|) / mean(|corrected|) over every row of the file (the QMC5883L
logs without their first 3000 still samples). Ours: the Calibrator fed with every row, as the
offline tool does (desktop capacity, separation from the data's range), then Q15 correct().
Reference: the same model fitted in float64 to every evaluated row
(host_sim/cli/benchmarks/reference.py numpy_fit; min/max over the rows), applied in float64.
"""
import os

import numpy as np
import pytest

from firmware.errors import CalibrationRejected
from firmware.calibrator import Calibrator
from host_sim.cli.benchmarks.reference import (DATASETS, HAVE, LOGS, PLANAR, STILL_ROWS,
                                               load, ours, reference)
from host_sim.cli.calibrate import DESKTOP_CAPACITY

MODELS = ("minmax", 4, 7, 10)
TOLERANCE = 1.10   # ours may be at most 10 % less spherical than the reference
pytestmark = pytest.mark.skipif(not HAVE, reason="no datasets directory at %s" % DATASETS)


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
