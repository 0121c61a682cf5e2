# Prints atan2/sin/cos/heading/Compass/AxisMap results over fixed integer grids as JSON lines
# (ints and strings only); tests/test_compass.py runs it on CPython and MicroPython and
# requires identical output.
import json

from firmware.axes import AxisMap
from firmware.compass import Compass, heading
from firmware.trig import atan2, cdeg_to_kang, cos, kang_to_cdeg, kang_to_str, sin

import sys  # noqa: E402
sys.path.append("tests/scenarios")  # smallrand, also when the script arrives on stdin (qemu)
from smallrand import SmallRand  # noqa: E402

_R = SmallRand(12345)


def rnd16():
    # LCG (Numerical Recipes constants): the same integers on both interpreters
    return _R.u16() - 32768


def emit(name, v):
    print(json.dumps({"name": name, "v": v}))


grid = list(range(-32768, 32768, 1237)) + [-32768, -1, 0, 1, 32767]
emit("atan2", [atan2(y, x) for y in grid for x in grid])
emit("sin", [sin(a) for a in range(-70000, 70000, 97)])
emit("cos", [cos(a) for a in range(-70000, 70000, 97)])

# tilted readings: integer rotations of a fixed field by the firmware's own sin/cos are fine
# here, only the bits matter
rows = []
c = Compass(field=6000, declination_kang=cdeg_to_kang(-1234))
for yaw in range(0, 65536, 2048):
    for pitch in range(-7282, 7283, 1820):  # -40..40 deg
        for roll in range(-7282, 7283, 1820):
            bx, bz = 3000, 5196
            sy, cy = sin(yaw), cos(yaw)
            x, y = (bx * cy) >> 15, -(bx * sy) >> 15
            sp, cp = sin(pitch), cos(pitch)
            x, z = (x * cp - bz * sp) >> 15, (x * sp + bz * cp) >> 15
            sr, cr = sin(roll), cos(roll)
            y, z = (y * cr + z * sr) >> 15, (-y * sr + z * cr) >> 15
            gx, gz = -(16384 * sp) >> 15, (16384 * cp) >> 15
            gy, gz = (gz * sr) >> 15, (gz * cr) >> 15
            b, g = [x, y, z], [gx, gy, gz]
            h = c.update(b, g)
            rows.append([heading(b, g), heading(b), h, c.pitch_kang, c.roll_kang, c.dip_kang,
                         c.magnitude, c.flags])
emit("heading_grid", rows)

rows = []
for i in range(400):
    b = [rnd16(), rnd16(), rnd16()]
    g = [rnd16() >> (i % 4), rnd16(), rnd16()]
    h = c.update(b, g)
    rows.append([h, c.pitch_kang, c.roll_kang, c.dip_kang, c.magnitude, c.flags, heading(b)])
emit("heading_random", rows)

emit("convert", [[kang_to_cdeg(a), kang_to_str(a), kang_to_str(a, True), cdeg_to_kang(a // 2)]
                 for a in range(-65536, 65537, 811)])

out = []
m = [0, 0, 0]
for spec in ("x,-y,-z", "-x,y,z", "y,x,-z", "-z,-x,y", " +Z, y ,-X"):
    a = AxisMap(spec)
    for v in ([1, 2, 3], [-32768, 32767, 0], [123, -456, 789]):
        a.apply(v, m)
        out.append([a.spec, a.det, m[0], m[1], m[2], a.inverse().spec])
emit("axes", out)
