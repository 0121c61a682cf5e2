"""firmware/busio_i2c.py: the drivers and the app through CircuitPython's busio.I2C shape
(tests/busio_fake.py over the simulated bus) give the same samples and headings as the
simulated bus directly, name bus faults and a held lock, always unlock, and allocate nothing
per read; on CPython, MicroPython and the 32-bit tiers (no CircuitPython interpreter here)."""
import pytest

from tests import mp

SCENARIO = "tests/scenarios/busio_parity.py"


def _check(lines):
    rows = {r[0]: r[1:] for r in lines}
    same_kind, same, n, _ = rows["samples"]
    assert same_kind and same and n == 40
    assert rows["nack"] == [0x0D, 0x06, 19, False]        # status register, ENODEV, unlocked
    assert rows["lock"] == [0x0D, 0x06, 110, False]       # ETIMEDOUT within the bound
    assert rows["short_wait"] == [False, 2]               # waited, then went through
    assert rows["app"] == [500, "ok", True]               # every heading the same
    return rows


def test_adapter_on_cpython_and_micropython_same_bits_and_no_allocation():
    cp = mp.json_lines(mp.run([SCENARIO], micro=False))
    _check(cp)
    mpl = mp.json_lines(mp.run([SCENARIO], micro=True))
    rows = _check(mpl)
    assert mpl[:5] == cp
    assert rows["alloc_per_read_x100"] == [0]


@pytest.mark.parametrize("tier", ["wasm", "x86-32"])
def test_adapter_on_the_32_bit_tiers(tier):
    t = mp.TIERS[tier]
    if t.reason is not None:
        pytest.skip(t.reason)
    cp = mp.json_lines(mp.run([SCENARIO], micro=False))
    out = mp.json_lines(mp.run([SCENARIO], tier))
    _check(out)
    assert out[:5] == cp


def test_lock_timeout_is_validated():
    from firmware.busio_i2c import BusioI2C
    with pytest.raises(ValueError, match="lock_timeout_us"):
        BusioI2C(object(), lock_timeout_us=1.5)
