"""Calibrator and Calibration: Q15 correction bounds, payload, acceptance reasons, recovery
of known iron from the simulator, and the time-sliced solve."""
import itertools
import json
import os
import sys
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import find, given, strategies as st

from tests import solve_ref
from firmware import calibration
from firmware.calibrate import acceptance
from firmware.calibrate import accum
from firmware.calibrate import calibrator
from firmware.errors import CalibrationRejected
from firmware.calibration import UNCALIBRATED, Calibration
from firmware.calibrate.calibrator import Calibrator
from tests import intcheck, mp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "scenarios"))
from calibrator_parity import CPG, V_UT, W, sim_raw  # noqa: E402

i16 = st.integers(min_value=-32768, max_value=32767)


@st.composite
def invw_q15(draw):
    """Any InvW our solver can produce: 9 ints, each row's absolute sum <= 32767."""
    out = []
    for _ in range(3):
        row = draw(st.lists(st.integers(-32767, 32767), min_size=3, max_size=3))
        t = sum(abs(v) for v in row)
        if t > 32767:
            row = [v * 32767 // t if v >= 0 else -((-v) * 32767 // t) for v in row]
        out += row
    return tuple(out)


def exact_q15(invw, raw, offset):
    d = [max(-32768, min(32767, raw[i] - offset[i])) for i in range(3)]
    return [Fr(sum(invw[3 * i + j] * d[j] for j in range(3)), 32768) for i in range(3)]


# ---- Q15 correction -------------------------------------------------------------------------

CHECKED, STATS = intcheck.load("calibration")


@given(invw_q15(), st.tuples(i16, i16, i16), st.tuples(i16, i16, i16))
def test_q15_correct_never_leaves_small_int_range_and_rounds_the_exact_result(m, raw, off):
    mod, stats = CHECKED, STATS
    c = mod.Calibration(model=10, offset=off, invw=m, field=1000, field_out=1000)
    out = [0, 0, 0]
    c.correct(raw, out)
    assert stats.max_abs < 1 << 30
    for got, want in zip(out, exact_q15(m, raw, off)):
        assert abs(got - want) <= Fr(1, 2)   # rounded to nearest: within 1 count


def app_note_literal(invw, raw, offset):
    """AN4246 section 3 as C does it: short iBp (the -= wraps), int (int32) sums, (short)."""
    def wrap(v, bits):
        m = 1 << bits
        v &= m - 1
        return v - m if v >= m >> 1 else v
    bp = [wrap(raw[i] - offset[i], 16) for i in range(3)]        # iBpx -= iVx on a short
    out = []
    for i in range(3):
        s = 0
        for j in range(3):
            s = wrap(s + wrap(invw[3 * i + j] * bp[j], 32), 32)     # int32 products and sums
        out.append(wrap(s >> 15, 16))                              # (short)(iSum >> 15)
    return out


def test_app_note_literal_code_wraps_where_ours_saturates():
    # a calibration our solver produced (tests/scenarios/calibrator_parity.py, model 10)
    c = Calibration(model=10, offset=(14398, -9596, 4803),
                    invw=(25173, -1154, 768, -1154, 30077, -1237, 768, -1237, 27945),
                    field=6013, field_out=5110)

    def literal_is_wrong(raw):
        want = exact_q15(c.invw, raw, c.offset)
        return any(abs(g - w) > 1 for g, w in zip(app_note_literal(c.invw, raw, c.offset), want))

    raw = find(st.tuples(i16, i16, i16), literal_is_wrong)
    want = exact_q15(c.invw, raw, c.offset)
    lit = app_note_literal(c.invw, raw, c.offset)
    out = [0, 0, 0]
    c.correct(raw, out)
    assert all(abs(g - w) <= Fr(1, 2) for g, w in zip(out, want))      # ours: rounded exact
    assert max(abs(g - w) for g, w in zip(lit, want)) > 1000           # literal: garbage
    assert max(abs(raw[i] - c.offset[i]) for i in range(3)) > 32767    # the short wrapped


@given(invw_q15(), st.tuples(i16, i16, i16))
def test_our_q15_sums_cannot_overflow_int32_while_an_unnormalised_matrix_can(m, raw):
    # row sums <= 32767 bound |sum| by 32767 * 32768 < 2**30; a Q15 matrix with entries up to
    # 32767 but larger row sums (e.g. W^-1 with det 1 written as 1.0 = 32767) does not.
    for i in range(3):
        assert abs(sum(m[3 * i + j] * raw[j] for j in range(3))) < 1 << 30
    big = (32767, 32767, 32767)
    assert abs(sum(big[j] * -32768 for j in range(3))) >= 1 << 31


def test_correct_allocates_nothing_on_micropython():
    out = json.loads(mp.run(["tests/scenarios/calibrator_alloc.py"], micro=True))
    assert out["correct_calls"] == 280 and out["correct_allocated"] == 0
    assert out["buffer_full"] and out["add_calls"] == 40 and out["add_allocated"] == 0
    assert out["correct_mem_total_bytes_per_1000"] == 0


def test_uncalibrated_correction_is_the_identity_for_half_the_int16_range():
    out = [0, 0, 0]
    for v in (-16383, -1000, -1, 0, 1, 777, 16383):
        UNCALIBRATED.correct((v, -v, v // 2), out)
        assert out == [v, -v, v // 2]
    assert UNCALIBRATED.model is None


# ---- payload --------------------------------------------------------------------------------

@given(st.sampled_from([None, "minmax", 4, 7, 10]), st.tuples(i16, i16, i16), invw_q15(),
       st.integers(1, (1 << 30) - 1), st.integers(1, (1 << 30) - 1), st.integers(0, 65535),
       st.integers(0, 65535), st.integers(0, 100))
def test_payload_round_trips(model, off, m, field, field_out, fe, n, cov):
    c = Calibration(model=model, offset=off, invw=m, field=field, field_out=field_out,
                    fit_error=fe, samples=n, coverage=cov)
    b = c.to_bytes()
    assert len(b) == calibration.PAYLOAD_SIZE
    d = Calibration.from_bytes(b)
    assert d == c and d.to_bytes() == b
    assert (d.model, d.offset, d.invw, d.field, d.fit_error) == (model, off, m, field, fe)


@pytest.mark.parametrize("kw, word", [
    (dict(field=-5), "field=-5"), (dict(field_out=-1), "field_out=-1"),
    (dict(field=0), "never 0"), (dict(field_out=0), "never 0"), (dict(coverage=101), "coverage"),
    (dict(fit_error=-1), "fit_error"), (dict(samples=-3), "samples"),
    (dict(field=1.5), "field=1.5"), (dict(offset=(1, 2, 40000)), "int16"),
    (dict(invw=(32767, 0, 0, 0, 32767.0, 0, 0, 0, 32767)), "int16")])
def test_a_record_whose_meaning_is_impossible_is_refused_naming_the_field(kw, word):
    args = dict(model=10, offset=(1, 2, 3), field=500, field_out=500, fit_error=120,
                samples=200, coverage=80)
    args.update(kw)
    with pytest.raises(ValueError, match=word.replace("(", r"\(").replace(".", r"\.")):
        Calibration(**args)


def test_payload_with_a_negative_field_is_refused_by_from_bytes():
    import struct
    good = bytearray(Calibration(model=4, offset=(1, 2, 3), field=500, field_out=500).to_bytes())
    struct.pack_into("<i", good, 38, -500)   # B, after version..samples (8), V (12), InvW (18)
    with pytest.raises(ValueError, match="field=-500"):
        Calibration.from_bytes(bytes(good))


def test_payload_refuses_what_correct_could_not_use():
    good = Calibration(model=4, offset=(1, 2, 3), field=500, field_out=500).to_bytes()
    with pytest.raises(ValueError, match="46"):
        Calibration.from_bytes(good[:-1])
    with pytest.raises(ValueError, match="version"):
        Calibration.from_bytes(b"\x09" + good[1:])
    with pytest.raises(ValueError, match="model code"):
        Calibration.from_bytes(good[:1] + b"\x05" + good[2:])
    bad = bytearray(good)
    bad[20:26] = (32767).to_bytes(2, "little") * 3    # row 0: |sum| = 98301 > 32767
    with pytest.raises(ValueError, match="row 0"):
        Calibration.from_bytes(bytes(bad))
    with pytest.raises(ValueError, match="int16"):
        Calibration(model=4, offset=(40000, 0, 0))


def test_payload_carries_the_dip_in_whole_degrees_and_equality_ignores_it():
    base = Calibration(model=10, offset=(1, 2, 3), field=500, field_out=500)
    assert base.to_bytes()[3] == 0 and Calibration.from_bytes(base.to_bytes()).dip_kang is None
    for deg in (-90, -60, -1, 0, 1, 33, 60, 90):
        kang = round(deg * 65536 / 360)
        c = base.with_dip(kang)
        assert c.to_bytes()[3] == deg + 128          # 0 is "not known": 38..218 otherwise
        back = Calibration.from_bytes(c.to_bytes())
        assert back.dip_kang == kang and back == base  # the same fit, whatever its dip
    # a dip rounds to the nearest whole degree (1 deg = 182 KANG)
    assert Calibration.from_bytes(base.with_dip(10923 + 100).to_bytes()).dip_kang == 11105  # 61
    bad = bytearray(base.to_bytes())
    bad[3] = 20                                      # -108 deg
    with pytest.raises(ValueError, match="dip byte 20"):
        Calibration.from_bytes(bytes(bad))
    with pytest.raises(ValueError, match="dip_kang"):
        Calibration(model=4, field=5, field_out=5, dip_kang=20000)


# ---- the Calibrator's sums ----------------------------------------------------------------

_off_rails = st.integers(-32767, 32766)  # a sample at an int16 rail is refused (test below)


@given(st.lists(st.tuples(_off_rails, _off_rails, _off_rails), min_size=1, max_size=300),
       st.integers(min_value=3, max_value=30))
def test_calibrator_sums_equal_batch_sums_through_evictions_and_separation_changes(pts, cap):
    cal = Calibrator(model=4, capacity=cap)   # separation grows with the data's range
    kept = sum(1 for p in pts if cal.add(*p))
    held = [tuple(cal.buffer.data[3 * i:3 * i + 3]) for i in range(cal.count)]
    assert kept >= cal.count
    assert cal.moments.s == solve_ref.batch(held, cal.moments.c)


# ---- synthetic calibration through the simulator ------------------------------------------

@pytest.fixture(scope="module")
def sim():
    raw = sim_raw(6000)   # 30 s figure-8 at 200 Hz, QMC5883L +-2 G, noise 24 counts RMS
    return [(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]) for i in range(6000)]


def ref_fit(pts, model):
    from desktop.benchmarks.reference import numpy_fit
    return numpy_fit(pts, model)


def true_cal():
    w = np.array(W)
    a = np.linalg.inv(w).T @ np.linalg.inv(w)
    k = np.cbrt(np.linalg.det(a))
    ev, vec = np.linalg.eigh(a / k)
    return (np.array(V_UT) * CPG / 100, vec @ np.diag(np.sqrt(ev)) @ vec.T,
            50.0 * CPG / 100 / np.sqrt(k))


@pytest.mark.parametrize("model", [4, 7, 10])
def test_known_iron_from_the_simulator_is_recovered_as_well_as_by_float64(sim, model):
    cal = Calibrator(model=model, counts_per_gauss=CPG)
    for p in sim:
        cal.add(*p)
    c = cal.solve(accept=False)
    held = [tuple(cal.buffer.data[3 * i:3 * i + 3]) for i in range(cal.count)]
    rv, rinvw, rb = ref_fit(held, model)      # float64, same model, same samples
    ours_v = np.array(c.offset, dtype=float)
    ours_w = np.array(c.invw, dtype=float).reshape(3, 3) / 32768 * c.field / c.field_out
    assert np.abs(ours_v - rv).max() <= 0.5 + 1e-6            # V rounded to the count
    assert np.abs(ours_w - rinvw).max() < 2e-4                 # Q15 quantisation
    assert abs(c.field - rb) <= 0.5 + 1e-6
    if model == 10:   # the simulated soft iron is a full matrix: only 10 elements model it
        tv, tinvw, tb = true_cal()
        # hard iron 2.4x the field, rotated soft iron: within 0.2 % of B / 0.005 of W^-1
        assert np.abs(ours_v - tv).max() < 0.002 * tb
        assert np.abs(ours_w - tinvw).max() < 0.005
        assert abs(c.field - tb) < 0.002 * tb
        assert np.abs(ours_v - tv).max() <= np.abs(rv - tv).max() + 0.5
        assert np.abs(ours_w - tinvw).max() <= np.abs(rinvw - tinvw).max() + 2e-4
        assert c.fit_error < 100 and c.coverage >= 90


def test_corrected_simulator_samples_lie_on_a_sphere_of_radius_field_out(sim):
    cal = Calibrator(model=10, counts_per_gauss=CPG)
    for p in sim:
        cal.add(*p)
    c = cal.solve()
    out = [0, 0, 0]
    mags = []
    for p in sim[::10]:
        c.correct(p, out)
        mags.append((out[0] ** 2 + out[1] ** 2 + out[2] ** 2) ** 0.5)
    mags = np.array(mags)
    assert abs(mags.mean() - c.field_out) < 0.002 * c.field_out
    assert mags.std() / mags.mean() < 0.01   # noise is 24 / 6000 counts per axis


def test_time_sliced_solve_gives_the_same_calibration_and_ignores_later_samples(sim):
    cal = Calibrator(model=10, counts_per_gauss=CPG)
    for p in sim[:5000]:
        cal.add(*p)
    whole = cal.solve(accept=False)
    job = cal.solve_steps(accept=False)
    steps = 0
    extra = itertools.cycle(sim[5000:])  # the solve has hundreds of bounded slices
    while True:
        try:
            next(job)
        except StopIteration as e:
            sliced = e.value
            break
        steps += 1
        for _ in range(20):          # the app keeps sampling between steps
            cal.add(*next(extra))
    assert steps > 20
    assert (sliced.offset, sliced.invw, sliced.field, sliced.fit_error) == \
        (whole.offset, whole.invw, whole.field, whole.fit_error)


def test_ten_element_solve_of_a_full_buffer_takes_under_100_ms_on_micropython():
    out = json.loads(mp.run(["tests/scenarios/calibrator_bench.py"], micro=True))
    assert out["held"] == 300
    assert out["solve_10_us"] < 100000
    assert out["sliced_10_steps"] > 20
    # the common path (a rejected sample) costs the same with the buffer empty and full
    empty, full = out["add_rejected_empty_us"][0], out["add_rejected_full_us"][0]
    assert full <= 3 * empty + 20 and empty <= 3 * full + 20


def test_calibrator_results_are_bit_identical_on_micropython():
    lines = mp.json_lines(mp.parity(["tests/scenarios/calibrator_parity.py"]))
    assert len(lines) == 8
    assert [r[0] for r in lines[1:5]] == ["minmax", "4", "7", "10"]
    assert all(len(r[1]) == calibration.PAYLOAD_SIZE for r in lines[1:5])   # all accepted
    # the halves check's sums, on the real log (accepted) and on two hard-iron states
    assert lines[7][0] == ["10", "inconsistent_samples"] and len(lines[7][1]) == 2


# ---- acceptance: every reason reachable ----------------------------------------------------

def sphere(n, centre, radius, axes=(1.0, 1.0, 1.0), zmin=-1.0, seed=1, noise=0.0, hyper=False):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(8 * n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u = u[u[:, 2] >= zmin][:n]
    if hyper:   # x^2 + y^2 - z^2 = 1, z in [-1, 1]
        z = rng.uniform(-1, 1, size=n)
        a = rng.uniform(0, 2 * np.pi, size=n)
        r = np.sqrt(1 + z * z)
        u = np.c_[r * np.cos(a), r * np.sin(a), z]
    p = u * np.array(axes) * radius + np.array(centre) + rng.normal(scale=noise, size=u.shape)
    return [tuple(int(v) for v in q) for q in np.rint(p)]


def calibrator_with(pts, model=10, **kw):
    cal = Calibrator(model=model, **kw)
    for p in pts:
        cal.add(*p)
    return cal


def rejected(cal, model=None):
    with pytest.raises(CalibrationRejected) as e:
        cal.solve(model=model)
    return e.value


def test_too_few_samples_for_the_model():
    cal = calibrator_with(sphere(60, (0, 0, 0), 6000), counts_per_gauss=CPG)
    assert 40 <= cal.count < 100
    e = rejected(cal, 10)
    assert e.reason == acceptance.REASON_TOO_FEW_SAMPLES and "needs 100" in e.detail
    assert cal.solve(model=4).model == 4


def test_flat_spin_is_refused_as_planar_by_every_model():
    from host_sim import motion
    from host_sim.boards import make_board
    from host_sim.world import World
    import struct
    b = make_board("qmc5883l", world=World(hard_iron_ut=V_UT, motion=motion.flat_spin(5)))
    b.bus.writeto_mem(0x0D, 0x09, b"\x0d")
    cal = Calibrator(model=10, counts_per_gauss=CPG)
    for _ in range(4000):
        b.clock.advance(5000)
        cal.add(*struct.unpack("<hhh", b.bus.readfrom_mem(0x0D, 0, 6)))
    for m in ("minmax", 4, 7, 10):
        e = rejected(cal, m)
        assert e.reason == acceptance.REASON_PLANAR, (m, e)


def test_low_coverage_when_samples_cover_a_cap():
    cal = calibrator_with(sphere(2000, (500, -300, 200), 6000, zmin=0.65), separation=600)
    e = rejected(cal, 4)
    assert e.reason == acceptance.REASON_LOW_COVERAGE and "needs 30" in e.detail


def test_singular_when_the_quadric_is_not_an_ellipsoid():
    cal = calibrator_with(sphere(300, (0, 0, 0), 5000, hyper=True), separation=300)
    e = rejected(cal, 10)
    assert e.reason == acceptance.REASON_SINGULAR


def test_offset_out_of_range_when_the_centre_is_beyond_int16():
    pts = [p for p in sphere(3000, (45000, 0, 0), 20000, seed=4) if p[0] <= 32767]
    cal = calibrator_with(pts, separation=2000)
    e = rejected(cal, 4)
    assert e.reason == acceptance.REASON_OFFSET_OUT_OF_RANGE


def test_soft_iron_out_of_range_beyond_five_to_one():
    pts = sphere(3000, (100, 100, 100), 6000, axes=(2.0, 1.0, 2.0 / 5.6), seed=5, noise=2)
    e = rejected(calibrator_with(pts, separation=500), 10)
    assert e.reason == acceptance.REASON_SOFT_IRON_OUT_OF_RANGE
    ok = sphere(3000, (100, 100, 100), 6000, axes=(2.0, 1.0, 2.0 / 4.5), seed=5, noise=2)
    assert calibrator_with(ok, separation=500).solve(model=10).model == 10


def test_field_out_of_range_with_and_without_the_sensitivity():
    weak = sphere(2000, (100, 200, 300), 600)         # 5 uT at 12000 counts/G
    e = rejected(calibrator_with(weak, counts_per_gauss=CPG, separation=60), 10)
    assert e.reason == acceptance.REASON_FIELD_OUT_OF_RANGE and "5 uT" in e.detail
    strong = sphere(2000, (100, 200, 300), 12000)     # 100 uT
    e = rejected(calibrator_with(strong, counts_per_gauss=CPG), 10)
    assert e.reason == acceptance.REASON_FIELD_OUT_OF_RANGE
    tiny = sphere(3000, (0, 0, 0), 12)                # unknown sensitivity: 12 counts
    e = rejected(calibrator_with(tiny, separation=1), 4)
    assert e.reason == acceptance.REASON_FIELD_OUT_OF_RANGE and "< 16" in e.detail


def test_fit_error_high_for_a_sphere_fit_to_a_two_to_one_ellipsoid():
    pts = sphere(3000, (0, 0, 0), 6000, axes=(1.3, 1.0, 0.65), seed=6)
    cal = calibrator_with(pts, counts_per_gauss=CPG)
    e = rejected(cal, 4)
    assert e.reason == acceptance.REASON_FIT_ERROR_HIGH and "> 15.00 %" in e.detail
    assert cal.solve(model=10).fit_error < 20


def test_not_better_until_the_current_fit_error_has_aged():
    pts = sphere(3000, (100, 200, 300), 6000, seed=7, noise=30)
    cal = calibrator_with(pts, counts_per_gauss=CPG)
    first = cal.solve()
    assert cal.current is first and first.fit_error > 0
    e = rejected(cal)
    assert e.reason == acceptance.REASON_NOT_BETTER
    cal.age(calibrator._FIT_ERROR_DOUBLING_S // 2)
    assert cal.aged_fit_error() == first.fit_error + first.fit_error // 2
    second = cal.solve()             # same fit error, now below the aged one
    assert second.fit_error == first.fit_error and cal.current is second
    assert cal.aged_fit_error() == second.fit_error     # aging restarts


def test_a_higher_order_model_gets_through_at_three_and_a_half_percent():
    pts = sphere(3000, (100, 200, 300), 6000, seed=8, noise=10)
    cal = calibrator_with(pts, counts_per_gauss=CPG,
                          current=Calibration(model=4, fit_error=1, field=6000, field_out=6000))
    c = cal.solve(model=10)
    assert 1 < c.fit_error <= 350
    cal.current = Calibration(model=10, fit_error=1, field=6000, field_out=6000)
    assert rejected(cal, 10).reason == acceptance.REASON_NOT_BETTER


def test_aging_doubles_per_period_and_saturates():
    cal = Calibrator(current=Calibration(model=10, fit_error=100, field=1, field_out=1))
    assert cal.aged_fit_error() == 100
    cal.age(calibrator._FIT_ERROR_DOUBLING_S)
    assert cal.aged_fit_error() == 200
    cal.age(calibrator._FIT_ERROR_DOUBLING_S)
    assert cal.aged_fit_error() == 400
    cal.age(100 * calibrator._FIT_ERROR_DOUBLING_S)
    assert cal.aged_fit_error() >= 1 << 30


def test_auto_model_follows_the_sample_count():
    pts = sphere(3000, (0, 0, 0), 6000, seed=9, noise=5)
    cal = Calibrator(model="auto", counts_per_gauss=CPG)
    models = []
    for i, p in enumerate(pts):
        cal.add(*p)
        if cal.count in (45, 75, 105) and cal.count not in [m[0] for m in models]:
            models.append((cal.count, cal._pick_model(None)))
    assert [m for _, m in models] == [4, 7, 10]


def test_min_max_is_seed_002_with_a_diagonal_q15_matrix():
    pts = sphere(3000, (1000, -2000, 500), 5000, axes=(1.2, 1.0, 0.8), seed=10)
    cal = calibrator_with(pts, model="minmax", counts_per_gauss=CPG)
    c = cal.solve()
    allp = np.array(pts, dtype=float)      # the min/max article: extremes of every reading
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    assert np.abs(np.array(c.offset) - (lo + hi) / 2).max() <= 0.5
    assert [c.invw[1], c.invw[2], c.invw[3], c.invw[5], c.invw[6], c.invw[7]] == [0] * 6
    scale = np.array([c.invw[0], c.invw[4], c.invw[8]], dtype=float)
    h = (hi - lo) / 2
    assert np.allclose(scale / scale.max(), h.min() / h * (1 / (h.min() / h).max()), atol=1e-4)


def usable_or_refused(pts, model, sep):
    """Solve; a Calibration must be usable by correct(), a failure a named refusal."""
    cal = Calibrator(model=model, capacity=200, separation=sep)
    for p in pts:
        cal.add(*p)
    try:
        c = cal.solve()
    except CalibrationRejected as e:
        assert e.reason in REASONS and e.detail
        return e.reason
    assert all(-32768 <= v <= 32767 for v in c.offset)
    assert all(sum(abs(v) for v in c.invw[3 * i:3 * i + 3]) <= 32767 for i in range(3))
    assert c.field >= 16 and 0 < c.field_out <= c.field and c.fit_error <= 1500
    return None


@given(st.lists(st.tuples(i16, i16, i16), min_size=0, max_size=250),
       st.sampled_from(["minmax", 4, 7, 10]), st.integers(1, 3000))
def test_any_samples_give_a_usable_calibration_or_a_named_refusal(pts, model, sep):
    usable_or_refused(pts, model, sep)


REASONS = {v for k, v in vars(acceptance).items() if k.startswith("REASON_")}


@given(st.integers(0, 2 ** 32 - 1), st.integers(20, 1500), st.sampled_from(["minmax", 4, 7, 10]),
       st.floats(-1.0, 0.9), st.floats(0.0, 50.0))
def test_random_ellipsoids_give_a_usable_calibration_or_a_named_refusal(seed, n, model, zmin,
                                                                         noise):
    rng = np.random.default_rng(seed)
    radius = float(rng.uniform(20, 15000))
    centre = rng.uniform(-30000, 30000, size=3)
    g = rng.normal(size=(3, 3)) * float(rng.uniform(0, 0.6))
    w = np.eye(3) + (g + g.T) / 2
    u = rng.normal(size=(6 * n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u = u[u[:, 2] >= zmin][:n]
    p = np.clip(np.rint(u * radius @ w.T + centre + rng.normal(scale=noise, size=u.shape)),
                -32768, 32767)
    usable_or_refused([tuple(int(v) for v in q) for q in p], model, max(1, int(radius // 8)))


def test_constructor_refuses_unknown_models():
    with pytest.raises(ValueError, match="model"):
        Calibrator(model=5)
    with pytest.raises(ValueError, match="model"):
        Calibrator().solve(model=9)


def test_a_fit_over_more_of_the_sphere_replaces_a_partial_one_with_a_lower_fit_error():
    # The first fit of a session sees part of the sphere and looks better than it is; a later
    # fit covering >= 15 points more replaces it if its fit error is within 3/2 of the current's.
    pts = sphere(3000, (100, 200, 300), 6000, seed=11, noise=30)
    partial = Calibration(model=10, offset=(100, 200, 300), field=6000, field_out=6000,
                          fit_error=40, coverage=55)
    cal = calibrator_with(pts, counts_per_gauss=CPG, current=partial)
    fe = cal.solve(accept=False).fit_error
    assert partial.fit_error < fe <= partial.fit_error * 3 // 2
    c = cal.solve()
    assert cal.current is c and c.coverage >= partial.coverage + 15
    # the same fit error at the same coverage is still refused
    same = Calibration(model=10, offset=(100, 200, 300), field=6000, field_out=6000,
                       fit_error=40, coverage=c.coverage)
    cal.current = same
    e = rejected(cal, 10)
    assert e.reason == acceptance.REASON_NOT_BETTER and "coverage" in e.detail


def test_samples_at_a_chips_rails_never_enter_the_fit_and_are_counted():
    # int16 rails (a clipping chip) always; the HMC5883L's -4096 marker when it is the chip's
    c = Calibrator(model=10, counts_per_gauss=12000)
    assert c.add(100, 200, 300) and c.count == 1
    for s in ((32767, 0, 0), (0, -32768, 5), (7, 8, 32767)):
        assert not c.add(*s)
    assert c.count == 1 and c.railed == 3
    assert c.add(-4096, 900, 900)  # a plain reading on a QMC chip
    h = Calibrator(model=10, counts_per_gauss=1090, overflow=-4096)
    assert not h.add(-4096, 12, 13) and h.railed == 1 and h.count == 0
    from firmware.calibrate.calibrator import Collector
    col = Collector(counts_per_gauss=1090, overflow=-4096)
    col.feed([-4096, -4096, -4096])
    assert col.calibrator.railed == 1 and col.calibrator.count == 0
