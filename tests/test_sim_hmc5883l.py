"""HMC5883L model through the bus only (host_sim/hmc5883l.py); expectations from hardware.md
and the Honeywell datasheet, decoded here with struct."""
import math
import struct

import pytest
from hypothesis import given, strategies as st

from host_sim import motion
from host_sim.boards import make_board
from host_sim.world import World

A = 0x1E
RDY, LOCK = 1, 2
GAINS = (1370, 1090, 820, 660, 440, 390, 330, 230)
DO_HZ_X4 = (3, 6, 12, 30, 60, 120, 300)        # 0.75 ... 75 Hz


def board(world=None, noise=False, mount=(1, 2, 3)):
    if world is None:
        world = World(field_ut=50.0, inclination_deg=0.0)   # 0.5 G on sensor x
    return make_board("hmc5883l", world=world, noise=noise, mount=mount)


def rd(b, reg, n=1):
    return b.bus.readfrom_mem(A, reg, n)


def wr(b, reg, *vals):
    b.bus.writeto_mem(A, reg, bytes(vals))


def status(b):
    return rd(b, 0x09)[0]


def xzy(b):
    return struct.unpack(">hhh", rd(b, 0x03, 6))


def single(b):
    wr(b, 0x02, 0x01)
    b.sleep_us(6500)
    return xzy(b)


def test_power_on_defaults_and_identification():
    b = board()
    assert rd(b, 0x00, 3) == b"\x10\x20\x01"
    assert rd(b, 0x0A, 3) == b"H43"
    assert status(b) == 0


def test_single_measurement_takes_6ms_then_idles():
    b = board()
    wr(b, 0x02, 0x01)
    b.sleep_us(5500)
    assert status(b) & RDY == 0
    b.sleep_us(600)
    assert status(b) & RDY
    assert rd(b, 0x02)[0] & 0x03 == 0x03          # mode register reads idle
    assert xzy(b) == (545, 0, 0)                   # 0.5 G * 1090 counts/G, X Z Y
    assert status(b) & RDY == 0                    # cleared by reading all six bytes
    b.sleep_us(1000000)
    assert status(b) & RDY == 0 and b.mag.measurements == 1


def test_continuous_first_set_after_two_periods_then_one_per_period():
    for do in range(7):
        b = board()
        wr(b, 0x00, do << 2)
        t0 = b.clock.now_us
        wr(b, 0x02, 0x00)
        period = 4000000 // DO_HZ_X4[do]
        b.sleep_us(t0 + 2 * period - 300 - b.clock.now_us)
        assert status(b) & RDY == 0, do
        b.sleep_us(t0 + 2 * period - b.clock.now_us)
        assert status(b) & RDY, do
        xzy(b)
        b.sleep_us(period - 400)
        assert status(b) & RDY == 0, do
        b.sleep_us(400)
        assert status(b) & RDY, do


@given(st.integers(-2048, 2047), st.integers(-2048, 2047), st.integers(-2048, 2047))
def test_data_bytes_are_x_z_y_msb_first(x, y, z):
    b = board()
    b.mag.inject_raw(x, y, z)
    wr(b, 0x02, 0x01)
    b.sleep_us(6100)
    raw = rd(b, 0x03, 6)
    assert struct.unpack(">hhh", raw) == (x, z, y)
    assert raw[0] == (x >> 8) & 0xFF and raw[1] == x & 0xFF


counts = st.integers(-40000, 40000)


@given(st.tuples(counts, counts, counts))
def test_axis_outside_adc_range_reads_minus_4096_until_a_good_measurement(v):
    b = board()
    b.mag.inject_raw(*v)
    got = single(b)
    want = tuple(c if -2048 <= c <= 2047 else -4096 for c in (v[0], v[2], v[1]))
    assert got == want
    b.mag.inject_raw(10, 20, 30)
    assert single(b) == (10, 30, 20)


def test_real_field_overflow_reads_minus_4096():
    w = World(field_ut=0.0, hard_iron_ut=(250.0, 0.0, 0.0))   # 2.5 G > 2047 / 1090 G
    b = board(w)
    assert single(b) == (-4096, 0, 0)
    wr(b, 0x01, 0xE0)                                  # +-8.1 G: 575 counts
    single(b)                                          # first set after a gain change: old gain
    assert single(b) == (575, 0, 0)


