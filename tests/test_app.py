"""CompassApp end to end through host_sim: detection, calibration in the background, storage,
heading accuracy after calibration, progress, the solve policy, aging, allocation and parity.

Tolerances (independent of the code's output): the simulated chips carry their datasheet
noise (QMC5883L 2 mG RMS per axis, MPU6050 6.4 mg), which at 60 deg dip is about 0.5 deg of
heading per single sample (2 mG over a 0.25 G horizontal field), so one sample may be off by
~2 deg (4 sigma); the mean of 16 samples must be within 1 deg of the world's true heading. The
fitted hard iron must match the world's to 1 uT (2 % of the field).
"""
import json
import os
import sys

import pytest

from firmware.app import CompassApp, status_line
from firmware.store import CalStore
from firmware.calibration import Calibration
from tests import mp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "scenarios"))
import app_world as W  # noqa: E402
from host_sim import motion  # noqa: E402

SESSION_S = 40                 # a 30 s figure8() period and then some
END_S = 10                     # then still: the session ends once it brings no new direction
MEAN_TOL_CDEG = 100            # mean of 16 samples within 1 deg of the true heading
SINGLE_TOL_CDEG = 300          # any single sample within 3 deg
HARD_IRON_TOL_UT = 1.0
REASONS = ("too_few_samples", "planar", "singular", "low_coverage", "offset_out_of_range",
           "soft_iron_out_of_range", "field_out_of_range", "fit_error_high", "not_better")


