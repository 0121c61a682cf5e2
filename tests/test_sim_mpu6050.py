"""MPU-6050 model and the GY-87 bypass through the bus only (host_sim/mpu6050.py); expectations
from hardware.md and the InvenSense product spec / register map, decoded here with struct."""
import math
import struct

import pytest
from hypothesis import given, strategies as st

from host_sim import motion
from host_sim.boards import make_board
from host_sim.mpu6050 import MPU6050Sim
from host_sim.bus import SimI2C
from host_sim.clock import SimClock
from host_sim.world import World

A = 0x68
LSB_PER_G = (16384, 8192, 4096, 2048)


def board(world=None, noise=False, accel_mount=(1, -2, -3)):
    return make_board("gy87", world=world or World(), noise=noise, accel_mount=accel_mount)


def rd(b, reg, n=1):
    return b.bus.readfrom_mem(A, reg, n)


def wr(b, reg, *vals):
    b.bus.writeto_mem(A, reg, bytes(vals))


def accel(b):
    return struct.unpack(">hhh", rd(b, 0x3B, 6))


def slow_rate(b):
    wr(b, 0x1A, 0x01)                                # DLPF on: 1 kHz gyro rate
    wr(b, 0x19, 9)                                   # / (1 + 9) = 100 Hz sample rate


def awake(world=None, noise=False, **kw):
    b = board(world, noise, **kw)
    wr(b, 0x6B, 0x00)
    b.sleep_us(2000)
    return b


def test_who_am_i_is_0x68_at_both_addresses():
    bus = SimI2C(SimClock())
    bus.attach(0x68, MPU6050Sim())
    bus.attach(0x69, MPU6050Sim())
    assert bus.readfrom_mem(0x68, 0x75, 1) == b"\x68" == bus.readfrom_mem(0x69, 0x75, 1)


def test_power_on_asleep_with_sensor_registers_at_zero():
    b = board()
    assert rd(b, 0x6B)[0] == 0x40
    assert rd(b, 0x6A)[0] == 0 and rd(b, 0x37)[0] == 0
    b.sleep_us(100000)
    assert accel(b) == (0, 0, 0)
    assert rd(b, 0x3A)[0] & 1 == 0


def test_writing_0x00_or_0x01_wakes_and_data_updates():
    for v in (0x00, 0x01):
        b = board()
        slow_rate(b)
        wr(b, 0x6B, v)
        b.sleep_us(10100)
        assert rd(b, 0x3A)[0] & 1                    # DATA_RDY
        assert rd(b, 0x3A)[0] & 1 == 0               # cleared by reading INT_STATUS
        assert accel(b) == (0, 0, 16384)


def test_sleeping_again_freezes_the_registers():
    w = World(motion=motion.waypoints([(0, 0, 0, 0), (0.05, 0, 90, 0)]))
    b = awake(w)
    assert accel(b) == (0, 0, 16384)
    wr(b, 0x6B, 0x40)
    b.sleep_us(100000)                               # the board has pitched up meanwhile
    assert accel(b) == (0, 0, 16384)


def test_accel_full_scale_settings():
    for afs, lsb in enumerate(LSB_PER_G):
        b = awake()
        wr(b, 0x1C, afs << 3)
        b.sleep_us(2000)
        assert accel(b) == (0, 0, lsb)
        assert rd(b, 0x3F, 2) == struct.pack(">h", lsb)   # MSB first


@given(st.floats(-89, 89), st.floats(-179, 179), st.floats(0, 359))
def test_accelerometer_reads_specific_force_plus_1g_on_the_up_axis(pitch, roll, yaw):
    # chip axes: x forward, y left, z up. The up direction in the body frame (x fwd, y right,
    # z down) is -Gp (AN4248 Gp = "down" in body axes): (sin th, -sin ph cos th, -cos ph cos th).
    b = awake(World(motion=motion.still(yaw, pitch, roll)))
    th, ph = math.radians(pitch), math.radians(roll)
    up_body = (math.sin(th), -math.sin(ph) * math.cos(th), -math.cos(ph) * math.cos(th))
    up_chip = (up_body[0], -up_body[1], -up_body[2])
    got = accel(b)
    for i in range(3):
        assert abs(got[i] - 16384 * up_chip[i]) <= 1


def test_nose_up_and_left_side_up_poses():
    b = awake(World(motion=motion.still(0, 90, 0)))        # pitch up 90: x points up
    assert accel(b) == (16384, 0, 0)
    b = awake(World(motion=motion.still(0, 0, 90)))        # roll 90: right wing down, left up
    assert accel(b) == (0, 16384, 0)
    b = awake(World(motion=motion.still(0, 0, 180)))       # upside down
    assert accel(b) == (0, 0, -16384)


