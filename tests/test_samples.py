"""firmware/calibrate/samples.py: distance-separated sample buffer and sphere coverage.

The reference for every decision is a brute-force model written here from the rule itself
(keep a sample only if its cell of side s is empty and no held sample is closer than s; FIFO
eviction when full), independent of the hash table the firmware uses.
"""
import json
import math
import random

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from firmware.calibrate import samples
from firmware.calibrate.samples import (KEPT, MAX_SEPARATION, N_REGIONS, REJECTED, REPLACED, SampleBuffer,
                              region, separation_for)
from tests import intcheck, mp


# ---------------------------------------------------------------- reference model

class RefBuffer:
    """Brute force: scans every held sample (age order, oldest first)."""

    def __init__(self, capacity, s):
        self.capacity = capacity
        self.s = s
        self.held = []

    def offer(self, p):
        s = self.s
        cell = tuple(c // s for c in p)
        taken = any(tuple(c // s for c in q) == cell for q in self.held)
        near = any(sum((a - b) ** 2 for a, b in zip(p, q)) < s * s for q in self.held)
        if taken or near:
            return REJECTED, None
        self.held.append(tuple(p))
        if len(self.held) > self.capacity:
            return REPLACED, self.held.pop(0)
        return KEPT, None


def held_by_age(buf):
    out = []
    v = [0, 0, 0]
    for k in range(buf.count):
        buf.sample(buf.slot_by_age(k), v)
        out.append(tuple(v))
    return out


def rebuilt_table(buf):
    """The hash table obtained by inserting the held samples afresh in age order."""
    size = len(buf._table)
    t = [0] * size
    for k in range(buf.count):
        slot = buf.slot_by_age(k)
        c = buf._cells[3 * slot:3 * slot + 3]
        i = samples._hash(c, 0) & (size - 1)
        while t[i]:
            i = (i + 1) & (size - 1)
        t[i] = slot + 1
    return t


int16 = st.integers(min_value=-32768, max_value=32767)


@st.composite
def offer_runs(draw, max_len=120):
    """A separation, a capacity small enough to wrap, and clustered int16 points (conflicts are
    common), with some points anywhere in int16 (including the extremes)."""
    s = draw(st.integers(min_value=1, max_value=3000))
    capacity = draw(st.integers(min_value=1, max_value=24))
    centre = [draw(int16) for _ in range(3)]
    spread = draw(st.integers(min_value=1, max_value=6)) * s
    pts = []
    for _ in range(draw(st.integers(min_value=1, max_value=max_len))):
        if draw(st.integers(min_value=0, max_value=9)) == 0:
            pts.append(tuple(draw(st.sampled_from([-32768, 32767, 0])) if
                             draw(st.booleans()) else draw(int16) for _ in range(3)))
        else:
            off = [draw(st.integers(min_value=-spread, max_value=spread)) for _ in range(3)]
            pts.append(tuple(max(-32768, min(32767, c + o)) for c, o in zip(centre, off)))
    return s, capacity, pts


# ---------------------------------------------------------------- the rule, by properties

@given(offer_runs())
def test_offer_decisions_and_fifo_match_the_brute_force_reference(run):
    s, capacity, pts = run
    buf = SampleBuffer(capacity=capacity, separation=s)
    ref = RefBuffer(capacity, s)
    for p in pts:
        r = buf.offer(*p)
        want, evicted = ref.offer(p)
        assert r == want, (p, r, want)
        if r == REPLACED:
            assert tuple(buf.evicted) == evicted
        assert buf.count <= buf.capacity
        assert held_by_age(buf) == ref.held


@given(offer_runs())
def test_every_pair_of_held_samples_is_at_least_separation_apart(run):
    s, capacity, pts = run
    buf = SampleBuffer(capacity=capacity, separation=s)
    for p in pts:
        buf.offer(*p)
        held = held_by_age(buf)
        for i in range(len(held)):
            for j in range(i):
                assert sum((a - b) ** 2 for a, b in zip(held[i], held[j])) >= s * s


@given(offer_runs(max_len=300))
def test_hash_table_equals_a_fresh_rebuild_after_wraparound(run):
    # Backward-shift deletion leaves the table exactly as if the deleted sample had never been
    # inserted (Knuth 6.4, Algorithm R), so after any churn the table must equal the one built
    # by inserting the held samples in age order: no stale entry, none missing, none misplaced.
    s, capacity, pts = run
    buf = SampleBuffer(capacity=capacity, separation=s)
    for p in pts:
        buf.offer(*p)
        assert list(buf._table) == rebuilt_table(buf)
    for slot in range(buf.count):
        for a in range(3):
            assert buf._cells[3 * slot + a] == buf.data[3 * slot + a] // s


@given(offer_runs(max_len=60), st.integers(min_value=-3, max_value=3),
       st.integers(min_value=-3, max_value=3), st.integers(min_value=-3, max_value=3))
def test_decisions_are_origin_independent_for_whole_cell_translations(run, a, b, c):
    # Distance separation has no origin (Judd): moving every sample by whole cells (the hard
    # iron changing by a multiple of s) changes no decision.
    s, capacity, pts = run
    t = (a * s, b * s, c * s)
    moved = [tuple(p[k] + t[k] for k in range(3)) for p in pts]
    if any(not -32768 <= v <= 32767 for q in moved for v in q):
        return
    b1 = SampleBuffer(capacity=capacity, separation=s)
    b2 = SampleBuffer(capacity=capacity, separation=s)
    assert [b1.offer(*p) for p in pts] == [b2.offer(*q) for q in moved]


def test_fifo_evicts_in_arrival_order_and_keeps_slots_a_prefix():
    buf = SampleBuffer(capacity=5, separation=100)
    pts = [(1000 * i - 15000, 700 * i - 9000, -300 * i) for i in range(23)]  # all far apart
    evicted = []
    for i, p in enumerate(pts):
        r = buf.offer(*p)
        assert r == (KEPT if i < 5 else REPLACED)
        if r == REPLACED:
            evicted.append(tuple(buf.evicted))
        assert buf.count == min(i + 1, 5)
    assert evicted == pts[:18]
    assert held_by_age(buf) == pts[18:]
    assert sorted(tuple(buf.data[3 * k:3 * k + 3]) for k in range(5)) == sorted(pts[18:])


def test_kept_samples_spread_evenly_around_a_ring_far_from_the_origin():
    # Judd's failure case for angle separation: the hard iron (8000 counts) is larger than the
    # field radius (1500). Distance separation still spaces samples evenly along the ring.
    R, V, s = 1500, (8000, -3000, 500), 150
    buf = SampleBuffer(capacity=200, separation=s)
    for k in range(20000):
        a = 2 * math.pi * ((k * 0.6180339887) % 1.0)
        buf.offer(V[0] + round(R * math.cos(a)), V[1] + round(R * math.sin(a)), V[2])
    angles = sorted(math.atan2(buf.data[3 * i + 1] - V[1], buf.data[3 * i] - V[0])
                    for i in range(buf.count))
    gaps = [b - a for a, b in zip(angles, angles[1:])] + [angles[0] + 2 * math.pi - angles[-1]]
    chord = [2 * R * math.sin(g / 2) for g in gaps]
    assert min(chord) >= s - 1                      # never closer than s (rounding of the ring)
    assert max(chord) < 2 * math.sqrt(3) * s         # no hole: a cell diagonal at most, twice
    assert buf.count >= 2 * math.pi * R / (2 * math.sqrt(3) * s)


@pytest.mark.parametrize("via_newest", [True, False])
def test_exactly_separation_apart_is_kept_and_just_closer_is_rejected(via_newest):
    # s = 5: (3, 4, 0) is exactly 5 counts, (3, 3, 0) is 4.24. Tested both against the newest
    # sample (the first check of offer) and against an older one (found through the hash).
    buf = SampleBuffer(capacity=8, separation=5)
    assert buf.offer(4, 4, 0) == KEPT
    if not via_newest:
        assert buf.offer(-20000, 0, 0) == KEPT
    assert buf.offer(7, 7, 0) == REJECTED
    assert buf.offer(7, 8, 0) == KEPT


def test_reject_then_clear_then_keep():
    buf = SampleBuffer(capacity=4, separation=50)
    assert buf.offer(0, 0, 0) == KEPT
    assert buf.offer(10, 10, 10) == REJECTED
    buf.clear()
    assert buf.count == 0
    assert buf.offer(10, 10, 10) == KEPT
    out = [9, 9, 9]
    buf.sample(0, out)
    assert out == [10, 10, 10]
    with pytest.raises(IndexError):
        buf.sample(1, out)


@pytest.mark.parametrize("p", [(32768, 0, 0), (0, -32769, 0), (0, 0, -(1 << 31))])
def test_offer_refuses_values_outside_int16(p):
    buf = SampleBuffer(capacity=4, separation=50)
    with pytest.raises(ValueError):
        buf.offer(*p)
    assert buf.count == 0


@pytest.mark.parametrize("p", [(1.5, 0, 0), (0, "7", 0), (0, 0, 1 << 40), (0, None, 0)])
def test_offer_says_not_int_for_floats_text_and_ints_beyond_32_bits(p):
    # the int array refuses them before anything changes; Calibrator.add turns the code into
    # the exception (tests/test_api_inputs.py)
    buf = SampleBuffer(capacity=4, separation=50)
    assert buf.offer(*p) == samples.NOT_INT
    assert buf.count == 0
    err = samples.bad_sample(*p)
    assert isinstance(err, ValueError if p[2] == 1 << 40 else TypeError)


@pytest.mark.parametrize("cap,sep", [(0, 50), (samples.MAX_CAPACITY + 1, 50), (10, 0),
                                     (10, MAX_SEPARATION + 1)])
def test_constructor_refuses_bad_capacity_or_separation(cap, sep):
    with pytest.raises(ValueError):
        SampleBuffer(capacity=cap, separation=sep)


@given(offer_runs(max_len=80), st.integers(min_value=1, max_value=4000))
def test_set_separation_keeps_the_rule_prefers_newer_samples_and_keeps_age_order(run, new_s):
    s, capacity, pts = run
    buf = SampleBuffer(capacity=capacity, separation=s)
    for p in pts:
        buf.offer(*p)
    before = held_by_age(buf)
    dropped = buf.set_separation(new_s)
    after = held_by_age(buf)
    assert dropped == len(before) - len(after)
    # survivors in their old relative order
    it = iter(before)
    assert all(any(q == p for q in it) for p in after)
    # exactly what a newest-first greedy pass under the new rule keeps
    ref = RefBuffer(len(before) + 1, new_s)
    kept = [p for p in reversed(before) if ref.offer(p)[0] != REJECTED]
    assert after == kept[::-1]
    assert list(buf._table) == rebuilt_table(buf)
    if new_s <= s:
        assert all(sum((a - b) ** 2 for a, b in zip(p, q)) >= new_s ** 2
                   for i, p in enumerate(after) for q in after[:i])


# ---------------------------------------------------------------- cost per offer

def _sphere_points(n, R, V, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v = v / np.linalg.norm(v, axis=1)[:, None]
    return [tuple(int(round(R * c + V[k])) for k, c in enumerate(row)) for row in v]


def test_lookups_per_offer_are_bounded_whatever_the_fill():
    # At most 27 cell look-ups per offer, empty or full; table entries read per look-up stay
    # near the linear-probing figure for load <= 1/3 (about 1.6) whatever the fill.
    R, V = 6000, (1200, -800, 300)
    buf = SampleBuffer(capacity=300, separation=separation_for(R, 225))
    pts = _sphere_points(12000, R, V, 3) + _sphere_points(8000, R, (V[0] + 3000, V[1], V[2]), 4)
    stats = {"empty": [0, 0, 0], "full": [0, 0, 0]}
    for p in pts:
        phase = "full" if buf.count == buf.capacity else "empty"
        buf.offer(*p)
        st_ = stats[phase]
        st_[0] += 1
        st_[1] += buf.last_cells
        st_[2] += buf.last_probes
        assert buf.last_cells <= 27
    assert stats["full"][0] > 5000  # the hard-iron jump made the buffer wrap for a long time
    for phase, (n, cells, probes) in stats.items():
        assert probes / cells < 2.0, (phase, probes / cells)


def test_separation_for_fills_a_sphere_to_about_the_requested_count():
    for R, n in [(545, 100), (1500, 225), (6000, 225)]:
        s = separation_for(R, n)
        buf = SampleBuffer(capacity=4 * n, separation=s)
        for p in _sphere_points(25000, R, (0, 0, 0), R):
            buf.offer(*p)
        assert 0.75 * n <= buf.count <= 1.25 * n, (R, n, s, buf.count)
    assert separation_for(10, 10 ** 6) == 1
    with pytest.raises(ValueError):
        separation_for(0, 10)


# ---------------------------------------------------------------- regions and coverage

BAND_Z = [1.0, 0.98, 0.86, 0.64, 0.34, 0.0]
BAND_N = [1, 6, 11, 15, 17]


def ref_region(dx, dy, dz):
    """Float reference of the documented partition."""
    r = math.sqrt(dx * dx + dy * dy + dz * dz)
    zr = abs(dz) / r
    band = next(b for b in range(5) if zr >= BAND_Z[b + 1])
    first = sum(BAND_N[:band]) + (0 if dz >= 0 else 50)
    ang = math.atan2(dy, dx) % (2 * math.pi)
    return first + min(BAND_N[band] - 1, int(ang / (2 * math.pi / BAND_N[band])))


def test_partition_has_100_regions_of_equal_area_by_construction():
    # Area on the unit sphere between z = a and z = b is 2*pi*(b - a) (Archimedes).
    assert sum(BAND_N) * 2 == N_REGIONS
    for b in range(5):
        area = 2 * math.pi * (BAND_Z[b] - BAND_Z[b + 1]) / BAND_N[b]
        assert area == pytest.approx(4 * math.pi / N_REGIONS, rel=1e-12)
        assert samples._Z_FIFTIETHS[b] == round(50 * BAND_Z[b + 1])
    # sector boundaries: unit vectors at 2*pi*k/n in Q14, within one LSB
    for b in range(1, 5):
        t = samples._BOUNDS[b]
        n = BAND_N[b]
        assert len(t) == 2 * n
        for k in range(n):
            a = 2 * math.pi * k / n
            assert abs(t[2 * k] - 16384 * math.cos(a)) <= 0.5
            assert abs(t[2 * k + 1] - 16384 * math.sin(a)) <= 0.5


def test_region_matches_float_reference_and_areas_are_equal_monte_carlo():
    rng = np.random.default_rng(7)
    n = 100000
    v = rng.normal(size=(n, 3))
    v = v / np.linalg.norm(v, axis=1)[:, None]
    radii = rng.choice([1000, 6000, 40000, 65535], size=n)
    counts = [0] * N_REGIONS
    disagree = 0
    for row, R in zip(v, radii):
        d = [int(round(R * c)) for c in row]
        if d == [0, 0, 0]:
            continue
        g = region(*d)
        counts[g] += 1
        disagree += g != ref_region(*d)
    assert disagree < 0.001 * n  # only points on a boundary may fall either side
    mean = n / N_REGIONS
    assert min(counts) > 0.85 * mean and max(counts) < 1.15 * mean  # +-15 % is ~4.7 sigma


@given(st.integers(-65535, 65535), st.integers(-65535, 65535), st.integers(-65535, 65535))
def test_region_is_in_range_and_matches_reference_away_from_boundaries(dx, dy, dz):
    g = region(dx, dy, dz)
    if dx == dy == dz == 0:
        assert g == -1
        return
    assert 0 <= g < N_REGIONS
    # any disagreement must be a point within 1e-3 (relative) of a band or sector boundary
    if g != ref_region(dx, dy, dz):
        r = math.sqrt(dx * dx + dy * dy + dz * dz)
        zr = abs(dz) / r
        near_band = min(abs(zr - z) for z in BAND_Z) < 1e-3 or (dz == 0 or abs(dz) / r < 1e-3)
        ang = math.atan2(dy, dx) % (2 * math.pi)
        near_sector = any(min(abs(ang - 2 * math.pi * k / n) for k in range(n + 1)) * max(
            math.hypot(dx, dy) / r, 1e-9) < 1e-3 for n in BAND_N[1:])
        assert near_band or near_sector, (dx, dy, dz, g, ref_region(dx, dy, dz))


def _coverage_of(pts, V, R, capacity=300):
    buf = SampleBuffer(capacity=capacity, separation=separation_for(R, capacity * 3 // 4))
    for p in pts:
        buf.offer(*p)
    return buf.coverage(*V), buf


def test_coverage_full_sphere_is_near_100_and_motioncal_gaps_good():
    R, V = 6000, (2500, -1800, 900)
    cov, buf = _coverage_of(_sphere_points(4000, R, V, 11), V, R)
    assert cov >= 95
    assert buf.gaps_x100 < 1500  # MotionCal: gaps < 15 is good
    assert sum(buf.region_counts) == buf.count
    # seen from a wrong centre the same samples look less even
    buf.coverage(V[0] + 5000, V[1], V[2])
    assert buf.gaps_x100 > 1500


def test_coverage_hemisphere_is_about_half():
    R, V = 6000, (-700, 300, 1500)
    pts = [p for p in _sphere_points(8000, R, V, 12) if p[2] > V[2]]
    cov, buf = _coverage_of(pts, V, R)
    assert 45 <= cov <= 50


@pytest.mark.parametrize("tilt_deg", [0, 20, 45, 70, 90])
def test_coverage_of_planar_data_is_low(tilt_deg):
    # Judd's degenerate case: a vehicle that only turns flat gives one ring of samples. A great
    # circle crosses the ~20-degree regions about 20-40 times, never most of the sphere.
    R, V = 6000, (400, 400, -900)
    t = math.radians(tilt_deg)
    rng = random.Random(tilt_deg)
    pts = []
    for k in range(3000):
        a = 2 * math.pi * rng.random()
        x, y, z = R * math.cos(a), R * math.sin(a), rng.uniform(-0.02, 0.02) * R
        y, z = y * math.cos(t) - z * math.sin(t), y * math.sin(t) + z * math.cos(t)
        pts.append((V[0] + round(x), V[1] + round(y), V[2] + round(z)))
    cov, buf = _coverage_of(pts, V, R)
    assert cov <= 40, cov
    assert buf.gaps_x100 > 6000


def test_coverage_of_empty_buffer_is_zero_with_all_gaps():
    buf = SampleBuffer(capacity=10, separation=10)
    assert buf.coverage(0, 0, 0) == 0
    assert buf.gaps_x100 == 100 * N_REGIONS
    buf.offer(5, 5, 5)
    assert buf.coverage(5, 5, 5) == 0  # a sample at the centre has no direction


# ---------------------------------------------------------------- small-int bounds

@settings(max_examples=150)
@given(st.integers(min_value=1, max_value=MAX_SEPARATION), st.integers(min_value=1, max_value=6),
       st.lists(st.tuples(int16, int16, int16), min_size=1, max_size=40),
       st.tuples(int16, int16, int16))
def test_offer_and_coverage_never_leave_small_int_range(s, capacity, pts, centre):
    mod, stats = intcheck.load("calibrate.samples")
    buf = mod.SampleBuffer(capacity=capacity, separation=s)
    # clustered copies force the near/far distance arithmetic, extremes the cell arithmetic
    extra = [(max(-32768, min(32767, x + s - 1)), y, max(-32768, min(32767, z - s + 1)))
             for x, y, z in pts]
    extra += [(-32768, -32768, -32768), (32767, 32767, 32767), (32767, -32768, 0)]
    for p in pts + extra:
        buf.offer(*p)
    buf.coverage(*centre)
    assert stats.max_abs < 1 << 30


@given(st.integers(-65535, 65535), st.integers(-65535, 65535), st.integers(-65535, 65535))
def test_region_never_leaves_small_int_range(dx, dy, dz):
    mod, stats = intcheck.load("calibrate.samples")
    mod.region(dx, dy, dz)
    assert stats.max_abs < 1 << 30


# ---------------------------------------------------------------- MicroPython

def test_samples_bit_identical_on_micropython():
    lines = mp.json_lines(mp.parity(["tests/scenarios/samples_parity.py"]))
    offers = lines[0]
    assert offers[0] == "offers"
    assert offers[1][REPLACED] > 0  # the sequence wraps the buffer
    assert offers[6] == 64


def test_offer_and_coverage_allocate_nothing_on_micropython():
    out = json.loads(mp.run(["tests/scenarios/samples_alloc.py"], micro=True))
    assert out["control_list"] == [True, True]  # the harness does see an allocation
    for path in ("reject_newest", "reject_taken_cell", "reject_neighbour", "keep", "replace",
                 "coverage", "walk_2000"):
        assert out[path][0] is True, (path, out[path])   # the path behaved as intended
        assert out[path][1] is False, (path, out[path])  # heap_lock saw no allocation
    # the reject paths are the ones named: newest-sample test, own cell, a neighbour cell
    assert out["reject_newest"][2] == 0
    assert out["reject_taken_cell"][2] == 1
    assert 1 < out["reject_neighbour"][2] <= 27
    for path in ("reject_newest", "reject_taken_cell", "reject_neighbour", "replace"):
        assert out[path][-1] == 0, (path, out[path])     # gc.mem_alloc() delta in bytes


def test_offer_cost_counts_per_path_agree_on_both_interpreters():
    # Cells looked up and entries read per offer, per path; the time column (MicroPython, heap
    # locked) is for the benchmark and not asserted here.
    cp = mp.json_lines(mp.run(["tests/scenarios/samples_cost.py"], micro=False))
    mu = mp.json_lines(mp.run(["tests/scenarios/samples_cost.py"], micro=True))
    assert [row[:4] for row in cp] == [row[:4] for row in mu]
    rows = dict((row[0], row[1:]) for row in mu)
    assert rows["reject_newest"][1] == 0                       # decided before any hashing
    assert rows["reject_own_cell"][1] == rows["reject_own_cell"][0]   # exactly one cell
    for name in ("random_filling", "random_full", "smooth_stream"):
        offers, cells, probes, _ = rows[name]
        assert cells <= 27 * offers and probes < 2 * cells
