"""The attitude filter (firmware/gyro/attitude.py) on its own: accuracy on exact synthetic motion
(floats make the truth, the filter sees int16 counts), the small-int bound over any input
(hypothesis drives an instrumented copy), the same bits on MicroPython, and 0 B per update.
The app with the simulated GY-87 is in tests/test_gyro.py."""
import math
from array import array

import pytest
from hypothesis import given, settings, strategies as st

from tests import intcheck, mp

from firmware.gyro import attitude
from firmware.gyro.attitude import ACC_OK, FIELD, MAG_OK, Attitude
from firmware.compass import Compass

CPS = 65.5          # counts per deg/s at +-500 deg/s (MPU6050 product spec table 6.1)
CPG = 16384
DT = 20000          # 50 Hz
ALL = MAG_OK | FIELD | ACC_OK


def kang_deg(k):
    return k * 360.0 / 65536


def err_deg(a, b):
    return (a - b + 180.0) % 360.0 - 180.0


class Truth:
    """A board with AN4248 angles (yaw, pitch, roll in degrees) and a field of 50 uT at 60 deg
    dip (2000 counts horizontal): what its sensors read, as int16."""

    def __init__(self):
        self.gyro = array("h", (0, 0, 0))
        self.grav = array("h", (0, 0, 0))
        self.field = array("h", (0, 0, 0))
        self.compass = Compass()

    @staticmethod
    def rot(yaw, pitch, roll):
        # world (NED) -> body, AN4248 eqs. 1-3: Rx(roll) Ry(pitch) Rz(yaw)
        cy, sy = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        cp, sp = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
        cr, sr = math.cos(math.radians(roll)), math.sin(math.radians(roll))
        rz = ((cy, sy, 0), (-sy, cy, 0), (0, 0, 1))
        ry = ((cp, 0, -sp), (0, 1, 0), (sp, 0, cp))
        rx = ((1, 0, 0), (0, cr, sr), (0, -sr, cr))

        def mul(a, b):
            return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
        return mul(rx, mul(ry, rz))

    def set(self, pose, rates_dps=(0, 0, 0), bias_dps=(0, 0, 0), accel_g=(0, 0, 0),
            magnet=(0, 0, 0)):
        r = self.rot(*pose)
        b_ned = (2000.0, 0.0, 3464.0)
        f_ned = (accel_g[0], accel_g[1], accel_g[2] - 1.0)  # specific force: a - g
        for i in range(3):
            self.field[i] = round(sum(r[i][k] * b_ned[k] for k in range(3)) + magnet[i])
            # AN4248 gravity sign: -f
            self.grav[i] = round(-CPG * sum(r[i][k] * f_ned[k] for k in range(3)))
            self.gyro[i] = round((rates_dps[i] + bias_dps[i]) * CPS)
        self.compass.update(self.field, self.grav)

    def filter(self, **kw):
        return Attitude(self.gyro, self.grav, self.field, self.compass, 655, CPG, **kw)


def started(pose=(30, 5, -8), **kw):
    t = Truth()
    t.set(pose)
    a = t.filter(**kw)
    a.update(DT, ALL)
    return t, a


def test_the_first_good_sample_starts_the_filter_at_the_compass_attitude():
    t, a = started((30, 5, -8))
    assert abs(err_deg(kang_deg(a.heading_kang), 30)) < 0.1
    assert abs(kang_deg(a.pitch_kang) - 5) < 0.1 and abs(kang_deg(a.roll_kang) + 8) < 0.1
    t2 = Truth()
    t2.set((30, 0, 0))
    b = t2.filter()
    assert b.update(DT, MAG_OK | FIELD) == -1 and not b.started  # no gravity: not yet


def test_a_level_turn_is_followed_to_within_a_tenth_of_a_degree():
    # the rate ramps up to 90 deg/s in 0.5 s (a gyro samples a continuous rate; the filter
    # integrates by the trapezoid rule, exact for a rate linear in time)
    t, a = started((0, 0, 0))
    yaw = 0.0
    rate = 0.0
    for _ in range(500):  # 10 s
        r = min(90.0, rate + 90.0 * DT / 0.5e6)
        yaw += (rate + r) / 2 * DT / 1e6
        rate = r
        t.set((yaw, 0, 0), (0, 0, rate))
        a.update(DT, ALL)
        assert abs(err_deg(kang_deg(a.heading_kang), yaw)) < 0.1
    assert a.source == attitude.SOURCE_MAG


