"""The mounting check's verdict across a reboot (firmware/mountnote.py, read back by
firmware/app_persist.py load): the calibration is fitted in the chip's own axes and saved whatever
MAG_AXES says, so a board rebooted with the same wrong MAG_AXES must say so again, not "ok";
with the MAG_AXES the data said it must give good headings; with any other, no stale warning.
A torn, corrupt or foreign verdict file is no verdict and never costs the calibration; a
record without one loads as before.

The simulated board: a GY-87 whose HMC5883L is turned against the MPU6050 (mount (2, 1, -3):
the data say MAG_AXES "y,x,-z") calibrated by the 40 s figure-8 of tests/test_mounting.py with
the boards' usual "x,-y,-z", its store in memory (tests/scenarios/app_world.py MemFs); a
"reboot" is a new CompassApp on the same board and the same files. Heading tolerances are
tests/test_app.py's (the chips' datasheet noise): the mean of 16 still samples within 1 deg of
the world's heading, each within 3 deg.
"""
import os
import sys
import zlib

import pytest

from firmware.app import CompassApp, status_line
from firmware.calibration import Calibration
from firmware.store_slots import decode_record
from firmware.store import CalStore
from host_sim import motion
from host_sim.boards import make_board
from tests import mp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "scenarios"))
import app_world as W  # noqa: E402

MOUNT = (2, 1, -3)        # the HMC5883L turned against the MPU6050
WRONG = "x,-y,-z"         # the boards' usual MAG_AXES: wrong for this board
SAID = "y,x,-z"           # what the data say (desktop.mounting.mag_axes(MOUNT))
OTHER = "-y,-x,-z"        # a third setting, also wrong
NOTE = 'check MAG_AXES: the data say "%s"' % SAID
NOTE_PATH = "/ecompass_mounting.txt"
DANCE_S = 40
REST_S = 20               # then still: the session ends
MEAN_TOL_CDEG = 100
SINGLE_TOL_CDEG = 300
WRONG_MIN_CDEG = 2000     # the wrong setting's heading, tilted, is off by tens of degrees


def _board():
    return make_board("gy87", world=W.make_world(), seed=3, accel=None, mount=MOUNT)


def _app(b, fs, axes, **kw):
    return CompassApp(b.bus, mag_axes=axes, accel_axes=W.ACCEL_AXES,
                      declination_cdeg=W.DECLINATION_CDEG, store=CalStore("/", fs=fs),
                      delay_us=b.sleep_us, ticks_us=b.clock.ticks_us, **kw)


def _dance(app, b, statuses=None):
    b.world.motion = motion.figure8()
    end = b.clock.now_us + DANCE_S * 1000000
    while b.clock.now_us < end:
        app.step()
        if statuses is not None:
            statuses.append(app.status)
    W.hold(b, 30.0, 0.0, 0.0)
    end = b.clock.now_us + REST_S * 1000000
    while b.clock.now_us < end and app.collector is not None:
        app.step()


def _copy(fs):
    out = W.MemFs()
    out.files = dict(fs.files)
    return out


@pytest.fixture(scope="module")
def danced():
    """The board calibrated with the wrong MAG_AXES: its board, its files, the app."""
    b = _board()
    fs = W.MemFs()
    app = _app(b, fs, WRONG)
    statuses = []
    _dance(app, b, statuses)
    assert app.collector is None and app.stored >= 1 and app.save_errors == 0
    return {"board": b, "fs": fs, "app": app, "statuses": statuses}


def _tilted(app, b):
    """(statuses, accuracy reasons, heading errors) over the tilted poses, 16 samples each."""
    sts, reasons, errs = [], [], []
    for pose in W.TILTED_POSES:
        W.hold(b, *pose)
        for _ in range(3):  # the set latched before the move, and one more
            app.step()
        e = []
        for _ in range(16):
            assert app.step(), app.status
            sts.append(app.status)
            reasons.append(app.accuracy_reason())
            e.append(W.heading_error_cdeg(app, b))
        errs.append(e)
    return sts, reasons, errs


