"""LIS3MDL model through the bus only (host_sim/lis3mdl.py): the datasheet's facts
(docs/hardware.md) and the model choices its docstring states, decoded here with struct."""
import math
import struct

from hypothesis import given, settings, strategies as st

from host_sim.world import World
from tests.simboards import Bench

WHO, CTRL1, CTRL2, CTRL3, CTRL4, CTRL5, STATUS, OUT = 0x0F, 0x20, 0x21, 0x22, 0x23, 0x24, 0x27, 0x28
INC = 0x80
ZYXDA, ZYXOR = 0x08, 0x80
GAINS = (6842, 3421, 2281, 1711)
DO_PERIOD = (1600000, 800000, 400000, 200000, 100000, 50000, 25000, 12500)


def bench(noise=False, mount=(1, 2, 3), world=None):
    return Bench("lis3mdl", world=world, noise=noise, mount=mount)


def xyz(b):
    return struct.unpack("<hhh", b.rd(OUT | INC, 6))


def run(b, ctrl1=0x7C, ctrl2=0x00, ctrl5=0x40):
    """UHP, 80 Hz (12.5 ms), the range, BDU, then continuous."""
    b.wr(CTRL1, ctrl1)
    b.wr(CTRL2, ctrl2)
    b.wr(CTRL4, 0x0C)
    b.wr(CTRL5, ctrl5)
    b.wr(CTRL3, 0x00)


def test_identity_and_power_on_defaults():
    b = bench()
    assert b.rd(WHO)[0] == 0x3D
    assert b.rd(CTRL1 | INC, 5) == bytes((0x10, 0x00, 0x03, 0x00, 0x00))
    assert b.rd(0x30)[0] == 0xE8                       # INT_CFG
    b.sleep_us(2000000)
    assert b.rd(STATUS)[0] == 0                        # power-down: no data


def test_multi_byte_transfers_advance_only_with_sub7_and_wrap_in_the_data_block():
    b = bench()
    run(b)
    b.sleep_us(12600)
    b.bus.settle()                                     # the set is placed: now overwrite it
    b.chip.out[:] = [0x0201, 0x0403, 0x0605]
    assert b.rd(OUT, 6) == b"\x01" * 6                 # SUB(7) = 0: the same register
    assert b.rd(OUT | INC, 8) == bytes((1, 2, 3, 4, 5, 6, 1, 2))   # Z_H -> X_L, not TEMP_OUT
    b.wr(CTRL1, 0x10, 0x20)                            # no SUB(7): both bytes to CTRL_REG1
    assert b.rd(CTRL1 | INC, 2) == b"\x20\x00"


def test_each_full_scale_has_its_sensitivity():
    for fs, cpg in enumerate(GAINS):
        b = bench()
        run(b, ctrl2=fs << 5)
        b.sleep_us(12600)
        assert b.rd(STATUS)[0] & ZYXDA
        assert xyz(b) == (int(cpg / 2 + 0.5), 0, 0)    # 0.5 G on x


@given(st.integers(-60000, 60000), st.integers(-60000, 60000), st.integers(-60000, 60000))
@settings(max_examples=60)
def test_data_lsb_first_and_saturated_at_int16(x, y, z):
    b = bench()
    run(b)
    b.chip.inject_raw(x, y, z)
    b.sleep_us(12600)
    assert xyz(b) == tuple(max(-32768, min(32767, v)) for v in (x, y, z))


def test_output_rates_of_do_and_fast_odr():
    for do in range(3, 8):
        b = bench()
        run(b, ctrl1=0x60 | do << 2)
        t0 = b.clock.now_us
        b.sleep_us(DO_PERIOD[do] - 300)
        assert b.rd(STATUS)[0] & ZYXDA == 0, do
        b.sleep_us(t0 + DO_PERIOD[do] - b.clock.now_us)
        assert b.rd(STATUS)[0] & ZYXDA, do
    b = bench()
    run(b, ctrl1=0x62)                                  # FAST_ODR in UHP: 155 Hz
    b.sleep_us(6452)
    assert b.rd(STATUS)[0] & ZYXDA


def test_zyxda_clears_on_a_data_read_and_zyxor_marks_an_overwritten_set():
    b = bench()
    run(b)
    b.sleep_us(12600)
    assert b.rd(STATUS)[0] == 0x0F                     # ZYXDA, ZDA, YDA, XDA
    xyz(b)
    assert b.rd(STATUS)[0] == 0
    b.sleep_us(2 * 12500)                              # two sets, the first never read
    assert b.rd(STATUS)[0] == 0xFF                     # ZYXOR, ZOR, YOR, XOR too
    xyz(b)
    assert b.rd(STATUS)[0] == 0 and b.chip.overrun == 1


def test_bdu_holds_a_new_set_until_the_block_is_read_whole():
    for bdu in (0x40, 0x00):
        b = bench()
        run(b, ctrl5=bdu)
        b.chip.inject_raw(1, 2, 3)
        b.sleep_us(12600)
        assert b.rd(OUT | INC, 2) == b"\x01\x00"       # X only
        b.chip.inject_raw(7, 8, 9)
        b.sleep_us(12500)
        rest = struct.unpack("<hh", b.rd((OUT + 2) | INC, 4))
        assert rest == ((2, 3) if bdu else (8, 9))
        if bdu:
            assert xyz(b) == (7, 8, 9)                 # released when the block was whole


def test_single_mode_converts_once_then_powers_down():
    b = bench()
    b.wr(CTRL1, 0x70)                                  # 10 Hz
    b.wr(CTRL3, 0x01)
    b.sleep_us(100500)
    assert b.rd(STATUS)[0] & ZYXDA and b.rd(CTRL3)[0] & 0x03 == 0x03
    xyz(b)
    b.sleep_us(1000000)
    assert b.rd(STATUS)[0] == 0 and b.chip.measurements == 1


def test_soft_reset_restores_the_defaults_and_stops_conversions():
    b = bench()
    run(b, ctrl2=0x60)
    b.wr(CTRL2, 0x04)
    assert b.rd(CTRL1 | INC, 5) == bytes((0x10, 0x00, 0x03, 0x00, 0x00))
    b.sleep_us(200000)
    assert b.rd(STATUS)[0] == 0


def test_temperature_8_lsb_per_degree_from_25_with_temp_en():
    b = bench(world=World(temperature_c=35.0))
    assert struct.unpack("<h", b.rd(0x2E | INC, 2))[0] == 0
    b.wr(CTRL1, 0x80 | 0x10)
    assert struct.unpack("<h", b.rd(0x2E | INC, 2))[0] == 80


def test_noise_is_the_datasheet_rms_per_axis():
    b = bench(noise=True, world=World(field_ut=0.0))
    run(b, ctrl2=0x40)                                 # +-12 G: 2281 counts/G
    n = 400
    acc = [0.0, 0.0, 0.0]
    for _ in range(n):
        b.sleep_us(12500)
        v = xyz(b)
        for i in range(3):
            acc[i] += v[i] * v[i]
    rms_mg = [1000.0 * math.sqrt(a / n) / 2281 for a in acc]
    for got, want in zip(rms_mg, (3.2, 3.2, 4.1)):
        assert abs(got - want) < 0.15 * want, rms_mg
