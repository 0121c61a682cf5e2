"""Assertions that one known, open limit breaks on some boards: there a strict expected
failure (it xfails while the assertion fails, and fails once it holds, so the entry gets
removed with the limit), elsewhere a plain assert.

    from tests.known_limits import JUMP_NOISE, expect
    expect(seen[-1] == "ok", setup, {"icm20948": JUMP_NOISE}, seen[-5:])
"""
import pytest

# docs/faults.md and docs/chips.md (known limits)
JUMP_NOISE = ("the fixed heading-jump limits (firmware/fieldwatch.py) say 'heading jumped' "
              "with the heading within the documented accuracy, at this board's sample rate "
              "and noise (docs/faults.md, known limits)")


def expect(cond, setup, known, msg=""):
    """assert cond, unless `setup` is in `known` (setup -> the limit's text): then a strict
    expected failure."""
    cause = known.get(setup)
    if cause is None:
        assert cond, msg
    elif cond:
        pytest.fail("[XPASS(strict)] %s: expected to fail (%s) and it holds: remove the entry"
                    % (setup, cause))
    else:
        pytest.xfail("%s: %s" % (setup, cause))