def test_the_check_says_wrong_and_keeps_its_verdict_beside_the_record(danced):
    app, fs = danced["app"], danced["fs"]
    assert app.mounting == ("wrong", SAID) and app.status == NOTE
    line = fs.files[NOTE_PATH]
    text, crc = line[:-1].rsplit(b" ", 1)
    assert text == b"wrong hmc5883l %s %s %s" % (WRONG.encode(), W.ACCEL_AXES.encode(),
                                                   SAID.encode())
    assert int(crc, 16) == zlib.crc32(text) and line.endswith(b"\n")
    # the record is the store's format as before: reserved bytes 0, a payload Calibration reads
    rng = app.mag.range_code
    st = CalStore("/", fs=fs, sensor="hmc5883l", range_code=rng)
    st.load()
    rec = fs.files[st.path]
    assert rec[25:28] == bytes(3)
    assert Calibration.from_bytes(decode_record(rec, "hmc5883l", rng)[1]) == app.calibration


def test_a_reboot_with_the_same_wrong_setting_says_so_again_and_never_ok(danced):
    b = danced["board"]
    app = _app(b, _copy(danced["fs"]), WRONG)
    assert app.load_reason is None and app.calibration == danced["app"].calibration
    assert app.collector is None  # a good calibration: no session, the verdict is the stored one
    assert app.mounting == ("wrong", SAID)
    sts, reasons, errs = _tilted(app, b)
    assert set(sts) == {NOTE} and set(reasons) == {"mag_axes"}
    assert app.accuracy == 0 and "| %s |" % NOTE in status_line(app)
    # what the warning is about: tilted, the heading is off by tens of degrees
    assert max(abs(x) for e in errs for x in e) > WRONG_MIN_CDEG


def test_a_reboot_with_the_setting_the_data_said_gives_good_headings_and_ok(danced):
    b = danced["board"]
    app = _app(b, _copy(danced["fs"]), SAID)
    assert app.load_reason is None and app.calibration == danced["app"].calibration
    assert app.collector is None and app.mounting == ("ok", SAID)
    sts, reasons, errs = _tilted(app, b)
    assert set(sts) == {"ok"} and "mag_axes" not in reasons and app.accuracy > 0
    for e in errs:
        assert abs(sum(e)) / len(e) < MEAN_TOL_CDEG, errs
        assert max(abs(x) for x in e) < SINGLE_TOL_CDEG, errs


def test_a_reboot_with_a_third_setting_shows_no_stale_warning_and_a_calibration_checks_it(
        danced):
    b = danced["board"]
    fs = _copy(danced["fs"])
    app = _app(b, fs, OTHER)
    assert app.load_reason is None and app.mounting is None
    sts, reasons, _ = _tilted(app, b)
    assert not any(s.startswith("check MAG_AXES") for s in sts) and "mag_axes" not in reasons
    # a calibration made with this setting checks it: the data say the same
    CalStore("/", fs=fs).erase()
    app = _app(b, fs, OTHER)
    statuses = []
    _dance(app, b, statuses)
    assert app.mounting == ("wrong", SAID) and app.status == NOTE
    assert fs.files[NOTE_PATH].startswith(b"wrong hmc5883l %s " % OTHER.encode())
    assert _app(b, fs, OTHER).mounting == ("wrong", SAID)


def test_after_the_fix_a_dip_measured_through_the_wrong_setting_is_learned_afresh(danced):
    """The calibration is in chip axes; the dip saved with it was measured in the body frame,
    through the wrong MAG_AXES: with the setting fixed it is no reference (kept, it would
    make every tilted sample interference)."""
    b = danced["board"]
    fs = _copy(danced["fs"])
    rng = danced["app"].mag.range_code
    st = CalStore("/", fs=fs, sensor="hmc5883l", range_code=rng)
    wrong_dip = 40 * 65536 // 360  # the world's is 60 deg
    st.save(Calibration.from_bytes(st.load()).with_dip(wrong_dip).to_bytes())
    wrong_dip = Calibration.from_bytes(st.load()).dip_kang  # (saved in whole degrees)
    files = dict(fs.files)
    app = _app(b, fs, SAID)
    assert app.mounting == ("ok", SAID) and app.calibration.dip_kang is None
    sts, reasons, errs = _tilted(app, b)
    assert set(sts) == {"ok"}, sts
    assert app.dip.armed  # learned here, through the right setting
    for e in errs:
        assert abs(sum(e)) / len(e) < MEAN_TOL_CDEG, errs
    assert fs.files == files  # boot writes nothing
    # the same wrong setting keeps it (the status is the check's anyway)
    assert _app(b, fs, WRONG).calibration.dip_kang == wrong_dip


