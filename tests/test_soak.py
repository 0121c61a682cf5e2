"""A short run of the fault campaign (python -m host_sim soak; make soak runs the long one),
every fault class included, magnets too: step() never raises, no stored calibration is lost
or replaced by a worse one, no heading is "ok" while wrong by more than the documented
accuracy (docs/faults.md: 5 deg), every fault that needs detecting is detected within a
second, and the fault-free sessions run alongside raise no false alarm. Beside it: the session
of make soak that once held a wrong heading "ok" (replayed alone), the goals make soak exits 1
on, and the cost of the jump limits (a steady turn that stays "ok")."""
import subprocess
import sys

import pytest

from firmware.store import CalStore
from host_sim.boards import make_board
from desktop import soak
from desktop.memfs import MemFs
from tests.known_limits import JUMP_NOISE, expect

NEED_NO_DETECTION = {"stall", "accel_absent"}  # a pause; a missing part found at boot


def test_a_short_fault_campaign_has_no_exception_no_loss_and_no_wrong_but_ok():
    st = soak.campaign(sessions=100, seconds=40, seed=5)
    assert st["steps"] > 100000 and st["total_faults"] >= 200
    assert set(st["faults"]) == set(soak.CLASSES)           # every class drawn...
    assert min(st["faults"].values()) >= 8                  # ...several times
    assert st["exceptions"] == 0
    assert st["lost"] == 0
    assert st["wrong_but_ok"] == 0 and st["wrong_by_class"] == {}
    for cls, d in st["detect_ms"].items():
        assert d["max_ms"] < 1000, (cls, d)  # every detected fault within a second
    # every magnet (and every other class but those two) was seen while it lasted
    assert st["detect_ms"]["magnet"]["n"] == st["faults"]["magnet"]
    # (a fault injected just before a reboot that re-initialised the chip is not missed)
    for cls in set(soak.CLASSES) - NEED_NO_DETECTION - {"range"}:
        n = st["detect_ms"][cls]["n"] + st["reboot_cleared"].get(cls, 0)
        assert n == st["faults"][cls], cls
    assert sum(st["reboot_cleared"].values()) <= 2
    # the fault-free sessions: essentially all ok (false alarms), and none wrong
    c = st["clean"]
    assert c["sessions"] == 10 and c["steps"] > 9000
    assert c["not_ok"] <= c["steps"] // 1000 and c["wrong_but_ok"] == 0


def test_make_soaks_session_where_a_magnet_moved_in_under_4_deg_a_step_is_never_ok_and_wrong():
    # make soak (seed 1, 600 sessions), session 554: a 16 uT magnet across the horizontal
    # field moves in over 0.2 s on a GY-271 at 50 Hz, turning the heading by 2.5, 3.9 and
    # 3.8 deg a step while |B| and the dip stay within their limits; the one-step jump limit
    # (4 deg) let the second and third through as "ok", 6.4 and 9.9 deg off. --only replays
    # the session as the whole campaign runs it.
    st = soak.campaign(sessions=600, seconds=60, seed=1, only=[554])
    assert st["steps"] > 2900 and st["clean"]["steps"] == 0
    assert st["faults"]["magnet"] == 1 and st["detect_ms"]["magnet"]["n"] == 1
    assert st["wrong_but_ok"] == 0 and st["wrong_by_class"] == {}
    assert st["goals_failed"] == []


