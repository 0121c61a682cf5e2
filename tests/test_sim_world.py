"""World physics, motion scripts, mountings, PRNG, boards and CPython/MicroPython parity
(host_sim/world.py, motion.py, prng.py, clock.py, boards.py)."""
import math
import struct

import pytest
from hypothesis import given, strategies as st

from host_sim import motion
from host_sim.boards import CHIPS, make_board
from host_sim.clock import SimClock
from host_sim.prng import Prng
from host_sim.world import World, check_mount, mount_apply, mount_inverse, random_iron
from tests import mp

angles = st.tuples(st.floats(0, 360), st.floats(-89, 89), st.floats(-180, 180))
signed_perms = st.permutations([1, 2, 3]).flatmap(
    lambda p: st.tuples(*[st.sampled_from([a, -a]) for a in p]))


def norm(v):
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


# --- physics ------------------------------------------------------------------------------
@given(angles, st.floats(20, 70), st.floats(-89, 89))
def test_field_magnitude_is_constant_under_rotation(a, b_ut, incl):
    w = World(field_ut=b_ut, inclination_deg=incl, motion=motion.still(*a))
    assert abs(norm(w.field_body(0)) - b_ut) < 1e-9 * b_ut


@given(angles)
def test_gravity_magnitude_is_one_g(a):
    w = World(motion=motion.still(*a))
    assert abs(norm(w.gravity_body(0)) - 1.0) < 1e-12


@given(st.floats(-89, 89))
def test_level_board_sees_the_inclination(incl):
    w = World(field_ut=50.0, inclination_deg=incl)
    b = w.field_body(0)
    assert abs(math.degrees(math.atan2(b[2], b[0])) - incl) < 1e-9
    assert abs(b[1]) < 1e-12 and w.gravity_body(0) == [0.0, 0.0, 1.0]


def test_true_heading_is_magnetic_plus_declination():
    w = World(declination_deg=12.5, motion=motion.still(355.0))
    assert abs(w.true_heading_deg(0) - 7.5) < 1e-9
    assert abs(w.magnetic_heading_deg(0) - 355.0) < 1e-9


def _qmc_body_reading(b):
    """Read a noise-free QMC5883L on a GY-271 and map chip axes (x fwd, y left, z up) to the
    AN4248 body frame from the physical facts: body = (x, -y, -z)."""
    b.bus.writeto_mem(0x0D, 0x09, b"\x0d")
    b.sleep_us(5100)
    x, y, z = struct.unpack("<hhh", b.bus.readfrom_mem(0x0D, 0x00, 6))
    return (x, -y, -z)


@given(st.floats(0, 359.99))
def test_heading_from_a_noise_free_level_board_equals_yaw(yaw):
    b = make_board("gy271", world=World(motion=motion.still(yaw)), noise=False)
    bx, by, bz = _qmc_body_reading(b)
    heading = math.degrees(math.atan2(-by, bx)) % 360.0
    err = (heading - yaw + 180.0) % 360.0 - 180.0
    assert abs(err) < 0.03                         # quantisation: 1 count in 3000


@given(st.floats(0, 359.99), st.floats(-80, 80), st.floats(-170, 170))
def test_tilt_compensated_heading_from_gy87_registers_equals_yaw(yaw, pitch, roll):
    # AN4248 eqs. 13, 15, 22 on noise-free register readings; the chips' axes map to the body
    # frame as derived from physical facts: magnetometer (x, -y, -z), accelerometer -> Gp
    # (-x, y, z) (it reads +1 g up, Gp points down).
    b = make_board("gy87", world=World(motion=motion.still(yaw, pitch, roll)), noise=False)
    i2c = b.bus
    i2c.writeto_mem(0x68, 0x6B, b"\x00")
    i2c.writeto_mem(0x68, 0x37, b"\x02")
    i2c.writeto_mem(0x1E, 0x01, b"\x20")
    i2c.writeto_mem(0x1E, 0x02, b"\x01")
    b.sleep_us(6100)
    mx, mz, my = struct.unpack(">hhh", i2c.readfrom_mem(0x1E, 0x03, 6))
    ax, ay, az = struct.unpack(">hhh", i2c.readfrom_mem(0x68, 0x3B, 6))
    bpx, bpy, bpz = mx, -my, -mz
    gpx, gpy, gpz = -ax, ay, az
    phi = math.atan2(gpy, gpz)
    theta = math.atan(-gpx / (gpy * math.sin(phi) + gpz * math.cos(phi)))
    bfx = (bpx * math.cos(theta) + bpy * math.sin(theta) * math.sin(phi)
           + bpz * math.sin(theta) * math.cos(phi))
    bfy = bpy * math.cos(phi) - bpz * math.sin(phi)
    heading = math.degrees(math.atan2(-bfy, bfx)) % 360.0
    err = (heading - yaw + 180.0) % 360.0 - 180.0
    assert abs(err) < 1.0                          # 12-bit HMC data at 1090 counts/G


