"""Check the axis settings: lay the board flat, tip the nose down, roll it right.

    python3 examples/check_axes.py                    # on the host: the simulated board
    from examples.check_axes import check; check()    # on a board: follow the prompts

With ACCEL_AXES right, the pitch reads negative with the nose down and the roll positive with
the right side down (AN4248's body frame: x forward, y right, z down); with MAG_AXES right,
the tilt-compensated heading stays where it was through the three poses. The script says
whether they do and, if not, prints the ACCEL_AXES / MAG_AXES lines to put in
boards/<board>/board.py: ACCEL_AXES from where gravity pointed in the poses (which chip axis
was down when flat, which went down with the nose), MAG_AXES as the one of the 24 rotations
that holds the heading and the dip through them with that ACCEL_AXES. The calibration dance
finds a wrong MAG_AXES by itself (the status line's `check MAG_AXES`, docs/calibration.md,
troubleshooting); only the poses tell which way is forward.

The heading needs a calibration: the stored one, else the script first collects while you
turn the board (on the host: the simulated figure-8). On the host check(mount=(2, 1, -3))
turns the simulated magnetometer against the breakout (host_sim.world's mountings), and
check(accel_mount=...) the accelerometer; the settings checked are boards/host/board.py's.
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.app import CompassApp, status_line
from firmware.axes import AxisMap
from firmware.compass import Compass
from firmware.trig import kang_to_str

POSES = (("flat", "lay the board flat, components up, the nose (X arrow) pointing anywhere",
          0.0, 0.0),
         ("nose down", "tip the nose down about 45 degrees, still pointing the same way",
          -45.0, 0.0),
         ("roll right", "back flat, then roll it right about 45 degrees (the right side "
          "down)", 0.0, 45.0))
YAW = 40.0            # the simulated board's heading in the poses
AVERAGE = 16          # samples averaged per pose
HOLD_KANG = 1820      # 10 deg: a heading that moves more between the poses is no heading
_AXES = "xyz"


def _settings():
    # the board's board.py (on the host: boards/host/board.py, which get_bus() imported)
    try:
        import board
    except ImportError:
        board = None
    return (getattr(board, "MAG_AXES", "x,-y,-z"), getattr(board, "ACCEL_AXES", "-x,y,z"),
            getattr(board, "STORE_DIR", "/"))


def _rotations():
    # the 24 magnetometer maps a board can have (det +1)
    out = []
    for p in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        for s in range(8):
            spec = ",".join(("-" if s >> i & 1 else "") + _AXES[p[i]] for i in range(3))
            if AxisMap(spec).det == 1:
                out.append(spec)
    return out


def _signed_axis(v, skip=-1):
    # (axis, sign) of the largest |component| of v, leaving axis `skip` out
    best = -1
    for i in range(3):
        if i != skip and (best < 0 or abs(v[i]) > abs(v[best])):
            best = i
    return best, (1 if v[best] > 0 else -1)


def accel_axes_from(flat, nose):
    """ACCEL_AXES from the accelerometer's readings (chip axes, counts) lying flat and with
    the nose down: body z (down) is the chip axis that read -1 g flat (a chip reads +1 g on
    an axis pointing up), body x (forward) the one that went down with the nose, y = z x x;
    the map negated for AN4248's sign (+1 g down)."""
    z = _signed_axis(flat)
    z = (z[0], -z[1])
    x = _signed_axis([-c for c in nose], skip=z[0])
    ya = 3 - x[0] - z[0]
    # y = z cross x for signed unit axes: the sign of the permutation (z, x, y) times theirs
    even = (z[0], x[0], ya) in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    y = (ya, z[1] * x[1] * (1 if even else -1))
    return ",".join(("-" if s > 0 else "") + _AXES[a] for a, s in (x, y, z))


def _body(spec, v):
    m = AxisMap(spec)
    return [m.sign[i] * v[m.axis[i]] for i in range(3)]


