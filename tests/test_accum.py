"""The moment sums are exact: any sequence of adds and removals leaves the batch sums."""
from hypothesis import given, strategies as st

from tests import solve_ref
from firmware.calibrate import accum
from firmware.calibrate.samples import KEPT, REJECTED, REPLACED, SampleBuffer

i16 = st.integers(min_value=-32768, max_value=32767)
points = st.tuples(i16, i16, i16)


def direct_sums(samples, c):
    # the definition, written independently of accum's loops
    out = {}
    for (i, j, k) in accum.EXPONENTS:
        out[(i, j, k)] = sum((x - c[0]) ** i * (y - c[1]) ** j * (z - c[2]) ** k
                             for x, y, z in samples)
    return out


def test_exponents_are_the_35_monomials_of_degree_0_to_4():
    assert len(accum.EXPONENTS) == accum.NUM_MOMENTS == 35
    assert len(set(accum.EXPONENTS)) == 35
    assert all(sum(e) <= 4 for e in accum.EXPONENTS)
    for n, e in enumerate(accum.EXPONENTS):
        assert accum.index(*e) == n


def test_index_refuses_degree_5():
    for e in ((5, 0, 0), (2, 2, 1), (-1, 0, 0)):
        try:
            accum.index(*e)
        except ValueError as err:
            assert "degree" in str(err)
        else:
            raise AssertionError("index%r accepted" % (e,))


@given(st.lists(points, min_size=1, max_size=30))
def test_streamed_sums_equal_the_definition(samples):
    m = accum.Moments()
    for p in samples:
        m.add(*p)
    assert m.c == samples[0]
    want = direct_sums(samples, samples[0])
    assert m.s == [want[e] for e in accum.EXPONENTS]


@given(st.lists(st.tuples(st.booleans(), points), min_size=1, max_size=60))
def test_sums_after_adds_and_removals_equal_batch_sums_over_the_held_samples(ops):
    m = accum.Moments()
    held = []
    for remove, p in ops:
        if remove and held:
            q = held.pop(len(held) // 2)
            m.sub(*q)
        else:
            held.append(p)
            m.add(*p)
        assert m.s == solve_ref.batch(held, m.c)


@given(st.lists(points, min_size=1, max_size=20), points)
def test_shifted_sums_equal_batch_sums_about_the_new_centre(samples, new_c):
    m = accum.Moments()
    for p in samples:
        m.add(*p)
    assert accum.shifted(m.c, m.s, new_c) == solve_ref.batch(samples, new_c)


@given(st.lists(points, min_size=1, max_size=400), st.integers(min_value=4, max_value=40),
       st.integers(min_value=1, max_value=3000))
def test_sums_follow_a_sample_buffer_through_evictions(samples, capacity, separation):
    # the way the Calibrator drives them: KEPT adds, REPLACED subtracts .evicted first
    buf = SampleBuffer(capacity=capacity, separation=separation)
    m = accum.Moments()
    for p in samples:
        r = buf.offer(*p)
        if r == REJECTED:
            continue
        if r == REPLACED:
            m.sub(*buf.evicted)
        else:
            assert r == KEPT
        m.add(*p)
    held = [tuple(buf.data[3 * i:3 * i + 3]) for i in range(buf.count)]
    assert m.s == solve_ref.batch(held, m.c)


def test_rebuild_equals_streaming_and_clear_forgets_the_centre():
    pts = [(100, -200, 300), (-5, 7, 9), (32767, -32768, 0)]
    a = accum.Moments()
    for p in pts:
        a.add(*p)
    b = accum.Moments()
    b.rebuild(pts)
    assert (a.c, a.s) == (b.c, b.s)
    b.clear()
    assert b.c is None and b.count == 0


def test_removing_from_empty_sums_is_refused():
    m = accum.Moments()
    try:
        m.sub(1, 2, 3)
    except ValueError as e:
        assert "(1, 2, 3)" in str(e)
    else:
        raise AssertionError("sub on empty sums accepted")


def test_degree_four_sums_of_a_full_int16_range_buffer_are_exact_long_ints():
    # the worst case the solver sees: 16383 samples at opposite int16 corners
    m = accum.Moments()
    m.add(-32768, -32768, -32768)
    for _ in range(16382):
        m.add(32767, 32767, 32767)
    assert m.s[accum.index(4, 0, 0)] == 16382 * 65535 ** 4
