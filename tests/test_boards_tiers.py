"""The app on every simulated board, on every interpreter: tests/scenarios/app_boards_parity.py
(app_parity.py's session with its faults, on each board of app_world.ALL_SETUPS and a GY-271
beside an MPU-6500, one process per interpreter) prints the same bits on CPython, the unix
port, the WebAssembly port and the 32-bit x86 port with its native kernels (firmware/fast.py)
and without (fast=False): every status change, a digest of every heading, every accepted
calibration's bytes, the still poses' headings, the stored record and the counters. A tier
that cannot run here skips with its reason (tests/mp.py). The CPython run is also held to
what the session must give."""
import functools
import os
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests import mp
from tests.scenarios import app_world as W
# the qemu firmware's single-precision floats round the simulator's registers otherwise
from tests.test_tiers import ARM_FLOAT_XFAIL

SCRIPT = "tests/scenarios/app_boards_parity.py"
# the scenario's sessions: every board, then the gyro-aided heading on a board of each gyroscope
# driver (the MPU-9250's and the MPU-6500's reads are the MPU6050's)
BOARDS = sorted(W.ALL_SETUPS) + sorted(W.PARITY_SETUPS)
GYRO = ["gy271/gyro", "icm20948/gyro"]
SESSIONS = BOARDS + GYRO
SINGLE_TOL_CDEG = 300  # a still pose's every heading within 3 deg (tests/test_app.py's bound)
# (name, tier, plain): "plain" runs CompassApp(fast=False), the plain kernels where the port has
# the native ones; the others take what the port has (firmware/compat.py kernels())
RUNS = (("cpython", "cpython", False), ("unix", "unix", False), ("wasm", "wasm", False),
        ("x86-32", "x86-32", False), ("x86-32-plain", "x86-32", True),
        ("arm", "arm", False))
# the runs with native kernels where the tier has the emitter
NATIVE = ("unix", "x86-32", "arm")


def _argv(plain):
    return [SCRIPT, "plain"] if plain else [SCRIPT]


@functools.lru_cache(maxsize=None)
def _outputs():
    """{run name: stdout or the AssertionError's text}; the available tiers run two at a
    time (each is one process: 5 s of CPU on CPython to 25 s on the WebAssembly port)."""
    todo = [(n, t, p) for n, t, p in RUNS if mp.TIERS[t].available]

    def one(run):
        name, tier, plain = run
        try:
            return name, mp.run(_argv(plain), tier, timeout=900)
        except AssertionError as e:
            return name, e
    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        return dict(pool.map(one, todo))


def _output(name):
    out = _outputs()[name]
    if isinstance(out, AssertionError):
        raise out
    return out


def _split(out):
    """(lines without the "kernels" lines, {board: kernels fast flag})."""
    lines, kernels = [], {}
    for ln in out.splitlines():
        if ln.startswith('["kernels"'):
            _, board, fast = mp.json_lines(ln)[0]
            kernels[board] = fast
        else:
            lines.append(ln)
    return lines, kernels


def _first_difference(want, got):
    board = None
    for i, (a, b) in enumerate(zip(want, got)):
        if a.startswith('["board"'):
            board = mp.json_lines(a)[0][1]
        if a != b:
            return "board %s, line %d:\n  cpython: %s\n  this:    %s" % (board, i + 1, a, b)
    return "lengths differ: %d lines against %d" % (len(want), len(got))


def _cases():
    for name, tier, plain in RUNS[1:]:
        marks = [pytest.mark.xfail(strict=False, reason=ARM_FLOAT_XFAIL)] if tier == "arm" else []
        yield pytest.param(name, tier, plain, marks=marks, id=name)


@pytest.mark.parametrize("name,tier,plain", list(_cases()))
def test_every_board_gives_cpythons_bits(name, tier, plain):
    if not mp.TIERS[tier].available:
        pytest.skip("%s tier skipped: %s" % (tier, mp.TIERS[tier].reason))
    want, want_kernels = _split(_output("cpython"))
    got, kernels = _split(_output(name))
    assert got == want, _first_difference(want, got)
    # the run took the path it names: the native kernels where the port has the emitter
    assert sorted(kernels) == sorted(SESSIONS)
    native = tier in NATIVE and not plain
    assert set(kernels.values()) == {native} and set(want_kernels.values()) == {False}


def _boards(out):
    boards = {}
    for ln in mp.json_lines(out):
        if ln[0] == "board":
            cur = boards[ln[1]] = []
        cur.append(ln)
    return boards


def test_the_scenario_runs_every_board_and_a_board_of_each_gyroscope():
    assert list(_boards(_output("cpython"))) == SESSIONS


@pytest.mark.parametrize("session", SESSIONS)
def test_the_session_on_each_board_calibrates_and_keeps_the_heading(session):
    # what the compared bits must say (CPython's run): a 10-element fit in force and stored,
    # the still poses within 3 deg, every injected fault counted once
    from host_sim import chips
    lines = _boards(_output("cpython"))[session]
    setup, gyro = session.split("/")[0], session.endswith("/gyro")
    # the accelerometer found: the board's IMU, else its module (a GY-521's MPU6050)
    assert lines[0][3] == {"gy9250": "MPU-9250", "icm20948": "ICM-20948",
                           "gy271+mpu6500": "MPU-6500"}.get(setup, "MPU6050")
    accepted = [ln for ln in lines if ln[0] == "accepted"]
    assert accepted and accepted[-1][3] == 10
    fit = [ln for ln in lines if ln[0] == "fit"][0]
    assert fit[1] == 10 and fit[5] == accepted[-1][7]
    # the store holds it, with the dip it measured (payload byte 3, firmware/calibration.py)
    seq, store = [ln for ln in lines if ln[0] == "store"][0][1:]
    assert store[:6] + store[8:] == fit[5][:6] + fit[5][8:] and store[6:8] != "00"
    seconds = [ln for ln in lines if ln[0] == "t"]
    assert len(seconds) == 41 and len({ln[3] for ln in seconds}) > 35   # a digest per second
    # the gyro's filter: its bias and uncertainty on each line, the status line says so
    assert all(len(ln) == (9 if gyro else 6) for ln in seconds)
    assert all(("gyro:" in ln[5]) == gyro for ln in seconds)
    poses = [ln for ln in lines if ln[0] == "pose"]
    assert len(poses) == len(W.TILTED_POSES)
    for ln in poses:
        want = (ln[1][0] * 100 + W.DECLINATION_CDEG) * 65536 // 36000
        assert ln[3] == "ok"
        for h in ln[2]:
            assert abs((h - want + 32768) % 65536 - 32768) < SINGLE_TOL_CDEG * 65536 // 36000
    end = [ln for ln in lines if ln[0] == "end"][0]
    errors = dict(end[7])
    assert seq >= end[5] >= 1                  # the record's sequence number, the saves
    assert errors.get("bus_error") == 3 and errors.get("overflow") == 1
    assert errors.get("interference")   # the magnet from 22 s to 25 s
    chip = (W.ALL_SETUPS.get(setup) or W.PARITY_SETUPS[setup])[0]
    if chips.mag(chips.board(chip)[0])["standby"] is None:
        # the MMC5603 is commanded per measurement: its reset costs no sample
        assert "timeout" not in errors and end[6] == 0
    else:
        assert errors.get("timeout") and end[6] >= 1  # re-initialised after the reset
