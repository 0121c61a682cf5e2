"""firmware/heading.py: KANG atan2/sin/cos, tilt-compensated heading, field checks.

References are computed here with floats (math/numpy) from the definitions: atan2 and sin
against math, the heading against AN4248's formula written out in floats, and the test
readings from AN4248's rotation Bp = Rx(phi) Ry(theta) Rz(psi) Br (eqs. 1-3).
"""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from firmware import fixedpoint, trig as H
from firmware.axes import AxisMap
from firmware.compass import FLAG_DIP_HIGH, FLAG_GIMBAL, FLAG_INTERFERENCE, FLAG_NO_FIELD, FLAG_NO_GRAVITY, Compass, heading
from firmware.trig import atan2, cdeg_to_kang, cos, kang_to_cdeg, kang_to_str, sin
from tests import intcheck, mp

KANG_PER_RAD = 65536 / (2 * math.pi)
DEG_PER_KANG = 360 / 65536
int16 = st.integers(min_value=-32768, max_value=32767)
vec16 = st.lists(int16, min_size=3, max_size=3)


def kang_err(a, exact_kang):
    """|a - exact| on the circle, in KANG."""
    e = (a - exact_kang) % 65536
    return min(e, 65536 - e)


def deg_err(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


# ------------------------------------------------------------------ AN4248 float reference

def rotate(yaw, pitch, roll, v):
    """Rx(roll) Ry(pitch) Rz(yaw) v, degrees (AN4248 eqs. 1-3)."""
    x, y, z = v
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    x, y = c * x + s * y, -s * x + c * y
    c, s = math.cos(math.radians(pitch)), math.sin(math.radians(pitch))
    x, z = c * x - s * z, s * x + c * z
    c, s = math.cos(math.radians(roll)), math.sin(math.radians(roll))
    y, z = c * y + s * z, -s * y + c * z
    return x, y, z


def readings(yaw, pitch, roll, incl=60.0, field=6000.0, one_g=16384.0):
    """Noise-free body-frame (b, g) ints for an orientation."""
    d = math.radians(incl)
    b = rotate(yaw, pitch, roll, (field * math.cos(d), 0.0, field * math.sin(d)))
    g = rotate(yaw, pitch, roll, (0.0, 0.0, one_g))
    return [round(v) for v in b], [round(v) for v in g]


def ref_angles(b, g):
    """AN4248 in floats: (heading deg 0..360, pitch deg, roll deg, dip deg) for ints b, g."""
    bx, by, bz = b
    gx, gy, gz = g
    phi = math.atan2(gy, gz)
    sp, cp = math.sin(phi), math.cos(phi)
    the = math.atan2(-gx, gy * sp + gz * cp)
    st_, ct = math.sin(the), math.cos(the)
    t = by * sp + bz * cp
    bfx = bx * ct + t * st_
    bfy = by * cp - bz * sp
    bfz = -bx * st_ + t * ct
    psi = math.degrees(math.atan2(-bfy, bfx)) % 360.0
    dip = math.degrees(math.atan2(bfz, math.hypot(bfx, bfy)))
    return psi, math.degrees(the), math.degrees(phi), dip


# ------------------------------------------------------------------ tables

def test_atan_table_entries_are_atan_rounded_to_kang_over_256():
    for i, t in enumerate(H._ATAN_T):
        assert abs(t - math.atan(i / 256) * KANG_PER_RAD * 256) <= 0.5
    assert len(H._ATAN_T) == 257


def test_sin_table_entries_are_sin_rounded_to_q19_with_mirror_entry():
    for i in range(257):
        assert abs(H._SIN_T[i] - math.sin(i * math.pi / 512) * (1 << 19)) <= 0.5
    assert H._SIN_T[257] == H._SIN_T[255]  # sin(90 + x) = sin(90 - x)


# ------------------------------------------------------------------ atan2

def test_atan_octant_core_is_exhaustively_within_055_kang_so_atan2_is_within_1():
    # _atan_octant(r, 32768) evaluates the table at the Q15 ratio r exactly. Any other
    # (n, d) adds at most the rounding of its ratio: 0.5 / 32768 rad = 0.16 KANG. So
    # worst(core) + 0.16 < 1 proves the 1-KANG bound for every int16 pair.
    r = np.arange(32768)
    got = np.array([H._atan_octant(int(i), 32768) for i in r])
    worst = np.abs(got - np.arctan(r / 32768) * KANG_PER_RAD).max()
    assert worst <= 0.55
    assert worst + 0.5 / 32768 * KANG_PER_RAD < 1.0


@pytest.mark.parametrize("radius", [1, 7, 100, 1000, 16384, 32767])
def test_atan2_within_1_kang_for_every_kang_angle_at_radius(radius):
    k = np.arange(65536)
    x = np.rint(radius * np.cos(k / KANG_PER_RAD)).astype(int)
    y = np.rint(radius * np.sin(k / KANG_PER_RAD)).astype(int)
    keep = (x != 0) | (y != 0)
    x, y = x[keep], y[keep]
    got = np.array([atan2(int(b), int(a)) for b, a in zip(y, x)])
    e = (got - np.arctan2(y, x) * KANG_PER_RAD) % 65536
    assert np.minimum(e, 65536 - e).max() <= 1.0
    assert got.min() >= -32768 and got.max() <= 32767


@given(int16, int16)
def test_atan2_within_1_kang_for_any_int16_pair(y, x):
    if x == 0 and y == 0:
        assert atan2(y, x) == 0  # defined, as math.atan2(0, 0)
        return
    a = atan2(y, x)
    assert -32768 <= a <= 32767
    assert kang_err(a, math.atan2(y, x) * KANG_PER_RAD) <= 1.0


def test_atan2_at_the_int16_corners_and_axes():
    for y, x in [(32767, 32767), (-32768, -32768), (-32768, 32767), (32767, -32768),
                 (0, -32768), (0, 32767), (-32768, 0), (32767, 0), (1, -32768), (-1, -32768)]:
        assert kang_err(atan2(y, x), math.atan2(y, x) * KANG_PER_RAD) <= 1.0
    assert atan2(0, -5) == -32768  # 180 deg is the int16 -32768
    assert atan2(5, 0) == 16384 and atan2(-5, 0) == -16384 and atan2(0, 5) == 0


@given(int16, int16)
def test_atan2_is_odd_in_y(y, x):
    if y == -32768 or (x == 0 and y == 0):
        return
    assert (atan2(-y, x) + atan2(y, x)) % 65536 == 0


# ------------------------------------------------------------------ sin / cos

def test_sin_and_cos_within_1_count_for_every_kang_angle():
    k = np.arange(65536)
    s = np.array([sin(int(a)) for a in k])
    c = np.array([cos(int(a)) for a in k])
    assert np.abs(s - np.sin(k / KANG_PER_RAD) * 32768).max() <= 1.0
    assert np.abs(c - np.cos(k / KANG_PER_RAD) * 32768).max() <= 1.0
    assert s.max() == 32767 and s.min() == -32767  # +-1.0 saturates to fit an int16


@given(st.integers(min_value=-(1 << 40), max_value=1 << 40))
def test_sin_cos_are_periodic_odd_even_and_quarter_shifted(a):
    assert sin(a) == sin(a + 65536) == sin(a & 0xFFFF)
    assert sin(-a) == -sin(a)
    assert cos(-a) == cos(a)
    assert cos(a) == sin(a + 16384)


def test_heading_reuses_the_fixedpoint_isqrt():
    assert H.isqrt is fixedpoint.isqrt  # one home for each primitive


@given(vec16)
def test_field_magnitude_is_within_a_count_of_exact_norm(b):
    if b == [0, 0, 0]:
        return
    c = Compass()
    c.update(b)
    exact = math.sqrt(sum(v * v for v in b))
    # the vector is scaled to 14 bits first: after s right shifts each component is off by
    # up to half a step (sqrt(3)/2 on the norm) and isqrt floors by < 1 step, a step = 2**s
    m, s = max(abs(v) for v in b), 0
    while m >= 16384:
        m >>= 1
        s += 1
    tol = 1.0 if s == 0 else (1 + math.sqrt(3) / 2) * (1 << s)
    assert abs(c.magnitude - exact) <= tol


# ------------------------------------------------------------------ conversions

@given(st.integers(min_value=-65536, max_value=65536))
def test_kang_to_cdeg_rounds_the_exact_conversion(a):
    assert abs(kang_to_cdeg(a) - a * 36000 / 65536) <= 0.5


@given(st.integers(min_value=-36000, max_value=36000))
def test_cdeg_to_kang_round_trips_within_a_centidegree(c):
    assert abs(cdeg_to_kang(c) - c * 65536 / 36000) <= 0.5
    assert abs(kang_to_cdeg(cdeg_to_kang(c)) - c) <= 1


def test_kang_to_str_formats_tenths_of_a_degree_and_wraps():
    assert kang_to_str(0) == "0.0"
    assert kang_to_str(16384) == "90.0"
    assert kang_to_str(65535) == "0.0"  # 359.995 rounds to a full turn
    assert kang_to_str(65536 - 18) == "359.9"
    assert kang_to_str(-16384) == "270.0"
    assert kang_to_str(-16384, signed=True) == "-90.0"
    assert kang_to_str(32768, signed=True) == "-180.0"
    assert kang_to_str(cdeg_to_kang(12346)) == "123.5"


@given(st.integers(min_value=0, max_value=65535))
def test_kang_to_str_is_the_angle_to_a_tenth(a):
    shown = float(kang_to_str(a))
    assert deg_err(shown, a * DEG_PER_KANG) <= 0.05 + 1e-9


# ------------------------------------------------------------------ heading

def tilt_grid(incl, field=6000.0, one_g=16384.0):
    for yaw in range(0, 360, 5):
        for pitch in range(-40, 41, 5):
            for roll in range(-40, 41, 5):
                yield yaw, pitch, roll, readings(yaw, pitch, roll, incl, field, one_g)


@pytest.mark.parametrize("incl,field,one_g", [(0, 6000, 16384), (60, 6000, 16384),
                                              (-70, 6000, 16384), (75, 6000, 16384),
                                              (66, 545, 4096)])
def test_tilted_heading_within_01_deg_of_an4248_float_formula(incl, field, one_g):
    worst = worst_yaw = worst_tilt = 0.0
    c = Compass()
    for yaw, pitch, roll, (b, g) in tilt_grid(incl, field, one_g):
        h = heading(b, g)
        psi, the, phi, _ = ref_angles(b, g)
        worst = max(worst, deg_err(h * DEG_PER_KANG, psi))
        worst_yaw = max(worst_yaw, deg_err(h * DEG_PER_KANG, yaw))
        c.update(b, g)
        assert c.heading_kang == h
        worst_tilt = max(worst_tilt, deg_err(c.pitch_kang * DEG_PER_KANG, the),
                         deg_err(c.roll_kang * DEG_PER_KANG, phi))
    assert worst <= 0.1
    assert worst_tilt <= 0.02
    # and the yaw the readings were made from (input rounding included)
    assert worst_yaw <= (0.1 if field > 1000 else 0.4)


@given(st.floats(0, 360), st.floats(-40, 40), st.floats(-40, 40), st.floats(-80, 80),
       st.floats(300, 12000), st.floats(2000, 16384))
def test_heading_matches_float_formula_for_any_tilt_within_40_deg(yaw, pitch, roll, incl,
                                                                   field, one_g):
    b, g = readings(yaw, pitch, roll, incl, field, one_g)
    psi = ref_angles(b, g)[0]
    # a horizontal field of few counts is itself coarse: allow 1 count of it in the bound
    bh = field * math.cos(math.radians(incl))
    assert deg_err(heading(b, g) * DEG_PER_KANG, psi) <= 0.1 + math.degrees(2.0 / bh)


def test_level_heading_without_g_matches_atan2_of_minus_by_bx():
    for yaw in range(0, 360, 3):
        b, _ = readings(yaw, 0, 0, 60)
        exact = math.degrees(math.atan2(-b[1], b[0])) % 360
        assert deg_err(heading(b) * DEG_PER_KANG, exact) <= 0.01
        assert deg_err(heading(b) * DEG_PER_KANG, yaw) <= 0.02


@given(vec16, st.sampled_from([1, 2, 4, 8]))
def test_heading_ignores_a_power_of_two_scale_of_b(b, k):
    if b == [0, 0, 0] or max(abs(v) for v in b) * k > 16383:
        return
    assert heading([v * k for v in b]) == heading(b)


@given(vec16)
def test_level_heading_of_a_mirrored_field_is_mirrored(b):
    if b[0] == 0 and b[1] == 0 or -32768 in b:
        return
    # (bx, -by) is the reflection of (bx, by): the heading changes sign, bit for bit
    assert heading([b[0], -b[1], b[2]]) == -heading(b) & 0xFFFF


def test_declination_is_added_and_wraps_past_north():
    b, g = readings(350, 10, -5)
    h0 = heading(b, g)
    h = heading(b, g, cdeg_to_kang(2000))  # +20 deg east
    assert h == (h0 + cdeg_to_kang(2000)) & 0xFFFF
    assert deg_err(h * DEG_PER_KANG, 10.0) <= 0.05
    b, g = readings(5, -10, 5)
    h = heading(b, g, cdeg_to_kang(-1000))  # -10 deg (west)
    assert 0 <= h <= 65535 and deg_err(h * DEG_PER_KANG, 355.0) <= 0.05
    c = Compass(declination_kang=cdeg_to_kang(-1000))
    assert c.update(b, g) == h == c.heading_kang


def test_pitch_at_plus_minus_90_is_defined_and_flagged():
    b = [1000, -2000, 5000]
    for gx in (-16384, 16384, -1, 1, -32768, 32767):
        c = Compass()
        h = c.update(b, [gx, 0, 0])
        assert 0 <= h <= 65535
        assert c.gimbal and c.flags & FLAG_GIMBAL
        assert abs(c.pitch_kang) == 16384 and c.roll_kang == 0
        psi = ref_angles(b, [gx, 0, 0])[0]  # roll 0 at the singularity, as math.atan2(0, 0)
        assert deg_err(h * DEG_PER_KANG, psi) <= 0.1


@pytest.mark.parametrize("pitch", [80.5, 82, 85, 88, 89, -89, -85])
def test_near_vertical_pitch_is_flagged_and_still_near_the_yaw(pitch):
    for yaw in range(0, 360, 30):
        b, g = readings(yaw, pitch, 20, 60)
        c = Compass()
        h = c.update(b, g)
        assert c.gimbal
        # roll comes from Gy, Gz ~ g cos(pitch): their rounding dominates, never garbage
        roll_res = math.degrees(2.0 / (16384 * math.cos(math.radians(pitch))))
        assert deg_err(h * DEG_PER_KANG, yaw) <= 0.1 + 2 * roll_res


def test_gimbal_flag_is_off_up_to_80_deg_pitch():
    for pitch in (-79.9, -60, 0, 60, 79.9):
        c = Compass()
        c.update(*readings(30, pitch, 10))
        assert not c.gimbal and not c.flags & FLAG_GIMBAL


# ------------------------------------------------------------------ field checks

@pytest.mark.parametrize("incl", [-80, -74, -30, 0, 45, 66, 74, 76, 85])
def test_dip_is_the_inclination_and_flagged_beyond_75_deg(incl):
    for yaw, pitch, roll in [(0, 0, 0), (123, 30, -20), (250, -35, 40)]:
        c = Compass()
        c.update(*readings(yaw, pitch, roll, incl))
        assert abs(c.dip_kang * DEG_PER_KANG - incl) <= 0.05
        assert c.dip_high == (abs(incl) > 75)
        assert bool(c.flags & FLAG_DIP_HIGH) == c.dip_high


def test_dip_without_g_assumes_a_level_board():
    c = Compass()
    c.update(readings(40, 0, 0, 66)[0])
    assert abs(c.dip_kang * DEG_PER_KANG - 66) <= 0.05
    assert c.pitch_kang == 0 and c.roll_kang == 0


def test_interference_flags_a_field_outside_the_tolerance_window():
    b, g = readings(100, 20, -10, 60, field=6000)
    c = Compass(field=6000)
    c.update(b, g)
    assert not c.interference and c.flags == 0
    assert abs(c.magnitude - 6000) <= 1
    for scale, flagged in [(1.09, False), (0.91, False), (1.12, True), (0.88, True), (3.0, True)]:
        c.update([round(v * scale) for v in b], g)
        assert c.interference == flagged, scale
        assert bool(c.flags & FLAG_INTERFERENCE) == flagged
    c.set_field(6000, field_tol_pct=5)  # configurable
    c.update([round(v * 1.07) for v in b], g)
    assert c.interference


def test_interference_check_is_off_without_a_reference_field():
    c = Compass()
    c.update([30000, 0, 0])
    assert not c.interference
    c.update([3, 0, 0])
    assert not c.interference


def test_bad_reference_field_or_tolerance_is_rejected_with_the_value():
    with pytest.raises(ValueError, match="-5"):
        Compass(field=-5)
    with pytest.raises(ValueError, match="150"):
        Compass(field=6000, field_tol_pct=150)


def test_a_magnet_brought_near_the_simulated_board_raises_interference():
    from host_sim import motion
    from host_sim import world as world_mod
    # 50 uT, QMC5883L at +-2 G: 120 counts/uT -> |B| = 6000 counts; MPU6050 16384 counts/g
    w = world_mod.World(field_ut=50.0, inclination_deg=60.0,
                        motion=motion.figure8(period_s=12, lobes=2, yaw_turns=1,
                                              pitch_amp=40, roll_amp=40))
    w.add_magnet((40.0, -25.0, 10.0), start_s=4.0, end_s=8.0, ramp_s=1.0, frame="world")
    mount = (1, -2, -3)  # chip x forward, y left, z up (breakout lying component side up)
    mag_map, acc_map = AxisMap("x,-y,-z"), AxisMap("-x,y,z")
    c = Compass(field=6000)
    raw, b, g = [0, 0, 0], [0, 0, 0], [0, 0, 0]
    seen = {}
    for i in range(120):
        t = i * 100000
        raw[:] = [round(v * 120) for v in w.sensor_field(t, mount)]
        mag_map.apply(raw, b)
        raw[:] = [round(v * 16384) for v in w.specific_force(t, mount)]
        acc_map.apply(raw, g)
        h = c.update(b, g)
        phase = "magnet" if 5.0 <= t / 1e6 <= 7.0 else "clear" if (t < 4e6 or t > 8e6) else "ramp"
        seen.setdefault(phase, []).append(c.interference)
        if phase == "clear":
            yaw = w.orientation(t)[0]
            assert deg_err(h * DEG_PER_KANG, yaw) <= 0.1  # the heading is right meanwhile
    assert not any(seen["clear"])
    assert all(seen["magnet"])


def test_zero_field_or_zero_gravity_is_an_error_not_a_heading():
    with pytest.raises(ValueError, match="field"):
        heading([0, 0, 0], [0, 0, 16384])
    with pytest.raises(ValueError, match="gravity"):
        heading([100, 0, 0], [0, 0, 0])
    c = Compass(field=6000)
    b, g = readings(77, 10, 10)
    good = c.update(b, g)
    assert c.update([0, 0, 0], g) == -1 and c.flags == FLAG_NO_FIELD
    assert c.heading_kang == good  # the last good value stays
    assert c.update(b, [0, 0, 0]) == -1 and c.flags == FLAG_NO_GRAVITY
    assert c.update(b, g) == good and c.flags == 0


# ------------------------------------------------------------------ small-int bound

# Two instrumented copies, so the heading path's headroom is not mixed with atan2's own
# (atan2 of an int16 pair forms n << 15 up to 2**30 - 2**15 by design).
CHECKED, STATS = intcheck.load("compass")
CHECKED_TRIG, STATS_TRIG = intcheck.load("trig")
CORNERS = (-32768, -32767, -16385, -1, 0, 1, 16384, 32767)
GS = ([-32768, -32768, -32768], [32767, 1, -1], [0, 0, 1], [1, 0, 0], [32767, -32768, 32767],
      [-16385, 16384, -1], [-32767, -32767, -32767])
# Bfx = Bx cos(theta) + (By sin(phi) + Bz cos(phi)) sin(theta) after scaling b to 14 bits
# (|b| <= sqrt(3) * 2**14): at most sqrt(3) * 2**14 * 32769 + 2**14 (Cauchy-Schwarz).
DESIGN_BOUND = math.sqrt(3) * (1 << 14) * 32769 + (1 << 14)


def corner_sweep(mod):
    c = mod.Compass(field=6000)
    for bx in CORNERS:
        for by in CORNERS:
            for bz in (-32768, 0, 1, 32767):
                b = [bx, by, bz]
                c.update(b)
                for g in GS:
                    c.update(b, g)


def test_every_intermediate_stays_below_2_30_at_the_int16_corners():
    corner_sweep(CHECKED)
    assert STATS.max_abs < 1 << 30


@settings(max_examples=max(1000, settings().max_examples))
@given(vec16, st.one_of(st.none(), vec16), st.integers(min_value=-65536, max_value=65536))
def test_heading_never_leaves_small_int_range_over_int16_inputs(b, g, decl):
    c = CHECKED.Compass(field=6000, declination_kang=decl)
    h = c.update(b, g)
    assert h == -1 or 0 <= h <= 65535
    if h >= 0:
        assert h == CHECKED.heading(b, g, decl) == heading(b, g, decl)
    assert STATS.max_abs < 1 << 30


@settings(max_examples=max(500, settings().max_examples))
@given(int16, int16, st.integers(min_value=-(1 << 29), max_value=(1 << 29) - 1))
def test_atan2_sin_cos_never_leave_small_int_range(y, x, a):
    CHECKED_TRIG.atan2(y, x)
    CHECKED_TRIG.sin(a)
    CHECKED_TRIG.cos(a)
    assert STATS_TRIG.max_abs < 1 << 30


def test_heading_path_headroom_matches_the_design_bound():
    mod, stats = intcheck.load("compass")
    corner_sweep(mod)
    # the analysis is tight (the corners reach > 0.8 of it) and holds
    assert 0.8 * DESIGN_BOUND < stats.max_abs <= DESIGN_BOUND < 1 << 30


# ------------------------------------------------------------------ MicroPython

def test_heading_bit_identical_on_micropython():
    out = mp.json_lines(mp.parity(["tests/scenarios/compass_parity.py"]))
    names = [row["name"] for row in out]
    assert names == ["atan2", "sin", "cos", "heading_grid", "heading_random", "convert", "axes"]
    assert all(len(row["v"]) >= 15 for row in out)


def test_heading_path_allocates_nothing_on_micropython():
    out = mp.json_lines(mp.run(["tests/scenarios/compass_alloc.py"], micro=True))[0]
    # the detector works: an oversized frame is seen by mem_total, and slips past heap_lock
    assert out["control_frame_bytes"] > 0 and out["control_under_lock"] == "ok"
    assert out["locked_loop"] == "ok"
    assert out["bytes"] == {k: 0 for k in out["bytes"]}
    assert len(out["bytes"]) >= 10
