"""Calibration mode (firmware/calibrate/calmode.py): where the heap cannot hold the heading line and a
session together, the board calibrates holding only what calibrating needs, then shows
headings again without the session's code. Forced here by saying there is no room (CPython
cannot measure its heap); tests/test_heap_sweep.py runs it where the heap is really short."""
import os
import sys

import pytest

from host_sim import motion

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware import compat  # noqa: E402
from firmware.app import status_line  # noqa: E402
from firmware.store import CalStore  # noqa: E402

HEADING_LINE = {"firmware.compass", "firmware.fast", "firmware.kang_tables"}


@pytest.fixture(autouse=True)
def _modules_back():
    """Calibration mode drops firmware modules from sys.modules by design; the modules and the
    kernel switch this process had before are put back for the tests that follow."""
    mods = {k: v for k, v in sys.modules.items() if k == "firmware" or k.startswith("firmware.")}
    pkg = sys.modules["firmware"]
    attrs = dict(pkg.__dict__)
    fast = compat.FAST
    yield
    for k in [k for k in sys.modules if k.startswith("firmware.")]:
        if k not in mods:
            del sys.modules[k]
    sys.modules.update(mods)
    pkg.__dict__.clear()
    pkg.__dict__.update(attrs)
    compat.FAST = fast
    compat._kernels = 0


@pytest.fixture
def no_room(monkeypatch):
    # 1 KB free, whenever asked (firmware/calibrate/calmode.py is imported afresh for each use)
    monkeypatch.setattr(compat, "free_bytes", lambda: 1024)


def test_a_board_without_room_calibrates_in_calibration_mode_then_shows_headings(no_room):
    fs = W.MemFs()
    b = W.make_sim("gy271", m=motion.figure8(), seed=3)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    app.step()
    assert app.mode == "calibrating" and app.compass is None and app.watch is None
    assert not HEADING_LINE & set(sys.modules)  # the heading line's code let go
    lines = []
    while b.clock.now_us < 90000000 and app.mode != "heading":
        ok = app.step()
        assert not ok or app.mode == "heading"  # no heading while calibrating
        if app.steps % 100 == 0:
            lines.append(status_line(app))
    assert app.mode == "heading", lines[-3:]
    assert lines[0].startswith("calibration mode (no heading) | calibrating | uncalibrated")
    assert app.calibration.model == 10 and app.stored >= 1 and app.collector is None
    assert "firmware.calibrate.session" not in sys.modules and "firmware.calibrate.solve" not in sys.modules
    # the heading line again, on the fit just saved
    W.run_until(app, b, b.clock.now_us / 1e6 + 2)
    assert app.step() is True and app.compass is not None
    assert status_line(app).split(" | ")[1] in ("ok", "interference", "heading jumped")


def test_calibration_mode_relearns_the_same_way(no_room):
    fs = W.MemFs()
    W.stored_calibration(fs)
    b = W.make_sim("gy271", m=motion.figure8(), seed=4)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    assert app.mode == "heading" and app.collector is None  # a good stored fit: no session
    assert app.calibrate() is None and app._calmode_due  # no room: the next step enters it
    app.step()
    assert app.mode == "calibrating" and app.collector is not None
    assert app.calibration.model == 10  # the stored fit stays in force meanwhile


def test_calibration_mode_names_the_same_machinery_as_the_session():
    # firmware/calibrate/calmode.py keeps its own copy (a session that failed to start may not have
    # loaded firmware/calibrate/session.py): the two lists stay one
    from firmware.calibrate import calmode
    from firmware.calibrate import session
    assert calmode.KEEP == ("calibrate.calmode",)
    assert "drop_part(\"calibrate\", (\"calibrate.calmode\",))" in open(session.__file__).read()


def test_the_heap_a_first_calibration_needs_is_one_figure():
    # the status line says what calibration mode measured (firmware/status.py keeps its own
    # copy: calibration mode's module is dropped when it is not running)
    from firmware import status
    from firmware.calibrate import calmode
    assert calmode.MODE_NEED_KB == status._MODE_NEED_KB


@pytest.mark.parametrize("tier", ["cpython", "unix", "x86-32-mpy"])
def test_between_solves_the_solver_stays_only_where_the_board_compiled_it(tier, tmp_path):
    # from .py sources a board compiles the solver again for every solve (~10x its import from
    # .mpy: about a second on a board, the sample loop stalled meanwhile), so it stays; from
    # .mpy files, frozen or ROMFS code it goes between solves (firmware/calibrate/calibrator.py)
    import json
    import subprocess
    from host_sim.cli import bench
    from tests import mp
    script = os.path.join(mp.ROOT, "tests", "scenarios", "compiled_here.py")
    if tier == "x86-32-mpy":
        t = mp.TIERS["x86-32"]
        if not t.available:
            pytest.skip("x86-32 tier: %s" % t.reason)
        d = bench.build_mpy(str(tmp_path / "mpy"), bench.MPY_CROSS_32, "x86")
        out = subprocess.run(t.cmd + [script, d], capture_output=True, text=True, timeout=120,
                             env=dict(os.environ, MICROPYPATH=".frozen"), cwd=str(tmp_path))
        assert out.returncode == 0, out.stderr
        r = json.loads(out.stdout.strip().splitlines()[-1])
        assert r == {"solve": False, "frozen": False, "kept": False}, r
        return
    r = mp.json_lines(mp.run([script, mp.ROOT], micro=tier != "cpython"))[-1]
    if tier == "cpython":
        assert r["solve"] is False and r["kept"] is False, r
    else:
        assert r == {"solve": True, "frozen": False, "kept": True}, r
