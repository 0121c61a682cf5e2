"""firmware/axes.py and boards/breakouts.py: sensor -> AN4248 body frame.

The breakout maps are re-derived here from physics, not from their specs: a chip's axis
vectors expressed in the body frame (x forward, y left, z up for a breakout lying component
side up), a magnetometer reading the field along them, an accelerometer reading the specific
force (+1 g up) along them, and AN4248's rotation for a tilted board.
"""
import itertools
import math

import pytest
from hypothesis import given, strategies as st

from boards.breakouts import BREAKOUTS, GY87, GY271, GY273, IN_PACKAGE, MIRRORED, breakout
from firmware.axes import AxisMap
from firmware.compass import Compass, heading

int16 = st.integers(min_value=-32768, max_value=32767)
vec16 = st.lists(int16, min_size=3, max_size=3)
ALL_MAPS = [",".join(("-" if neg else "") + "xyz"[a] for a, neg in zip(perm, signs))
            for perm in itertools.permutations(range(3))
            for signs in itertools.product((False, True), repeat=3)]


def matvec(m, v):
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


def det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


# ------------------------------------------------------------------ parsing

def test_spec_forms_parse_to_the_same_canonical_map():
    for spec in ("x,-y,-z", " X , -Y, -Z ", "+x,-y,-z", ("x", "-y", "-z"), ["x", "- y", "-z"],
                 AxisMap("x,-y,-z")):
        m = AxisMap(spec)
        assert m.spec == "x,-y,-z"
        assert m.axis == (0, 1, 2) and m.sign == (1, -1, -1)
        assert m == AxisMap("x,-y,-z") and hash(m) == hash(AxisMap("x,-y,-z"))
    assert AxisMap("y,x,z") != AxisMap("x,y,z")
    assert repr(AxisMap("-z,x,y")) == "AxisMap('-z,x,y')"


@pytest.mark.parametrize("spec,words", [("x,x,z", "used twice"), ("x,y", "need 3"),
                                        ("x,y,w", "not one of"), ("", "need 3"),
                                        ("x,y,z,x", "need 3"), (("x", "y", 3), "not an axis"),
                                        ("x,--y,z", "not one of"), ("xy,z,", "not one of")])
def test_bad_specs_raise_value_error_naming_the_spec(spec, words):
    with pytest.raises(ValueError) as e:
        AxisMap(spec)
    assert words in str(e.value)
    assert repr(spec)[:6] in str(e.value)


# ------------------------------------------------------------------ algebra

@pytest.mark.parametrize("spec", ALL_MAPS)
def test_apply_is_the_signed_permutation_matrix_and_det_is_its_determinant(spec):
    m = AxisMap(spec)
    mat = m.matrix()
    assert m.det == det3(mat)
    for v in ([1, 2, 3], [-7, 0, 11], [32767, -32767, 5]):
        out = [0, 0, 0]
        m.apply(v, out)
        assert out == matvec(mat, v)
    inv = m.inverse()
    for v in ([1, 2, 3], [-5, 9, -13]):
        body, back = [0, 0, 0], [0, 0, 0]
        m.apply(v, body)
        inv.apply(body, back)
        assert back == v
    assert inv.matrix() == tuple(zip(*mat))  # the inverse of a rotation is its transpose


@given(st.sampled_from(ALL_MAPS), vec16)
def test_apply_in_place_equals_apply_to_a_copy_and_saturates_minus_32768(spec, v):
    m = AxisMap(spec)
    expect = [0, 0, 0]
    m.apply(list(v), expect)
    buf = list(v)
    m.apply(buf, buf)
    assert buf == expect
    exact = matvec(m.matrix(), v)
    assert expect == [min(32767, e) for e in exact]  # only -(-32768) is clamped
    assert all(-32768 <= e <= 32767 for e in expect)


# ------------------------------------------------------------------ breakouts from physics

# breakout lying component side up, X arrow forward: chip x forward, y left, z up (body frame)
CHIP_AXES_IN_BODY = ((1, 0, 0), (0, -1, 0), (0, 0, -1))


def test_chip_axes_of_a_flat_breakout_are_right_handed():
    x, y, z = CHIP_AXES_IN_BODY
    cross = (x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0])
    assert cross == z