def test_a_tilted_wobbling_turn_keeps_heading_and_tilt_within_half_a_degree():
    # yaw 20 deg/s, roll 15 sin(2 pi 0.3 t), pitch 10 deg: the body rates from the Euler
    # kinematics (p = roll' - yaw' sin(pitch), q = yaw' sin(roll) cos(pitch), r = yaw'
    # cos(roll) cos(pitch), with pitch constant)
    t, a = started((0, 10, 0))
    worst = 0.0
    for i in range(1, 1500):
        s = i * DT / 1e6
        yaw, pitch = 20.0 * s, 10.0
        roll = 15.0 * math.sin(2 * math.pi * 0.3 * s)
        droll = 15.0 * 2 * math.pi * 0.3 * math.cos(2 * math.pi * 0.3 * (s - DT / 2e6))
        sp, cp = math.sin(math.radians(pitch)), math.cos(math.radians(pitch))
        sr, cr = math.sin(math.radians(roll)), math.cos(math.radians(roll))
        t.set((yaw, pitch, roll), (droll - 20.0 * sp, 20.0 * sr * cp, 20.0 * cr * cp))
        a.update(DT, ALL)
        if i > 50:
            worst = max(worst, abs(err_deg(kang_deg(a.heading_kang), yaw)),
                        abs(kang_deg(a.roll_kang) - roll), abs(kang_deg(a.pitch_kang) - pitch))
    assert worst < 0.5


def test_a_still_board_measures_its_gyro_bias_within_0_2_deg_per_s():
    t, a = started((45, 0, 0))
    bias = (3.0, -2.0, 1.5)
    for _ in range(60 * 50):  # 60 s still
        t.set((45, 0, 0), bias_dps=bias)
        a.update(DT, ALL)
    assert a.known and a.bias_estimates >= 25  # the integral's 2 s blocks of evidence
    for i in range(3):
        assert abs(a.bias[i] / 4096.0 / CPS - bias[i]) < 0.2
    assert abs(err_deg(kang_deg(a.heading_kang), 45)) < 0.5


def test_while_the_field_is_flagged_the_gyro_holds_and_the_uncertainty_grows():
    t, a = started((10, 0, 0), max_uncertainty_cdeg=150)
    for _ in range(400):  # 8 s: the bias (none) is known (two blocks of the integral's
        t.set((10, 0, 0))  # evidence after the start)
        a.update(DT, ALL)
    assert a.known and a.source == attitude.SOURCE_MAG
    u0 = a.uncertainty_cdeg
    yaw = 10.0
    for i in range(250):  # 5 s turning at 30 deg/s with a magnet the app flags
        yaw += 30.0 * DT / 1e6
        t.set((yaw, 0, 0), (0, 0, 30.0), magnet=(800, 600, 0))
        a.update(DT, FIELD | ACC_OK)
        assert abs(err_deg(kang_deg(a.heading_kang), yaw)) < 0.5
    assert a.source == attitude.SOURCE_GYRO and a.since_mag_us == 250 * DT
    assert a.uncertainty_cdeg == u0 + 5 * a.bias_cdps and a.vouched
    for _ in range(1000):  # 20 s more: past 1.5 deg, no longer vouched for
        t.set((yaw, 0, 0), magnet=(800, 600, 0))
        a.update(DT, FIELD | ACC_OK)
    assert not a.vouched
    t.set((yaw, 0, 0))
    a.update(DT, ALL)
    assert a.source == attitude.SOURCE_MAG and a.vouched


def test_an_acceleration_is_rejected_and_the_tilt_held():
    t, a = started((0, 0, 0))
    for i in range(100):  # 2 s of 0.5 g braking (heading north)
        t.set((0, 0, 0), accel_g=(-0.5, 0, 0))
        a.update(DT, ALL)
        assert a.accel_rejected
        assert abs(kang_deg(a.pitch_kang)) < 0.2 and abs(kang_deg(a.roll_kang)) < 0.2
        assert abs(err_deg(kang_deg(a.heading_kang), 0)) < 0.5
    t.set((0, 0, 0))
    a.update(DT, ALL)
    assert not a.accel_rejected


