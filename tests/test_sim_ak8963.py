"""AK8963 and AK09916 models through the bus only (host_sim/ak8963.py, host_sim/ak09916.py):
the datasheets' register maps, byte order, data-ready, overrun, the read that ST2 ends,
overflow, the fuse ROM and the mode rules, and the model choices their docstrings state."""
import struct

import pytest
from hypothesis import given, settings, strategies as st

from host_sim import motion
from host_sim.ak09916 import AK09916Sim
from host_sim.ak8963 import AK8963Sim
from host_sim.bus import SimI2C
from host_sim.clock import SimClock
from host_sim.world import World

A = 0x0C
# (model, its mode register, its continuous 100 Hz mode, ST1, HXL, ST2, bytes from HXL to ST2)
CHIPS = {"ak8963": (AK8963Sim, 0x0A, 0x16, 0x02, 0x03, 0x09, 7),
         "ak09916": (AK09916Sim, 0x31, 0x08, 0x10, 0x11, 0x18, 8)}


def rig(kind, world=None, **kw):
    cls = CHIPS[kind][0]
    bus = SimI2C(SimClock())
    w = world or World(field_ut=50.0, inclination_deg=0.0, motion=motion.still())
    chip = cls(w, mount=(1, 2, 3), noise=False, **kw)
    bus.attach(A, chip)
    return bus, chip


def rd(bus, reg, n=1):
    return bus.readfrom_mem(A, reg, n)


def wr(bus, reg, v):
    bus.writeto_mem(A, reg, bytes([v]))


def start(bus, kind):
    _, cntl, mode, *_ = CHIPS[kind]
    bus.sleep_us(200)
    wr(bus, cntl, mode)


def test_ids_and_auto_increment():
    bus, _ = rig("ak8963")
    assert rd(bus, 0x00) == b"\x48"
    assert rd(bus, 0x0C, 2) == bytes([0, 0x48])   # 0x0C wraps to 0x00
    bus, _ = rig("ak09916")
    assert rd(bus, 0x00, 2) == b"\x48\x09"
    assert len(rd(bus, 0x03, 2)) == 2 and rd(bus, 0x18, 2)[1] == 0x48  # 0x18 wraps to 0x00


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_power_on_is_power_down_without_data(kind):
    bus, _ = rig(kind)
    _, cntl, _, st1, *_ = CHIPS[kind]
    assert rd(bus, cntl) == b"\x00"
    bus.sleep_us(500000)
    assert rd(bus, st1)[0] & 1 == 0


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_continuous_mode_data_lsb_first_and_drdy_cleared_by_the_read(kind):
    bus, chip = rig(kind, asa=(128, 128, 128)) if kind == "ak8963" else rig(kind)
    _, cntl, mode, st1, hxl, st2, n = CHIPS[kind]
    start(bus, kind)
    bus.sleep_us(10100)
    assert rd(bus, st1)[0] & 1
    blk = rd(bus, hxl, n)
    assert struct.unpack("<hhh", blk[:6]) == (333, 0, 0)  # 50 uT north on x, 0.15 uT/LSB
    assert rd(bus, st1)[0] & 1 == 0
    if kind == "ak8963":
        assert blk[6] == 0x10   # ST2: BITM, 16-bit output


def test_ak8963_fuse_rom_only_in_its_mode_and_the_trim_divides_the_output():
    bus, chip = rig("ak8963", asa=(0xB0, 0x80, 0x40))
    assert rd(bus, 0x10, 3) == b"\x00\x00\x00"
    bus.sleep_us(200)
    wr(bus, 0x0A, 0x0F)
    assert rd(bus, 0x10, 4) == bytes([0xB0, 0x80, 0x40, 0xB0])  # 0x12 wraps to 0x10
    wr(bus, 0x0A, 0x00)
    bus.sleep_us(200)
    wr(bus, 0x0A, 0x16)
    bus.sleep_us(10100)
    x = struct.unpack("<hhh", rd(bus, 0x03, 7)[:6])[0]
    assert x == round(333.33 * 256 / (0xB0 + 128))   # Hadj = H (ASA + 128) / 256 = 333


