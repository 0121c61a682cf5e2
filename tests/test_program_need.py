"""The heap figure the status line quotes for the calibration program (firmware.status
PROGRAM_NEED_KB) agrees with the figure make bench measured (docs/benchmarks.md, "Every heap:
boards/main.py swept"): not below it (the board would be sent to a program that cannot finish) and
not more than one 4 KB step above it (a user with enough heap would be told to go elsewhere)."""
import os
import re

from firmware.status import PROGRAM_NEED_KB

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def measured_first_calibration_kb(text):
    """The largest 'first calibration on the board' heap of the swept installs, in KB."""
    rows = re.findall(r"^\| (\.mpy files[^|]*|what mip installs) \| ([0-9.]+) KB \|", text, re.M)
    assert rows, "docs/benchmarks.md has no 'boards/main.py swept' rows"
    return max(float(kb) for _, kb in rows)


def test_program_need_matches_the_bench():
    with open(os.path.join(ROOT, "docs", "benchmarks.md")) as f:
        kb = measured_first_calibration_kb(f.read())
    assert kb <= PROGRAM_NEED_KB <= kb + 4, (
        "firmware/status.py PROGRAM_NEED_KB = %d, but make bench measured a first calibration "
        "from %.1f KB (docs/benchmarks.md): set it to that figure rounded up" % (PROGRAM_NEED_KB, kb))


def test_the_reader_finds_a_drifted_figure():
    page = "| .mpy files (make deploy) | 144.0 KB | RP2040 | 92.0 KB |\n" \
           "| what mip installs | 124.0 KB | RP2040 | 92.0 KB |\n"
    kb = measured_first_calibration_kb(page)
    assert kb == 144.0 and not kb <= PROGRAM_NEED_KB


def test_a_board_short_of_heap_is_told_what_needs_less(tmp_path):
    """From .mpy files at 96 KB (an ESP32's ~110 KB less the port's own), the program says its
    figure and points at what needs less heap than .mpy files: a frozen or ROMFS build."""
    import pytest
    from desktop import bench
    from tests import mp
    if not mp.TIERS["x86-32"].available:
        pytest.skip("x86-32 tier: %s" % mp.TIERS["x86-32"].reason)
    session = str(tmp_path / "session.bin")
    bench.write_session(session, smoke=False)
    install = bench.board_install(str(tmp_path / "mpy"), "mpy")
    store = tmp_path / "store"
    store.mkdir()
    r = bench.board_run(install, session, 96, str(store))
    assert not r["traceback"], r["stderr"]
    said = [ln for ln in r["lines"] if "calibration program" in ln and "KB of heap" in ln]
    assert said, r["lines"][:3]
    assert "~%d KB" % PROGRAM_NEED_KB in said[0] and "ROMFS build" in said[0], said[0]
    assert "use .mpy files" not in said[0], said[0]
