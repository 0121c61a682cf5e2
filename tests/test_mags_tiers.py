"""The LIS3MDL, LIS2MDL and MMC5603 drivers on every interpreter: the same bits on CPython and
the MicroPython tiers (tests/scenarios/mags_parity.py), and a per-sample path that allocates
nothing on the 64-bit and 32-bit unix ports (tests/scenarios/mags_alloc.py)."""
import pytest

from tests import mp

KINDS = ["lis3mdl", "lis2mdl", "mmc5603"]


def test_drivers_print_the_same_bits_on_every_tier():
    out, ran = mp.parity_all(["tests/scenarios/mags_parity.py"])
    assert "unix" in ran
    rows = [dict(r) for r in mp.json_lines(out)]
    assert [r["kind"] for r in rows if "kind" in r] == KINDS
    samples = [r["rows"] for r in rows if "rows" in r]
    assert len(samples) == 3 and all(len(s) == 25 and len({tuple(v[1:]) for v in s}) > 20
                                     for s in samples)
    errors = [r["error"] for r in rows if "error" in r]
    assert errors.count("SensorOverflow") == 3 and errors.count("BusError") == 3
    assert errors.count("SensorNotFound") == 3 and errors.count("DataReadyTimeout") == 2


@pytest.mark.parametrize("tier", ["unix", "x86-32"])
def test_read_into_allocates_nothing(tier):
    if not mp.TIERS[tier].available:
        pytest.skip(mp.TIERS[tier].reason)
    out = mp.json_lines(mp.run(["tests/scenarios/mags_alloc.py"], tier))
    assert out[0]["control_bytes"] > 0          # the instrument sees a heap frame
    rows = [o for o in out if "chip" in o]
    assert sorted({o["chip"].split("/")[0] for o in rows}) == sorted(KINDS) and len(rows) == 12
    for o in rows:
        assert o["heap_locked_reads"] == o["reads"] == 200, o
        assert o["mem_total_bytes"] == 0, o
