"""HMC5883L driver against the independent register model (host_sim), public API only."""
import pytest
from hypothesis import example, given, settings, strategies as st

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.hmc5883l import HMC5883L
from host_sim import motion
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.world import World
from tests import intcheck
from tests.test_qmc5883l import Spy

ADDR = 0x1E
VALID = st.integers(min_value=-2048, max_value=2047)
GAINS = (1370, 1090, 820, 660, 440, 390, 330, 230)  # datasheet CRB table, GN 0..7
RATES = {3: 333334, 15: 66667, 30: 33334, 75: 13334}


def board_and_driver(gain=1, rate=15, averaging=8, **kw):
    b = make_board("hmc5883l", **kw)
    return b, HMC5883L(b.bus, gain=gain, rate=rate, averaging=averaging, delay_us=b.sleep_us)


@pytest.fixture(scope="module", params=range(8))
def hmc(request):
    return board_and_driver(gain=request.param, rate=75)


# -- decode: X, Z, Y MSB first; the valid range and the overflow marker, every gain

@given(x=VALID, y=VALID, z=VALID)
@example(x=-2048, y=2047, z=-1)
@example(x=255, y=256, z=-256)
def test_every_valid_count_decodes_msb_first_in_xyz_order(hmc, x, y, z):
    b, d = hmc
    b.mag.inject_raw(x, y, z)  # the next measurement
    assert d.read() == (x, y, z)


@given(v=st.one_of(st.integers(min_value=2048, max_value=40000),
                   st.integers(min_value=-40000, max_value=-2049)),
       axis=st.integers(0, 2))
@settings(max_examples=40)
def test_adc_overflow_minus_4096_raises_and_is_never_returned(hmc, v, axis):
    b, d = hmc
    raw = [0, 0, 0]
    raw[axis] = v
    b.mag.inject_raw(*raw)
    buf = [7, 7, 7]
    with pytest.raises(SensorOverflow) as e:
        d.read_into(buf)
    assert buf == [7, 7, 7]
    assert e.value.raw[axis] == -4096 and e.value.address == ADDR
    assert "-4096" in str(e.value) and "0x1E" in str(e.value)
    b.mag.inject_raw(1, 2, 3)  # the block was read whole: the next measurement arrives
    assert d.read() == (1, 2, 3)


def test_gain_sets_counts_per_gauss_and_range_code(hmc):
    b, d = hmc
    assert d.counts_per_gauss == GAINS[d.range_code] == b.mag.counts_per_gauss()
    assert d.KIND == "hmc5883l"