def test_a_steady_turn_at_40_deg_per_s_stays_ok_on_both_boards():
    # the jump limits' cost (docs/faults.md, fast turns): a board turning steadily at 40 deg/s
    # while waving its tilt, fault-free, says "ok" on every sample at the GY-271's 50 Hz and
    # at the GY-87's 15 Hz (two steps there allow 4 + 25 x 0.133 = 7.3 deg; 40 deg/s is 5.3)
    for setup, accel in soak.SETUPS:
        cal, kind, rng = soak.good_calibration(setup, accel)
        b = make_board(setup, world=soak.world(soak.Turning(10.0, 40.0, 1.0)), seed=77,
                       accel=accel)
        fs = MemFs()
        CalStore("/", sensor=kind, range_code=rng, fs=fs).save(cal.to_bytes())
        app = soak.app_on(b, CalStore("/", fs=fs))
        seen = {}
        while b.clock.now_us < 20000000:
            app.step()
            if b.clock.now_us > 2000000:
                seen[app.status] = seen.get(app.status, 0) + 1
                assert soak.err_deg(app, b) < 2.5
        assert list(seen) == ["ok"] and seen["ok"] > 250, (setup, seen)


def test_each_goal_missed_is_named_and_the_command_exits_1(monkeypatch, capsys):
    good = soak.campaign(sessions=1, seconds=5, seed=1, clean=1)
    assert good["goals_failed"] == [] and soak.failed_goals(good) == []
    bad = dict(good, exceptions=1, lost=1, wrong_but_ok=2, wrong_by_class={"magnet": 2},
               clean=dict(good["clean"], steps=1000, not_ok=2, wrong_but_ok=1),
               faults={"magnet": 3}, detect_ms={"magnet": {"n": 2, "median_ms": 60.0,
                                                            "max_ms": 1200.0}})
    got = soak.failed_goals(bad)
    assert [g.split(" (")[0] for g in got] == [
        "exceptions out of step() 1", "calibrations lost 1", "wrong-but-ok 2",
        "fault-free wrong-but-ok 1", "fault-free not ok 2 of 1000 samples",
        "magnet detected after 1200.0 ms", "magnet detected 2 of 3"]
    assert soak.failed_goals(dict(bad, gyro=True)) == got[:5]  # "gyro held" vouches instead
    bad["goals_failed"] = got
    monkeypatch.setattr(soak, "campaign", lambda *a, **k: bad)
    assert soak.main(["--sessions", "1"]) == 1
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("goals: FAILED: exceptions out of step() 1")
    assert last.endswith("magnet detected 2 of 3 (goal all)")
    monkeypatch.setattr(soak, "campaign", lambda *a, **k: good)
    assert soak.main(["--sessions", "1"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "goals: all met"


def test_soak_only_names_the_campaigns_sessions():
    p = subprocess.run([sys.executable, "-m", "host_sim", "soak", "--sessions", "10",
                        "--only", "12"], capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "0..11" in p.stderr


def test_soak_bad_arguments_are_one_line_and_exit_2():
    p = subprocess.run([sys.executable, "-m", "host_sim", "soak", "--sessions", "0"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "--sessions 0" in p.stderr


def test_with_the_gyro_aided_heading_no_exception_no_loss_and_nothing_wrong_presented_good():
    # every app runs use_gyro() where an MPU6050 answers: "gyro held" presents the heading as
    # good as "ok" does, so a held heading off by > 5 deg counts as wrong-but-ok too
    st = soak.campaign(sessions=60, seconds=40, seed=6, gyro=True)
    assert st["gyro"] and st["steps"] > 60000 and set(st["faults"]) == set(soak.CLASSES)
    assert st["exceptions"] == 0 and st["lost"] == 0
    assert st["wrong_but_ok"] == 0 and st["wrong_by_class"] == {}
    c = st["clean"]
    assert c["steps"] > 5000 and c["not_ok"] <= c["steps"] // 1000 and c["wrong_but_ok"] == 0


def test_the_campaign_on_the_akm_boards_has_no_exception_no_loss_and_no_wrong_but_ok():
    # the GY-9250 (AK8963) and the ICM-20948 (AK09916), every fault class but the absent
    # accelerometer (its own chip there): as above, and the fault-free sessions' false alarms
    # within what docs/faults.md states for them (heading noise at 100 Hz and 0.15 uT/LSB)
    st = soak.campaign(sessions=40, seconds=40, seed=5, setups=soak.AKM_SETUPS)
    assert st["steps"] > 100000 and set(st["faults"]) >= set(soak.CLASSES) - {"accel_absent"}
    assert st["exceptions"] == 0 and st["lost"] == 0
    assert st["wrong_but_ok"] == 0 and st["wrong_by_class"] == {}
    for cls, d in st["detect_ms"].items():
        assert cls in NEED_NO_DETECTION or d["max_ms"] < 1000, (cls, d)
    for cls in set(st["faults"]) - NEED_NO_DETECTION - {"range"}:
        n = st["detect_ms"][cls]["n"] + st["reboot_cleared"].get(cls, 0)
        assert n == st["faults"][cls], cls
    c = st["clean"]
    assert c["steps"] > 9000 and c["wrong_but_ok"] == 0
    # (the fixed jump limits against these boards' 100 Hz noise: docs/faults.md, known limits)
    assert c["not_ok"] <= 20 * c["steps"] // 1000, c


@pytest.mark.parametrize("setup", soak.CHIP_SETUPS, ids=[s for s, _ in soak.CHIP_SETUPS])
def test_a_short_campaign_on_each_other_chip_has_no_exception_no_loss_and_no_wrong_but_ok(
        setup):
    # the HMC5883L, QMC5883P, LIS3MDL, LIS2MDL and MMC5603 modules with a GY-521, and the
    # GY-9250 (AK8963) and the ICM-20948 (AK09916), alone: every fault class (the range glitch
    # to each chip's own range or rate register), the goals of make soak
    st = soak.campaign(sessions=8, seconds=30, seed=5, setups=(setup,))
    assert st["total_faults"] >= 12 and len(st["faults"]) >= 8
    assert st["exceptions"] == 0 and st["lost"] == 0
    assert st["wrong_but_ok"] == 0 and st["wrong_by_class"] == {}
    # the MMC5603 is commanded per measurement: after a brown-out it measures as before,
    # nothing to detect (tests/test_reliability.py)
    quiet = {"mag_reset"} if setup[0] == "mmc5603" else set()
    for cls, d in st["detect_ms"].items():
        assert d["max_ms"] < 1000, (cls, d)
    for cls in set(st["faults"]) - NEED_NO_DETECTION - {"range"} - quiet:
        n = st["detect_ms"][cls]["n"] + st["reboot_cleared"].get(cls, 0)
        assert n == st["faults"][cls], cls
    c = st["clean"]
    assert c["sessions"] == 2 and c["steps"] > 800 and c["wrong_but_ok"] == 0
    # the AKM boards at 100 Hz: false jump alarms within the 2 % docs/faults.md states
    assert c["not_ok"] <= 20 * c["steps"] // 1000, c
    expect(c["not_ok"] <= c["steps"] // 1000, setup[0],
           {"gy9250": JUMP_NOISE, "icm20948": JUMP_NOISE}, c)


@pytest.mark.xfail(strict=True, reason="docs/chips.md, known limits: fault-free LIS3MDL and "
                   "LIS2MDL sessions at 20 Hz say 'heading jumped' with the heading within "
                   "1.5 deg (85 and 136 of 1200 samples on these two streams)")
@pytest.mark.parametrize("setup", [("lis3mdl", True), ("lis2mdl", True)], ids=["lis3mdl",
                                                                             "lis2mdl"])
def test_the_st_chips_fault_free_turning_raises_no_false_alarm(setup):
    # the campaign above's fault-free streams 6 and 7 of seed 5 (turning 18 deg/s and
    # tilting): no fault, so every non-ok sample is a false alarm
    st = soak.campaign(sessions=6, seconds=30, seed=5, setups=(setup,), only=[6, 7])
    c = st["clean"]
    assert c["steps"] == 1200 and c["wrong_but_ok"] == 0
    assert c["not_ok"] <= c["steps"] // 1000, c
