"""Memory budgets that fail the build (desktop/benchmarks/budgets.py), on the 32-bit tiers
that are here: the x86-32 build (collects as a board does: live heap and the smallest heap that
completes) and the WebAssembly port (never collects while a script runs: what a run allocates
in total). The board profiles boot as boards/main.py does (desktop/benchmarks/profiles.py);
`make bench` prints the same figures beside the budgets in docs/benchmarks.md."""
import json
import os
import subprocess

import pytest

from desktop import bench
from desktop.benchmarks.budgets import BUDGETS, KB
from tests import mp

X86 = mp.TIERS["x86-32"]
WASM = mp.TIERS["wasm"]
# boot + 2000 headings on the WebAssembly port, .mpy files: everything allocated, transient
# boot work included (nothing is collected there); the headings themselves add nothing
WASM_HEADING_ALLOCATED = 112 * KB + 512  # 114,912 B with the chip table and the app's
#                                            declared state (114.6 KB before them)


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    """A recorded session, the firmware as x86 .mpy files and as a ROMFS image of them, and as
    bytecode-only .mpy files (no native code: firmware/fast.py and attitude_fast.py left out) for the WebAssembly
    port."""
    d = str(tmp_path_factory.mktemp("budgets"))
    session = os.path.join(d, "session.bin")
    bench.write_session(session, smoke=False)
    bench.write_session(session + ".gyro", smoke=False, mpu_bytes=14)
    out = {"dir": d, "session": session, "session_bytes": os.path.getsize(session)}
    if X86.available:
        out["mpy"] = bench.build_mpy(os.path.join(d, "mpy"), bench.MPY_CROSS_32, "x86")
        out["rom"] = os.path.join(d, "firmware.romfs")
        bench.romfs_image(os.path.join(out["mpy"], "firmware"), out["rom"])
        out["rom_bytes"] = os.path.getsize(out["rom"])
    if WASM.available:
        out["bytecode"] = bench.build_mpy(os.path.join(d, "bytecode"), bench.MPY_CROSS,
                                          "x64", skip=("fast.py", "gyro/attitude_fast.py"))
    return out


def _x86(build):
    if not X86.available:
        pytest.skip("x86-32 tier: %s" % X86.reason)
    return build


@pytest.fixture(scope="module")
def profiles_mpy(build):
    b = _x86(build)
    return bench.profiles(b["session"], b["mpy"], gyro_session=b["session"] + ".gyro")


@pytest.fixture(scope="module")
def profiles_romfs(build):
    b = _x86(build)
    return bench.profiles(b["session"], None, [b["rom"], "--romfs"])


def _ok(p):
    for name in ("calibrate", "heading"):
        assert "error" not in p[name], p[name]["error"]
        assert p[name]["complete"], p[name]
    return p


def test_a_calibrated_board_stays_within_its_heap_budget_from_mpy(profiles_mpy):
    h = _ok(profiles_mpy)["heading"]
    assert h["after"] <= BUDGETS["heading_live_mpy"], h["after"]
    assert h["bytes_per_sample"] == BUDGETS["bytes_per_sample"]


def test_the_gyro_aided_heading_costs_within_its_budget_and_nothing_per_sample(profiles_mpy):
    p = _ok(profiles_mpy)
    g, h = p["gyro"], p["heading"]
    assert "error" not in g and g["complete"], g
    assert g["after"] - h["after"] <= BUDGETS["gyro_extra_mpy"], (g["after"], h["after"])
    assert g["bytes_per_sample"] == BUDGETS["bytes_per_sample"]
    # the filter and the one kernel set in use stay (x86-32 has the emitter: the viper one),
    # its construction left
    assert set(g["modules"]) - set(h["modules"]) == {"gyro", "gyro.attitude",
                                                     "gyro.attitude_fast"}


def test_a_calibrated_board_stays_within_its_heap_budget_from_romfs(profiles_romfs):
    h = _ok(profiles_romfs)["heading"]
    assert h["after"] <= BUDGETS["heading_live_romfs"], h["after"]


def test_the_calibration_machinery_leaves_when_the_session_ends(profiles_mpy):
    p = _ok(profiles_mpy)
    c, h = p["calibrate"], p["heading"]
    assert c["model"] == 10 and c["ended"] is not None
    assert c["saved"] > c["ended"] + 20 * KB  # the machinery was there, and is gone
    assert c["ended"] - h["after"] <= BUDGETS["after_session_slack_mpy"], (c["ended"],
                                                                          h["after"])
    assert set(c["modules"]) == set(h["modules"])  # the same modules as a rebooted board
    assert c["bytes_per_sample"] == BUDGETS["bytes_per_sample"]


