"""The time-sliced solve (Calibrator.solve_steps): bounded work per slice, the same bits as
the solve in one go.

Work per slice is bounded by COUNTS, never by time: long-int operations counted exactly by
desktop/benchmarks/intcount.py's TInt (an operation whose operand or result is >= 2**30
is a heap-allocated long int on a 32-bit board), samples classified by the coverage count,
and Python lines executed (sys.settrace) as a proxy for the bytecode. Times are the bench's
business (`make bench`: desktop/benchmarks/solver.py).
"""
import math
import random
import sys

import pytest
from hypothesis import given, strategies as st

from tests import solve_ref
from firmware import fixedpoint
from firmware.calibrate import accum
from firmware.calibrate import calibrator
from firmware.calibrate import samples
from firmware.calibrate import solve
from firmware.errors import CalibrationRejected
from firmware.calibrate.calibrator import Calibrator
from desktop.benchmarks import intcount

MODELS = ("minmax", 4, 7, 10)
# Python lines a slice may execute (CPython's line events): the bytecode side of the bound.
# The longest in lines is a coverage chunk (COVERAGE_CHUNK = 4 samples through region():
# ~550 short lines); every other slice runs <= ~380 (a normal-equation chunk). On the
# MicroPython unix port the longest slices take ~15 us (make bench).
MAX_LINES_PER_SLICE = 600


def ellipsoid_points(n, seed, radius=6000.0, centre=(1400.0, -900.0, 450.0),
                     w=((1.15, 0.08, -0.03), (0.08, 0.92, 0.05), (-0.03, 0.05, 0.97)),
                     noise=20.0, cap=-1.0):
    """n int16 readings W d + V + noise, d uniform on a sphere (z/|d| >= cap); CPython only
    (random.gauss), self-contained so the expected bytes below cannot drift with host_sim."""
    rng = random.Random(seed)
    out = []
    while len(out) < n:
        d = [rng.gauss(0, 1) for _ in range(3)]
        r = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
        if r == 0 or d[2] / r < cap:
            continue
        d = [radius * v / r for v in d]
        out.append(tuple(int(round(sum(w[i][j] * d[j] for j in range(3)) + centre[i]
                                   + rng.gauss(0, noise))) for i in range(3)))
    return out


def filled(points, model=10, **kw):
    cal = Calibrator(model=model, capacity=300, **kw)
    for p in points:
        cal.add(*p)
    return cal


def run_slices(job, between=None):
    """Step a solve generator to its end: (result or CalibrationRejected, slices)."""
    n = 0
    while True:
        try:
            next(job)
        except StopIteration as e:
            return e.value, n + 1
        except CalibrationRejected as e:
            return e, n + 1
        n += 1
        if between is not None:
            between()


# Calibration.to_bytes() of the solve in one go (firmware/magcal.py before slicing, commit
# d4a57ba) on ellipsoid_points(3000, seed=7) with capacity 300: the slicing must not move a
# bit of it.
UNSLICED_BYTES = {
    "minmax": "01016400ed011c01760500007ffcffffc40100009966000000000000ff7f000000000000f579bf17"
              "0000b4150000",
    4: "0104640005031c016e0500007dfcffffb2010000ff7f000000000000ff7f000000000000ff7fc9170000"
       "c9170000",
    7: "01076400ef011c016b05000076fcffffb5010000c766000000000000ff7f000000000000017aab170000"
       "a6150000",
    10: "010a640022001c01740500007afcffffc1010000db5afbf73403fbf7d671def93403def9606b90170000"
        "ff120000",
}


def test_sliced_solve_gives_the_unsliced_calibration_bytes():
    pts = ellipsoid_points(3000, seed=7)
    for m in MODELS:
        cal = filled(pts, model=m)
        got, n = run_slices(cal.solve_steps(accept=False, group=1))
        assert not isinstance(got, Exception), got
        assert n > 100  # really sliced
        assert got.to_bytes().hex() == UNSLICED_BYTES[m], m
        assert got == cal.solve(accept=False)