def test_a_later_session_whose_check_passes_clears_the_verdict(danced):
    b = danced["board"]
    fs = _copy(danced["fs"])
    app = _app(b, fs, SAID)
    app.calibrate()  # a session in this boot checks afresh, whatever the stored verdict
    _dance(app, b)
    assert app.mounting == ("ok", SAID) and NOTE_PATH not in fs.files
    assert app.status == "ok"
    app = _app(b, fs, WRONG)
    assert app.load_reason is None and app.mounting is None


def test_a_verdict_is_written_when_it_changes_only():
    from firmware import mountnote

    class Counting(W.MemFs):
        writes = 0

        def open(self, path, mode):
            if path == NOTE_PATH and "w" in mode:
                Counting.writes += 1
            return W.MemFs.open(self, path, mode)

    class App:
        class mag:
            KIND = "hmc5883l"
        from firmware.axes import AxisMap
        _mag_map = AxisMap(WRONG)
        _acc_map = AxisMap(W.ACCEL_AXES)
        store = CalStore("/", fs=Counting())
        mounting = ("wrong", SAID)

    app = App()
    fs = app.store.fs
    mountnote.save(app)
    mountnote.save(app)
    assert Counting.writes == 1
    app.mounting = ("wrong", "-y,-x,-z")
    mountnote.save(app)
    assert Counting.writes == 2 and fs.files[NOTE_PATH].split()[4] == b"-y,-x,-z"
    app.mounting = ("spread", SAID)  # nothing said: (the session never keeps it)
    app.mounting = ("ok", WRONG)
    mountnote.save(app)
    assert NOTE_PATH not in fs.files
    mountnote.save(app)  # nothing to remove: no error
    assert Counting.writes == 2


def _line(text):
    return text + b" %08x\n" % zlib.crc32(text)


