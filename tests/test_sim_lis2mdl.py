"""LIS2MDL / LSM303AGR magnetometer model through the bus only (host_sim/lis2mdl.py): the
datasheet's facts (docs/hardware.md) and the model choices its docstring states."""
import math
import struct

from hypothesis import given, settings, strategies as st

from host_sim.world import World
from tests.simboards import Bench

WHO, CFG_A, CFG_B, CFG_C, STATUS, OUT, OFFSET = 0x4F, 0x60, 0x61, 0x62, 0x67, 0x68, 0x45
ZYXDA = 0x08
PERIOD = (100000, 50000, 20000, 10000)


def bench(noise=False, mount=(1, 2, 3), world=None, bridge=(0.0, 0.0, 0.0)):
    return Bench("lis2mdl", world=world, noise=noise, mount=mount, bridge_offset_g=bridge)


def xyz(b, reg=OUT):
    return struct.unpack("<hhh", b.rd(reg, 6))


def run(b, odr=3, cfg_b=0x02, cfg_c=0x10):
    b.wr(CFG_B, cfg_b)
    b.wr(CFG_C, cfg_c)
    b.wr(CFG_A, 0x80 | odr << 2)


def test_identity_and_power_on_idle():
    b = bench()
    assert b.rd(WHO)[0] == 0x40
    assert b.rd(CFG_A, 3) == b"\x03\x00\x00" and b.rd(0x63)[0] == 0xE0
    b.sleep_us(500000)
    assert b.rd(STATUS)[0] == 0


def test_fixed_sensitivity_of_1_5_mg_per_lsb():
    b = bench(world=World(field_ut=45.0, inclination_deg=0.0))
    run(b)
    b.sleep_us(10100)
    assert xyz(b) == (300, 0, 0)                        # 0.45 G / 1.5 mG


@given(st.integers(-60000, 60000), st.integers(-60000, 60000), st.integers(-60000, 60000))
@settings(max_examples=60)
def test_data_lsb_first_saturated_at_int16(x, y, z):
    b = bench()
    run(b)
    b.chip.inject_raw(x, y, z)
    b.sleep_us(10100)
    assert xyz(b) == tuple(max(-32768, min(32767, v)) for v in (x, y, z))


def test_the_address_advances_with_or_without_sub7_and_wraps_in_the_data_block():
    b = bench()
    run(b)
    b.sleep_us(10100)
    b.bus.settle()
    b.chip.out[:] = [0x0201, 0x0403, 0x0605]
    assert b.rd(OUT, 6) == b.rd(OUT | 0x80, 6) == bytes((1, 2, 3, 4, 5, 6))
    assert b.rd(OUT, 8)[6:] == b"\x01\x02"               # OUTZ_H -> OUTX_L, not TEMP_OUT


def test_output_rates():
    for odr, period in enumerate(PERIOD):
        b = bench()
        run(b, odr=odr)
        t0 = b.clock.now_us
        b.sleep_us(period - 300)
        assert b.rd(STATUS)[0] & ZYXDA == 0
        b.sleep_us(t0 + period - b.clock.now_us)
        assert b.rd(STATUS)[0] & ZYXDA


def test_status_overrun_and_bdu_as_the_lis3mdl():
    b = bench()
    run(b)
    b.sleep_us(10100)
    assert b.rd(STATUS)[0] == 0x0F
    b.sleep_us(10000)
    assert b.rd(STATUS)[0] == 0xFF
    xyz(b)
    assert b.rd(STATUS)[0] == 0
    b.chip.inject_raw(1, 2, 3)
    b.sleep_us(10000)
    assert b.rd(OUT, 2) == b"\x01\x00"
    b.chip.inject_raw(7, 8, 9)
    b.sleep_us(10000)
    assert struct.unpack("<hh", b.rd(OUT + 2, 4)) == (2, 3)   # BDU: held until whole
    assert xyz(b) == (7, 8, 9)


def test_offset_cancellation_removes_the_bridge_offset():
    b = bench(world=World(field_ut=0.0), bridge=(0.03, -0.045, 0.015))
    run(b, cfg_b=0x00)
    b.sleep_us(10100)
    assert xyz(b) == (20, -30, 10)
    b.wr(CFG_B, 0x02)                                     # OFF_CANC
    b.sleep_us(10000)
    assert xyz(b) == (0, 0, 0)


def test_the_hard_iron_offset_registers_are_subtracted_and_a_soft_reset_clears_them():
    b = bench(world=World(field_ut=45.0, inclination_deg=0.0))
    b.wr(OFFSET, 100, 0, 0xF6, 0xFF, 0, 0)                # +100, -10, 0
    run(b)
    b.sleep_us(10100)
    assert xyz(b) == (200, 10, 0)
    b.wr(CFG_A, 0x20)                                     # SOFT_RST
    assert b.rd(OFFSET, 6) == bytes(6) and b.rd(CFG_A, 3) == b"\x03\x00\x00"


def test_single_mode_converts_once_then_idles():
    b = bench()
    b.wr(CFG_A, 0x81)
    b.sleep_us(100500)
    assert b.rd(STATUS)[0] & ZYXDA and b.rd(CFG_A)[0] & 0x03 == 0x03
    xyz(b)
    b.sleep_us(1000000)
    assert b.rd(STATUS)[0] == 0 and b.chip.measurements == 1


def test_temperature_8_lsb_per_degree_from_25():
    b = bench(world=World(temperature_c=20.0))
    assert struct.unpack("<h", b.rd(0x6E, 2))[0] == -40


def test_noise_is_3_mg_rms_per_axis():
    b = bench(noise=True, world=World(field_ut=0.0))
    run(b)
    n = 600
    acc = [0.0, 0.0, 0.0]
    for _ in range(n):
        b.sleep_us(10000)
        v = xyz(b)
        for i in range(3):
            acc[i] += v[i] * v[i]
    for a in acc:
        rms_mg = 1.5 * math.sqrt(a / n)
        assert abs(rms_mg - 3.0) < 0.45, rms_mg
