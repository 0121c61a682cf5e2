"""QMC5883L model through the bus only (host_sim/qmc5883l.py); expectations from hardware.md
and the QST datasheet, decoded here with struct, never with firmware code."""
import math
import struct

from hypothesis import given, strategies as st

from host_sim import motion
from host_sim.boards import make_board
from host_sim.world import World

A = 0x0D
CONT_200HZ_2G = 0x0D     # hardware.md: MODE 01, ODR 200 Hz, RNG +-2 G, OSR 512
DRDY, OVL, DOR = 1, 2, 4
PERIOD_US = {0x00: 100000, 0x04: 20000, 0x08: 10000, 0x0C: 5000}   # ODR bits -> 1/ODR


def board(world=None, noise=False, mount=(1, 2, 3)):
    if world is None:
        world = World(field_ut=50.0, inclination_deg=0.0)   # level, heading 0: field on body x
    return make_board("qmc5883l", world=world, noise=noise, mount=mount)


def rd(b, reg, n=1):
    return b.bus.readfrom_mem(A, reg, n)


def wr(b, reg, *vals):
    b.bus.writeto_mem(A, reg, bytes(vals))


def status(b):
    return rd(b, 0x06)[0]


def xyz(b):
    return struct.unpack("<hhh", rd(b, 0x00, 6))


def start(b, ctrl1=CONT_200HZ_2G):
    wr(b, 0x0B, 0x01)
    t0 = b.clock.now_us
    wr(b, 0x09, ctrl1)
    return t0


def test_power_on_registers_and_chip_id():
    b = board()
    assert rd(b, 0x09, 3) == b"\x00\x00\x00"      # CTRL1 standby, CTRL2, SET/RESET
    assert rd(b, 0x0D)[0] == 0xFF
    assert status(b) == 0 and xyz(b) == (0, 0, 0)


def test_standby_produces_no_data():
    b = board()
    b.sleep_us(2000000)
    assert status(b) & DRDY == 0 and xyz(b) == (0, 0, 0)


def test_drdy_appears_one_odr_period_after_continuous_mode_starts():
    for odr_bits, period in PERIOD_US.items():
        b = board()
        t0 = start(b, 0x01 | odr_bits)
        b.sleep_us(t0 + period - 400 - b.clock.now_us)
        assert status(b) & DRDY == 0, hex(odr_bits)
        b.sleep_us(t0 + period - b.clock.now_us)
        assert status(b) & DRDY, hex(odr_bits)