def test_temperature_register_formula():
    b = awake(World(temperature_c=25.0))
    t = struct.unpack(">h", rd(b, 0x41, 2))[0]
    assert abs(t / 340.0 + 36.53 - 25.0) < 0.01


def test_sample_rate_follows_smplrt_div_and_dlpf():
    b = board()
    wr(b, 0x1A, 0x01)                                # DLPF on: 1 kHz gyro rate
    wr(b, 0x19, 9)                                   # / (1 + 9) = 100 Hz
    wr(b, 0x6B, 0x00)
    got = 0
    t0 = b.clock.now_us
    while b.clock.now_us < t0 + 1000000 + 2000:
        if rd(b, 0x3A)[0] & 1:
            got += 1
        b.sleep_us(2000)
    assert got == 100


def _std(vals):
    m = sum(vals) / len(vals)
    return math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1))


def test_accel_noise_is_400ug_per_root_hz_over_the_dlpf_bandwidth():
    for dlpf, bw in ((0, 260), (6, 5)):
        b = board(noise=True)
        wr(b, 0x1A, dlpf)
        wr(b, 0x6B, 0x00)
        zs = []
        for _ in range(600):
            b.sleep_us(1000)
            zs.append(accel(b)[2])
        expect = 400e-6 * math.sqrt(bw) * 16384       # 105.7 and 14.7 counts
        assert abs(_std(zs) - expect) < 0.12 * expect, dlpf


def test_device_reset_restores_power_on_state():
    b = awake()
    wr(b, 0x37, 0x02)
    wr(b, 0x6B, 0x80)
    assert rd(b, 0x6B)[0] == 0x40 and rd(b, 0x37)[0] == 0
    assert accel(b) == (0, 0, 0)


def test_gy87_hmc5883l_hidden_until_bypass_enabled_and_master_off():
    b = board()
    assert b.bus.scan() == [0x68, 0x77]
    wr(b, 0x6A, 0x20)                                # I2C_MST_EN on
    wr(b, 0x37, 0x02)                                # bypass on, but the master still owns it
    assert 0x1E not in b.bus.scan()
    wr(b, 0x6A, 0x00)
    assert b.bus.scan() == [0x1E, 0x68, 0x77]
    assert b.bus.readfrom_mem(0x1E, 0x0A, 3) == b"H43"
    wr(b, 0x6B, 0x80)                                # reset closes the bypass again
    assert 0x1E not in b.bus.scan()


def test_int_rd_clear_clears_data_ready_on_any_read():
    b = board()
    slow_rate(b)
    wr(b, 0x37, 0x10)
    wr(b, 0x6B, 0x00)
    b.sleep_us(10100)
    accel(b)
    assert rd(b, 0x3A)[0] & 1 == 0


def gyro(b):
    return struct.unpack(">hhh", rd(b, 0x43, 6))


@pytest.mark.parametrize("fs,cps", [(0, 131.0), (1, 65.5), (2, 32.8), (3, 16.4)])
def test_the_gyro_reads_the_board_rotation_through_the_mounting_at_each_range(fs, cps):
    b = awake(World(motion=motion.flat_spin(period_s=8)))   # +45 deg/s about body z (down)
    wr(b, 0x1B, fs << 3)
    b.sleep_us(2000)
    x, y, z = gyro(b)
    # mounting (1, -2, -3): chip z is up, so it reads -45 deg/s
    assert x == 0 and y == 0 and abs(z + 45 * cps) <= 1


def test_gyro_bias_temperature_coefficient_and_drift_add_up():
    w = World(temperature_c=35.0)
    b = make_board("gy87", world=w, noise=False, gyro={
        "gyro_bias_dps": (2.0, 0.0, -1.0), "gyro_temp_dps_per_c": (0.1, 0.0, 0.0),
        "gyro_drift_dps_per_s": (0.0, 0.5, 0.0)})
    wr(b, 0x6B, 0x00)
    b.sleep_us(2000000)                       # t = 2 s
    x, y, z = gyro(b)
    assert abs(x - (2.0 + 0.1 * 10) * 131) <= 1
    assert abs(y - 0.5 * b.clock.now_us / 1e6 * 131) <= 2
    assert abs(z + 131) <= 1


def test_a_rate_past_the_range_saturates():
    b = awake(World(motion=motion.flat_spin(period_s=0.5)))  # 720 deg/s, range +-250
    assert gyro(b)[2] == -32768


def test_gyro_noise_is_the_datasheet_total_rms():
    b = board(noise=True)
    wr(b, 0x6B, 0x00)
    xs = []
    for _ in range(2000):
        b.sleep_us(1000)
        xs.append(gyro(b)[0])
    assert abs(_std(xs) - 0.05 * 131) < 0.2 * 0.05 * 131
