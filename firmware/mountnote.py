"""The mounting check's verdict (firmware/calibrate/mountcheck.py) kept across a reboot, in a file beside
the calibration store's slots. Loaded when there is something to keep or read, and dropped
after (firmware.compat.drop): a board whose store holds no verdict never loads it.
"""
#     from firmware import mountnote
#     mountnote.save(app)        # after a check that said ok or wrong (firmware/calibrate/session.py)
#     mountnote.load(app, data)  # at boot, the file's bytes, once a record loaded (app_persist.py)
#
# app_persist.py and session.py import it by a string, so a board that never needs it interns
# none of its names. Why the verdict is kept, the file's line and what load() makes of it:
# docs/design.md (module notes, mountnote).
from firmware.axes import AxisMap
from firmware.compat import const

NAME = "_mounting.txt"    # after the store's prefix (app_persist.py and session.py hold it too)
_WRONG = "wrong"          # firmware.calibrate.mountcheck.WRONG: the only verdict written
_OK = "ok"                # firmware.calibrate.mountcheck.OK
_STATUS = 'check MAG_AXES: the data say "%s"'  # as firmware.calibrate.mountcheck.judge says it
_LINE_MAX = const(80)   # bytes read (persist.py too): a line has at most 59 (a 16-byte
#                           KIND, MAG_AXES "-x,-y,-z"); as long or longer is no line


def save(app):
    """Keep the answer of the check just made (app.mounting: ("ok" or "wrong", MAG_AXES the
    data say)) for the next boot. Nothing without a CalStore. OSError and MemoryError go to
    the caller (firmware/calibrate/session.py mount_check tries again at the next check)."""
    st = app.store
    prefix = getattr(st, "prefix", None)
    if prefix is None or getattr(st, "fs", None) is None:
        return
    path = prefix + NAME
    try:
        f = st.fs.open(path, "rb")
        try:
            kept = f.read(_LINE_MAX)
        finally:
            f.close()
    except OSError:  # none, or unreadable (at boot: no verdict either)
        kept = None
    v, said = app.mounting
    if v != _WRONG:
        if kept is not None:
            st.fs.remove(path)
        return
    from firmware.store_slots import crc32
    line = "%s %s %s %s %s" % (_WRONG, app.mag.KIND, app._mag_map.spec, app._acc_map.spec, said)
    line = ("%s %08x\n" % (line, crc32(line.encode()))).encode()
    if kept == line:
        return
    f = st.fs.open(path, "wb")
    try:
        f.write(line)
    finally:
        f.close()


def load(app, data):
    # At boot: the verdict in data (the file's bytes, at most _LINE_MAX), when it applies to
    # the settings in force (see docs/design.md, module notes). True when it says the stored
    # calibration was made through another MAG_AXES than the one in force: its dip (measured
    # in the body frame, firmware/fieldwatch.py DipCheck) is then no reference, and is learned
    # afresh.
    said = _parse(data, app.mag.KIND, app._acc_map.spec, app._mag_map.det)
    if said is None:
        return False
    now = app._mag_map.spec
    if said[0] == now:
        app.health.mounted(_WRONG, said[1], _STATUS % said[1])
        return False
    if said[1] == now:
        app.health.mounted(_OK, now, None)
    return True


def _parse(data, kind, accel, det):
    # (MAG_AXES judged, MAG_AXES said) of an intact line judged with this magnetometer and
    # this ACCEL_AXES, both maps of its handedness (det: +1 a rotation, -1 where the chip's
    # axes are a mirror of its accelerometer's); None for anything else
    i = data.rfind(b" ")
    if i < 0 or len(data) >= _LINE_MAX or data[-1:] != b"\n":
        return None  # torn (no newline yet), or longer than any line
    from firmware.store_slots import crc32
    try:
        if int(data[i + 1:-1], 16) != crc32(data[:i]):
            return None
        w = data[:i].decode().split(" ")
        if len(w) != 5 or w[0] != _WRONG or w[1] != kind:
            return None
        judged = AxisMap(w[2])
        acc = AxisMap(w[3])
        said = AxisMap(w[4])
    except ValueError:  # not hex, not text (UnicodeError), not an axis map
        return None
    if judged.det != det or said.det != det or acc.det != -1 or judged == said or acc.spec != accel:
        return None
    return judged.spec, said.spec
