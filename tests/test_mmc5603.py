"""MMC5603 driver (firmware/mmc5603.py) against the independent register model
(host_sim/mmc5603.py), public API only."""
import pytest
from hypothesis import example, given, settings, strategies as st

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.mmc5603 import MMC5603
from host_sim import motion
from host_sim.bus import RegisterDevice, RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.world import World
from tests import intcheck
from tests.simboards import Bench
from tests.test_qmc5883l import Spy

ADDR = 0x30
RANGES = {4: 8192, 8: 4096, 16: 2048, 30: 1024}
MEAS_US = (6600, 3500, 2000, 1200)


def bench_and_driver(rng=4, bw=0, world=None, noise=True, **kw):
    b = Bench("mmc5603", world=world or World(seed=7), noise=noise, **kw)
    return b, MMC5603(b.bus, range=rng, bw=bw, delay_us=b.sleep_us)


def expected(h, rng):
    """H (16384 counts/G) in the driver's counts: 2H / 2**(s + 1) rounded half up."""
    s = list(RANGES).index(rng) + 1
    return (2 * h + (1 << s)) >> (s + 1)


@pytest.fixture(scope="module", params=[4, 30])
def mmc(request):
    return request.param, bench_and_driver(rng=request.param, offset_g=(0.2, -0.15, 0.1))


@given(st.integers(-60000, 60000), st.integers(-60000, 60000), st.integers(-60000, 60000))
@example(-32768 * 2, 32767 * 2, 1)
@example(3, -3, 1)
def test_the_set_reset_pair_gives_the_field_rounded_to_the_range(mmc, x, y, z):
    rng, (b, d) = mmc
    for v in (x, y, z):
        if rng == 4 and not -32768 <= expected(v, 4) <= 32767:
            return
    b.chip.noise = False
    b.chip.inject_raw(x, y, z)
    assert d.read() == tuple(expected(v, rng) for v in (x, y, z))


@pytest.mark.parametrize("rng", [4, 8, 16, 30])
def test_ranges_and_the_physical_axes(rng):
    b, d = bench_and_driver(rng=rng, world=World(motion=motion.still(yaw=90)), noise=False)
    cpg = RANGES[rng]
    assert (d.counts_per_gauss, d.KIND) == (cpg, "mmc5603")
    x, y, z = d.read()                    # chip x fwd, y left, z up: (0, +25, -43.3) uT
    assert abs(x) <= 1 and abs(y - cpg // 4) <= 1 and abs(z + 43301 * cpg // 100000) <= 1


def test_an_offset_that_drifts_cancels_and_is_reported():
    w = World(field_ut=50.0, inclination_deg=60.0)
    b, d = bench_and_driver(world=w, noise=False, offset_g=(0.1, -0.2, 0.05),
                            offset_drift_g_per_c=0.003, offset_drift_g_per_s=0.002)
    first = d.read()
    assert [abs(o - round(t * 16384)) <= 2 for o, t in zip(d.offset, b.chip.offset_at(
        b.clock.now_us))] == [True, True, True]
    w.temperature_c = 60.0
    b.sleep_us(20000000)                  # 35 degC and 20 s later: the offset moved 0.145 G
    assert d.read() == first
    assert abs(d.offset[0] - (0.1 + 0.145) * 16384) <= 3


def test_every_sample_is_set_measure_reset_measure():
    b = Bench("mmc5603")
    spy = Spy(b.bus)
    d = MMC5603(spy, bw=3, delay_us=b.sleep_us)
    del spy.reads[:], spy.writes[:]
    t0 = b.clock.now_us
    d.read()
    assert spy.writes == [(ADDR, 0x1B, b"\x08"), (ADDR, 0x1B, b"\x01"),
                          (ADDR, 0x1B, b"\x10"), (ADDR, 0x1B, b"\x01")]
    assert spy.reads == [(ADDR, 0x18, 1), (ADDR, 0x00, 9)] * 2   # ready at the first poll
    assert b.clock.now_us - t0 <= d.period_us
    assert b.chip.sets == b.chip.resets == 1


def test_init_resets_the_chip_and_writes_no_continuous_mode_and_the_bandwidth():
    b = Bench("mmc5603")
    spy = Spy(b.bus)
    MMC5603(spy, bw=2, delay_us=b.sleep_us)
    assert spy.writes == [(ADDR, 0x1C, b"\x80"), (ADDR, 0x1A, b"\x00"), (ADDR, 0x1D, b"\x00"),
                          (ADDR, 0x1C, b"\x02")]
    assert b.chip.meas_us() == 2000


@pytest.mark.parametrize("bw", [0, 1, 2, 3])
def test_a_sample_takes_two_measurements_of_the_bandwidth(bw):
    b, d = bench_and_driver(bw=bw)
    t0 = b.clock.now_us
    d.read()
    took = b.clock.now_us - t0
    assert 2 * MEAS_US[bw] <= took <= d.period_us


def test_a_field_beyond_the_range_raises_overflow_naming_it():
    b, d = bench_and_driver(rng=4, noise=False)
    b.chip.inject_raw(5 * 16384, 0, 0)                      # 5 G on x
    buf = [7, 7, 7]
    with pytest.raises(SensorOverflow) as e:
        d.read_into(buf)
    assert buf == [7, 7, 7] and "+-4 G" in str(e.value) and "0x30" in str(e.value)
    assert e.value.raw == (5 * 16384, 0, 0)
    b.chip.inject_raw(16384, 0, 0)
    assert d.read() == (8192, 0, 0)


def test_a_measurement_on_the_rails_raises_overflow_at_any_range():
    b, d = bench_and_driver(rng=30, world=World(field_ut=4000.0, inclination_deg=0.0),
                            noise=False)                     # 40 G: beyond the chip
    with pytest.raises(SensorOverflow) as e:
        d.read()
    assert "rails" in str(e.value)


def test_no_measurement_done_times_out():
    bus = SimI2C(SimClock())
    bus.attach(ADDR, RegisterFile({0x39: 0x10}))             # never sets Meas_m_done
    d = MMC5603(bus, delay_us=bus.sleep_us)
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert e.value.address == ADDR and e.value.waited_us >= d.timeout_us


@pytest.mark.parametrize("after,reg", [(0, 0x1B), (2, 0x18), (3, 0x00)])
def test_bus_errors_name_the_register(after, reg):
    b, d = bench_and_driver()
    b.bus.inject_eio(after=after)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, reg, 5)
    assert d.read()


