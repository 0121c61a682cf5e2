"""Quick calibration (firmware/field/quickcal.py, CompassApp.quick_calibrate): the expected field
vector against the simulator, the heading accuracy it reaches (docs/quick_calibration.md; the
full measurement is in `make bench`: desktop/benchmarks/quickcal.py), the limit no
one-pose method can pass, and its refusals."""
import math
import random

import pytest

from firmware.axes import AxisMap
from firmware.calibration import Calibration
from firmware.errors import CalibrationRejected
from firmware.field.location import Location
from firmware.field.quickcal import QuickCal
from firmware.store import CalStore
from firmware.trig import cdeg_to_kang
from tests import location_world as L
from tests.location_world import W

SEEDS = 12
# Goals over the seeds (soft iron "dev": W's eigenvalues within 1 +- dev, random axes):
ONE_POSE_MAX_DEG = 2.0   # one pose, dev 1.5 % (the ellipsoid's axes within 3 % of each other)
ONE_POSE_RMS_DEG = 1.0   # one pose, dev 3 %: the typical error (the worst is ~3 deg)
TWO_POSE_MAX_DEG = 2.0   # two opposite poses, dev 3 %, level


def _errors(dev, poses, **kw):
    out = []
    for s in range(SEEDS):
        out += L.quick_cal_errors(s, dev, poses=poses, headings=8, **kw)
    return out


def test_one_pose_heading_error_within_2_deg_at_3_percent_axis_ratio():
    e = _errors(0.015, 1)
    assert max(abs(x) for x in e) <= ONE_POSE_MAX_DEG, max(abs(x) for x in e)


def test_one_pose_typical_error_at_3_percent_soft_iron_and_tilt():
    e = _errors(0.03, 1, tilt=20.0)
    rms = math.sqrt(sum(x * x for x in e) / len(e))
    assert rms <= ONE_POSE_RMS_DEG, rms


def test_two_opposite_poses_cancel_soft_iron():
    e1 = _errors(0.03, 1)
    e2 = _errors(0.03, 2)
    assert max(abs(x) for x in e2) <= TWO_POSE_MAX_DEG
    assert sum(x * x for x in e2) < 0.7 * sum(x * x for x in e1)


def _twin_boards(dev, yaw):
    """Two level boards (the same noise seed) that read the same at heading `yaw`: soft iron I + E and
    I - E, E = dev (u v^T + v u^T) with u along the horizontal field the chip senses there and
    v across it (eigenvalues +-dev, 0), hard irons differing by 2 E B0 (AN4246 eq. 8)."""
    w0 = L.world_at(L.ZURICH)
    b0 = L.board(w0, "qmc5883l", True)
    L.hold(b0, yaw)
    f = w0.sensor_field(b0.clock.now_us, b0.mount)          # uT in the chip's axes, W = I
    h = math.hypot(f[0], f[1])                              # the chip's z is vertical (level)
    u, v = (f[0] / h, f[1] / h, 0.0), (-f[1] / h, f[0] / h, 0.0)
    e = [[dev * (u[i] * v[j] + v[i] * u[j]) for j in range(3)] for i in range(3)]
    ef = [sum(e[i][j] * f[j] for j in range(3)) for i in range(3)]
    v1 = (10.0, -20.0, 15.0)
    v2 = tuple(v1[i] + 2 * ef[i] for i in range(3))
    out = []
    for sign, hard in ((1, v1), (-1, v2)):
        soft = tuple(tuple((i == j) + sign * e[i][j] for j in range(3)) for i in range(3))
        out.append(L.board(L.world_at(L.ZURICH, hard, soft), "qmc5883l", True, seed=1))
    return out