def test_a_field_that_disagrees_is_held_off_then_believed_once_the_hold_is_not_vouched():
    # vouched for up to 1.5 deg: the hold starts near 1.1 deg and grows by what is known of
    # the bias (0.05 deg/s here): ~8 s
    t, a = started((0, 0, 0), recovery_us=2000000, max_uncertainty_cdeg=150)
    for i in range(250):  # 5 s still: the bias is measured (until then the field's word goes)
        t.set((0, 0, 0))
        a.update(DT, ALL)
    assert a.known
    n = 0
    while a.source != attitude.SOURCE_MAG or n == 0:  # the field turns 40 deg at once (the
        t.set((0, 0, 0), magnet=(0, -1700, 0))  # app's checks see nothing)
        was = a.vouched
        a.update(DT, ALL)
        n += 1
        assert n < 1000
        if a.source == attitude.SOURCE_GYRO:
            assert abs(err_deg(kang_deg(a.heading_kang), 0)) < 0.2
    # held past the recovery period while the gyro vouched for the heading, then the filter
    # took the field's word (snapped to it: the heading shows it from the next sample)
    assert n * DT > 2000000 and not was
    a.update(DT, ALL)
    assert abs(err_deg(kang_deg(a.heading_kang), math.degrees(math.atan2(1700, 2000)))) < 1.0


def test_a_field_that_disagrees_with_a_held_heading_by_twice_its_uncertainty_is_not_taken():
    # a magnet the app's checks flag, then one that stays put and that they no longer flag:
    # 6 deg off the held heading (its uncertainty ~1.2 deg), it does not end the hold
    t, a = started((0, 0, 0))
    for i in range(250):
        t.set((0, 0, 0))
        a.update(DT, ALL)
    for i in range(50):
        t.set((0, 0, 0), magnet=(0, -210, 0))
        a.update(DT, FIELD | ACC_OK)
    for i in range(500):
        t.set((0, 0, 0), magnet=(0, -210, 0))
        a.update(DT, ALL)
        assert a.source == attitude.SOURCE_GYRO and a.vouched
        assert abs(err_deg(kang_deg(a.heading_kang), 0)) < 0.3
    t.set((0, 0, 0))  # it has gone: the field agrees and ends the hold
    a.update(DT, ALL)
    assert a.source == attitude.SOURCE_MAG


@pytest.mark.parametrize("name,value", [("gain", -1), ("gain", 1001), ("mag_gain", 2.5),
                                        ("recovery_us", -5), ("max_uncertainty_cdeg", 20000),
                                        ("accel_reject_cdeg", 50)])
def test_options_out_of_range_name_the_argument(name, value):
    t = Truth()
    t.set((0, 0, 0))
    with pytest.raises(ValueError, match=name):
        t.filter(**{name: value})
    with pytest.raises(ValueError, match="counts_per_dps_x10"):
        Attitude(t.gyro, t.grav, t.field, t.compass, 131, CPG)


# ------------------------------------------------------------------ small-int bound

CHECKED, STATS = intcheck.load("gyro.attitude")               # the class: orchestration, windows
CHECKED_PLAIN, STATS_PLAIN = intcheck.load("gyro.attitude_plain")  # the per-sample steps
CHECKED.use_kernels(CHECKED_PLAIN)
i16 = st.integers(min_value=-32768, max_value=32767)
vec = st.lists(i16, min_size=3, max_size=3)
sample = st.tuples(vec, vec, vec, st.integers(min_value=-10, max_value=3000000),
                   st.integers(min_value=0, max_value=7))


def checked_filter(pose, gains):
    # the constructor's scale factors are long-int arithmetic (once, at start): made by the
    # plain class, then the instrumented class runs every update
    t = Truth()
    t.set(pose)
    plain = t.filter(gain=gains[0], mag_gain=gains[1], bias_gain=gains[2])
    a = object.__new__(CHECKED.Attitude)
    a.__dict__.update(plain.__dict__)
    return t, a


@settings(max_examples=max(300, settings().max_examples), deadline=None)
@given(st.tuples(st.floats(0, 360), st.floats(-89, 89), st.floats(-180, 180)),
       st.tuples(st.integers(0, 1000), st.integers(0, 1000), st.integers(0, 1000)),
       st.lists(sample, min_size=1, max_size=40))
