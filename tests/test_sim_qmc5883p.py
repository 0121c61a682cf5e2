"""QMC5883P model through the bus only (host_sim/qmc5883p.py): the facts of hardware.md and
the model choices its docstring states."""
import struct

from hypothesis import given, strategies as st

from host_sim.boards import make_board
from host_sim.world import World

A = 0x2C


def board():
    return make_board("qmc5883p", world=World(field_ut=50.0, inclination_deg=0.0), noise=False,
                      mount=(1, 2, 3))


def rd(b, reg, n=1):
    return b.bus.readfrom_mem(A, reg, n)


def wr(b, reg, *vals):
    b.bus.writeto_mem(A, reg, bytes(vals))


def test_chip_id_and_power_on_suspend():
    b = board()
    assert rd(b, 0x00)[0] == 0x80
    assert rd(b, 0x0A, 2) == b"\x00\x00"
    b.sleep_us(500000)
    assert rd(b, 0x09)[0] & 1 == 0


def test_each_range_has_its_sensitivity():
    for rng, cpg in enumerate((1000, 2500, 3750, 15000)):
        b = board()
        wr(b, 0x0B, rng << 2)
        wr(b, 0x0A, 0x0D)                              # normal, 200 Hz
        b.sleep_us(5100)
        assert rd(b, 0x09)[0] & 1
        assert struct.unpack("<hhh", rd(b, 0x01, 6)) == (cpg // 2, 0, 0)   # 0.5 G on x
        assert rd(b, 0x09)[0] & 1 == 0                 # DRDY cleared by the data read


@given(st.integers(-60000, 60000), st.integers(-60000, 60000), st.integers(-60000, 60000))
def test_data_lsb_first_with_saturation_and_ovfl(x, y, z):
    b = board()
    b.mag.inject_raw(x, y, z)
    wr(b, 0x0A, 0x0D)
    b.sleep_us(5100)
    s = rd(b, 0x09)[0]
    sat = tuple(max(-32768, min(32767, v)) for v in (x, y, z))
    assert struct.unpack("<hhh", rd(b, 0x01, 6)) == sat
    assert bool(s & 2) == (sat != (x, y, z))


def test_single_mode_measures_once_then_suspends():
    b = board()
    wr(b, 0x0A, 0x02)                                  # single, 10 Hz timing
    b.sleep_us(100500)
    assert rd(b, 0x09)[0] & 1 and rd(b, 0x0A)[0] & 3 == 0
    rd(b, 0x01, 6)
    b.sleep_us(1000000)
    assert rd(b, 0x09)[0] & 1 == 0 and b.mag.measurements == 1


def test_soft_reset_and_axis_sign_register():
    b = board()
    wr(b, 0x29, 0x06)
    assert rd(b, 0x29)[0] == 0x06
    wr(b, 0x0A, 0x0D)
    wr(b, 0x0B, 0x80)
    assert rd(b, 0x0A, 2) == b"\x00\x00" and rd(b, 0x29)[0] == 0