def test_one_pose_cannot_meet_2_deg_at_3_percent_soft_iron():
    """Why the one-pose goal holds to +-1.5 % and not +-3 %: the twin boards read alike at the
    calibration pose, get the same calibration, and at the opposite heading their headings
    differ by ~4 dev rad; whatever one pose gives, one board is >= 2 dev rad = 3.4 deg off."""
    yaw = 30.0
    errs = []
    cals = []
    for b in _twin_boards(0.03, yaw):
        app = L.app_on(b, learn=False)
        app.set_location(L.ZURICH[0], L.ZURICH[1], L.YEAR_E3)
        L.hold(b, yaw)
        W.run_until(app, b, b.clock.now_us / 1e6 + 0.1)
        cals.append(app.quick_calibrate(L.true_heading_cdeg(b)))
        L.hold(b, yaw + 180.0)
        errs.append(L.mean_error_deg(app, b))
    assert all(abs(cals[0].offset[i] - cals[1].offset[i]) <= 2 for i in range(3)), cals
    spread = abs(errs[0] - errs[1])
    assert spread >= math.degrees(4 * 0.03) * 0.9, errs   # 6.9 deg, quantisation aside
    print("\nopposite heading, twin boards: %.2f and %.2f deg" % tuple(errs))
    assert max(abs(x) for x in errs) > 2.0 + 1.0, errs


def test_level_board_without_accelerometer():
    e = _errors(0.015, 1, accel=False)
    assert max(abs(x) for x in e) <= ONE_POSE_MAX_DEG


