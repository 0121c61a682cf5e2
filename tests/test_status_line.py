"""The status line a user watches tells the story: collecting with coverage, solving, saved
(once), calibrated, what to do when a fit is refused, and when the heading is not
tilt-compensated; no "planar" hint early in a correct figure-8."""
import sys

from host_sim import motion

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.app import status_line  # noqa: E402
from firmware.store import CalStore  # noqa: E402

PLANAR_HINT = "rotate about another axis"


def lines(app, b, seconds, every_s=0.5):
    out = []
    t = b.clock.now_us
    while b.clock.now_us < t + seconds * 1000000:
        W.run_until(app, b, (b.clock.now_us + every_s * 1000000) / 1e6)
        out.append(status_line(app))
    return out


def test_a_figure8_reads_collecting_solving_saved_once_then_calibrated_after_reboot():
    fs = W.MemFs()
    b = W.make_sim("gy271", m=motion.figure8(), seed=3)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    ls = lines(app, b, 40)
    assert ls[0].split(" | ")[2].startswith("uncalibrated; collecting")
    assert any("solving" in ln for ln in ls)
    first_cal = next(i for i, ln in enumerate(ls) if "model 10" in ln or "model 4" in ln)
    assert not any(PLANAR_HINT in ln for ln in ls[:first_cal])  # a correct figure-8
    saved = [ln for ln in ls if " | saved | " in ln or ln.endswith(" | saved")]
    assert 1 <= len(saved) <= app.stored and app.stored >= 1
    assert "collecting" in ls[-1] and "(level, no tilt)" not in ls[-1]
    # reboot: the stored calibration is in force, nothing to collect
    b2 = W.make_sim("gy271", m=motion.still(30.0, 10.0, 0.0), seed=4)
    app2 = W.make_app(b2, store=CalStore("/", fs=fs))
    ln = lines(app2, b2, 1)[-1]
    assert "calibrated: model 10" in ln and "collecting" not in ln and "saved" not in ln


def test_a_flat_spin_asks_to_rotate_about_another_axis_once_the_user_stops_adding_directions():
    b = W.make_sim("gy271", m=motion.flat_spin(period_s=8), seed=3)
    app = W.make_app(b)
    ls = lines(app, b, 60)
    assert any(PLANAR_HINT in ln for ln in ls)
    assert not any(PLANAR_HINT in ln for ln in ls[:4])  # not in the first two seconds
    assert all("uncalibrated" in ln for ln in ls)


def test_without_an_accelerometer_the_heading_is_marked_as_not_tilt_compensated():
    b = W.make_sim("gy271", m=motion.figure8(), seed=3)
    app = W.make_app(b, accel=False)
    ln = lines(app, b, 2)[-1]
    assert ln.startswith("heading ") and "(level, no tilt)" in ln.split(" | ")[0]


def test_the_status_line_a_board_prints_allocates_64_bytes_at_most_in_every_state():
    # boards/main.py writes status_view(app): the line in firmware/status.py's own buffer,
    # in each state tests/scenarios/status_alloc.py builds (collecting, solving, calibrated,
    # interference, no_memory, the app that did not fit, a jump, a location, the gyro on the
    # field and holding). A call allocates the memoryview (16 bytes on the
    # 32-bit build); one call frame over 11 words, which MicroPython takes from the heap
    # (py/objfun.c VM_MAX_STATE_ON_STACK), is 68 bytes or more and fails the bound. It was
    # ~2 KB when the line was joined from strings and app.__dict__ was copied, then 320 B
    # with such frames (accuracy.level's ten parameters, the line's own).
    import json
    from tests import mp
    t = mp.TIERS["x86-32"]
    if not t.available:
        import pytest
        pytest.skip("x86-32 tier: %s" % t.reason)
    out = json.loads(mp.run(["tests/scenarios/status_alloc.py"], "x86-32",
                            heap="4M").strip().splitlines()[-1])
    view, lines = out["view"], out["lines"]
    # each state is the one named (a line that changed shape would measure another)
    marks = {"collecting": "; collecting ", "solving": " | solving ",
             "calibrated": "calibrated: model 10", "no_memory_load": "not loaded: out of memory",
             "no_memory_calibrate": "no room to calibrate beside the heading",
             "jump": " | jump: field ",
             "app_did_not_fit": "the app did not fit", "location": " deg (model)",
             "location_no_date": "location: no date", "gyro_on_field": "gyro: on field",
             "gyro_held": "| gyro held |", "gyro_held_too_long": "(too long)"}
    assert set(view) == set(marks) and all(b <= 64 for b in view.values()), view
    for state, mark in marks.items():
        assert mark in lines[state], (state, lines[state])
    assert "| interference |" in lines["calibrated"]
    assert lines["gyro_on_field"].endswith("accuracy 3 high")