def test_ak8963_14_bit_output_is_four_times_coarser():
    bus, _ = rig("ak8963", asa=(128, 128, 128))
    bus.sleep_us(200)
    wr(bus, 0x0A, 0x06)   # BIT 0
    bus.sleep_us(10100)
    blk = rd(bus, 0x03, 7)
    assert struct.unpack("<h", blk[:2])[0] == 83 and blk[6] & 0x10 == 0


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_a_mode_is_taken_only_from_power_down_after_100_us(kind):
    bus, chip = rig(kind)
    _, cntl, mode, *_ = CHIPS[kind]
    wr(bus, cntl, mode)            # power-down entered at 0 us: too soon? (bus time < 100 us)
    assert chip.now_us < 100 and rd(bus, cntl) == b"\x00"
    bus.sleep_us(200)
    wr(bus, cntl, mode)
    assert rd(bus, cntl)[0] == mode
    other = 0x02 if kind == "ak8963" else 0x02
    wr(bus, cntl, other | (0x10 if kind == "ak8963" else 0))  # not from power-down: ignored
    assert rd(bus, cntl)[0] == mode


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_without_st2_the_registers_stay_held(kind):
    bus, chip = rig(kind)
    _, cntl, mode, st1, hxl, st2, n = CHIPS[kind]
    start(bus, kind)
    bus.sleep_us(10100)
    rd(bus, hxl, 6)                 # the data without ST2: the read stays open
    bus.sleep_us(50000)
    assert rd(bus, st1)[0] & 1 == 0 and rd(bus, st1)[0] & 2   # sets skipped, none ready
    rd(bus, st2)                    # ST2 ends it
    bus.sleep_us(10100)
    assert rd(bus, st1)[0] & 1


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_an_unread_set_is_replaced_and_dor_says_so(kind):
    bus, chip = rig(kind)
    _, cntl, mode, st1, hxl, st2, n = CHIPS[kind]
    start(bus, kind)
    bus.sleep_us(10100)
    assert rd(bus, st1)[0] == 0x01
    bus.sleep_us(30000)
    assert rd(bus, st1)[0] == 0x03   # DRDY and DOR: sets were lost
    rd(bus, hxl, n)
    assert rd(bus, st1)[0] == 0x00


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_overflow_is_on_the_sum_of_the_axes(kind):
    w = World(field_ut=50.0, motion=motion.still())
    w.add_magnet((2600.0, -2400.0, 0.0), 0.0, 10.0, ramp_s=0.0)
    bus, chip = rig(kind, world=w)
    _, cntl, mode, st1, hxl, st2, n = CHIPS[kind]
    start(bus, kind)
    bus.sleep_us(10100)
    blk = rd(bus, hxl, n)
    assert blk[-1] & 0x08          # HOFL, though no axis is at the rail
    assert max(abs(v) for v in struct.unpack("<hhh", blk[:6])) < 32000


@given(st.integers(-60000, 60000), st.integers(-60000, 60000), st.integers(-60000, 60000))
@settings(max_examples=50)
def test_injected_values_beyond_the_output_range_clip_and_set_hofl(x, y, z):
    for kind in sorted(CHIPS):
        bus, chip = rig(kind)
        _, cntl, mode, st1, hxl, st2, n = CHIPS[kind]
        lim = chip.LIMIT
        chip.inject_raw(x, y, z)
        start(bus, kind)
        bus.sleep_us(10100)
        blk = rd(bus, hxl, n)
        clipped = tuple(max(-lim, min(lim, v)) for v in (x, y, z))
        assert struct.unpack("<hhh", blk[:6]) == clipped
        assert bool(blk[-1] & 0x08) == (clipped != (x, y, z))


@pytest.mark.parametrize("kind", sorted(CHIPS))
def test_soft_reset_and_brown_out_return_to_power_down(kind):
    bus, chip = rig(kind)
    _, cntl, mode, *_ = CHIPS[kind]
    start(bus, kind)
    srst = 0x0B if kind == "ak8963" else 0x32
    wr(bus, srst, 0x01)
    assert rd(bus, cntl) == b"\x00"
    start(bus, kind)
    chip.brown_out()
    assert rd(bus, cntl) == b"\x00"


def test_ak8963_default_fuse_values_come_from_the_seed():
    a = AK8963Sim(seed=1).asa
    assert a == AK8963Sim(seed=1).asa and all(0xA0 <= v <= 0xBF for v in a)
    assert AK8963Sim(seed=2).asa != a
