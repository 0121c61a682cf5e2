import math

from hypothesis import given, strategies as st

from firmware.fixedpoint import bit_length, icbrt, isqrt, rdiv, sat16
from tests import intcheck, mp


@given(st.integers(min_value=0, max_value=1 << 200))
def test_isqrt_is_exact_floor(n):
    assert isqrt(n) == math.isqrt(n)


@given(st.integers(min_value=-(1 << 300), max_value=1 << 300))
def test_icbrt_is_exact_floor(n):
    r = icbrt(n)
    assert r ** 3 <= n < (r + 1) ** 3


def test_icbrt_exact_on_cubes_and_neighbours():
    for r in list(range(-40, 41)) + [12345678901234567, -(1 << 100) - 7]:
        assert icbrt(r ** 3) == r
        assert icbrt(r ** 3 - 1) == r - 1
        if r not in (-1, 0):  # 0 and 1 are cubes themselves
            assert icbrt(r ** 3 + 1) == r


@given(st.integers(min_value=0, max_value=(1 << 30) - 1))
def test_isqrt_small_branch_never_leaves_small_int_range(n):
    mod, stats = intcheck.load("fixedpoint")
    assert mod.isqrt(n) == math.isqrt(n)
    assert stats.max_abs < 1 << 30


@given(st.integers(min_value=-(1 << 80), max_value=1 << 80))
def test_bit_length_matches_cpython(n):
    assert bit_length(n) == n.bit_length()


@given(st.integers(min_value=-(1 << 70), max_value=1 << 70),
       st.integers(min_value=1, max_value=1 << 40), st.booleans())
def test_rdiv_rounds_half_away_from_zero(n, d, neg):
    if neg:
        d = -d
    r = rdiv(n, d)
    assert abs(2 * (n - r * d)) <= abs(d)
    if abs(2 * (n - r * d)) == abs(d):  # a tie goes away from zero
        assert abs(r) * abs(d) > abs(n)


@given(st.integers(min_value=-(1 << 40), max_value=1 << 40))
def test_sat16_clamps(v):
    assert sat16(v) == max(-32768, min(32767, v))


def test_fixedpoint_bit_identical_on_micropython():
    out = mp.parity(["tests/scenarios/fixedpoint_table.py"])
    assert len(mp.json_lines(out)[0]) == 300