@pytest.mark.parametrize("case", ["cap", "planar", "few", "hmc"])
def test_sliced_solve_refuses_and_accepts_like_the_solve_in_one_go(case):
    if case == "cap":
        pts = ellipsoid_points(2000, seed=3, cap=0.4)
    elif case == "planar":
        pts = [(p[0], p[1], 450 + (p[2] - 450) // 50) for p in ellipsoid_points(2000, seed=4)]
    elif case == "few":
        pts = ellipsoid_points(60, seed=5)
    else:  # HMC5883L scale: small numbers, separation derived from the data
        pts = ellipsoid_points(2000, seed=6, radius=545.0, centre=(120.0, -40.0, 60.0),
                               noise=3.0)
    for m in MODELS:
        a, _ = run_slices(filled(pts, model=m).solve_steps(accept=False, group=1))
        try:
            b = filled(pts, model=m).solve(accept=False)
        except CalibrationRejected as e:
            b = e
        if isinstance(b, Exception):
            assert isinstance(a, CalibrationRejected) and (a.reason, a.detail) == (
                b.reason, b.detail)
        else:
            assert a == b


# ---------------------------------------------------------------- the pieces, exactly

@given(st.lists(st.tuples(*[st.integers(-32768, 32767)] * 3), min_size=1, max_size=30),
       st.tuples(*[st.integers(-40000, 40000)] * 3), st.tuples(*[st.integers(-40000, 40000)] * 3))
def test_shifted_steps_equals_shifted_and_the_batch_sums(pts, c, new_c):
    s = solve_ref.batch(pts, c)
    out = [0] * accum.NUM_MOMENTS
    for _ in accum.shifted_steps(c, s, new_c, out):
        pass
    assert out == accum.shifted(c, s, new_c) == solve_ref.batch(pts, new_c)


@given(st.integers(0, 1 << 3000))
def test_isqrt_and_icbrt_steps_equal_fixedpoint(n):
    r = [None]
    solve_ref._run(solve.isqrt_steps(n, r))
    assert r[0] == fixedpoint.isqrt(n)
    solve_ref._run(solve.icbrt_steps(n, r))
    assert r[0] == fixedpoint.icbrt(n)


@given(st.integers(-(1 << 3000), 1 << 3000), st.integers(-(1 << 3000), 1 << 3000))
def test_mul_steps_is_the_exact_product(a, b):
    r = [None]
    solve_ref._run(solve.mul_steps(a, b, r))
    assert r[0] == a * b


@pytest.mark.parametrize("model", [4, 7, 10])
def test_sliced_fit_equals_one_bareiss_elimination_of_the_normal_equations(model):
    pts = ellipsoid_points(400, seed=11)
    cal = filled(pts)
    c, s = cal.moments.snapshot()
    f = solve_ref.fit(c, s, model)
    # the unsliced reference: shifted, normal_equations, bareiss_step, back_substitute
    n = s[0]
    cm = (c[0] + fixedpoint.rdiv(s[1], n), c[1] + fixedpoint.rdiv(s[2], n),
          c[2] + fixedpoint.rdiv(s[3], n))
    m, r, yy = solve.normal_equations(accum.shifted(c, s, cm), model)
    nc = len(m)
    a = [m[i] + [r[i]] for i in range(nc)]
    prev = 1
    for k in range(nc - 1):
        prev = solve.bareiss_step(a, k, prev, nc + 1)
    beta = solve_ref.back_substitute(a, nc)
    d = a[nc - 1][nc - 1]
    assert f.c == cm and f.D == d and f.beta_num == beta
    assert f.p_num == yy * d - sum(beta[i] * r[i] for i in range(nc))
    assert f.det_a2 == solve.det3(f.a2)


def test_coverage_steps_equals_coverage_with_chunks_of_any_size():
    pts = ellipsoid_points(3000, seed=9, cap=-0.3)
    cal = filled(pts)
    buf = cal.buffer
    v = cal.centre_estimate()
    want = buf.coverage(*v)
    counts, gaps = bytes(buf.region_counts), buf.gaps_x100
    for chunk in (1, 3, samples.COVERAGE_CHUNK, 1000):
        out = [None]
        for _ in buf.coverage_steps(v[0], v[1], v[2], out, chunk=chunk):
            pass
        assert out[0] == want and bytes(buf.region_counts) == counts
        assert buf.gaps_x100 == gaps


# ---------------------------------------------------------------- bounded work per slice

def _long_ops_per_slice(cal, model, group=1):
    intcount.instrument(cal)
    job = cal.solve_steps(model=model, accept=False, group=group)
    per = []
    while True:
        a = intcount.snapshot()
        try:
            next(job)
        except (StopIteration, CalibrationRejected):
            d = intcount.delta(a)
            per.append(d[1] + d[2])
            return per
        d = intcount.delta(a)
        per.append(d[1] + d[2])


@pytest.mark.parametrize("model", MODELS)
def test_no_slice_does_more_than_slice_ops_long_int_operations(model):
    # full buffer (the bench's case) and a small-number (HMC5883L-like) one
    for pts in (ellipsoid_points(3000, seed=7),
                ellipsoid_points(2000, seed=6, radius=545.0, centre=(120.0, -40.0, 60.0),
                                 noise=3.0)):
        per = _long_ops_per_slice(filled(pts, model=model), model)
        assert max(per) <= solve.SLICE_OPS, (model, max(per), per.index(max(per)))
        assert sum(per) > 2 * solve.SLICE_OPS  # the count sees the solve's long ints


@pytest.mark.parametrize("group", [3, calibrator.DEFAULT_SLICE_GROUP])
def test_a_group_of_slices_per_next_does_at_most_group_times_the_work_and_the_same_fit(group):
    pts = ellipsoid_points(3000, seed=7)
    fine = _long_ops_per_slice(filled(pts), 10)
    per = _long_ops_per_slice(filled(pts), 10, group)
    assert max(per) <= group * solve.SLICE_OPS and sum(per) == sum(fine)
    assert len(per) == (len(fine) + group - 1) // group
    a, _ = run_slices(filled(pts).solve_steps(accept=False, group=group))
    assert a.to_bytes().hex() == UNSLICED_BYTES[10]


def test_coverage_slices_classify_at_most_chunk_samples(monkeypatch):
    calls = [0]
    region = samples.region

    def counted(dx, dy, dz):
        calls[0] += 1
        return region(dx, dy, dz)

    monkeypatch.setattr(samples, "region", counted)
    cal = filled(ellipsoid_points(3000, seed=7))
    job = cal.solve_steps(accept=False, group=1)
    per = []
    while True:
        calls[0] = 0
        try:
            next(job)
        except StopIteration:
            break
        per.append(calls[0])
    assert max(per) == samples.COVERAGE_CHUNK
    assert sum(per) == cal.count


@pytest.mark.parametrize("model", MODELS)
def test_no_slice_executes_more_than_a_few_hundred_lines(model):
    cal = filled(ellipsoid_points(3000, seed=7), model=model)
    job = cal.solve_steps(accept=False, group=1)
    lines = [0]

    def tracer(frame, event, arg):
        if event == "line":
            lines[0] += 1
        return tracer

    per = []
    old = sys.gettrace()
    try:
        while True:
            lines[0] = 0
            sys.settrace(tracer)
            try:
                next(job)
            except StopIteration:
                sys.settrace(old)
                per.append(lines[0])
                break
            sys.settrace(old)
            per.append(lines[0])
    finally:
        sys.settrace(old)
    assert max(per) <= MAX_LINES_PER_SLICE, (max(per), per.index(max(per)))