def test_every_intermediate_stays_below_2_30_for_any_input(pose, gains, samples):
    t, a = checked_filter(pose, gains)
    a.update(DT, ALL)
    own = array("h", (0, 0, 0))
    for g, grav, f, dt, flags in samples:
        t.gyro[:] = array("h", g)
        t.grav[:] = array("h", grav)
        t.field[:] = array("h", f)
        h = a.update(dt, flags)
        assert 0 <= h <= 65535
        CHECKED.gravity(a.st, own)  # predict()'s: the filter's gravity for the app
    assert STATS.max_abs < 1 << 30 and STATS_PLAIN.max_abs < 1 << 30


def test_the_bound_holds_through_the_evidence_holds_and_the_start_up_gains():
    # the integral's blocks, a hold after the field pulled as hard as it can (a field turning
    # at 360 deg/s, taken whatever its error: mag_reject 180 deg, the largest gains), the
    # filter's gravity, the start-up gains ramping
    t = Truth()
    t.set((10, 0, 0))
    plain = t.filter(gain=1000, mag_gain=1000, bias_gain=1000, mag_reject_cdeg=18000)
    a = object.__new__(CHECKED.Attitude)
    a.__dict__.update(plain.__dict__)
    grav = array("h", (0, 0, 0))
    pulled = 0
    for i in range(1500):
        s = i % 300
        th = math.radians(7.2 * i)
        t.gyro[:] = array("h", (300 if s < 150 else -300, 0, 0))
        t.field[:] = array("h", (round(2000 * math.cos(th)), round(2000 * math.sin(th)), 3464))
        # a 1 s step just before each hold: the largest pull a sample can add
        a.update(1000000 if s == 199 else 20000, ALL if s < 200 else FIELD | ACC_OK)
        CHECKED.gravity(a.st, grav)
        if s == 200:
            pulled = max(pulled, a.st[58] // 1000)  # the hold's uncertainty at its start
    assert pulled >= 9000  # the pull's cap (90 deg) was reached
    assert STATS.max_abs < 1 << 30 and STATS_PLAIN.max_abs < 1 << 30


def test_the_slot_numbers_agree_across_the_filters_modules():
    import re

    def slots(name):
        with open("firmware/gyro/%s.py" % name) as f:
            return dict(re.findall(r"^(_[A-Z_0-9]+) = const\((\d+)\)", f.read(), re.M))
    main = slots("attitude")
    for other in ("attitude_plain", "attitude_setup"):
        o = slots(other)
        common = set(main) & set(o) - {"_TIMES", "_UNKNOWN_CDPS", "_SETTLE_US",
                                       "_BIAS_MAX", "_CHUNK_US", "_ONE28", "_M14"}
        assert len(common) >= 10, (other, common)
        assert {k: main[k] for k in common} == {k: o[k] for k in common}, other


def test_the_bound_holds_at_full_scale_rates_for_minutes():
    # the largest rates on every axis, slow loops (several chunks a sample), no corrections
    t, a = checked_filter((0, 0, 0), (1000, 1000, 1000))
    for i in range(3000):
        s = 32767 if i % 3 else -32768
        t.gyro[:] = array("h", (s, 32767 if s < 0 else -32768, s))
        a.update(70000 if i % 5 else 20000, ALL if i % 7 else 0)
    assert STATS.max_abs < 1 << 30 and STATS_PLAIN.max_abs < 1 << 30
    assert STATS_PLAIN.max_abs > 1 << 27  # the full-scale rates reach the bound's order


# ------------------------------------------------------------------ MicroPython

def test_same_bits_on_micropython():
    out = mp.json_lines(mp.parity(["tests/scenarios/attitude_parity.py"]))
    assert [r["name"] for r in out] == ["attitude", "slow"]
    assert len(out[0]["rows"]) == 30


def test_an_update_allocates_nothing_on_micropython():
    out = mp.json_lines(mp.run(["tests/scenarios/attitude_alloc.py"], micro=True))[0]
    assert out["bytes"] == 0 and out["locked"] == out["updates"] == 1500


@pytest.mark.parametrize("name", [n for n in ("unix", "x86-32") if n in mp.TIERS])
def test_the_viper_mirrors_give_the_plain_bits_on_native_tiers(name):
    # viper words are 32 bits on x86-32, as on the boards: an overflow shows as a mismatch
    if not mp.TIERS[name].available:
        pytest.skip("%s tier: %s" % (name, mp.TIERS[name].reason))
    out = mp.json_lines(mp.run(["tests/scenarios/attitude_fast.py"], name, timeout=900))[-1]
    assert out["mismatch"] == {} and out["compared"] > 15000
