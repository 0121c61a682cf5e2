"""LIS2MDL / LSM303AGR magnetometer driver (firmware/lis2mdl.py) against the independent
register model (host_sim/lis2mdl.py), public API only."""
import struct

import pytest
from hypothesis import example, given, settings, strategies as st

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.lis2mdl import LIS2MDL
from host_sim import motion
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.hmc5883l import HMC5883LSim
from host_sim.lis3mdl import LIS3MDLSim
from host_sim.world import World
from tests import intcheck
from tests.simboards import Bench
from tests.test_qmc5883l import Spy

ADDR = 0x1E
PERIODS = {10: 100000, 20: 50000, 50: 20000, 100: 10000}


def bench_and_driver(odr=100, world=None, noise=True, **kw):
    b = Bench("lis2mdl", world=world or World(seed=5), noise=noise, **kw)
    return b, LIS2MDL(b.bus, odr=odr, delay_us=b.sleep_us)


@pytest.fixture(scope="module")
def lis():
    return bench_and_driver()


@given(st.integers(-10922, 10922), st.integers(-10922, 10922), st.integers(-10922, 10922))
@example(-10922, 10922, -1)
def test_counts_are_three_times_the_chip_lsb(lis, x, y, z):
    b, d = lis
    b.chip.inject_raw(x, y, z)
    assert d.read() == (3 * x, 3 * y, 3 * z)


def test_2000_counts_per_gauss_and_the_physical_axes():
    # level, heading east, 50 uT at 60 deg down: a chip x fwd, y left, z down (its own axes
    # are left-handed) senses (0, +25, +43.3) uT
    b, d = bench_and_driver(world=World(motion=motion.still(yaw=90)), noise=False,
                            mount=(1, -2, 3), bridge_offset_g=(0, 0, 0))
    assert (d.counts_per_gauss, d.range_code, d.KIND) == (2000, 0, "lis2mdl")
    x, y, z = d.read()
    assert abs(x) <= 3 and abs(y - 500) <= 3 and abs(z - 866) <= 3


@pytest.mark.parametrize("odr", [10, 20, 50, 100])
def test_reads_follow_the_output_rate(odr):
    b, d = bench_and_driver(odr=odr)
    d.read()
    t0 = b.clock.now_us
    for _ in range(3):
        d.read()
    period = PERIODS[odr]
    lag = period // 16 + 400
    assert 3 * period - lag <= b.clock.now_us - t0 <= 3 * period + lag


def test_init_writes_the_documented_registers_and_reads_them_back_in_one_transfer():
    b = Bench("lis2mdl")
    spy = Spy(b.bus)
    LIS2MDL(spy, odr=50, delay_us=b.sleep_us)
    assert spy.writes == [(ADDR, 0x60, b"\x20"),            # SOFT_RST
                          (ADDR, 0x61, b"\x02"),            # OFF_CANC
                          (ADDR, 0x62, b"\x10"),            # BDU
                          (ADDR, 0x60, b"\x88")]            # COMP_TEMP_EN, 50 Hz, continuous
    assert (ADDR, 0xE0, 3) in spy.reads
    assert b.rd(0x45, 6) == bytes(6)                        # hard-iron registers left at 0


def test_the_bridge_offset_is_cancelled_by_the_chip():
    b, d = bench_and_driver(world=World(field_ut=0.0), noise=False,
                            bridge_offset_g=(0.03, -0.045, 0.015))
    assert d.read() == (0, 0, 0)


def test_every_read_is_the_status_then_the_whole_block():
    b = Bench("lis2mdl")
    spy = Spy(b.bus)
    d = LIS2MDL(spy, odr=100, delay_us=b.sleep_us)
    del spy.reads[:]
    for _ in range(10):
        d.read()
    assert set(spy.reads) == {(ADDR, 0x67, 1), (ADDR, 0xE8, 6)}


