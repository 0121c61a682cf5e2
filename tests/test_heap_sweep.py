"""Every heap a board may have: boards/main.py itself (desktop/benchmarks/boardrun.py) on
the x86-32 build (a collector like a board's), from `.mpy` files (make deploy) and from `.py`
sources (mip), with an empty store (a first calibration) and with a stored calibration, at
heaps from 32 KB to 512 KB. No run may end in a traceback: each completes, or its last status
line says what the board cannot do, and the board keeps running to the end of the scenario.
`make bench` sweeps in 4 KB steps and writes the smallest heaps (docs/benchmarks.md); here
the step is HEAP_SWEEP_STEP_KB (32 by default) to keep `make test` short."""
import os
import shutil

import pytest

from desktop import bench
from desktop.benchmarks.budgets import BUDGETS, KB
from tests import mp

X86 = mp.TIERS["x86-32"]
STEP = int(os.environ.get("HEAP_SWEEP_STEP_KB", "32"))
HEAPS = list(range(32, 513, STEP))
# what a board that cannot do its job says instead (firmware/status.py, boards/main.py)
SAYS_WHY = ("out of memory", "no room to calibrate", "not loaded", "save failed: no_memory")


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    if not X86.available:
        pytest.skip("x86-32 tier: %s" % X86.reason)
    d = str(tmp_path_factory.mktemp("sweep"))
    session = os.path.join(d, "session.bin")
    bench.write_session(session, smoke=False)
    out = {"session": session}
    for kind in ("mpy", "py"):
        out[kind] = bench.board_install(os.path.join(d, kind), kind)
    # a store holding the calibration a roomy board makes
    store = os.path.join(d, "calibrated")
    os.makedirs(store)
    r = bench.board_run(out["mpy"], session, 512, store)
    assert r["complete"], r
    out["store"] = store
    return out


def _check(results):
    for r in results:
        assert not r["traceback"], (r["kb"], r["exit"], r["stderr"])
        assert r["final"] is not None, (r["kb"], r["lines"][-3:])  # ran to the end
        last = r["lines"][-1] if r["lines"] else ""
        assert r["complete"] or any(w in last for w in SAYS_WHY), (r["kb"], last)


@pytest.mark.parametrize("kind", ["mpy", "py"])
@pytest.mark.parametrize("stored", [False, True], ids=["first_calibration", "calibrated"])
def test_no_heap_ends_in_a_traceback_and_each_board_says_why(world, kind, stored):
    results = bench.board_sweep(world[kind], world["session"], HEAPS,
                                world["store"] if stored else None)
    _check(results)
    best = bench.smallest_complete(results)
    assert best is not None, [(r["kb"], r["lines"][-1:]) for r in results]
    budget = BUDGETS["board_%s_%s" % ("heading" if stored else "calibrate", kind)] // KB
    assert best <= budget, (best, budget)


def test_a_status_line_reads_never_save_failed_none(world):
    r = bench.board_run(world["mpy"], world["session"], 176,
                        str(world["store"]) + "-none")  # a fresh, empty store folder
    assert not any("save failed: None" in ln for ln in r["lines"])


@pytest.fixture(autouse=True)
def _tidy(world):
    yield
    shutil.rmtree(str(world["store"]) + "-none", ignore_errors=True)


def test_a_board_running_from_sources_says_so_when_its_heap_is_short(world):
    import tempfile
    with tempfile.TemporaryDirectory() as st:
        r = bench.board_run(world["py"], world["session"], 160, st)
    assert any(ln.startswith("eCompass: running from .py sources") for ln in r["lines"]), \
        r["lines"][:4]
    with tempfile.TemporaryDirectory() as st:
        r = bench.board_run(world["mpy"], world["session"], 160, st)
    assert not any("running from .py sources" in ln for ln in r["lines"])


def test_a_first_calibration_stays_short_of_the_name_tables_next_block(world, tmp_path):
    # MicroPython's table of interned names grows in one block of 1280 entries (~9 KB on a
    # 32-bit port) past 1260 names; made mid-session it is held by every later solve
    # (docs/design.md, memory). boards/main.py's first calibration (the calibration program), to
    # its restart, interns far fewer (boardrun.py's and the wrapper's own included)
    import subprocess
    wrapper = os.path.join(mp.ROOT, "tests", "scenarios", "board_names.py")
    boardrun = os.path.join(mp.ROOT, "desktop", "benchmarks", "boardrun.py")
    store = tmp_path / "store"
    store.mkdir()
    p = subprocess.run(X86.cmd + ["-X", "heapsize=160k", wrapper, boardrun,
                                  os.path.relpath(world["session"], world["mpy"]),
                                  os.path.relpath(str(store), world["mpy"]),
                                  str(bench.BOARD_DANCE_S), str(bench.BOARD_END_S)],
                       cwd=world["mpy"], env=dict(os.environ, MICROPYPATH="."),
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-400:]
    lines = p.stdout.splitlines()
    assert any("eCompass: calibrating" in ln for ln in lines[:3]), lines[:3]
    final = [ln for ln in lines if ln.startswith("boardrun:")][-1]
    assert final.startswith("boardrun: restart at "), final  # saved: into the heading
    q = [ln for ln in lines if ln.startswith("qstr pool:")][-1]
    names = int(q.split("n_qstr=")[1].split(",")[0])
    assert names <= 1260, names