def _read_qmc_stream(w, n, noise, seed=1):
    b = make_board("gy271", world=w, noise=noise, seed=seed)
    b.bus.writeto_mem(0x0D, 0x09, b"\x0d")
    out = []
    for _ in range(n):
        b.sleep_us(50000)                          # 20 Hz: spread over the motion
        out.append(struct.unpack("<hhh", b.bus.readfrom_mem(0x0D, 0x00, 6)))
    return out


CPG = 120.0   # QMC5883L at +-2 G: 12000 counts/G = 120 counts/uT


def test_hard_iron_moves_the_centre_of_the_readings():
    v = (30.0, -20.0, 10.0)
    w = World(field_ut=50.0, hard_iron_ut=v, motion=motion.figure8())
    rs = _read_qmc_stream(w, 600, noise=False)
    for r in rs:                                    # a sphere of radius B around V
        d = [r[i] - v[i] * CPG for i in range(3)]
        assert abs(norm(d) - 50.0 * CPG) < 2.0
    for i in range(3):
        mid = (max(r[i] for r in rs) + min(r[i] for r in rs)) / 2
        assert abs(mid - v[i] * CPG) < 0.02 * 50.0 * CPG


def _inv3(m):
    a, b, c = m[0]
    d, e, f = m[1]
    g, h, i = m[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return [[(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
            [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
            [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det]]


def test_soft_iron_readings_lie_on_the_ellipsoid_of_w_w_transpose():
    v = (25.0, 15.0, -35.0)
    wm = ((1.12, 0.08, -0.05), (0.03, 0.88, 0.06), (-0.07, 0.04, 1.03))   # full, non-symmetric
    w = World(field_ut=50.0, hard_iron_ut=v, soft_iron=wm, motion=motion.figure8())
    rs = _read_qmc_stream(w, 600, noise=True)
    wwt = [[sum(wm[i][k] * wm[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    a = _inv3(wwt)
    b2 = (50.0 * CPG) ** 2
    ratios, plain = [], []
    for r in rs:
        d = [r[i] - v[i] * CPG for i in range(3)]
        q = sum(d[i] * a[i][j] * d[j] for i in range(3) for j in range(3))
        ratios.append(q / b2)
        plain.append((d[0] ** 2 + d[1] ** 2 + d[2] ** 2) / b2)
    assert all(abs(x - 1.0) < 0.04 for x in ratios)              # AN4246 ellipsoid, in noise
    assert abs(sum(ratios) / len(ratios) - 1.0) < 0.003
    assert max(plain) - min(plain) > 0.3                           # W really distorts


def _coverage(w, period_us, dt_us=50000):
    regions = set()
    for t in range(0, period_us, dt_us):
        b = w.field_body(t)
        n = norm(b)
        band = min(9, int((b[2] / n + 1.0) * 5.0))                 # 10 equal-area z bands
        sector = min(9, int((math.atan2(b[1], b[0]) + math.pi) / (2 * math.pi) * 10.0))
        regions.add((band, sector))
    return len(regions)


@pytest.mark.parametrize("incl", [0.0, 30.0, 60.0, 75.0, -60.0])
def test_figure8_field_direction_covers_the_sphere(incl):
    w = World(inclination_deg=incl, motion=motion.figure8())
    assert _coverage(w, 30000000) >= 95                             # of 100 regions


def test_flat_spin_covers_only_a_ring():
    w = World(inclination_deg=60.0, motion=motion.flat_spin(period_s=10.0))
    assert _coverage(w, 30000000) <= 12


# --- motion scripts -----------------------------------------------------------------------
def test_still_and_flat_spin():
    assert motion.still(10, 20, 30).at(123456) == (10.0, 20.0, 30.0)
    s = motion.flat_spin(period_s=8.0, yaw0=10.0)
    assert s.at(2000000) == (100.0, 0.0, 0.0)
    assert motion.flat_spin(period_s=8.0, clockwise=False).at(2000000)[0] == 270.0


def test_arc_moves_linearly_then_holds():
    a = motion.arc(10.0, 100.0, duration_s=3.0, start_s=1.0)
    assert a.at(0)[0] == 10.0 and a.at(1000000)[0] == 10.0
    assert abs(a.at(2500000)[0] - 55.0) < 1e-9
    assert a.at(4000000)[0] == 100.0 and a.at(99000000)[0] == 100.0


def test_waypoints_are_piecewise_constant():
    m = motion.waypoints([(0, 0, 0, 0), (1.5, 90, 10, 0), (3, 180, 0, -20)])
    assert m.at(0) == (0.0, 0.0, 0.0) and m.at(1499999) == (0.0, 0.0, 0.0)
    assert m.at(1500000) == (90.0, 10.0, 0.0) and m.at(5000000) == (180.0, 0.0, -20.0)
    with pytest.raises(ValueError):
        motion.waypoints([(2, 0, 0, 0), (1, 0, 0, 0)])


def test_sequence_runs_scripts_in_turn_with_local_time():
    m = motion.sequence([(1.0, motion.still(5)), (2.0, motion.flat_spin(period_s=4.0))])
    assert m.at(999999)[0] == 5.0
    assert m.at(1000000)[0] == 0.0 and m.at(2000000)[0] == 90.0
    assert m.at(4000000)[0] == 270.0                                # the last one continues


def test_motion_is_deterministic():
    f = motion.figure8()
    assert [f.at(t) for t in range(0, 10000000, 333333)] == \
        [motion.figure8().at(t) for t in range(0, 10000000, 333333)]


# --- interference -------------------------------------------------------------------------
def test_magnet_ramps_in_and_out_over_its_window():
    w = World(field_ut=0.0)
    w.add_magnet((100.0, 0.0, 0.0), start_s=1.0, end_s=3.0, ramp_s=0.5)
    m = (1, 2, 3)
    assert w.sensor_field(999999, m)[0] == 0.0
    assert abs(w.sensor_field(1250000, m)[0] - 50.0) < 1e-9
    assert w.sensor_field(2000000, m)[0] == 100.0
    assert abs(w.sensor_field(2750000, m)[0] - 50.0) < 1e-9
    assert w.sensor_field(3000000, m)[0] == 0.0


def test_world_frame_magnet_rotates_with_the_board_sensor_frame_one_does_not():
    for yaw, expect_world in ((0.0, (80.0, 0.0)), (90.0, (0.0, -80.0))):
        w = World(field_ut=0.0, motion=motion.still(yaw))
        w.add_magnet((80.0, 0.0, 0.0), 0.0, 10.0, ramp_s=0.0, frame="world")
        f = w.sensor_field(5000000, (1, 2, 3))
        assert abs(f[0] - expect_world[0]) < 1e-9 and abs(f[1] - expect_world[1]) < 1e-9
        w2 = World(field_ut=0.0, motion=motion.still(yaw))
        w2.add_magnet((80.0, 0.0, 0.0), 0.0, 10.0, ramp_s=0.0, frame="sensor")
        assert w2.sensor_field(5000000, (1, 2, 3)) == [80.0, 0.0, 0.0]


def test_magnet_shows_up_in_the_chip_readings():
    w = World(field_ut=50.0, inclination_deg=0.0)
    w.add_magnet((0.0, 0.0, 100.0), start_s=0.5, end_s=2.0, ramp_s=0.0)
    b = make_board("gy271", world=w, noise=False)
    b.bus.writeto_mem(0x0D, 0x09, b"\x0d")

    def fresh_z():      # the first read returns the set held by the data lock since the last
        b.bus.readfrom_mem(0x0D, 0x00, 6)
        b.sleep_us(5000)
        return struct.unpack("<hhh", b.bus.readfrom_mem(0x0D, 0x00, 6))[2]

    b.sleep_us(100000)
    z0 = fresh_z()
    b.sleep_us(900000)
    z1 = fresh_z()
    assert z1 - z0 == 12000                                          # 100 uT = 1 G


# --- mountings ----------------------------------------------------------------------------
def test_drifting_and_switching_hard_iron():
    w = World(field_ut=50.0, hard_iron_ut=(10.0, 0.0, 0.0))
    w.drift_iron((0.5, -1.0, 0.0), start_s=2.0, end_s=6.0)
    assert w.hard_iron_at(1000000) == (10.0, 0.0, 0.0)
    assert w.hard_iron_at(4000000) == pytest.approx((11.0, -2.0, 0.0))
    assert w.hard_iron_at(9000000) == pytest.approx((12.0, -4.0, 0.0))   # held at its end
    m = (1, -2, -3)
    base = w.sensor_field(1000000, m)
    assert [a - b for a, b in zip(w.sensor_field(4000000, m), base)] == pytest.approx(
        [1.0, -2.0, 0.0], abs=1e-9)  # a still board: only the drift moves the reading
    w.drift_iron(None)
    w.switch_iron((0.0, 0.0, 20.0), period_s=4.0, start_s=1.0, end_s=9.0)
    got = [w.hard_iron_at(int(t * 1e6))[2] for t in (0.5, 1.5, 3.5, 5.5, 7.5, 9.5)]
    assert got == [0.0, 0.0, 20.0, 0.0, 20.0, 0.0]
    with pytest.raises(ValueError):
        w.switch_iron((1, 0, 0), 0)


def test_check_mount_rejects_non_permutations():
    for bad in ((1, 1, 3), (1, 2), (0, 2, 3), (1, 2, 4)):
        with pytest.raises(ValueError):
            check_mount(bad)


@given(signed_perms, st.tuples(st.floats(-100, 100), st.floats(-100, 100), st.floats(-100, 100)))
def test_mount_inverse_undoes_the_mount(m, v):
    back = mount_apply(mount_inverse(m), mount_apply(m, v))
    assert back == list(v)


@given(angles)
def test_board_mountings_match_the_documented_sensor_to_body_maps(a):
    # boards.py documents: magnetometer body = (x, -y, -z), accelerometer Gp = (-x, y, z)
    w = World(motion=motion.still(*a))
    b = make_board("gy87", world=w)
    s = w.sensor_field(0, b.mount)
    f = w.field_body(0)
    assert max(abs(s[0] - f[0]), abs(-s[1] - f[1]), abs(-s[2] - f[2])) < 1e-9
    acc = w.specific_force(0, b.accel_mount)
    g = w.gravity_body(0)
    assert max(abs(-acc[0] - g[0]), abs(acc[1] - g[1]), abs(acc[2] - g[2])) < 1e-12


# --- boards -------------------------------------------------------------------------------
def test_every_board_builds_and_answers_at_its_addresses():
    expect = {"qmc5883l": [0x0D], "gy271": [0x0D], "hmc5883l": [0x1E], "qmc5883p": [0x2C],
              "gy87": [0x68, 0x77], "gy87-qmc": [0x68, 0x77], "gy9250": [0x68],
              "icm20948": [0x68],   # an IMU's magnetometer: behind its bypass
              "lis3mdl": [0x1C], "lis2mdl": [0x1E], "mmc5603": [0x30]}
    for chip in CHIPS:
        b = make_board(chip)
        assert b.bus.scan() == expect[chip], chip
        assert (b.accel is not None) == (chip in ("gy87", "gy87-qmc", "gy9250", "icm20948"))
    b = make_board("gy271", accel=True)
    assert b.bus.scan() == [0x0D, 0x68]
    with pytest.raises(ValueError):
        make_board("lsm303")


def test_board_sleep_us_is_the_bus_clock():
    b = make_board("gy271")
    t = b.clock.now_us
    b.sleep_us(777)
    assert b.clock.now_us == t + 777


# --- prng and clock -----------------------------------------------------------------------
def test_prng_is_deterministic_per_seed_and_stream():
    a = [Prng(3, 9).next_u32() for _ in range(1)] + [Prng(3, 9).uniform()]
    assert a == [Prng(3, 9).next_u32()] + [Prng(3, 9).uniform()]
    assert Prng(3, 9).next_u32() != Prng(3, 10).next_u32() != Prng(4, 9).next_u32()


def test_prng_gauss_has_zero_mean_unit_variance():
    g = Prng(11)
    xs = [g.gauss() for _ in range(20000)]
    mean = sum(xs) / len(xs)
    var = sum((x - mean) ** 2 for x in xs) / (len(xs) - 1)
    assert abs(mean) < 0.03 and abs(var - 1.0) < 0.04
    assert sum(1 for x in xs if abs(x) > 3.0) < 0.005 * len(xs)


@given(st.integers(-2 ** 40, 2 ** 40), st.integers(0, 2 ** 40), st.integers(1, 1000))
def test_prng_uniform_and_randrange_stay_in_range(seed, stream, n):
    g = Prng(seed, stream)
    for _ in range(20):
        u = g.uniform()
        assert 0.0 < u < 1.0
        assert 0 <= g.randrange(n) < n


def test_clock_is_integer_and_monotonic():
    c = SimClock()
    c.advance(5)
    c.sleep_ms(2)
    assert c.now_us == 2005 and isinstance(c.now_us, int)
    with pytest.raises(ValueError):
        c.advance(-1)


def test_random_iron_is_reproducible_and_symmetric():
    v, w = random_iron(4)
    assert (v, w) == random_iron(4) and (v, w) != random_iron(5)
    assert all(w[i][j] == w[j][i] for i in range(3) for j in range(3))


# --- parity -------------------------------------------------------------------------------
def test_sim_register_bytes_identical_on_cpython_and_micropython():
    rows = mp.json_lines(mp.parity(["tests/scenarios/sim_parity.py"]))
    qmc = [r for r in rows if r[0] == 0]
    hmc = [r for r in rows if r[0] == 1]
    tail = [r for r in rows if r[0] == 2][0]
    assert len(qmc) == 400 and len(hmc) == 300
    assert len(set(tuple(r[2:8]) for r in qmc)) > 300               # noise and motion move it
    assert tail[1] == 3 * 5                                          # the EIO burst was seen


# --- rotation rate and the board's own acceleration ----------------------------------------
def test_a_level_clockwise_spin_is_a_positive_rate_about_body_z():
    w = World(motion=motion.flat_spin(period_s=8))
    p, q, r = w.angular_rate_body(1234567)
    assert abs(p) < 1e-6 and abs(q) < 1e-6 and abs(r - 45.0) < 45e-6
    # through the 360 -> 0 wrap of the yaw angle too (matrices, not angles, are differenced)
    assert abs(w.angular_rate_body(8000000)[2] - 45.0) < 45e-6


@given(st.floats(-40, 40), st.floats(-60, 60), st.floats(-170, 170))
def test_the_rate_follows_the_euler_kinematics(yaw_rate, pitch, roll_rate):
    # yaw and roll turning at constant rates with pitch held: p = roll' - yaw' sin(pitch),
    # q = yaw' sin(roll) cos(pitch), r = yaw' cos(roll) cos(pitch) (AN4248 angles)
    class Turn:
        duration_us = None

        def at(self, t_us):
            s = t_us / 1e6
            return ((yaw_rate * s) % 360, pitch, roll_rate * s)
    t = 1700000
    w = World(motion=Turn())
    roll = math.radians(roll_rate * t / 1e6)
    sp, cp = math.sin(math.radians(pitch)), math.cos(math.radians(pitch))
    want = (roll_rate - yaw_rate * sp, yaw_rate * math.sin(roll) * cp,
            yaw_rate * math.cos(roll) * cp)
    got = w.angular_rate_body(t)
    assert all(abs(g - e) < 1e-3 for g, e in zip(got, want)), (got, want)


def test_a_board_braking_feels_the_deceleration_on_top_of_gravity():
    w = World(motion=motion.still(yaw=0))
    w.add_acceleration((-0.5, 0.0, 0.0), 1.0, 3.0, ramp_s=0.2)
    mount = (1, -2, -3)  # chip x forward, z up: a level board reads +1 g on z
    assert w.specific_force(0, mount) == [0.0, 0.0, 1.0]
    f = w.specific_force(2000000, mount)   # heading north, decelerating: -0.5 g on x
    assert abs(f[0] + 0.5) < 1e-12 and abs(f[2] - 1.0) < 1e-12
    assert abs(w.specific_force(1100000, mount)[0] + 0.25) < 1e-9   # half way up its ramp
    w2 = World(motion=motion.still(yaw=90))   # heading east, the same world acceleration
    assert abs(w2.specific_force(0, mount)[1]) < 1e-12
    w2.add_acceleration((-0.5, 0.0, 0.0), 1.0, 3.0)
    f = w2.specific_force(2000000, mount)     # seen from the side: chip y (left) reads -0.5 g
    assert abs(f[0]) < 1e-9 and abs(f[1] + 0.5) < 1e-9
    with pytest.raises(ValueError, match="frame"):
        w.add_acceleration((1, 0, 0), 0, 1, frame="sensor")
