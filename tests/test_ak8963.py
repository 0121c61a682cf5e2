"""The AK8963 driver (firmware/ak8963.py) against its register model (host_sim/ak8963.py) on
the simulated GY-9250: the fuse ROM's sensitivity applied in integers, the read that ends with
ST2, overflow, skipped sets, the mode sequence, and the driver's errors."""
import pytest
from hypothesis import given, settings, strategies as st

from firmware.ak8963 import AK8963
from firmware.errors import DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.mpu9250 import MPU9250
from host_sim import motion
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.world import World
from tests import intcheck
from tests.test_qmc5883l import Spy


def board(asa=None, yaw=0.0, world=None, **kw):
    w = world or World(field_ut=50.0, inclination_deg=0.0, motion=motion.still(yaw, 0, 0))
    b = make_board("gy9250", world=w, noise=False, **kw)
    if asa is not None:
        b.mag.asa = tuple(asa)
    MPU9250(b.bus).enable_bypass()
    return b


def test_the_fuse_rom_is_read_and_each_axis_is_adjusted_to_the_field():
    # north along the board's x: the AK8963's y (its x is the MPU-9250's y); 50 uT = 333.3
    # counts at 0.15 uT/LSB once ASA is applied, whatever each axis's own sensitivity
    for asa in ((0xB0, 0xB2, 0xA6), (0x80, 0x80, 0x80), (0x00, 0xFF, 0x40)):
        for yaw, axis in ((0, 1), (90, 0)):
            b = board(asa, yaw)
            d = AK8963(b.bus, delay_us=b.sleep_us)
            assert d.asa == asa
            v = d.read()
            assert abs(abs(v[axis]) - 333) <= 1, (asa, yaw, v)
            assert abs(v[1 - axis]) <= 1 and abs(v[2]) <= 1
            # the chip's own counts are off by its trim: a driver without ASA would be too
            raw = b.mag.out[axis]
            assert abs(raw * (asa[axis] + 128) / 256 - v[axis]) <= 0.5
            assert asa[axis] == 0x80 or abs(raw - v[axis]) > 5


def test_sensitivity_range_and_kind():
    b = board()
    d = AK8963(b.bus, delay_us=b.sleep_us)
    assert (d.KIND, d.range_code, d.counts_per_gauss, d.period_us) == ("ak8963", 0, 667, 10000)
    assert d.config_ok() and not getattr(d, "MIRROR", False)
    assert AK8963(b.bus, rate=8, delay_us=b.sleep_us).period_us == 125000
    with pytest.raises(ValueError) as e:
        AK8963(b.bus, rate=50)
    assert "rate=50" in str(e.value) and "8, 100" in str(e.value)


def test_start_up_writes_the_datasheets_mode_sequence():
    b = board()
    spy = Spy(b.bus)
    AK8963(spy, delay_us=b.sleep_us)
    # power-down, fuse ROM access (ASA read), power-down, 16-bit continuous mode 2
    assert spy.writes == [(0x0C, 0x0A, b"\x00"), (0x0C, 0x0A, b"\x0f"), (0x0C, 0x0A, b"\x00"),
                          (0x0C, 0x0A, b"\x16")]


@given(st.integers(-32768, 32767), st.integers(-32768, 32767), st.integers(-32768, 32767),
       st.integers(0, 255), st.integers(0, 255), st.integers(0, 255))
@settings(max_examples=300)
def test_the_adjustment_is_the_datasheets_within_half_a_count_and_stays_small_int(
        x, y, z, ax, ay, az):
    mod, stats = _checked()
    bus = SimI2C(SimClock())
    regs = {0x00: 0x48, 0x02: 0x01, 0x10: ax, 0x11: ay, 0x12: az}
    for i, v in enumerate((x, y, z)):
        regs[3 + 2 * i] = v & 0xFF
        regs[4 + 2 * i] = (v >> 8) & 0xFF
    bus.attach(0x0C, RegisterFile(regs))
    d = mod.AK8963(bus, delay_us=bus.sleep_us)
    out = [0, 0, 0]
    d.read_into(out)
    for h, a, o in zip((x, y, z), (ax, ay, az), out):
        exact = h * ((a - 128) * 0.5 / 128 + 1)       # Hadj (datasheet 8.3.11)
        if -32768 <= exact <= 32767:
            assert abs(o - exact) <= 0.5
        else:
            assert o == (32767 if exact > 0 else -32768)  # held at the rail
    assert stats.max_abs < 1 << 24


_CHECKED = {}


def _checked():
    if not _CHECKED:
        _CHECKED["m"] = intcheck.load("ak8963")
    return _CHECKED["m"]


def test_overflow_hofl_is_sensor_overflow():
    # the datasheet's limit is on the sum |X| + |Y| + |Z| (4912 uT), not on each axis
    w = World(field_ut=50.0, motion=motion.still())
    w.add_magnet((2600.0, -2400.0, 0.0), 0.0, 1000.0, ramp_s=0.0)
    b = board(world=w)
    d = AK8963(b.bus, delay_us=b.sleep_us)
    with pytest.raises(SensorOverflow) as e:
        d.read()
    assert "HOFL" in str(e.value) and e.value.address == 0x0C and len(e.value.raw) == 3
    assert max(abs(v) for v in e.value.raw) < 32760  # no axis at the rail


def test_st2_ends_each_read_so_the_next_set_arrives():
    b = board()
    d = AK8963(b.bus, delay_us=b.sleep_us)
    seen = set()
    for _ in range(20):
        d.read()
        seen.add(b.mag.latched)
    assert len(seen) == 20 and not b.mag.reading  # every read a new set, the lock released


def test_a_slow_reader_counts_the_skipped_sets():
    b = board()
    d = AK8963(b.bus, delay_us=b.sleep_us)
    d.read()
    b.sleep_us(35000)              # three sets of 100 Hz go by unread
    d.read()
    assert d.skipped == 1 and b.mag.skipped >= 2


def test_power_down_times_out_and_a_reset_chip_is_configured_again():
    b = board()
    d = AK8963(b.bus, delay_us=b.sleep_us)
    b.bus.writeto_mem(0x0C, 0x0A, b"\x00")
    with pytest.raises(DataReadyTimeout):
        d.read()
    assert not d.config_ok()
    b.mag.brown_out()
    d.configure()
    assert d.config_ok() and d.asa == b.mag.asa and len(d.read()) == 3


def test_probe_wrong_wia_and_missing_chip():
    bus = SimI2C(SimClock())
    bus.attach(0x0C, RegisterFile({0x00: 0x12}))
    with pytest.raises(SensorNotFound) as e:
        AK8963(bus)
    assert "0x12" in str(e.value) and "0x48" in str(e.value)
    with pytest.raises(SensorNotFound):
        AK8963(SimI2C(SimClock()))


def test_behind_a_closed_bypass_it_is_not_there():
    b = make_board("gy9250")
    with pytest.raises(SensorNotFound):
        AK8963(b.bus, delay_us=b.sleep_us)