def test_a_reset_chip_still_reads_right_and_configure_restores_the_bandwidth():
    b, d = bench_and_driver(bw=3, world=World(motion=motion.still(yaw=90)), noise=False)
    before = d.read()
    b.chip.brown_out()                    # BW back to 0 (6.6 ms): nothing readable says so
    assert d.config_ok()
    assert d.read() == before
    d.configure()
    assert b.chip.meas_us() == 1200 and d.read() == before


def test_another_chip_at_0x30_is_refused_by_its_product_id():
    bus = SimI2C(SimClock())
    bus.attach(ADDR, RegisterFile({0x39: 0x20}))
    with pytest.raises(SensorNotFound) as e:
        MMC5603(bus, delay_us=bus.sleep_us)
    assert "no MMC5603 at 0x30: ID register 0x39 reads 0x20, expected 0x10" in str(e.value)


@pytest.mark.parametrize("kw,unit", [({"range": 2}, "gauss"), ({"bw": 4}, "bandwidth")])
def test_bad_options_name_option_and_unit(kw, unit):
    b = Bench("mmc5603")
    with pytest.raises(ValueError) as e:
        MMC5603(b.bus, delay_us=b.sleep_us, **kw)
    assert str(e.value).startswith("MMC5603 %s=" % list(kw)[0]) and unit in str(e.value)


# -- any two measurements: exact arithmetic, small ints throughout

class TwoBlocks(RegisterDevice):
    """Product ID 0x10, Meas_m_done always, and the data block from a queue of 9-byte blocks."""

    def __init__(self):
        RegisterDevice.__init__(self)
        self.blocks = []
        self.cur = bytes(9)

    def read_reg(self, reg):
        if reg == 0x39:
            return 0x10
        if reg == 0x18:
            return 0x40
        if reg == 0x00 and self.blocks:
            self.cur = self.blocks.pop(0)
        return self.cur[reg] if reg < 9 else 0


_CHECKED = {}


def _checked(rng):
    if rng not in _CHECKED:
        mod, stats = intcheck.load("mmc5603")
        bus = SimI2C(SimClock())
        dev = bus.attach(ADDR, TwoBlocks())
        _CHECKED[rng] = (dev, mod.MMC5603(bus, range=rng, delay_us=bus.sleep_us), stats)
    return _CHECKED[rng]


def _codes(block):
    return [block[2 * i] << 12 | block[2 * i + 1] << 4 | block[6 + i] >> 4 for i in range(3)]


@given(st.binary(min_size=9, max_size=9), st.binary(min_size=9, max_size=9),
       st.sampled_from([4, 8, 16, 30]))
@settings(max_examples=300)
def test_any_two_measurements_give_the_exact_rounded_field_or_overflow(a, r, rng):
    dev, d, stats = _checked(rng)
    dev.blocks[:] = [a, r]
    ca, cr = _codes(a), _codes(r)
    s = list(RANGES).index(rng) + 1
    want = [(ca[i] - cr[i] + (1 << s)) >> (s + 1) for i in range(3)]
    rails = any(c in (0, 0xFFFFF) for c in ca + cr)
    out = [0, 0, 0]
    if rails or not all(-32768 <= w <= 32767 for w in want):
        with pytest.raises(SensorOverflow):
            d.read_into(out)
    else:
        d.read_into(out)
        assert out == want
        assert d.offset == [(ca[i] + cr[i] - 1048576) >> 1 for i in range(3)]
    assert stats.max_abs < 1 << 30