@pytest.mark.parametrize("gain", [0, 1, 5, 7])
def test_physical_axes_heading_east_level(gain):
    # Level board heading east, B = 50 uT, inclination 60: chip (x fwd, y left, z up) senses
    # (0, +25, -43.3) uT (AN4248 eqs. 1-3 with the chip's mounting).
    b, d = board_and_driver(gain=gain, world=World(motion=motion.still(yaw=90)), noise=False)
    x, y, z = d.read()
    cpg = GAINS[gain]
    assert abs(x) <= 1
    assert abs(y - 25 * cpg // 100) <= 1
    assert abs(z + 43301 * cpg // 100000) <= 1


# -- the first sample after a gain change

def test_first_measurement_after_a_gain_change_keeps_the_old_gain_on_the_chip():
    # Why the driver discards: read raw registers the way a naive driver would.
    b, d = board_and_driver(gain=1, world=World(motion=motion.still()), noise=False)
    before = d.read()
    b.bus.writeto_mem(ADDR, 0x01, bytes([5 << 5]))  # CRB: gain 5
    while not b.bus.readfrom_mem(ADDR, 0x09, 1)[0] & 1:
        b.sleep_us(1000)
    raw = b.bus.readfrom_mem(ADDR, 0x03, 6)
    x = int.from_bytes(raw[0:2], "big", signed=True)
    assert x == before[0]  # still 1090 counts/G


@pytest.mark.parametrize("new", range(8))
def test_set_gain_returns_only_samples_with_the_new_gain(new):
    b, d = board_and_driver(gain=1, world=World(motion=motion.still()), noise=False)
    old_x = d.read()[0]  # 25 uT north component at 1090 counts/G
    d.set_gain(new)
    x = d.read()[0]
    assert abs(x - 25 * GAINS[new] // 100) <= 1
    assert (d.range_code, d.counts_per_gauss) == (new, GAINS[new])
    assert new == 1 or x != old_x


# -- data lock, data-ready wait, faults

def test_driver_reads_the_data_block_whole_and_a_partial_read_locks_it():
    b = make_board("hmc5883l")
    spy = Spy(b.bus)
    d = HMC5883L(spy, rate=75, delay_us=b.sleep_us)
    del spy.reads[:]
    samples = [d.read() for _ in range(20)]
    b.mag.inject_raw(5000, 0, 0)
    with pytest.raises(SensorOverflow):
        d.read()
    assert len(set(samples)) > 1
    assert all(r in ((ADDR, 0x09, 1), (ADDR, 0x03, 6)) for r in spy.reads)
    assert (ADDR, 0x03, 6) in spy.reads

    # A read that stops early sets LOCK: later measurements are lost until all six are read.
    d.read()
    b.mag.inject_raw(100, 200, 300)
    b.sleep_us(13334 + 1000)                       # that measurement is placed
    assert b.bus.readfrom_mem(ADDR, 0x03, 2) == (100).to_bytes(2, "big")  # X only: LOCK
    assert b.bus.readfrom_mem(ADDR, 0x09, 1)[0] & 0x02
    b.mag.inject_raw(-5, -6, -7)
    b.sleep_us(5 * 13334)                          # measurements come and are lost
    assert b.bus.readfrom_mem(ADDR, 0x09, 1)[0] & 0x02
    assert b.bus.readfrom_mem(ADDR, 0x05, 4) == (300).to_bytes(2, "big") + (200).to_bytes(2, "big")
    assert not b.bus.readfrom_mem(ADDR, 0x09, 1)[0] & 0x02  # all six read: unlocked
    assert d.read()  # and the driver carries on with new measurements
    assert d.read()


@pytest.mark.parametrize("rate", [3, 15, 30, 75])
def test_reads_follow_the_output_rate(rate):
    b, d = board_and_driver(rate=rate)
    d.read()
    t0 = b.clock.now_us
    for _ in range(3):
        d.read()
    period = RATES[rate]
    lag = period // 16 + 400
    assert 3 * period - lag <= b.clock.now_us - t0 <= 3 * period + lag


def test_idle_chip_times_out_within_the_bound():
    b, d = board_and_driver(rate=75)
    d.read()
    b.bus.writeto_mem(ADDR, 0x02, b"\x02")  # MODE idle: no measurements
    t0 = b.clock.now_us
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert e.value.address == ADDR and e.value.waited_us >= d.timeout_us
    polls = d.timeout_us // 833 + 1
    assert d.timeout_us <= b.clock.now_us - t0 <= d.timeout_us + polls * 200


@pytest.mark.parametrize("after,reg", [(0, 0x09), (1, 0x03)])
@pytest.mark.parametrize("errno", [19, 5])
def test_nack_or_eio_becomes_bus_error(after, reg, errno):
    b, d = board_and_driver(rate=75)
    b.sleep_us(13334 + 1000)  # a measurement is ready: transfer 0 is the status, 1 the data
    if errno == 5:
        b.bus.inject_eio(after=after)
    else:
        b.bus.inject_nack(after=after)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, reg, errno)
    assert "0x1E" in str(e.value) and "errno %d" % errno in str(e.value)
    assert d.read()


def test_dead_device_raises_bus_error():
    b, d = board_and_driver()
    b.bus.kill(ADDR)
    with pytest.raises(BusError) as e:
        d.read()
    assert e.value.errno == 19


# -- self test (datasheet: positive bias, gain 5, limits 243..575)

def test_self_test_passes_in_zero_field_and_restores_the_gain():
    b, d = board_and_driver(gain=2, world=World(field_ut=0.0), noise=False)
    passed, raw = d.self_test()
    assert passed
    assert abs(raw[0] - 452) <= 2 and abs(raw[1] - 452) <= 2 and abs(raw[2] - 421) <= 2
    assert (d.range_code, d.counts_per_gauss) == (2, 820)
    assert b.mag.counts_per_gauss() == 820
    assert d.read() == (0, 0, 0)


def test_self_test_fails_when_the_bias_reading_overflows():
    # A 6 G field along x (a magnet on the chip) drives the biased x reading past the ADC range.
    w = World(field_ut=600.0, inclination_deg=0.0)
    b, d = board_and_driver(world=w, noise=False)
    with pytest.raises(SensorOverflow):
        d.read()
    passed, raw = d.self_test()
    assert not passed and raw[0] == -4096


# -- probe and options

def _bus_with(regs):
    bus = SimI2C(SimClock())
    bus.attach(ADDR, RegisterFile(regs))
    return bus


def test_wrong_id_is_rejected_with_the_bytes_read():
    with pytest.raises(SensorNotFound) as e:
        HMC5883L(_bus_with({0x0A: 0x48, 0x0B: 0x34, 0x0C: 0x34}))
    assert "0x48 0x34 0x34" in str(e.value) and "0x1E" in str(e.value)
    assert e.value.address == ADDR


def test_absent_chip_raises_sensor_not_found():
    with pytest.raises(SensorNotFound) as e:
        HMC5883L(SimI2C(SimClock()))
    assert "0x1E" in str(e.value) and "errno 19" in str(e.value)


def test_init_writes_the_documented_registers():
    b = make_board("hmc5883l")
    spy = Spy(b.bus)
    HMC5883L(spy, gain=5, rate=30, averaging=4, delay_us=b.sleep_us)
    assert spy.writes == [(ADDR, 0x00, bytes([0b01010100])),  # MA 4, DO 30 Hz, normal
                          (ADDR, 0x01, bytes([0xA0])),        # GN 5
                          (ADDR, 0x02, b"\x00")]              # continuous


@pytest.mark.parametrize("kw", [{"gain": 8}, {"rate": 7}, {"averaging": 3}, {"gain": -1}])
def test_bad_options_raise_value_error(kw):
    b = make_board("hmc5883l")
    with pytest.raises(ValueError) as e:
        HMC5883L(b.bus, delay_us=b.sleep_us, **kw)
    assert list(kw)[0] in str(e.value)


# -- decode bound and the output-range check on arbitrary bytes

_CHECKED = {}


def _checked_driver():
    if not _CHECKED:
        mod, stats = intcheck.load("hmc5883l")
        bus = _bus_with({0x0A: 0x48, 0x0B: 0x34, 0x0C: 0x33, 0x09: 0x01})
        _CHECKED.update(bus=bus, stats=stats, drv=mod.HMC5883L(bus, delay_us=bus.sleep_us),
                        mod=mod)
    return _CHECKED["bus"], _CHECKED["drv"], _CHECKED["stats"], _CHECKED["mod"]


@given(st.binary(min_size=6, max_size=6))
@example(b"\xf0\x00\x00\x00\x00\x00")   # -4096 on X
@example(b"\x08\x00\x00\x00\x00\x00")   # 2048: outside the output range, not the marker
@example(b"\xf8\x00\x07\xff\xff\xff")   # -2048, 2047, -1: all valid
def test_decode_bound_and_range_check_on_any_bytes(raw):
    bus, d, stats, mod = _checked_driver()
    bus.writeto_mem(ADDR, 0x03, raw)
    x, z, y = (int.from_bytes(raw[i:i + 2], "big", signed=True) for i in (0, 2, 4))
    out = [0, 0, 0]
    if all(-2048 <= v <= 2047 for v in (x, y, z)):
        d.read_into(out)
        assert out == [x, y, z]
    else:
        with pytest.raises(mod.SensorOverflow) as e:
            d.read_into(out)
        assert e.value.raw == (x, y, z)
        assert ("-4096" in str(e.value)) == (-4096 in (x, y, z))
    assert stats.max_abs < 1 << 30


def test_self_test_passes_in_the_earth_field_upside_down():
    w = World(field_ut=50.0, inclination_deg=70.0, motion=motion.still(30, 180, 0))
    b, d = board_and_driver(world=w, noise=True)
    passed, raw = d.self_test()
    assert passed, raw