@given(v=st.sampled_from([10923, -10923, 32767, -32768]), axis=st.integers(0, 2))
@settings(max_examples=12)
def test_beyond_16_gauss_raises_overflow_and_is_never_returned(lis, v, axis):
    b, d = lis
    raw = [1, 2, 3]
    raw[axis] = v
    b.chip.inject_raw(*raw)
    buf = [7, 7, 7]
    with pytest.raises(SensorOverflow) as e:
        d.read_into(buf)
    assert buf == [7, 7, 7] and e.value.raw[axis] == v and e.value.address == ADDR
    assert "16 G" in str(e.value)
    b.chip.inject_raw(4, 5, 6)
    assert d.read() == (12, 15, 18)


def test_an_overrun_is_counted():
    b, d = bench_and_driver(noise=False)
    d.read()
    b.sleep_us(2 * 10000 + 100)
    d.read()
    assert d.skipped == 1


def test_idle_times_out():
    b, d = bench_and_driver()
    d.read()
    b.wr(0x60, 0x83)                                        # MD idle
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert e.value.address == ADDR


@pytest.mark.parametrize("after,reg", [(0, 0x67), (1, 0x68)])
def test_nack_becomes_bus_error(after, reg):
    b, d = bench_and_driver()
    b.sleep_us(10100)
    b.bus.inject_nack(after=after)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, reg, 19)
    assert d.read()


def test_a_reset_chip_fails_config_ok_until_configure():
    b, d = bench_and_driver()
    d.read()
    b.chip.brown_out()
    assert not d.config_ok()
    d.configure()
    assert d.config_ok()
    d.read()
    b.chip.glitch(0x62, 0x00)                               # BDU off behind the driver's back
    assert not d.config_ok()


@pytest.mark.parametrize("other,who", [(HMC5883LSim, "0x00"), (LIS3MDLSim, "0x00")])
def test_the_other_chips_at_0x1e_are_not_taken_for_a_lis2mdl(other, who):
    bus = SimI2C(SimClock())
    bus.attach(ADDR, other(World()))
    with pytest.raises(SensorNotFound) as e:
        LIS2MDL(bus, delay_us=bus.sleep_us)
    assert "no LIS2MDL at 0x1E: ID register 0x4F reads %s, expected 0x40" % who in str(e.value)


@pytest.mark.parametrize("kw,unit", [({"range": 50}, "gauss"), ({"odr": 25}, "Hz")])
def test_bad_options_name_option_and_unit(kw, unit):
    b = Bench("lis2mdl")
    with pytest.raises(ValueError) as e:
        LIS2MDL(b.bus, delay_us=b.sleep_us, **kw)
    assert str(e.value).startswith("LIS2MDL %s=" % list(kw)[0]) and unit in str(e.value)


_CHECKED = {}


def _checked_driver():
    if not _CHECKED:
        mod, stats = intcheck.load("lis2mdl")
        bus = SimI2C(SimClock())
        regs = RegisterFile({0x4F: 0x40})
        regs.select = lambda reg: setattr(regs, "pointer", reg & 0x7F)
        bus.attach(ADDR, regs)
        _CHECKED.update(regs=regs, drv=mod.LIS2MDL(bus, delay_us=bus.sleep_us), stats=stats)
    return _CHECKED["regs"], _CHECKED["drv"], _CHECKED["stats"]


@given(st.binary(min_size=6, max_size=6))
@example(b"\xaa\x2a\x00\x00\x00\x00")                      # 10922 on X: the largest in range
@example(b"\xab\x2a\x00\x00\x00\x00")                      # 10923: beyond
def test_decode_scale_and_bound_on_any_bytes(raw):
    regs, d, stats = _checked_driver()
    regs.regs[0x67] = 0x08
    regs.regs[0x68:0x6E] = raw
    v = struct.unpack("<hhh", raw)
    out = [0, 0, 0]
    if all(-10922 <= c <= 10922 for c in v):
        d.read_into(out)
        assert tuple(out) == tuple(3 * c for c in v)
    else:
        with pytest.raises(SensorOverflow) as e:
            d.read_into(out)
        assert e.value.raw == v
    assert stats.max_abs < 1 << 30