def rot(yaw, pitch, roll):
    """AN4248 R = Rx(roll) Ry(pitch) Rz(yaw), world (NED) -> body."""
    c, s = math.cos, math.sin
    p, t, y = math.radians(roll), math.radians(pitch), math.radians(yaw)
    rz = ((c(y), s(y), 0), (-s(y), c(y), 0), (0, 0, 1))
    ry = ((c(t), 0, -s(t)), (0, 1, 0), (s(t), 0, c(t)))
    rx = ((1, 0, 0), (0, c(p), s(p)), (0, -s(p), c(p)))

    def mm(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return mm(rx, mm(ry, rz))


def in_package(rel):
    """The magnetometer's axis vectors in the body frame when its axes are `rel` (the
    accelerometer's axes, boards/breakouts.py IN_PACKAGE) and the accelerometer's are those
    of a flat breakout."""
    out = []
    for a in rel:
        v = CHIP_AXES_IN_BODY["xyz".index(a[-1])]
        out.append(tuple(-c for c in v) if a[0] == "-" else v)
    return tuple(out)


def chip_readings(yaw, pitch, roll, incl=60.0, field=6000.0, one_g=16384.0,
                  mag_axes=CHIP_AXES_IN_BODY):
    """What the chips of a flat breakout read: field and specific force along chip axes."""
    r = rot(yaw, pitch, roll)
    d = math.radians(incl)
    b_body = matvec(r, (field * math.cos(d), 0.0, field * math.sin(d)))
    down = matvec(r, (0.0, 0.0, 1.0))  # world down in body axes
    f_body = [-one_g * v for v in down]  # specific force at rest points up
    mag = [round(sum(a * b for a, b in zip(axis, b_body))) for axis in mag_axes]
    acc = [round(sum(a * f for a, f in zip(axis, f_body))) for axis in CHIP_AXES_IN_BODY]
    an4248_g = [round(one_g * v) for v in down]  # AN4248 Gp: +1 g on z for a level board
    return mag, acc, [round(v) for v in b_body], an4248_g


@pytest.mark.parametrize("name", sorted(BREAKOUTS))
def test_breakout_maps_turn_chip_readings_into_an4248_body_vectors(name):
    maps = breakout(name)
    mag_map = AxisMap(maps["mag"])
    mirror = name in MIRRORED  # a left-handed magnetometer (LIS2MDL): its z into the board
    assert mag_map.det == (-1 if mirror else 1)  # else a rotation: both frames right-handed
    acc_map = AxisMap(maps["accel"]) if "accel" in maps else AxisMap("-x,y,z")
    assert acc_map.det == -1  # rotation then the specific-force sign flip
    axes = in_package(IN_PACKAGE[name]) if name in IN_PACKAGE else CHIP_AXES_IN_BODY
    if mirror:
        axes = (axes[0], axes[1], tuple(-c for c in axes[2]))
    x, y, z = axes  # the magnetometer's frame is right-handed too (left-handed: mirrored)
    cross = (x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0])
    assert cross == (tuple(-c for c in z) if mirror else z)
    for yaw, pitch, roll in [(0, 0, 0), (90, 0, 0), (37, 25, -30), (200, -40, 170), (300, 80, 10)]:
        mag, acc, b_body, g_body = chip_readings(yaw, pitch, roll, mag_axes=axes)
        b, g = [0, 0, 0], [0, 0, 0]
        mag_map.apply(mag, b)
        acc_map.apply(acc, g)
        assert b == b_body
        assert g == g_body


def test_level_accelerometer_reads_plus_1g_up_and_maps_to_plus_1g_on_z():
    _, acc, _, g_body = chip_readings(0, 0, 0)
    assert acc == [0, 0, 16384]  # chip z points up
    g = [0, 0, 0]
    AxisMap(GY87["accel"]).apply(acc, g)
    assert g == g_body == [0, 0, 16384]


@pytest.mark.parametrize("yaw,pitch,roll", [(0, 0, 0), (45, 0, 0), (135, 20, -15),
                                            (270, -35, 30), (359, 10, 40)])
def test_gy87_chip_readings_give_the_yaw_through_maps_and_heading(yaw, pitch, roll):
    mag, acc, _, _ = chip_readings(yaw, pitch, roll)
    b, g = [0, 0, 0], [0, 0, 0]
    AxisMap(GY87["mag"]).apply(mag, b)
    AxisMap(GY87["accel"]).apply(acc, g)
    h = heading(b, g) * 360 / 65536
    assert abs((h - yaw + 180) % 360 - 180) <= 0.1


def test_without_the_map_a_flat_breakout_reads_east_as_west():
    # taking chip axes as body axes (y left instead of right) mirrors the heading: the
    # map is what makes 90 deg read 90 deg
    mag, acc, _, _ = chip_readings(90, 0, 0)
    b, g = [0, 0, 0], [0, 0, 0]
    AxisMap("x,y,z").apply(mag, b)
    AxisMap("x,y,z").apply(acc, g)
    c = Compass()
    assert abs(c.update(b, g) * 360 / 65536 - 270) <= 0.1


def test_breakout_names_and_table():
    assert breakout("GY-271") is GY271 and breakout("gy_273") is GY273 and breakout("gy87") is GY87
    with pytest.raises(ValueError, match="gy9999"):
        breakout("gy9999")
    for maps in BREAKOUTS.values():
        for spec in maps.values():
            AxisMap(spec)  # every spec parses