@pytest.mark.parametrize("chip, accel", [("qmc5883l", True), ("gy87", None)])
def test_expected_field_matches_the_simulated_sensor(chip, accel):
    # noise-free, no iron: what the board senses is what QuickCal expects (counts)
    rng = random.Random(5)
    b = L.board(L.world_at(L.ZURICH), chip, accel)
    app = L.app_on(b, accel, learn=False)
    app.set_location(*L.ZURICH, year_e3=L.YEAR_E3)
    qc = QuickCal(app.location, app.mag.counts_per_gauss, app._mag_map)
    cpg = app.mag.counts_per_gauss
    for _ in range(6):
        L.hold(b, rng.uniform(0, 360), rng.uniform(-40, 40), rng.uniform(-40, 40))
        app.step()  # the world caches its rotation per time: let the clock move
        f = b.world.sensor_field(b.clock.now_us, b.mount)
        g = b.world.gravity_body(b.clock.now_us)
        e = qc.expected([round(v * 16384) for v in g], cdeg_to_kang(L.true_heading_cdeg(b)))
        tol = max(2, cpg * 48 // 100000 // 100)  # 1 % of |B| or 2 counts
        for i in range(3):
            assert abs(e[i] - f[i] / 100 * cpg) <= tol, (e, f)


def test_result_is_a_4_element_equivalent_and_survives_the_store():
    b = L.board(L.world_at(L.ZURICH, W.HARD_IRON_UT))
    L.hold(b, 75.0, 10.0, -5.0)
    fs = W.MemFs()
    app = L.app_on(b, store=CalStore("/", fs=fs), learn=False)
    app.set_location(*L.ZURICH, year_e3=L.YEAR_E3)
    W.run_until(app, b, 0.2)
    cal = app.quick_calibrate(L.true_heading_cdeg(b))
    assert cal.model == 4 and cal.coverage == 0 and cal.invw == (32767, 0, 0, 0, 32767, 0, 0,
                                                                 0, 32767)
    assert cal.field == app.location.field_counts(12000) and cal.samples == 32
    true_v = [h / 100 * 12000 for h in W.HARD_IRON_UT]
    assert all(abs(cal.offset[i] - true_v[i]) < 40 for i in range(3)), (cal.offset, true_v)
    assert app.calibration is cal and app.stored == 1
    again = L.app_on(b, store=CalStore("/", fs=fs), learn=False)
    assert again.calibration == cal or again.calibration.offset == cal.offset
    assert abs(L.mean_error_deg(app, b)) < 1.0
    assert app.accuracy == 2 and app.accuracy_reason() == "quick"


def test_a_later_full_calibration_replaces_the_quick_one():
    b = L.board(L.world_at(L.ZURICH, W.HARD_IRON_UT, W.SOFT_IRON), seed=2)
    L.hold(b, 10.0)
    app = L.app_on(b)  # learn=None: collects, the configured model is 10
    app.set_location(*L.ZURICH, year_e3=L.YEAR_E3)
    W.run_until(app, b, 0.2)
    app.quick_calibrate(L.true_heading_cdeg(b))
    b.world.motion = W.motion.figure8()
    W.run_until(app, b, 40)
    assert app.calibration.model in (7, 10) and app.calibration.coverage > 0


# --- refusals -----------------------------------------------------------------------------
def test_no_location_is_refused():
    b = L.board(L.world_at(L.ZURICH))
    app = L.app_on(b, learn=False)
    with pytest.raises(CalibrationRejected) as e:
        app.quick_calibrate(9000)
    assert e.value.reason == "no_location" and "set_location" in e.value.detail
    app.set_location(*L.ZURICH, year_e3=2032000)
    with pytest.raises(CalibrationRejected) as e:
        app.quick_calibrate(9000)
    assert e.value.reason == "no_location" and "outside model validity" in e.value.detail
    assert app.calibration.model is None


def test_blackout_zone_is_refused():
    loc = Location(860000000, 1400000000, 2026500)  # near the north magnetic pole
    assert loc.status == "blackout zone"
    with pytest.raises(CalibrationRejected) as e:
        QuickCal(loc, 12000, AxisMap("x,-y,-z"))
    assert e.value.reason == "blackout_zone"


def test_an_offset_beyond_1800_mg_is_refused():
    qc = QuickCal(Location(*L.ZURICH, year_e3=L.YEAR_E3), 12000, AxisMap("x,-y,-z"))
    qc.add((30000 * 4, 0, 0), None, 4, 0)
    with pytest.raises(CalibrationRejected) as e:
        qc.result()
    assert e.value.reason == "offset_out_of_range" and "1800 mG" in e.value.detail


def test_poses_that_disagree_are_a_field_mismatch():
    # the second pose's heading is typed 90 deg wrong
    b = L.board(L.world_at(L.ZURICH, W.HARD_IRON_UT))
    L.hold(b, 20.0)
    app = L.app_on(b, learn=False)
    app.set_location(*L.ZURICH, year_e3=L.YEAR_E3)
    first = app.quick_calibrate(L.true_heading_cdeg(b))
    L.hold(b, 200.0)
    W.run_until(app, b, b.clock.now_us / 1e6 + 0.2)
    with pytest.raises(CalibrationRejected) as e:
        app.quick_calibrate((L.true_heading_cdeg(b) + 9000) % 36000, refine=True)
    assert e.value.reason == "field_mismatch" and "full calibration" in e.value.detail
    assert app.calibration is first


@pytest.mark.parametrize("kw, exc, words", [
    ({"true_heading_cdeg": 90.0}, TypeError, ("true_heading_cdeg", "hundredths of a degree")),
    ({"true_heading_cdeg": 36000}, ValueError, ("true_heading_cdeg", "0..35999")),
    ({"true_heading_cdeg": 0, "samples": 0}, ValueError, ("samples",)),
])
def test_bad_arguments(kw, exc, words):
    b = L.board(L.world_at(L.ZURICH))
    app = L.app_on(b, learn=False)
    app.set_location(*L.ZURICH, year_e3=L.YEAR_E3)
    with pytest.raises(exc) as e:
        app.quick_calibrate(**kw)
    for w in words:
        assert w in str(e.value)
    assert app.calibration.model is None


def test_calibration_record_of_a_quick_cal_is_valid():
    # the record passes Calibration's own validation and round-trips through bytes
    qc = QuickCal(Location(*L.ZURICH, year_e3=L.YEAR_E3), 1090, AxisMap("x,-y,-z"))
    qc.add((300 * 8, -200 * 8, 100 * 8), (0, 0, 16384 * 8), 8, 0)
    cal = qc.result()
    assert Calibration.from_bytes(cal.to_bytes()).offset == cal.offset


def test_cpython_and_micropython_agree():
    from tests import mp
    out = dict(mp.json_lines(mp.parity(["tests/scenarios/location_parity.py"]))[0])
    assert out["errors"] == ["TypeError", "ValueError", "ValueError"]
    assert out["no_location"] == "no_location" and out["status"] == "ok"
    assert out["accuracy_before"] == 0 and out["accuracy"] == 2 and "(quick)" in out["line"]