_GOOD = _line(b"wrong hmc5883l x,-y,-z -x,y,z y,x,-z")
_BAD = {
    "torn in half": _GOOD[:len(_GOOD) // 2],
    "without its newline": _GOOD[:-1],
    "a flipped bit": _GOOD[:20] + bytes([_GOOD[20] ^ 4]) + _GOOD[21:],
    "zeros": bytes(len(_GOOD)),
    "empty": b"",
    "garbage": bytes(range(256)),
    "longer than any line": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,x,-z" + b" " * 200),
    "not text": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,\xff,-z"),
    "a mirror MAG_AXES judged": _line(b"wrong hmc5883l x,y,z -x,y,z y,x,-z"),
    "a mirror MAG_AXES said": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,x,z"),
    "an axis twice": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,y,-z"),
    "not an axis": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,x,-w"),
    "a rotation for ACCEL_AXES": _line(b"wrong hmc5883l x,-y,-z x,y,z y,x,-z"),
    "the same map twice": _line(b"wrong hmc5883l x,-y,-z -x,y,z x,-y,-z"),
    "another verdict": _line(b"ok hmc5883l x,-y,-z -x,y,z y,x,-z"),
    "another magnetometer": _line(b"wrong qmc5883l x,-y,-z -x,y,z y,x,-z"),
    "another ACCEL_AXES": _line(b"wrong hmc5883l x,-y,-z -y,-x,-z y,x,-z"),
    "a word more": _line(b"wrong hmc5883l x,-y,-z -x,y,z y,x,-z 1"),
    "a crc not hex": b"wrong hmc5883l x,-y,-z -x,y,z y,x,-z zzzzzzzz\n",
}


@pytest.mark.parametrize("name", sorted(_BAD) + ["unreadable", "a directory"])
def test_a_torn_corrupt_or_foreign_verdict_is_no_verdict_and_the_calibration_loads(danced,
                                                                                    name):
    b = danced["board"]
    fs = _copy(danced["fs"])
    if name == "unreadable":
        fs.bad[NOTE_PATH] = "eio"
    elif name == "a directory":
        fs.bad[NOTE_PATH] = "dir"
    else:
        fs.files[NOTE_PATH] = _BAD[name]
    app = _app(b, fs, WRONG)
    assert app.load_reason is None and app.calibration == danced["app"].calibration
    assert app.mounting is None and app.health.axes_status is None
    W.hold(b, 30.0, 0.0, 0.0)
    for _ in range(5):
        app.step()
    assert not app.status.startswith("check MAG_AXES")
    # the good line in the same place is a verdict (the test's lines are the format's)
    fs.bad.pop(NOTE_PATH, None)
    fs.files[NOTE_PATH] = _GOOD
    assert _app(b, fs, WRONG).mounting == ("wrong", SAID)


def test_every_torn_write_of_the_verdict_boots_with_the_calibration(danced):
    b = danced["board"]
    fs = _copy(danced["fs"])
    line = fs.files[NOTE_PATH]
    for n in range(len(line)):
        fs.files[NOTE_PATH] = line[:n]
        app = _app(b, fs, WRONG)
        assert app.load_reason is None and app.mounting is None, n
        assert app.calibration == danced["app"].calibration


def test_a_record_without_a_verdict_loads_as_before_and_boot_writes_nothing():
    # a record made by hand (tests/scenarios/app_world.py), as older firmware left it
    b = W.make_sim("gy271", m=motion.still(30.0, 20.0, -15.0))
    fs = W.MemFs()
    W.stored_calibration(fs)
    files = dict(fs.files)
    for axes in (W.MAG_AXES, SAID):
        app = CompassApp(b.bus, mag_axes=axes, accel_axes=W.ACCEL_AXES,
                         store=CalStore("/", fs=fs), delay_us=b.sleep_us,
                         ticks_us=b.clock.ticks_us, learn=False)
        assert app.load_reason is None and app.calibration.model == 10
        assert app.mounting is None and app.health.axes_status is None
        for _ in range(5):
            app.step()
        assert not app.status.startswith("check MAG_AXES")
        assert fs.files == files  # boot reads; it writes nothing


def test_the_verdict_is_read_the_same_on_micropython():
    mp.parity(["tests/scenarios/mounting_note.py"])


def test_a_board_without_a_verdict_file_loads_nothing_for_it(danced):
    import firmware
    fs = _copy(danced["fs"])
    del fs.files[NOTE_PATH]
    sys.modules.pop("firmware.mountnote", None)
    firmware.__dict__.pop("mountnote", None)
    import builtins
    real = builtins.__import__
    seen = []

    def watch(name, globals=None, locals=None, fromlist=(), level=0):
        seen.append(" ".join((name,) + tuple(fromlist or ())))
        return real(name, globals, locals, fromlist, level)
    builtins.__import__ = watch
    try:
        app = _app(danced["board"], fs, WRONG)
        without = [n for n in seen if "mountnote" in n]
        # with the file, its code comes and goes again
        fs.files[NOTE_PATH] = danced["fs"].files[NOTE_PATH]
        app = _app(danced["board"], fs, WRONG)
    finally:
        builtins.__import__ = real
    assert without == [] and app.mounting == ("wrong", SAID)
    assert "firmware.mountnote load" in seen
    assert "firmware.mountnote" not in sys.modules and not hasattr(firmware, "mountnote")


def test_the_boot_and_the_session_name_the_verdicts_code_by_strings_only():
    """MicroPython interns (for good: qstrs are never freed) the names of a module's import
    statements when the module loads; firmware/app_persist.py loads at every boot and
    firmware/calibrate/session.py at every calibration, so they name firmware/mountnote.py and its
    file by strings of more than 10 characters, which stay strings. A calibrated board's heap
    after boot is then the same to the byte (tests/test_budgets.py), and no name is added to
    a qstr pool that a session leaves nearly full in a fragmented heap."""
    import ast
    from firmware import mountnote
    for name in ("app_persist", "calibrate/session"):
        src = open(os.path.join(mp.ROOT, "firmware", name + ".py")).read()
        strings = []
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                names = [a.name for a in node.names] + [getattr(node, "module", None) or ""]
                assert not any("mountnote" in n for n in names), (name, node.lineno)
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                strings.append(node.value)
        assert "firmware.mountnote" in strings and mountnote.NAME in strings, name
        assert all(len(s) > 10 for s in ("firmware.mountnote", mountnote.NAME))


def test_a_verdict_is_kept_in_the_handedness_of_the_chip():
    # a chip whose axes are a mirror of its accelerometer's (driver MIRROR): its maps are
    # mirrors, and a line of rotations is no verdict for it (nor a line of mirrors for others)
    from firmware import mountnote
    mirrors = _line(b"wrong lsm9ds1 x,y,-z -x,y,z y,x,z")
    assert mountnote._parse(mirrors, "lsm9ds1", "-x,y,z", -1) == ("x,y,-z", "y,x,z")
    assert mountnote._parse(mirrors, "lsm9ds1", "-x,y,z", 1) is None
    assert mountnote._parse(_GOOD, "hmc5883l", "-x,y,z", -1) is None
    assert mountnote._parse(_GOOD, "hmc5883l", "-x,y,z", 1) == ("x,-y,-z", "y,x,-z")