def test_the_calibration_program_holds_only_what_calibrating_needs_at_its_solving_peak(build):
    # boards/main.py runs it alone on a board without a calibration: at the solving peak it
    # holds neither the heading line (app, compass, fast, trig, the status line) nor what
    # only boot, a save or the history need, and the peak stays within its budget (make
    # bench: docs/benchmarks.md, calibration program)
    b = _x86(build)
    r = bench.program_profile(b["session"], b["mpy"])
    assert "error" not in r and r["complete"], r
    held = set(r["peak_modules"])
    assert not held & {"app", "appsetup", "compass", "fast", "trig", "kang_tables", "status",
                       "accuracy", "fieldwatch", "detect", "devinit", "boot", "persist",
                       "slots", "calibrate.history", "calibrate.session"}, held
    assert {"calibrate.calibrator", "calibrate.samples", "calibrate.accum",
            "calibrate.program"} <= held, held
    assert r["peak_solving"] <= BUDGETS["program_peak_mpy"], r["peak_solving"]


@pytest.mark.parametrize("kind", ["mpy", "romfs"])
def test_a_first_calibration_completes_within_its_smallest_heap_budget(build, kind):
    b = _x86(build)
    # at the budget and at every KB of the 7 above: the smallest heap is not monotone, so
    # one heap that completes says little of its neighbours (budgets.py)
    net = BUDGETS["min_heap_calibrate_" + kind]
    heap = net + b["session_bytes"] + (b["rom_bytes"] if kind == "romfs" else 0)
    extra = [b["rom"], "--romfs"] if kind == "romfs" else []
    with bench.ProfileRun(b["mpy"] if kind == "mpy" else None, extra) as pr:
        for kb in range((heap + KB - 1) // KB, (heap + KB - 1) // KB + 8):
            r = pr.run(b["session"], "program", heap="%dk" % kb, flags=["--min"],
                       fresh_store=True)
            assert r.get("complete") is True, (kb, r)


def test_the_webassembly_port_allocates_within_budget_for_boot_and_headings(build):
    if not WASM.available:
        pytest.skip("wasm tier: %s" % WASM.reason)
    os.makedirs(os.path.join(build["dir"], "st-wasm"))
    # every name relative to the build folder (what a run allocates grows with its paths)
    bench.stage_benchmark("profiles", build["dir"])
    env = dict(os.environ, MICROPYPATH="bytecode:.:.frozen")
    out = {}
    for profile in ("calibrate", "heading"):  # the first leaves the record the second boots
        p = subprocess.run(WASM.cmd + ["-m", "desktop.benchmarks.profiles",
                                       os.path.basename(build["session"]), "st-wasm", profile],
                           cwd=build["dir"], env=env, capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0, p.stderr[-2000:]
        out[profile] = json.loads(p.stdout.strip().splitlines()[-1])  # (a qstr line before)
    h = out["heading"]
    assert out["calibrate"]["complete"] and h["complete"]
    assert h["after"] <= WASM_HEADING_ALLOCATED, h["after"]
    assert h["after"] - h["boot"] <= 64  # 2000 headings: nothing (a collection is not run)


# importing the app from its sources (a mip install compiles on the board): the parser holds a
# module's docstrings until it is compiled (docs/design.md, memory). 100 KB with the docstrings
# firmware/app.py had; 75 KB once they were comments.
APP_FROM_SOURCE_KB = 80


def test_the_app_compiles_from_its_sources_in_a_small_heap(tmp_path):
    _x86({})
    import shutil
    shutil.copytree(os.path.join(mp.ROOT, "firmware"), str(tmp_path / "firmware"),
                    ignore=shutil.ignore_patterns("__pycache__"))
    p = subprocess.run([mp.X86_32, "-X", "heapsize=%dk" % APP_FROM_SOURCE_KB, "-c",
                        "import firmware.app; print('ok')"], cwd=str(tmp_path),
                       env=dict(os.environ, MICROPYPATH="."), capture_output=True, text=True,
                       timeout=120)
    assert p.stdout.strip() == "ok", p.stderr[-400:]