class Session:
    def __init__(self, setup, **kw):
        self.b = W.make_sim(setup)
        self.fs = W.MemFs()
        self.store = W.mem_store(self.fs)
        self.app = W.make_app(self.b, store=self.store, **kw)
        self.progress = []      # (t_s, progress dict) once per simulated second
        self.accepts = []       # (t_us, Calibration) in order
        self.collecting = None  # (progress, held samples, coverage) at the session's last step
        self.ended_at_s = None  # when the collector left, once the board lies still
        self.late_accepts = 0   # fits accepted after the board was put down (its last solve)
        self._next = 0
        W.run_until(self.app, self.b, SESSION_S, self._watch)
        self.final = self.app.progress()  # other tests go on stepping the app
        # then the board is put down: no new direction, and the session ends
        W.hold(self.b, 30.0, 0.0, 0.0)
        W.run_until(self.app, self.b, SESSION_S + END_S, self._ended)

    def _ended(self, app):
        if app.accepted > len(self.accepts) + self.late_accepts:
            self.late_accepts += 1
        if app.collector is None and self.ended_at_s is None:
            self.ended_at_s = self.b.clock.now_us / 1e6

    def _watch(self, app):
        now = self.b.clock.now_us
        if app.accepted > len(self.accepts):
            self.accepts.append((now, app.calibration))
        if app.collector is not None:
            self.collecting = (app.progress(), app.calibrator.count, app.calibrator.coverage())
        if now >= self._next:
            self._next += 1000000
            self.progress.append((now // 1000000, app.progress()))


@pytest.fixture(scope="module", params=sorted(W.ALL_SETUPS))
def session(request):
    return Session(request.param)


def ut(app, counts):
    return counts * 100.0 / app.mag.counts_per_gauss


def still_errors(app, b, pose, n=16):
    W.hold(b, *pose)
    for _ in range(3):  # the set latched before the move, and one more
        app.step()
    errs = []
    for _ in range(n):
        assert app.step(), app.status
        errs.append(W.heading_error_cdeg(app, b))
    return errs


def test_board_axis_constants_match_the_breakout_derivation():
    # every breakout the board files name (GY-271, GY-273, GY-87) lying flat, X forward;
    # no accelerometer on a GY-271/273: the GY-521 module lying the same way, as GY-87's
    # (the IMU breakouts, GY-9250 / GY-91 / ICM-20948, have their own maps: test_axes.py)
    from boards.breakouts import breakout
    from boards.esp32 import board as esp32
    from boards.host import board as host
    from boards.rp2040 import board as rp2040
    for board in (esp32, rp2040, host):
        assert {breakout(b)["mag"] for b in ("gy271", "gy273", "gy87")} == {board.MAG_AXES}
        assert board.ACCEL_AXES == breakout("gy87")["accel"]
    # the setups of every other chip: their breakout's maps (host_sim/chips.py DEMOS)
    from host_sim import chips
    for name, (chip, accel) in W.ALL_SETUPS.items():
        b = W.make_sim(name, m=motion.still())
        maps = breakout(chips.demo(chips.board(chip)[0])[2]) if chip not in ("gy87", "gy271") \
            else breakout(chip)
        assert W.axes(b) == (maps["mag"], maps.get("accel", W.ACCEL_AXES)), name


def test_every_setting_of_a_board_file_is_read_by_the_code_that_runs_on_it():
    # a setting nothing reads (the BREAKOUT these files once had) misleads whoever edits it:
    # each upper-case name a board file assigns is read by boards/main.py (firmware/runner.py), the CircuitPython
    # code.py / boot.py, host_sim (the simulated board), desktop/ or the board file itself, as a name,
    # an attribute or a getattr string; tests do not count
    import ast
    import glob
    ROOT = mp.ROOT
    files = sorted(glob.glob(os.path.join(ROOT, "boards", "*", "board.py"))) + [
        os.path.join(ROOT, "boards", "circuitpython", "wiring.py")]
    readers = files + [os.path.join(ROOT, "boards", "main.py"),
                       os.path.join(ROOT, "firmware", "runner.py"),
                       os.path.join(ROOT, "firmware", "runner_program.py"),
                       os.path.join(ROOT, "firmware", "runner_heading.py")] + sorted(
        glob.glob(os.path.join(ROOT, "boards", "circuitpython", "*.py"))) + sorted(
        glob.glob(os.path.join(ROOT, "host_sim", "**", "*.py"), recursive=True)) + sorted(
        glob.glob(os.path.join(ROOT, "desktop", "**", "*.py"), recursive=True))
    read = set()
    for f in readers:
        for node in ast.walk(ast.parse(open(f).read())):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
                read.add(node.id)
            elif isinstance(node, ast.Attribute):
                read.add(node.attr)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                read.add(node.value)
    assert len(files) == 4
    unread = []
    for f in files:
        for node in ast.parse(open(f).read()).body:
            if isinstance(node, ast.Assign):
                for t in node.targets:
                    if isinstance(t, ast.Name) and t.id.isupper() and t.id not in read:
                        unread.append("%s: %s" % (os.path.relpath(f, ROOT), t.id))
    assert unread == []


def test_the_app_detects_the_magnetometer_and_the_accelerometer(session):
    from host_sim import chips
    assert session.app.mag.KIND == chips.board(session.b.chip)[0]
    assert session.app.accel is not None
    assert session.app.load_reason == "missing"  # first run: an empty store


def test_a_figure8_is_calibrated_stored_and_matches_the_world_iron(session):
    app = session.app
    c = app.calibration
    assert app.accepted >= 1 and c.model == 10
    assert app.stored == app.accepted and app.save_errors == 0
    # the store holds that fit, and the dip it measured once the board moved calmly
    stored = Calibration.from_bytes(session.store.load())
    assert stored == c and stored.dip_kang is not None
    for i in range(3):
        assert abs(ut(app, c.offset[i]) - W.HARD_IRON_UT[i]) < HARD_IRON_TOL_UT
    assert app.errors.get("bus_error", 0) == 0 and app.errors.get("timeout", 0) == 0


@pytest.mark.parametrize("pose", W.TILTED_POSES)
def test_tilted_still_headings_after_calibration_are_within_a_degree(session, pose):
    errs = still_errors(session.app, session.b, pose)
    assert abs(sum(errs)) / len(errs) < MEAN_TOL_CDEG, errs
    assert max(abs(e) for e in errs) < SINGLE_TOL_CDEG, errs


def test_restart_with_the_same_store_loads_the_calibration_and_reports_heading_at_once(session):
    pose = (210.0, 15.0, -20.0)
    b = W.make_sim(session.b.chip, m=motion.still(*pose), seed=11)
    store = CalStore("/", fs=session.fs)  # a fresh store object over the same "flash"
    app = W.make_app(b, store=store)
    assert app.load_reason is None
    assert app.calibration == session.app.calibration
    assert app.calibrator is None  # heading-only: nothing to collect
    assert app.calibrate().calibrator.current == app.calibration  # a new fit must beat it
    app.step()  # the chip's first set was measured before the clock started: skip it
    assert app.step() and app.status == "ok"
    assert abs(W.heading_error_cdeg(app, b)) < SINGLE_TOL_CDEG


def test_progress_reports_coverage_samples_model_fit_error_and_refusals(session):
    app = session.app
    prog = session.progress
    first_accept_s = session.accepts[0][0] // 1000000
    before = [p for t, p in prog if t < first_accept_s]
    assert before and all(p["model"] is None and p["fit_error"] is None for p in before)
    reasons = [p["last_reason"] for t, p in prog if p["last_reason"]]
    assert reasons and set(reasons) <= set(REASONS)
    samples = [p["samples"] for t, p in prog if p["collecting"]]
    assert samples == sorted(samples)  # the buffer only grows below its capacity
    cov = [p["coverage"] for t, p in prog if p["collecting"]]
    assert all(0 <= c <= 100 for c in cov) and cov[-1] >= 50
    assert any(p["solving"] for t, p in prog)
    last = session.final
    c = session.accepts[-1][1]
    assert last["model"] == c.model == 10
    assert last["fit_error"] == c.fit_error
    assert last["accepted"] == len(session.accepts)  # kept when the session ended
    p, count, coverage = session.collecting
    assert p["coverage"] == coverage  # the cache is up to date
    assert p["samples"] == count >= samples[-1]


def test_the_calibration_session_ends_once_a_good_fit_is_saved_and_the_board_rests(session):
    # the machinery leaves (firmware/calibrate/session.py): nothing collects, the counters stay. While
    # the figure-8 goes on the session goes on (a later fit may be better)
    app = session.app
    assert session.final["collecting"]
    assert app.calibration.model == 10 and app.calibration.fit_error <= 500
    assert app.stored >= 1 and not app._unsaved
    # within 3 s of quiet + one solve (~2 s at 50 Hz) of being put down
    assert SESSION_S < session.ended_at_s <= SESSION_S + 6, session.ended_at_s
    assert app.collector is None and app.calibrator is None and not app.solving
    assert app.progress()["samples"] == 0 and not app.progress()["collecting"]
    # (the counters stay: every fit accepted, the one a last solve may accept after the
    # board was put down included)
    assert app.accepted == len(session.accepts) + session.late_accepts and app.solves >= 2
    assert session.late_accepts <= 1


def test_worst_stall_is_measured_and_solves_run_in_many_slices(session):
    app = session.app
    assert app.worst_stall_us > 0
    assert app.solves >= 2 and app.slices >= 10 * app.accepted


def test_four_element_fallback_gives_an_early_heading_then_ten_elements_replace_it(session):
    models = [c.model for t, c in session.accepts]
    if session.b.chip == "gy87":
        assert models[-1] == 10  # the 4-element fit may be refused (fit error) on this iron
        return
    assert models[0] == 4 and session.accepts[0][1].samples < 100  # before 10 could run
    assert models[-1] == 10 and session.accepts[-1][0] > session.accepts[0][0]


def test_without_fallback_the_first_calibration_is_the_configured_model():
    s = Session("gy271", fallback=False)
    assert [c.model for t, c in s.accepts][0] == 10


def test_the_calibration_ages_by_measured_time():
    # a stored calibration with a large fit error: aging adds fe * seconds / 60000
    b = W.make_sim("gy271", m=motion.still(10.0, 0.0, 0.0))
    fs = W.MemFs()
    st = W.mem_store(fs)
    fe = 6000
    st.save(Calibration(model=4, offset=(5400, -4200, 3600), field=6000, field_out=6000,
                        fit_error=fe, samples=100, coverage=60).to_bytes())
    app = W.make_app(b, store=CalStore("/", fs=fs))  # fit error > 5 %: a session starts
    t0 = b.clock.now_us
    W.run_until(app, b, 30.5)
    elapsed_s = (b.clock.now_us - t0) // 1000000
    assert elapsed_s == 30
    assert app.calibrator.aged_fit_error() == fe + fe * elapsed_s // 60000


def test_mirror_axis_maps_are_refused_at_construction():
    b = W.make_sim("gy271", m=motion.still())
    with pytest.raises(ValueError, match="mirror"):
        CompassApp(b.bus, mag_axes="x,y,-z", delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)
    with pytest.raises(ValueError, match="rotation"):
        CompassApp(b.bus, accel_axes="x,-y,-z", delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)


def test_the_store_is_bound_to_the_sensor_found():
    b = W.make_sim("gy87", m=motion.still())
    store = CalStore("/", sensor="qmc5883l", range_code=0, fs=W.MemFs())
    app = W.make_app(b, store=store)
    assert (store.sensor, store.range_code) == ("hmc5883l", app.mag.range_code)


def test_run_reports_every_n_steps_or_every_interval_and_the_status_line_reads():
    b = W.make_sim("gy271")
    app = W.make_app(b)
    lines = []
    good = app.run(100, report=lambda a: lines.append(status_line(a)), every=25)
    assert good == 100 and len(lines) == 4
    times = []
    app.run(200, report=lambda a: times.append(b.clock.now_us), every_us=500000)
    assert len(times) >= 7 and all(500000 <= y - x < 600000 for x, y in zip(times, times[1:]))
    W.run_until(app, b, 12)
    line = status_line(app)
    h = app.heading_kang * 3600 // 65536
    assert ("heading %d." % (h // 10)) in line or ("heading %d." % ((h + 1) // 10)) in line
    assert "model 10 fit" in line and "collecting" in line and "samples" in line


def test_the_app_path_allocates_nothing_and_a_ten_element_solve_is_sliced_on_micropython():
    out = json.loads(mp.run(["tests/scenarios/app_alloc.py"], micro=True))
    assert out["instrument_bytes"] == 0
    assert out["model"] == 10 and out["passes"] < 20
    # drivers, correct, axes, heading and the app's bookkeeping: not one byte, frames included
    assert out["app_path_bytes_per_step"] == 0
    # the whole step, Calibrator.add included, frames counted (mem_total): nothing
    assert out["mem_total_bytes_per_step"] == 0
    assert out["calibrator_add_bytes_per_call"] == 0
    assert out["gc_net_bytes"] == 0
    assert out["heap_locked_steps"] == out["steps"]
    # the solve: ~30 slices, none near a 50 Hz sample period (20 ms) on the unix port
    assert out["solve_steps"] >= 20
    assert 0 < out["solve_worst_stall_us"] < 5000


def test_a_session_gives_the_same_calibration_bytes_and_headings_on_both_interpreters():
    lines = mp.json_lines(mp.parity(["tests/scenarios/app_parity.py"]))
    accepted = [ln for ln in lines if ln[0] == "accepted"]
    assert accepted and accepted[-1][2] == 10
    store = [ln for ln in lines if ln[0] == "store"][0]
    # the store holds the last accepted calibration, saved with the dip it measured (payload
    # byte 3, firmware/calibration.py; 0 there means not known)
    fit = accepted[-1][5]
    assert store[2][:6] + store[2][8:] == fit[:6] + fit[8:] and store[2][6:8] != "00"
    poses = [ln for ln in lines if ln[0] == "pose"]
    assert len(poses) == len(W.TILTED_POSES)
    for ln in poses:
        want = (ln[1][0] * 100 + W.DECLINATION_CDEG) * 65536 // 36000
        for h in ln[2]:
            assert abs((h - want + 32768) % 65536 - 32768) < SINGLE_TOL_CDEG * 65536 // 36000
    end = [ln for ln in lines if ln[0] == "end"][0]
    errors = dict(end[7])
    assert errors.get("bus_error") and errors.get("overflow") and errors.get("timeout")
    assert errors.get("interference") and end[6] >= 1  # re-initialised after the reset


# the same session on every other board, on every interpreter: tests/test_boards_tiers.py


def test_the_board_main_runs_on_the_simulated_board_and_boots_with_its_stored_calibration(
        tmp_path):
    # one main.py for every board (boards/main.py); what differs lives in boards/<b>/board.py.
    # No stored calibration: the calibration program alone, a progress line every 0.5 s, a
    # restart once its fit is saved, then the heading from the store
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "40"],
                 micro=False).splitlines()
    assert out[0].startswith("eCompass: calibrating (qmc5883l, accelerometer MPU6050)")
    i = [k for k, ln in enumerate(out) if ln.startswith("restarted at ")][0]
    progress = [ln for ln in out[1:i] if ln.startswith("calibrating: ")]
    t = int(out[i].split()[2])
    assert len(progress) >= 2 * t - 2  # every 0.5 s
    assert "saved and read back" in progress[-1] and "model 10 fit" in progress[-1]
    assert out[i + 1] == "eCompass: qmc5883l, accelerometer MPU6050, stored calibration: loaded"
    status = [ln for ln in out[i + 2:] if ln.startswith("heading ")]
    assert status and all("model 10 fit" in ln and "---.-" not in ln for ln in status)
    assert out[-1] == "stopped at 40 s"
    # reboot, on MicroPython this time: the calibration comes from the store at once
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "2"],
                 micro=True).splitlines()
    assert out[0] == "eCompass: qmc5883l, accelerometer MPU6050, stored calibration: loaded"
    assert "model 10 fit" in out[1]
    # calibrate() at the REPL: the request runs the program once more, then the heading
    (tmp_path / "calibrate.req").write_text("calibrate")
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "40"],
                 micro=True).splitlines()
    assert out[0].startswith("eCompass: calibrating") and any(
        ln.startswith("restarted at ") for ln in out)
    assert not (tmp_path / "calibrate.req").exists()
