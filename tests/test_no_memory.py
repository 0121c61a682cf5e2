"""A MemoryError never escapes CompassApp(), step() or status_line(), and the board says what
it could not do (docs/design.md, memory). Here the heap "runs out" where a job's code is
imported (CPython has no heap to fill); tests/test_heap_sweep.py fills a real one."""
import builtins
import sys

import pytest

from host_sim import motion

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.app import status_line  # noqa: E402
from firmware.store import CalStore  # noqa: E402


@pytest.fixture
def no_room_for(monkeypatch):
    """no_room_for.names: the firmware modules whose import raises MemoryError meanwhile."""
    real = builtins.__import__

    class Gate:
        names = set()

    def imp(name, globals=None, locals=None, fromlist=(), level=0):
        wanted = {name[len("firmware."):]} if name.startswith("firmware.") else set()
        if name.startswith("firmware") and fromlist:  # from firmware(.part) import x
            pre = name[len("firmware."):] + "." if name != "firmware" else ""
            wanted |= {pre + f for f in fromlist}
        if wanted & Gate.names:
            raise MemoryError("memory allocation failed (test)")
        return real(name, globals, locals, fromlist, level)
    monkeypatch.setattr(builtins, "__import__", imp)
    return Gate


def _calibrated_store():
    fs = W.MemFs()
    W.stored_calibration(fs)
    return CalStore("/", fs=fs)


def test_a_load_short_of_memory_is_not_uncalibrated_and_is_tried_again(no_room_for):
    no_room_for.names = {"app_persist"}
    b = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app = W.make_app(b, store=_calibrated_store())
    assert app.load_reason == "no_memory" and app.no_memory == "load"
    assert app.collector is None  # no session for a board that has a calibration
    W.run_until(app, b, 1.0)
    ln = status_line(app)
    assert app.status == "out of memory" and "stored calibration not loaded" in ln
    no_room_for.names = set()
    W.run_until(app, b, 7.0)  # retried every 5 s
    assert app.calibration.model == 10 and app.no_memory is None and app.status != "out of memory"


def test_no_room_for_a_session_says_what_calibrating_needs_and_keeps_the_heading(no_room_for):
    no_room_for.names = {"calibrate.session"}
    b = W.make_sim("gy271", m=motion.figure8(), seed=3)
    app = W.make_app(b, store=CalStore("/", fs=W.MemFs()))
    W.run_until(app, b, 2.0)
    assert app.collector is None and app.no_memory == "calibrate"
    ln = status_line(app)
    assert "no room to calibrate beside the heading" in ln and "calibrate()" in ln, ln
    assert app.status == "out of memory" and app.heading_kang >= 0
    no_room_for.names = set()
    W.run_until(app, b, 65.0)  # tried again after 60 s
    assert app.collector is not None or app.calibration.model is not None


def test_the_app_that_did_not_fit_keeps_stepping_says_so_and_is_made_when_there_is_room(
        no_room_for):
    no_room_for.names = {"app_setup"}
    b = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app = W.make_app(b, store=_calibrated_store())
    assert app.no_memory == "start" and app.step() is False
    assert "the app did not fit" in status_line(app)
    no_room_for.names = set()
    for _ in range(300):  # tried again every 256 steps
        app.step()
    assert app._args is None and app.calibration.model == 10 and app.step() is True


def test_the_status_line_without_room_is_a_fixed_line(no_room_for):
    b = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app = W.make_app(b, store=_calibrated_store())
    no_room_for.names = {"status"}
    assert status_line(app).startswith("status line: out of memory")


def test_iron_that_changed_with_no_room_for_a_session_asks_for_the_program(no_room_for):
    # relearning on a board short of heap: calibrate() finds no room, .relearn_due tells
    # boards/main.py to restart into the calibration program, and run() returns for it
    fs = W.MemFs()
    W.stored_calibration(fs)
    b = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app = W.make_app(b, store=CalStore("/", fs=fs), learn=False)
    no_room_for.names = {"calibrate.session"}
    app.learning.relearn(app)  # what 30 s of interference lead to (tests/test_app.py drives it for real)
    assert app.collector is None and app.no_memory == "calibrate" and app.relearn_due
    assert app.run(100) == 0  # returns at once: boards/main.py restarts into the program


def test_every_documented_attribute_exists_while_the_app_did_not_fit(no_room_for):
    # docs/api.md's attributes and calls, on the app that tries again every 256 steps
    no_room_for.names = {"app_setup"}
    b = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app = W.make_app(b, store=CalStore("/", fs=W.MemFs()))
    assert app.no_memory == "start"
    for name in ("calibration", "stored", "collector", "pending", "change", "compass",
                 "accepted", "refused", "accuracy", "status", "heading_kang", "last_reason",
                 "relearning", "load_reason", "save_errors", "location", "mounting", "errors",
                 "relearn_due", "not_installed"):
        getattr(app, name)
    assert app.accuracy_reason() and app.progress()["model"] is None
    assert app.coverage() == 0 and app.calibrate() is None and app.step() is False


def test_the_board_starts_afresh_when_the_app_did_not_fit(monkeypatch, capsys):
    # firmware/runner.py: an app whose construction found no room is let go with the modules
    # it loaded, and the boot tries again from a clean heap (a retry inside the fragmented
    # heap it left could fail for good: docs/design.md, memory)
    import types
    waits = []
    board = types.SimpleNamespace(STORE_DIR="/nowhere", MAG_AXES="x,-y,-z", ACCEL_AXES="-x,y,z",
                                  DECLINATION_CDEG=0, CALIBRATE="never",
                                  make_i2c=lambda: None, delay_us=waits.append)
    monkeypatch.setitem(sys.modules, "board", board)
    monkeypatch.delitem(sys.modules, "firmware.runner", raising=False)
    import firmware.boot
    import firmware.runner as runner
    made = []

    def start(i2c, store_dir, **options):
        made.append(types.SimpleNamespace(no_memory="start" if not made else None))
        return made[-1], "calibration.json imported" if len(made) == 1 else None
    monkeypatch.setattr(firmware.boot, "start", start)
    dropped = []
    monkeypatch.setattr(runner, "drop", lambda *names: dropped.extend(names))
    runner._boot()
    assert len(made) == 2 and runner.app is made[1]
    assert {"app", "app_setup", "store"} <= set(dropped)
    out = capsys.readouterr().out
    assert "eCompass: out of memory at boot" in out
    assert "eCompass: calibration.json imported" in out  # the import's word is not lost
    assert waits == [5000000]  # one pause between the tries
