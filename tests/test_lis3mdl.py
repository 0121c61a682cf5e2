"""LIS3MDL driver (firmware/lis3mdl.py) against the independent register model
(host_sim/lis3mdl.py), public API only."""
import struct

import pytest
from hypothesis import example, given, settings, strategies as st

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.lis3mdl import LIS3MDL
from host_sim import motion
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.hmc5883l import HMC5883LSim
from host_sim.world import World
from tests import intcheck
from tests.simboards import Bench
from tests.test_qmc5883l import Spy

ADDR = 0x1C
GAINS = {4: 6842, 8: 3421, 12: 2281, 16: 1711}
PERIODS = {5: 200000, 10: 100000, 20: 50000, 40: 25000, 80: 12500}


def bench_and_driver(rng=4, odr=80, mode="uhp", world=None, noise=True, address=None, **kw):
    b = Bench("lis3mdl", world=world or World(seed=3), noise=noise, address=address, **kw)
    return b, LIS3MDL(b.bus, b.address, range=rng, odr=odr, mode=mode, delay_us=b.sleep_us)


@pytest.fixture(scope="module", params=[4, 16])
def lis(request):
    return bench_and_driver(rng=request.param)


@given(st.integers(-32767, 32766), st.integers(-32767, 32766), st.integers(-32767, 32766))
@example(-32767, 32766, -1)
@example(255, 256, -256)
def test_every_unsaturated_count_decodes_lsb_first(lis, x, y, z):
    b, d = lis
    b.chip.inject_raw(x, y, z)
    assert d.read() == (x, y, z)


@pytest.mark.parametrize("rng", [4, 8, 12, 16])
def test_range_sets_counts_per_gauss_and_the_physical_axes(rng):
    # level, heading east, B 50 uT at 60 deg down: a chip x fwd, y left, z up senses
    # (0, +25, -43.3) uT (AN4248 eqs. 1-3 through the mounting)
    b, d = bench_and_driver(rng=rng, world=World(motion=motion.still(yaw=90)), noise=False)
    cpg = GAINS[rng]
    assert (d.counts_per_gauss, d.range_code, d.KIND) == (cpg, [4, 8, 12, 16].index(rng), "lis3mdl")
    assert b.chip.counts_per_gauss() == cpg
    x, y, z = d.read()
    assert abs(x) <= 1 and abs(y - 25 * cpg // 100) <= 1 and abs(z + 43301 * cpg // 100000) <= 1


@pytest.mark.parametrize("odr", [5, 10, 20, 40, 80])
def test_reads_follow_the_output_rate(odr):
    b, d = bench_and_driver(odr=odr)
    d.read()
    t0 = b.clock.now_us
    for _ in range(3):
        d.read()
    period = PERIODS[odr]
    lag = period // 16 + 400
    assert 3 * period - lag <= b.clock.now_us - t0 <= 3 * period + lag
    assert d.period_us == period


def test_init_writes_the_documented_registers_and_reads_them_back_in_one_transfer():
    b = Bench("lis3mdl")
    spy = Spy(b.bus)
    LIS3MDL(spy, range=12, odr=40, mode="hp", delay_us=b.sleep_us)
    assert spy.writes == [(ADDR, 0x21, b"\x04"),                  # SOFT_RST
                          (ADDR, 0x20, bytes([0x40 | 6 << 2])),   # OM hp, DO 40 Hz
                          (ADDR, 0x21, bytes([2 << 5])),          # FS +-12 G
                          (ADDR, 0x23, bytes([2 << 2])),          # OMZ hp
                          (ADDR, 0x24, b"\x40"),                  # BDU
                          (ADDR, 0x22, b"\x00")]                  # continuous
    assert (ADDR, 0xA0, 5) in spy.reads                           # CTRL_REG1..5 with SUB(7)


def test_every_read_is_the_status_then_the_whole_block_with_sub7():
    b = Bench("lis3mdl")
    spy = Spy(b.bus)
    d = LIS3MDL(spy, odr=80, delay_us=b.sleep_us)
    del spy.reads[:]
    samples = [d.read() for _ in range(10)]
    assert len(set(samples)) > 1
    assert set(spy.reads) == {(ADDR, 0x27, 1), (ADDR, 0xA8, 6)}


@given(v=st.sampled_from([32767, -32768, 40000, -40000, 100000]), axis=st.integers(0, 2))
@settings(max_examples=20)
def test_a_saturated_axis_raises_overflow_naming_the_range_and_is_never_returned(lis, v, axis):
    b, d = lis
    raw = [1, 2, 3]
    raw[axis] = v
    b.chip.inject_raw(*raw)
    buf = [7, 7, 7]
    with pytest.raises(SensorOverflow) as e:
        d.read_into(buf)
    assert buf == [7, 7, 7]
    assert e.value.address == ADDR and e.value.raw[axis] == max(-32768, min(32767, v))
    assert "+-%d G" % d.TABLES[0][d.range_code] in str(e.value) and "0x1C" in str(e.value)
    b.chip.inject_raw(4, 5, 6)
    assert d.read() == (4, 5, 6)


def test_an_overrun_is_counted_and_the_newest_set_returned():
    b, d = bench_and_driver(noise=False)
    d.read()
    b.chip.inject_raw(1, 1, 1)
    b.chip.inject_raw(2, 2, 2)
    b.sleep_us(2 * 12500 + 100)           # two sets, the first overwritten unread
    assert d.read() == (2, 2, 2)
    assert d.skipped == 1 and not d.suspect


def test_power_down_times_out_within_the_bound():
    b, d = bench_and_driver()
    d.read()
    b.wr(0x22, 0x03)                      # MD power-down
    t0 = b.clock.now_us
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert e.value.address == ADDR and e.value.waited_us >= d.timeout_us
    assert b.clock.now_us - t0 <= d.timeout_us + 12500


@pytest.mark.parametrize("after,reg", [(0, 0x27), (1, 0x28)])
@pytest.mark.parametrize("errno", [19, 5])
def test_nack_or_eio_becomes_bus_error(after, reg, errno):
    b, d = bench_and_driver()
    b.sleep_us(12600)
    if errno == 5:
        b.bus.inject_eio(after=after)
    else:
        b.bus.inject_nack(after=after)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, reg, errno)
    assert d.read()