def test_partial_read_sets_lock_and_holds_the_data():
    w = World(field_ut=50.0, inclination_deg=0.0, motion=motion.flat_spin(period_s=2.0))
    b = board(w)
    wr(b, 0x00, 0x18)                                  # 75 Hz
    wr(b, 0x02, 0x00)
    b.sleep_us(30000)
    x_first = struct.unpack(">h", rd(b, 0x03, 2))[0]   # X only: a partial read
    assert status(b) & LOCK
    n = b.mag.measurements
    b.sleep_us(200000)                                 # many measurements come and go
    assert struct.unpack(">h", rd(b, 0x03, 2))[0] == x_first
    assert b.mag.measurements == n
    rd(b, 0x05, 4)                                     # the rest of the six bytes
    assert status(b) & LOCK == 0
    b.sleep_us(14000)
    assert struct.unpack(">h", rd(b, 0x03, 2))[0] != x_first


@pytest.mark.parametrize("reg,val", [(0x02, 0x00), (0x00, 0x10), (0x01, 0x20)])
def test_lock_cleared_by_mode_or_configuration_write(reg, val):
    b = board()
    single(b)
    rd(b, 0x03, 2)
    assert status(b) & LOCK
    wr(b, reg, val)
    assert status(b) & LOCK == 0


def test_pointer_returns_to_0x03_after_the_six_data_bytes():
    b = board()
    b.mag.inject_raw(0x123, -0x234, 0x345)
    wr(b, 0x02, 0x01)
    b.sleep_us(6100)
    raw = rd(b, 0x03, 12)
    assert raw[:6] == raw[6:] and struct.unpack(">hhh", raw[:6]) == (0x123, 0x345, -0x234)
    assert rd(b, 0x09, 4)[1:] == b"H43"                # status, then the ID registers
    assert rd(b, 0x0C, 2) == b"3\x10"                  # past 0x0C the pointer wraps to 0x00


def test_every_gain_code_scales_counts_per_gauss():
    for gn, cpg in enumerate(GAINS):
        b = board()
        wr(b, 0x01, gn << 5)
        single(b)                                      # still the old gain
        want = math.floor(0.5 * cpg + 0.5)
        got = single(b)[0]
        assert got == (want if want <= 2047 else -4096), gn


def test_first_sample_after_gain_change_uses_the_old_gain():
    b = board()
    assert single(b)[0] == 545                         # 1090 counts/G
    wr(b, 0x01, 0xA0)                                  # GN 5: 390 counts/G
    assert single(b)[0] == 545
    assert single(b)[0] == 195


def test_self_test_bias_adds_about_1_1_gauss_per_axis():
    w = World(field_ut=0.0)
    b = board(w)
    wr(b, 0x01, 0xA0)                                  # GN 5 as in the datasheet self-test
    single(b)
    wr(b, 0x00, 0x11)                                  # MS = 01 positive bias
    x, z, y = single(b)
    assert abs(x - 452) <= 2 and abs(y - 452) <= 2 and abs(z - 421) <= 2   # hardware.md
    wr(b, 0x00, 0x12)                                  # MS = 10 negative bias
    assert single(b) == (-x, -z, -y)


def _std(vals):
    m = sum(vals) / len(vals)
    return math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1))


def test_noise_floor_is_2_milligauss_and_averaging_reduces_it():
    for cra, expect in ((0x18, 2.74), (0x78, 2.74 / math.sqrt(8))):   # 0.002 G * 1370
        b = board(noise=True)
        wr(b, 0x01, 0x00)                              # GN 0 (datasheet noise condition)
        wr(b, 0x00, cra)
        wr(b, 0x02, 0x00)
        xs = []
        b.sleep_us(30000)
        for _ in range(500):
            b.sleep_us(13334)
            xs.append(xzy(b)[0])
        sd = _std(xs)
        # quantisation adds 1/12 count^2 of variance
        assert abs(sd - math.sqrt(expect ** 2 + 1 / 12)) < 0.15 * expect + 0.1, (cra, sd)


def test_writes_to_read_only_registers_are_ignored():
    b = board()
    single(b)
    before = rd(b, 0x03, 10)
    wr(b, 0x03, 1, 2, 3, 4, 5, 6)
    wr(b, 0x0A, 0x00)
    assert rd(b, 0x03, 6) == before[:6] and rd(b, 0x0A, 3) == b"H43"


def test_self_test_outputs_the_bias_alone_whatever_the_earth_field():
    # Datasheet "Self Test Operation": the unbiased acquisition is subtracted from the biased
    # one, so the output is the ~1.1 G strap field even in a 0.5 G field, board upside down.
    w = World(field_ut=50.0, inclination_deg=60.0, motion=motion.still(0, 180, 0))
    b = board(w)
    wr(b, 0x01, 0xA0)
    single(b)
    wr(b, 0x00, 0x11)
    x, z, y = single(b)
    assert abs(x - 452) <= 2 and abs(y - 452) <= 2 and abs(z - 421) <= 2
