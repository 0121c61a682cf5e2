"""Gyro-aided heading in the app (CompassApp.use_gyro, firmware/attitude.py) on the simulated
GY-87: the scenarios of docs/gyro.md with their stated tolerances, each beside the
magnetometer-only app where that is the point. Figures for the same scenarios (and the
10-minute still run) are in make bench."""
import pytest

from host_sim import motion
from tests import gyro_world as G

from firmware.app import STATUS_GYRO_HELD, STATUS_INTERFERENCE, STATUS_OK

BIAS = {"gyro_bias_dps": (0.5, -0.4, 0.6)}


def magnet_pass(gyro):
    # still 10 s (the bias is measured), then a slow turn; a 9 uT magnet passes 15-20 s
    m = motion.sequence([(10, motion.still(yaw=20)), (60, motion.arc(20, 110, 30))])
    b = G.board(m, gyro=BIAS)
    b.world.add_magnet((5.4, 7.2, 0.0), 15, 20, ramp_s=0.5, frame="world")
    app = G.app(b, gyro=gyro)
    worst = [0.0, 0.0]
    seen = {}

    def each(a):
        t = b.clock.now_us / 1e6
        if 15.0 <= t <= 20.0:
            worst[0] = max(worst[0], abs(G.err_deg(a, b)))
            seen[a.status] = seen.get(a.status, 0) + 1
        elif t > 1.0:
            worst[1] = max(worst[1], abs(G.err_deg(a, b)))
    G.run(app, b, 25, each)
    return app, worst, seen


def test_a_9_ut_magnet_passing_for_5_s_the_gyro_holds_the_heading_within_3_deg():
    app, worst, seen = magnet_pass(True)
    assert worst[0] <= 3.0, worst     # goal: <= 3 deg during the pass
    assert worst[1] <= 2.5, worst     # and around it
    # the heading is held, not flagged: never "interference" (nor "ok" once it is in)
    assert STATUS_INTERFERENCE not in seen and seen.get(STATUS_GYRO_HELD, 0) > 200
    assert app.attitude.bias_estimates > 0


def test_the_same_pass_without_the_gyro_is_not_ok():
    app, worst, seen = magnet_pass(False)
    assert seen.get(STATUS_INTERFERENCE, 0) > 200 and worst[0] > 5.0


def test_half_a_g_of_braking_for_2_s_moves_neither_tilt_nor_heading_by_2_deg():
    b = G.board(motion.still(yaw=0, pitch=5, roll=-3), gyro=BIAS)
    b.world.add_acceleration((-0.5, 0.0, 0.0), 10, 12, ramp_s=0.2)
    app = G.app(b)
    worst = [0.0, 0.0]

    def each(a):
        t = b.clock.now_us / 1e6
        if 9.8 <= t <= 12.5:
            at = a.attitude
            tilt = max(abs(at.pitch_kang * 360 / 65536 - 5), abs(at.roll_kang * 360 / 65536 + 3))
            worst[0] = max(worst[0], tilt)
            worst[1] = max(worst[1], abs(G.err_deg(a, b)))
    G.run(app, b, 14, each)
    assert worst[0] <= 2.0 and worst[1] <= 2.0, worst


def test_one_second_after_a_360_deg_per_s_turn_the_heading_is_within_2_deg():
    m = motion.sequence([(5, motion.still(yaw=0)), (10, motion.arc(0, 360, 1.0))])
    b = G.board(m, gyro=BIAS)
    app = G.app(b)
    G.run(app, b, 7.0)  # the turn is 5-6 s
    assert abs(G.err_deg(app, b)) <= 2.0
    assert app.status in (STATUS_OK, STATUS_GYRO_HELD)


def test_a_still_board_estimates_a_3_deg_per_s_bias_within_0_2_in_60_s():
    b = G.board(motion.still(yaw=70, pitch=-4, roll=6),
                gyro={"gyro_bias_dps": (3.0, 3.0, -3.0)})
    app = G.app(b)
    G.run(app, b, 60)
    cpd = app.accel.counts_per_dps_x10 / 10.0
    est = [v / 4096.0 / cpd for v in app.attitude.bias]
    # the body axes: sensor (x, -y, -z) for this mounting
    for got, want in zip(est, (3.0, -3.0, 3.0)):
        assert abs(got - want) <= 0.2, est
    assert abs(G.err_deg(app, b)) <= 1.0


def test_use_gyro_without_an_mpu6050_says_so():
    from host_sim.boards import make_board
    from firmware.app import CompassApp
    b = make_board("gy271")
    app = CompassApp(b.bus, delay_us=b.sleep_us, ticks_us=b.clock.ticks_us, learn=False)
    with pytest.raises(ValueError, match="MPU6050"):
        app.use_gyro()


def test_through_the_calibration_dance_the_held_heading_is_never_ok_and_wrong():
    # the figure-8 gesture (roll +-180, pitch +-85 deg, ~300 deg/s): the trapezoid rule keeps
    # the gyro's heading within the documented 5 deg wherever it is shown as ok or held;
    # near vertical (|pitch| > 80 deg) the heading is the compass's
    b = G.board(motion.figure8(period_s=30), gyro=BIAS)
    app = G.app(b)
    worst = [0.0]

    def each(a):
        if b.clock.now_us > 2000000 and a.status in (STATUS_OK, STATUS_GYRO_HELD):
            worst[0] = max(worst[0], abs(G.err_deg(a, b)))
    G.run(app, b, 60, each)
    assert worst[0] <= 5.0, worst
