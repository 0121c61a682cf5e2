"""MMC5603NJ model through the bus only (host_sim/mmc5603.py): the datasheet's facts
(docs/hardware.md) and the model choices its docstring states."""
import math

from host_sim.world import World
from tests.simboards import Bench

PID, STATUS1, ODR, CTRL0, CTRL1, CTRL2 = 0x39, 0x18, 0x1A, 0x1B, 0x1C, 0x1D
DONE = 0x40
SET, RESET, TM_M, TM_T, AUTO_SR, CMM_FREQ = 0x08, 0x10, 0x01, 0x02, 0x20, 0x80
MEAS_US = (6600, 3500, 2000, 1200)
NULL = 524288


def bench(world=None, noise=False, offset=(0.0, 0.0, 0.0), **kw):
    return Bench("mmc5603", world=world, noise=noise, mount=(1, 2, 3), offset_g=offset, **kw)


def codes(b):
    d = b.rd(0x00, 9)
    return tuple(d[2 * i] << 12 | d[2 * i + 1] << 4 | d[6 + i] >> 4 for i in range(3))


def measure(b, magnetise=None):
    if magnetise:
        b.wr(CTRL0, magnetise)
    b.wr(CTRL0, TM_M)
    b.sleep_us(MEAS_US[b.chip.ctrl1 & 3])
    assert b.rd(STATUS1)[0] & DONE
    return codes(b)


def test_identity_write_only_controls_and_power_on():
    b = bench()
    assert b.rd(PID)[0] == 0x10
    assert b.rd(STATUS1)[0] == 0x10                      # OTP_read_done, no data
    b.wr(ODR, 100)
    b.wr(CTRL1, 0x03)
    assert b.rd(ODR)[0] == 0 and b.rd(CTRL1)[0] == 0     # write-only: they read 0
    assert codes(b) == (NULL, NULL, NULL)


def test_a_measurement_takes_the_bandwidth_time_and_a_data_read_clears_done():
    for bw, t in enumerate(MEAS_US):
        b = bench()
        b.wr(CTRL1, bw)
        b.wr(CTRL0, TM_M)
        b.sleep_us(t - 200)
        assert b.rd(STATUS1)[0] & DONE == 0, bw
        b.sleep_us(200)
        assert b.rd(STATUS1)[0] & DONE, bw
        codes(b)
        assert b.rd(STATUS1)[0] & DONE == 0


def test_20_bit_output_16384_counts_per_gauss_sign_flipped_by_set_and_reset():
    b = bench(World(field_ut=50.0, inclination_deg=0.0))        # 0.5 G on x
    assert measure(b, SET) == (NULL + 8192, NULL, NULL)
    assert measure(b, RESET) == (NULL - 8192, NULL, NULL)
    assert measure(b) == (NULL - 8192, NULL, NULL)              # stays RESET
    assert b.chip.sets == 1 and b.chip.resets == 1


def test_the_offset_is_common_to_set_and_reset_and_cancels_in_their_difference():
    off = (0.1, -0.2, 0.05)
    b = bench(World(field_ut=50.0, inclination_deg=60.0), offset=off)
    a = measure(b, SET)
    r = measure(b, RESET)
    for i in range(3):
        assert abs((a[i] + r[i]) / 2 - NULL - off[i] * 16384) <= 1
    h = [(a[i] - r[i]) / 2 for i in range(3)]
    assert abs(h[0] - 0.25 * 16384) <= 1 and abs(h[2] - 0.433 * 16384) <= 2


def test_the_offset_drifts_with_temperature_and_time_and_the_pair_difference_does_not():
    w = World(field_ut=50.0, inclination_deg=60.0)
    b = bench(w, offset=(0.1, 0.0, 0.0), offset_drift_g_per_c=0.002, offset_drift_g_per_s=0.001)
    a0, r0 = measure(b, SET), measure(b, RESET)
    w.temperature_c = 45.0
    b.sleep_us(10000000)
    a1, r1 = measure(b, SET), measure(b, RESET)
    assert abs((a1[0] - a0[0]) - (0.04 + 0.01) * 16384) <= 2     # 20 degC, 10 s
    assert abs((a1[0] - r1[0]) - (a0[0] - r0[0])) <= 1


def test_auto_sr_sets_before_each_measurement():
    b = bench(World(field_ut=50.0, inclination_deg=0.0))
    b.wr(CTRL0, RESET)
    b.wr(CTRL0, AUTO_SR | TM_M)                # a register: TM_M alone would clear Auto_SR_en
    b.sleep_us(6600)
    assert codes(b) == (NULL + 8192, NULL, NULL)


def test_the_outputs_saturate_at_the_20_bit_rails():
    b = bench(World(field_ut=4000.0, inclination_deg=0.0))      # 40 G on x
    assert measure(b, SET)[0] == 1048575 and measure(b, RESET)[0] == 0


def test_continuous_mode_needs_cmm_freq_en_and_runs_at_the_odr():
    b = bench()
    b.wr(ODR, 100)
    b.wr(CTRL2, 0x10)                                           # Cmm_en without Cmm_freq_en
    b.sleep_us(50000)
    assert b.rd(STATUS1)[0] & DONE == 0
    b.wr(CTRL0, CMM_FREQ)
    b.wr(CTRL2, 0x10)
    t0 = b.clock.now_us
    for k in range(1, 6):                      # one measurement each 10 ms
        b.sleep_us(t0 + 10000 * k - 300 - b.clock.now_us)
        assert b.rd(STATUS1)[0] & DONE == 0, k
        b.sleep_us(t0 + 10000 * k - b.clock.now_us)
        assert b.rd(STATUS1)[0] & DONE, k
        codes(b)


def test_software_reset_restores_power_on():
    b = bench(World(field_ut=50.0, inclination_deg=0.0))
    b.wr(CTRL1, 0x03)
    b.wr(CTRL0, RESET)
    b.wr(CTRL1, 0x80)
    assert b.chip.meas_us() == 6600 and measure(b)[0] == NULL + 8192   # SET after power-on


def test_temperature_output():
    b = bench(World(temperature_c=25.0))
    b.wr(CTRL0, TM_T)
    b.sleep_us(7000)
    assert b.rd(STATUS1)[0] & 0x80 and b.rd(0x09)[0] == 125      # (25 + 75) / 0.8


def test_noise_is_2_mg_rms_per_measurement():
    b = bench(World(field_ut=0.0), noise=True)
    n = 300
    acc = [0.0, 0.0, 0.0]
    for _ in range(n):
        v = measure(b, SET)
        for i in range(3):
            acc[i] += (v[i] - NULL) ** 2
    for a in acc:
        assert abs(1000.0 * math.sqrt(a / n) / 16384 - 2.0) < 0.3