def test_a_reset_chip_fails_config_ok_until_configure():
    b, d = bench_and_driver(rng=8)
    d.read()
    assert d.config_ok()
    b.chip.brown_out()                    # power-on defaults: power-down, +-4 G
    assert not d.config_ok()
    with pytest.raises(DataReadyTimeout):
        d.read()
    d.configure()
    assert d.config_ok() and b.chip.counts_per_gauss() == 3421
    d.read()


def test_a_glitched_range_fails_config_ok():
    b, d = bench_and_driver(rng=4)
    b.chip.glitch(0x21, 0x60)             # +-16 G behind the driver's back
    assert not d.config_ok()
    d.configure()
    assert d.config_ok()


def test_0x1e_holding_an_hmc5883l_is_not_taken_for_a_lis3mdl():
    bus = SimI2C(SimClock())
    bus.attach(0x1E, HMC5883LSim(World()))
    with pytest.raises(SensorNotFound) as e:
        LIS3MDL(bus, 0x1E, delay_us=bus.sleep_us)
    msg = str(e.value)
    assert "LIS3MDL" in msg and "0x1E" in msg and "0x0F reads 0x00, expected 0x3D" in msg
    assert e.value.address == 0x1E


def test_the_sa1_high_address_works():
    b, d = bench_and_driver(address=0x1E)
    assert d.address == 0x1E and d.read()


def test_absent_chip_raises_sensor_not_found():
    with pytest.raises(SensorNotFound) as e:
        LIS3MDL(SimI2C(SimClock()))
    assert "0x1C" in str(e.value) and "errno 19" in str(e.value)


def test_a_chip_that_does_not_keep_its_configuration_is_rejected():
    bus = SimI2C(SimClock())
    regs = RegisterFile({0x0F: 0x3D})
    regs.write_reg = lambda reg, value: None      # answers the ID, keeps nothing
    bus.attach(ADDR, regs)
    with pytest.raises(SensorNotFound) as e:
        LIS3MDL(bus, delay_us=bus.sleep_us)
    assert "register 0x20 written 0x74 reads back 0x00" in str(e.value)


@pytest.mark.parametrize("kw,unit", [({"range": 2}, "gauss"), ({"odr": 155}, "Hz"),
                                     ({"mode": "fast"}, "operating mode")])
def test_bad_options_raise_value_error_naming_option_and_unit(kw, unit):
    b = Bench("lis3mdl")
    with pytest.raises(ValueError) as e:
        LIS3MDL(b.bus, delay_us=b.sleep_us, **kw)
    name = list(kw)[0]
    assert str(e.value).startswith("LIS3MDL %s=" % name) and unit in str(e.value)


# -- decode and the saturation check on arbitrary bytes, small ints throughout

_CHECKED = {}


def _checked_driver():
    if not _CHECKED:
        mod, stats = intcheck.load("lis3mdl")
        bus = SimI2C(SimClock())
        regs = RegisterFile({0x0F: 0x3D})
        regs.select = lambda reg: setattr(regs, "pointer", reg & 0x7F)
        bus.attach(ADDR, regs)
        drv = mod.LIS3MDL(bus, delay_us=bus.sleep_us)
        _CHECKED.update(bus=bus, regs=regs, drv=drv, stats=stats, mod=mod)
    return _CHECKED["regs"], _CHECKED["drv"], _CHECKED["stats"], _CHECKED["mod"]


@given(st.binary(min_size=6, max_size=6), st.booleans())
@example(b"\xff\x7f\x00\x00\x00\x00", False)   # 32767 on X
@example(b"\x00\x00\x00\x80\x00\x00", True)    # -32768 on Y, with an overrun
@example(b"\xfe\x7f\x01\x80\xff\xff", False)   # 32766, -32767, -1: in range
def test_decode_bound_and_saturation_check_on_any_bytes(raw, overrun):
    regs, d, stats, mod = _checked_driver()
    regs.regs[0x27] = 0x08 | (0x80 if overrun else 0)
    regs.regs[0x28:0x2E] = raw
    v = struct.unpack("<hhh", raw)
    skipped = d.skipped
    out = [0, 0, 0]
    if all(-32767 <= c <= 32766 for c in v):
        d.read_into(out)
        assert tuple(out) == v
    else:
        with pytest.raises(SensorOverflow) as e:
            d.read_into(out)
        assert e.value.raw == v
    assert d.skipped == skipped + overrun
    assert stats.max_abs < 1 << 30