def test_a_reader_keeping_up_gets_odr_sets_per_second():
    for odr_bits, period in PERIOD_US.items():
        b = board()
        t0 = start(b, 0x01 | odr_bits)
        got = 0
        while b.clock.now_us < t0 + 1000000 + period // 2:   # sets due at t0 + k/ODR, k <= ODR
            if status(b) & DRDY:
                rd(b, 0x00, 6)
                got += 1
            b.sleep_us(period // 4)
        assert got == 1000000 // period, hex(odr_bits)
        assert status(b) & DOR == 0


def test_reading_any_data_register_clears_drdy():
    for reg in range(6):
        b = board()
        start(b)
        b.sleep_us(6000)
        assert status(b) & DRDY
        rd(b, reg)
        assert status(b) & DRDY == 0


def test_dor_set_when_a_set_is_skipped_and_cleared_by_reading_data():
    b = board()
    start(b)
    b.sleep_us(5000 * 3 + 500)       # three sets completed, none read
    s = status(b)
    assert s & DRDY and s & DOR
    rd(b, 0x00)
    assert status(b) & DOR == 0


def test_partial_block_read_freezes_the_output_until_0x05_is_read():
    b = board()
    m = b.mag
    for k in range(1, 8):
        m.inject_raw(100 * k, 200 * k, 300 * k)
    start(b)
    b.sleep_us(5200)
    assert status(b) & DRDY
    x, y = struct.unpack("<hh", rd(b, 0x00, 4))      # a driver reading X and Y only
    assert (x, y) == (100, 200)
    for _ in range(5):                                # the known field failure: frozen
        b.sleep_us(5000)
        s = status(b)
        assert s & DRDY == 0 and s & DOR
        assert struct.unpack("<hh", rd(b, 0x00, 4)) == (100, 200)
    rd(b, 0x04, 2)                                    # reading up to 0x05 releases the lock
    b.sleep_us(5000)
    assert status(b) & DRDY
    assert xyz(b) == (200, 400, 600)                  # the next set queued, skipped ones lost


def test_full_block_reads_track_a_moving_field():
    w = World(field_ut=50.0, inclination_deg=0.0, motion=motion.flat_spin(period_s=1.0))
    b = board(w)
    start(b)
    seen = set()
    for _ in range(100):
        b.sleep_us(5000)
        seen.add(xyz(b))
    assert len(seen) > 90


@given(st.integers(-32768, 32767), st.integers(-32768, 32767), st.integers(-32768, 32767))
def test_data_bytes_are_int16_lsb_first_x_y_z(x, y, z):
    b = board()
    start(b)
    b.mag.inject_raw(x, y, z)
    b.sleep_us(5100)
    raw = rd(b, 0x00, 7)
    assert raw[6] & DRDY == 0                         # cleared by the data reads before it
    assert struct.unpack("<hhh", raw[:6]) == (x, y, z)
    assert raw[0] == x & 0xFF and raw[1] == (x >> 8) & 0xFF


def test_inject_raw_latch_replaces_the_output_immediately():
    b = board()
    b.mag.inject_raw(-5, 6, -7, latch=True)
    assert status(b) & DRDY and xyz(b) == (-5, 6, -7)


@given(st.integers(-100000, 100000), st.integers(-100000, 100000), st.integers(-100000, 100000))
def test_out_of_range_axis_saturates_and_sets_ovl(x, y, z):
    b = board()
    start(b)
    b.mag.inject_raw(x, y, z)
    b.mag.inject_raw(1, 2, 3)
    b.sleep_us(5100)
    s = status(b)
    sat = tuple(max(-32768, min(32767, v)) for v in (x, y, z))
    assert xyz(b) == sat
    assert bool(s & OVL) == (sat != (x, y, z))
    b.sleep_us(5000)
    assert status(b) & OVL == 0 and xyz(b) == (1, 2, 3)   # clears with an in-range set


def test_sensitivity_12000_and_3000_counts_per_gauss():
    # 50 uT = 0.5 G along sensor x (identity mounting, level, heading 0, no inclination)
    for ctrl1, expect in ((CONT_200HZ_2G, 6000), (CONT_200HZ_2G | 0x10, 1500)):
        b = board()
        start(b, ctrl1)
        b.sleep_us(5100)
        assert xyz(b) == (expect, 0, 0)


def test_strong_field_saturates_at_2g_and_fits_at_8g():
    w = World(field_ut=0.0, hard_iron_ut=(300.0, 0.0, -300.0))     # 3 G: beyond +-2 G scale
    for ctrl1, expect, ovl in ((CONT_200HZ_2G, (32767, 0, -32768), True),
                               (CONT_200HZ_2G | 0x10, (9000, 0, -9000), False)):
        b = board(w)
        start(b, ctrl1)
        b.sleep_us(5100)
        assert bool(status(b) & OVL) == ovl
        assert xyz(b) == expect


def test_rol_pnt_rolls_the_pointer_over_within_0x00_to_0x06():
    b = board()
    start(b)
    b.mag.inject_raw(0x0102, 0x0304, 0x0506)
    b.sleep_us(5100)
    wr(b, 0x0A, 0x40)
    raw = rd(b, 0x00, 9)
    assert raw[:6] == b"\x02\x01\x04\x03\x06\x05" and raw[7:9] == b"\x02\x01"
    wr(b, 0x0A, 0x00)
    raw = rd(b, 0x05, 4)                               # without ROL_PNT: 0x05..0x08
    t = struct.unpack("<h", raw[2:4])[0]
    assert raw[0] == 0x05 and t == struct.unpack("<h", rd(b, 0x07, 2))[0]


def test_soft_reset_restores_defaults_and_standby():
    b = board()
    start(b)
    wr(b, 0x0A, 0x41)
    b.sleep_us(6000)
    wr(b, 0x0A, 0x80)
    assert rd(b, 0x09, 3) == b"\x00\x00\x00"
    assert status(b) == 0
    b.sleep_us(100000)
    assert status(b) & DRDY == 0


def test_int_enb_zero_enables_the_drdy_pin():
    b = board()
    start(b)
    b.sleep_us(5100)
    assert status(b) & DRDY and b.mag.drdy_pin()
    wr(b, 0x0A, 0x01)                                  # INT_ENB = 1 disables the pin
    assert status(b) & DRDY and not b.mag.drdy_pin()


def test_temperature_is_lsb_first_at_about_100_counts_per_degree():
    w = World(temperature_c=20.0)
    b = board(w)
    start(b)
    b.sleep_us(5100)
    rd(b, 0x00, 6)
    t20 = struct.unpack("<h", rd(b, 0x07, 2))[0]
    w.temperature_c = 30.0
    b.sleep_us(5000)
    rd(b, 0x00, 6)
    t30 = struct.unpack("<h", rd(b, 0x07, 2))[0]
    assert 950 <= t30 - t20 <= 1050


def _std(vals):
    m = sum(vals) / len(vals)
    return math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1)), m


def test_noise_is_2_milligauss_rms_at_osr_512():
    b = board(noise=True)
    start(b)
    xs = []
    for _ in range(600):
        b.sleep_us(5000)
        xs.append(xyz(b)[0])
    sd, mean = _std(xs)
    assert 21.0 < sd < 27.0                            # 2 mG * 12000 counts/G = 24
    assert abs(mean - 6000) < 4


def test_lower_osr_is_noisier():
    b = board(noise=True)
    start(b, CONT_200HZ_2G | 0xC0)                     # OSR 64
    xs = []
    for _ in range(600):
        b.sleep_us(5000)
        xs.append(xyz(b)[0])
    sd, _ = _std(xs)
    assert 60.0 < sd < 76.0                            # 24 * sqrt(512 / 64) = 67.9


def test_changing_odr_restarts_the_sample_clock():
    b = board()
    start(b, 0x01)                                     # 10 Hz
    b.sleep_us(90000)
    t0 = b.clock.now_us
    wr(b, 0x09, CONT_200HZ_2G)
    b.sleep_us(t0 + 4800 - b.clock.now_us)
    assert status(b) & DRDY == 0
    b.sleep_us(300)
    assert status(b) & DRDY


def test_data_registers_ignore_writes():
    b = board()
    b.mag.inject_raw(7, 8, 9, latch=True)
    wr(b, 0x00, 1, 2, 3, 4, 5, 6)
    assert xyz(b) == (7, 8, 9)
