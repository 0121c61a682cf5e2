"""The bound checker itself must catch an overflow, or every proof that uses it is void."""
import pytest

from tests import intcheck


def test_intcheck_catches_q15_square_of_minus_one():
    mod, stats = intcheck.load("fixedpoint")
    assert mod.isqrt((1 << 30) - 1) == 32767
    assert stats.max_abs < (1 << 30)
    src_mod, _ = intcheck.load("fixedpoint", limit=1 << 20)
    with pytest.raises(intcheck.SmallIntOverflow):
        src_mod.isqrt((1 << 30) - 1)