def _measure(app, n=AVERAGE):
    """The mean magnetometer and accelerometer readings (chip counts) over n steps."""
    for _ in range(5):  # the sample latched before the move, and a few more
        app.step()
    mag = [0, 0, 0]
    acc = [0, 0, 0]
    for _ in range(n):
        app.step()
        for i in range(3):
            mag[i] += app.raw[i]
            acc[i] += app._acc[i]
    return [v // n for v in mag], [v // n for v in acc]


def _headings(app, poses, mag_axes, accel_axes):
    # per pose: (heading, pitch, roll, dip) in KANG with these maps
    out = []
    cal = app.calibration
    for mag, acc in poses:
        cor = [0, 0, 0]
        cal.correct(mag, cor)
        c = Compass()
        c.update(_body(mag_axes, cor), _body(accel_axes, acc))
        out.append((c.heading_kang, c.pitch_kang, c.roll_kang, c.dip_kang))
    return out


def _spread(hs):
    # the largest heading difference between poses plus the largest dip difference (KANG)
    worst = 0
    for a in hs:
        for b in hs:
            d = (a[0] - b[0]) & 0xFFFF
            d = 65536 - d if d > 32768 else d
            worst = max(worst, d + abs(a[3] - b[3]))
    return worst


def _calibrated(app, host):
    if app.calibration.model is not None:
        return True
    print("no calibration yet: turn the board through figure-8s (over, under and around)")
    steps = 0
    while app.calibration.model != 10 and (not host or steps < 2500):
        app.step()
        steps += 1
        if steps % 100 == 0 and not host:
            print(status_line(app))
    return app.calibration.model is not None


def check(seed=1, mount=None, accel_mount=None):
    """The guided check (see the module docstring); returns a dict: accel_ok, mag_ok and the
    ACCEL_AXES / MAG_AXES found."""
    i2c, delay_us = get_bus(seed)
    host = delay_us is not None
    mag_axes, accel_axes, store_dir = _settings()
    if host:
        import board
        from host_sim import motion
        if mount is not None:
            board.sim.mag.mount = tuple(mount)
        if accel_mount is not None:
            board.sim.accel.mount = tuple(accel_mount)
        app = CompassApp(i2c, mag_axes=mag_axes, accel_axes=accel_axes, delay_us=delay_us,
                         ticks_us=board.ticks_us)
    else:
        from firmware.store import CalStore
        app = CompassApp(i2c, mag_axes=mag_axes, accel_axes=accel_axes,
                         store=CalStore(store_dir))  # the calibration boards/main.py stored
    if app.accel is None:
        print("no accelerometer found: nothing to check (MAG_AXES alone cannot be wrong for a "
              "level board's heading)")
        return None
    print('checking MAG_AXES "%s", ACCEL_AXES "%s"' % (mag_axes, accel_axes))
    if not _calibrated(app, host):
        print("no calibration: run the app and calibrate first (README, first calibration)")
        return None
    readings = []
    for n, (name, text, pitch, roll) in enumerate(POSES):
        print("%d. %s" % (n + 1, text))
        if host:
            board.sim.world.motion = motion.still(YAW, pitch, roll)
        else:
            input("   then press Enter ")
        readings.append(_measure(app))
    hs = _headings(app, readings, mag_axes, accel_axes)
    for (name, _, _, _), h in zip(POSES, hs):
        print("   %-10s pitch %6s deg, roll %6s deg, heading %5s deg" % (
            name, kang_to_str(h[1], True), kang_to_str(h[2], True), kang_to_str(h[0])))
    # ACCEL_AXES: pitch negative nose down, roll positive right side down
    pitch_ok = hs[1][1] < -2730 and abs(hs[1][2]) < 2730        # < -15 deg; roll within 15
    roll_ok = hs[2][2] > 2730 and abs(hs[2][1]) < 2730
    right_acc = accel_axes_from(readings[0][1], readings[1][1])
    accel_ok = pitch_ok and roll_ok and abs(hs[0][1]) < 2730 and abs(hs[0][2]) < 2730
    if accel_ok:
        print("pitch and roll move the right way: ACCEL_AXES is right")
    else:
        print("pitch %s with the nose down (should be negative), roll %s with the right side "
              "down (should be positive): ACCEL_AXES is wrong"
              % (kang_to_str(hs[1][1], True), kang_to_str(hs[2][2], True)))
        accel_axes = right_acc
        hs = _headings(app, readings, mag_axes, accel_axes)
        if _body(accel_axes, readings[2][1])[1] <= 0:
            print("(the roll went the other way after the fix: do the poses again, right "
                  "side down)")
    # MAG_AXES: the rotation that holds the heading and the dip through the poses
    best = min(_rotations(), key=lambda s: _spread(_headings(app, readings, s, accel_axes)))
    moved = _spread(hs)
    mag_ok = moved <= HOLD_KANG or best == mag_axes
    if mag_ok:
        print("the heading holds through the poses (within %s deg): MAG_AXES is right"
              % kang_to_str(moved))
    else:
        print("the heading and dip move by %s deg through the poses: MAG_AXES is wrong"
              % kang_to_str(moved))
        mag_axes = best
    if not (accel_ok and mag_ok):
        print("put these lines in boards/<board>/board.py:")
        print('ACCEL_AXES = "%s"' % accel_axes)
        print('MAG_AXES = "%s"' % mag_axes)
    return {"accel_ok": accel_ok, "mag_ok": mag_ok, "accel_axes": accel_axes,
            "mag_axes": mag_axes}


if __name__ == "__main__":
    check()
