"""The mounting check (firmware/calibrate/mounting.py's pairs, firmware/calibrate/mountcheck.py's verdict): a wrong
MAG_AXES is found and the right one named after a calibration dance, a right one never raises
it, the integer bounds hold, the same verdicts on CPython and MicroPython, its heap.

The simulated sessions (desktop/mounting.py Session) run CompassApp through a 40 s
figure-8 (host_sim.motion.figure8, the dance of tests/test_app.py) on a board whose
magnetometer is mounted as asked while MAG_AXES stays the boards' usual "x,-y,-z"; every
calibration the app accepts is checked as the board checks it. Bounds (independent of the
code's output): the right setting's spread must stay within STEADY (the dip's sine steady to
0.10 RMS) and every wrong one's above UNSTEADY (0.20); the figures docs/calibration.md quotes
(right <= 0.06, wrong >= 0.27) are asserted here too.
"""
import json
import os
import subprocess
from array import array

import pytest
from hypothesis import given, settings, strategies as st

from firmware.calibrate import mountcheck
from firmware.axes import AxisMap
from firmware.calibration import Calibration
from firmware.calibrate.mounting import BINS, WIDTH, Pairs, _bin
from host_sim import motion
from desktop import bench, mounting as M
from tests import intcheck, mp

RIGHT_MAX_Q10 = 62        # 0.06: docs/calibration.md's "right setting" figure
WRONG_MIN_Q10 = 277       # 0.27: ... and its "wrong setting" figure
FOUND_BY_S = 10          # docs/calibration.md: each wrong rotation first found within 10 s
SOAK_SESSIONS = 60        # make soak runs 600 (python -m desktop.mounting)
HEAP_BUDGET = 2048        # bytes the session holds for the check (the goal)


# --- the rotations and the bins ---------------------------------------------------------------
@pytest.mark.parametrize("mount", M.rotations())
def test_the_24_candidates_are_the_24_rotations_named_after_the_map_in_use(mount):
    mm = AxisMap(M.mag_axes(mount)).m
    specs = [mountcheck._spec(mm, k) for k in range(24)]
    assert specs[0] == M.mag_axes(mount)
    assert len(set(specs)) == 24
    assert all(AxisMap(s).det == 1 for s in specs)


def test_the_mount_helpers_give_the_boards_own_maps():
    assert M.mag_axes(M.MOUNT) == "x,-y,-z" and M.accel_axes(M.MOUNT) == "-x,y,z"
    assert len(set(M.rotations())) == 24


def test_the_bins_split_the_directions_of_gravity_into_24():
    seen = set()
    for face in range(3):
        for sgn in (1, -1):
            for s1 in (1, -1):
                for s2 in (1, -1):
                    v = [0, 0, 0]
                    v[face] = sgn * 16000
                    v[(face + 1) % 3] = s1 * 9000
                    v[(face + 2) % 3] = s2 * 7000
                    seen.add(_bin(v))
    assert seen == set(range(BINS))


# --- the pairs ----------------------------------------------------------------------------------
def _acc(x, y, z):
    return array("h", (x, y, z))


def test_a_pair_is_taken_only_when_the_accelerometer_is_still_and_reads_one_g():
    p = Pairs(16384, 20000)
    raw = _acc(100, 200, 300)
    assert not p.feed(raw, _acc(0, 0, 16384))       # the first step: no previous sample
    assert p.feed(raw, _acc(0, 0, 16384))           # still, 1 g
    assert p.count == 1
    assert not p.feed(raw, _acc(0, 0, 16400))       # the same bin, not stiller (moved 16)
    assert not p.feed(raw, _acc(0, 15000, 6000))    # moved 1.2 g in one step: a fast turn
    assert p.feed(raw, _acc(0, 15000, 6000))        # still there: another bin takes it
    assert p.count == 2
    for a in (_acc(0, 0, 19000), _acc(0, 0, 19000)):  # 1.16 g: linear acceleration
        assert not p.feed(raw, a)
    assert not p.feed(raw, _acc(0, 0, 14000)) and not p.feed(raw, _acc(0, 0, 14000))  # 0.85 g


def test_a_bin_keeps_the_stillest_pair_it_was_offered():
    p = Pairs(16384, 20000)
    p.feed(_acc(1, 1, 1), _acc(0, 0, 15800))
    assert p.feed(_acc(1, 1, 1), _acc(0, 500, 16384))      # moved a little: taken
    assert p.feed(_acc(2, 2, 2), _acc(0, 510, 16384))      # moved less: replaces it
    assert not p.feed(_acc(3, 3, 3), _acc(0, 700, 16384))  # moved more: kept out
    b = WIDTH * _bin((0, 510, 16384))
    # score: moved 0 since the last step, |a|^2 off 1 g^2 by 31^2 (on a >> 4), >> 4
    assert list(p.data[b:b + 7]) == [2, 2, 2, 0, 510, 16384, 961 >> 4] and p.count == 1
    assert sum(1 for i in range(BINS) if p.data[WIDTH * i + 6] == -1) == BINS - 1
    # as still, nearer 1 g: the hand's acceleration less likely in it
    assert not p.feed(_acc(4, 4, 4), _acc(0, 200, 16384))  # moved: not stiller
    assert p.feed(_acc(5, 5, 5), _acc(0, 200, 16384))      # still again, 1.0001 g: taken
    assert not p.feed(_acc(6, 6, 6), _acc(0, 200, 16800))  # moved and 2.5 % off 1 g
    assert not p.feed(_acc(6, 6, 6), _acc(0, 200, 16800))  # still, but further off 1 g
    assert list(p.data[b:b + 7]) == [5, 5, 5, 0, 200, 16384, 144 >> 4] and p.count == 1


def test_the_pairs_refuse_options_naming_the_argument_and_its_unit():
    for args in ((16384.0,), (100,), (16384, 0), (16384, 20000.0)):
        with pytest.raises(ValueError, match=r"counts_per_g=.*counts per g.*period_us=.* us"):
            Pairs(*args)


# --- simulated sessions -------------------------------------------------------------------------
@pytest.mark.parametrize("chip,accel", M.BOARDS, ids=[c for c, _ in M.BOARDS])
def test_every_wrong_magnetometer_rotation_is_found_and_the_right_one_named(chip, accel):
    found = []
    for mount in M.rotations():
        s = M.Session(chip, accel, mount=mount)
        right = M.mag_axes(mount)
        v, axes = s.verdict
        last = s.checks[-1]
        assert last[0] <= M.SECONDS
        if right == M.MAG_AXES:
            assert v == mountcheck.OK and last[3] <= RIGHT_MAX_Q10, s.checks
        else:
            assert (v, axes) == (mountcheck.WRONG, right), (mount, s.checks)
            assert last[3] >= WRONG_MIN_Q10 and last[4] <= RIGHT_MAX_Q10, (mount, s.checks)
            first = min(c[0] for c in s.checks if c[1:3] == (mountcheck.WRONG, right))
            assert first <= FOUND_BY_S, (mount, s.checks)
            found.append(mount)
        # no check of the session named another mapping than the right one
        assert all(c[2] == right for c in s.checks if c[1] in (mountcheck.OK, mountcheck.WRONG))
    assert len(found) == 23


# the other chips' boards (host_sim/chips.py BOARDS): each chip mounted every way its
# handedness allows (a mirror for the LIS2MDL, rotations for the rest) against the board's
# accelerometer, with the board's own MAG_AXES (boards/breakouts.py); sessions of
# CHIP_SECONDS, each wrong mounting named within FOUND_BY_S all the same
CHIP_BOARDS = ("lis3mdl", "lis2mdl", "mmc5603", "gy9250", "icm20948")
CHIP_SECONDS = 12


def mountings(board):
    """The 24 mountings of `board`'s magnetometer of its handedness, its own first."""
    from host_sim import chips
    kind, _, _, _, own = chips.board(board)
    rots = M.rotations()
    if chips.mag(kind)["mirror"]:
        rots = [(a, b, -c) for a, b, c in rots]  # each rotation followed by z turned over
    assert own in rots
    return [own] + [m for m in rots if m != own]


@pytest.mark.parametrize("board", CHIP_BOARDS)
def test_every_wrong_mounting_of_each_chip_is_found_with_its_handedness(board):
    from boards.breakouts import breakout
    from host_sim import chips
    kind, imu, _, _, own = chips.board(board)
    given = M.mag_axes(own)
    assert given == breakout(chips.demo(kind)[2])["mag"]
    det = -1 if chips.mag(kind)["mirror"] else 1
    found = []
    for mount in mountings(board):
        s = M.Session(board, None if imu else True, mount=mount, mag_axes=given,
                      seconds=CHIP_SECONDS)
        right = M.mag_axes(mount)
        assert AxisMap(right).det == det
        v, axes = s.verdict
        if mount == own:
            assert v == mountcheck.OK and s.checks[-1][3] <= RIGHT_MAX_Q10, s.checks
        else:
            assert (v, axes) == (mountcheck.WRONG, right), (mount, s.checks)
            first = min(c[0] for c in s.checks if c[1:3] == (mountcheck.WRONG, right))
            assert first <= FOUND_BY_S, (mount, s.checks)
            found.append(mount)
        assert all(c[2] == right for c in s.checks if c[1] in (mountcheck.OK, mountcheck.WRONG))
    assert len(found) == 23
    # and a map of the other handedness is refused on this chip's board at construction
    other = M.mag_axes((own[0], own[1], -own[2]))
    with pytest.raises(ValueError, match="rotation" if det == -1 else "mirror"):
        M.Session(board, None if imu else True, mag_axes=other, seconds=0)


def test_no_false_alarm_over_a_seeded_soak_of_right_settings_on_rough_boards():
    st = M.soak(SOAK_SESSIONS, seed=1)
    assert st["false_alarms"] == 0, st["alarms"]
    assert st["checks"] >= SOAK_SESSIONS
    # nearly every session ends confirming its setting; the others had too little spread
    assert st["last"].get(mountcheck.OK, 0) >= SOAK_SESSIONS - 3, st["last"]


def test_the_soak_command_names_its_goal_and_exits_1_on_a_false_alarm(monkeypatch, capsys):
    st = {"sessions": 1, "seed": 1, "seconds": 40, "checks": 2, "false_alarms": 0, "alarms": [],
          "last": {"ok": 1}, "board": {"ok": 1}, "worst_sigma_q10": 40}
    monkeypatch.setattr(M, "soak", lambda *a: st)
    assert M.main(["--sessions", "1"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "goal: no false alarm: met"
    st.update(false_alarms=1, alarms=[[100003, "qmc5883l", 12.5, mountcheck.WRONG, "y,x,-z"]])
    assert M.main(["--sessions", "1"]) == 1
    last = capsys.readouterr().out.splitlines()[-1]
    assert last == "goal: no false alarm: FAILED, 1 (100003 qmc5883l 12.5 %s)" % mountcheck.WRONG


def test_wrong_settings_on_random_rough_boards_and_worlds_are_found():
    for i in range(12):
        s = M.random_session(7 * 100003 + i, wrong=True, rough=True)
        assert s.verdict == (mountcheck.WRONG, s.right), (i, s.checks)


def _world(m, magnet=False):
    w = M.World(field_ut=50.0, inclination_deg=60.0, declination_deg=4.0,
                hard_iron_ut=(45.0, -35.0, 30.0),
                soft_iron=((1.18, 0.09, -0.06), (0.09, 0.88, 0.07), (-0.06, 0.07, 1.04)),
                motion=m)
    if magnet:  # tests/scenarios/app_parity.py's magnet, held through the middle of the dance
        w.add_magnet((0.0, 90.0, 40.0), 12.0, 25.0, ramp_s=0.3, frame="sensor")
    return w


def test_a_flat_spin_or_the_soak_campaign_turning_says_not_enough_spread_never_wrong():
    # the app accepts no fit from these motions (planar data), so each session's pairs are
    # checked with the calibration a figure-8 on the same board gave
    from desktop.soak import Turning
    for mount in (M.MOUNT, (2, 1, -3)):
        cal = M.Session("qmc5883l", True, mount=mount, world=_world(motion.figure8())
                        ).app.calibration
        for m in (motion.flat_spin(period_s=8.0), Turning(0.0, 10.0, 0.3)):
            s = M.Session("qmc5883l", True, mount=mount, world=_world(m))
            r = mountcheck.check(s.pairs, cal, M.MAG_AXES, M.ACCEL_AXES)
            assert r[0] == mountcheck.SPREAD, (mount, r, s.pairs.count)
            assert all(c[1] == mountcheck.SPREAD for c in s.checks), s.checks


def test_a_magnet_during_the_dance_raises_no_false_alarm():
    s = M.Session("qmc5883l", True, world=_world(motion.figure8(), magnet=True))
    assert s.checks and all(c[1] != mountcheck.WRONG for c in s.checks), s.checks


def test_the_existing_board_scenarios_confirm_their_settings():
    import sys
    sys.path.insert(0, os.path.join(mp.ROOT, "tests", "scenarios"))
    import app_world as W
    for setup in sorted(W.SETUPS):
        chip, accel = W.SETUPS[setup]
        for seed in (3, 5):
            s = M.Session(chip, accel, seed=seed, world=W.make_world())
            assert s.verdict == (mountcheck.OK, W.MAG_AXES), (setup, seed, s.checks)
            assert all(c[1] != mountcheck.WRONG for c in s.checks)


# --- integer bounds -----------------------------------------------------------------------------
_I16 = st.integers(min_value=-32768, max_value=32767)
_VEC = st.tuples(_I16, _I16, _I16)


@st.composite
def _invw(draw):
    rows = []
    for _ in range(3):
        row = draw(st.lists(st.integers(-32767, 32767), min_size=3, max_size=3))
        t = sum(abs(v) for v in row)
        if t > 32767:  # scale the row into Calibration's bound (row absolute sum <= 32767)
            row = [(1 if v >= 0 else -1) * (abs(v) * 32767 // t) for v in row]
        rows += row
    return tuple(rows)


_CHECKED = []


def _checked():
    # the two modules instrumented once (the stats keep the largest magnitude seen over all
    # examples)
    if not _CHECKED:
        _CHECKED.extend((intcheck.load("calibrate.mounting"), intcheck.load("calibrate.mountcheck")))
    return _CHECKED


@settings(max_examples=max(300, settings().max_examples), deadline=None)
@given(st.lists(st.tuples(_VEC, _VEC), min_size=1, max_size=80), _invw(), _VEC,
       st.sampled_from([M.mag_axes(m) for m in M.rotations()]),
       st.sampled_from([M.accel_axes(m) for m in M.rotations()]),
       st.integers(256, 32767), st.integers(1000, 1000000))
def test_every_intermediate_stays_a_small_int(steps, invw, offset, mag_axes, accel_axes, cpg,
                                              period):
    (pm, sm), (cm, sc) = _checked()
    p = pm.Pairs(cpg, period)
    for raw, acc in steps:  # and the same again: a still board fills its bin
        p.feed(array("h", raw), array("h", acc))
        p.feed(array("h", raw), array("h", acc))
    cal = Calibration(model=10, offset=offset, invw=invw, field=1000, field_out=1000)
    cm.check(p, cal, mag_axes, accel_axes)
    assert sm.max_abs < 1 << 30 and sc.max_abs < 1 << 30


def test_full_scale_vectors_in_every_bin_stay_small_ints():
    # the largest sums: 24 pairs whose cosines are all at the rails
    cm, sc = _checked()[1]
    p = Pairs(16384, 20000)
    for i in range(BINS):
        o = WIDTH * i
        p.data[o:o + 7] = array("h", (32767, -32768, 32767, -32768, 32767, -32768, 0))
    p.count = BINS
    for mag_axes in ("x,-y,-z", "-z,x,-y"):
        cm.check(p, Calibration(), mag_axes, "-x,y,z")
    assert sc.max_abs < 1 << 30


# --- tiers: the same verdicts, the heap, nothing per sample ---------------------------------------
def _parity_lines(out):
    lines = mp.json_lines(out)
    checks = [ln for ln in lines if ln[0] == "check"]
    settings_ = [ln for ln in lines if ln[0] == "setting"]
    assert checks and all(c[2:4] == ["wrong", "y,x,-z"] for c in checks)
    assert len(settings_) == 24
    assert [s[1] for s in settings_ if s[2] == "ok"] == ["y,x,-z"]
    assert all(s[2:4] == ["wrong", "y,x,-z"] for s in settings_ if s[1] != "y,x,-z")


@pytest.fixture(scope="module")
def cpython_verdicts():
    out = mp.run(["tests/scenarios/mounting_parity.py"], micro=False)
    _parity_lines(out)
    return out


@pytest.mark.parametrize("tier", ["unix", "wasm", "x86-32"])
def test_the_same_verdicts_on_every_micropython_tier(tier, cpython_verdicts):
    t = mp.TIERS[tier]
    if not t.available:
        pytest.skip("%s tier: %s" % (tier, t.reason))
    mp.parity_tier(["tests/scenarios/mounting_parity.py"], tier, expected=cpython_verdicts)


def test_feeding_allocates_nothing_on_micropython():
    r = json.loads(mp.run(["tests/scenarios/mounting_heap.py"], micro=True))
    assert r["feed_calls"] == 96 and r["feed_allocated"] == 0 and r["after_feeding"] == 0
    assert r["bins"] == BINS


def test_the_session_holds_at_most_2_kb_for_the_check_on_a_32_bit_board(tmp_path):
    """x86-32, the modules as .mpy files (as `make deploy` installs them): the pairs module
    and a full Pairs while the session collects, plus what a check leaves on it."""
    t = mp.TIERS["x86-32"]
    if not t.available:
        pytest.skip("x86-32 tier: %s" % t.reason)
    bench.build_mpy(str(tmp_path), os.path.join(mp.TOOLS, "mpy-cross-x86-32"), "x86")
    # run from the build folder: the modules' paths (their __file__, interned) as short as a
    # board's "/lib/firmware/..."
    env = dict(os.environ, MICROPYPATH=".")
    out = subprocess.run([mp.X86_32, os.path.join(mp.ROOT, "tests", "scenarios",
                                                  "mounting_heap.py")],
                         cwd=str(tmp_path), env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    assert r["feed_allocated"] == 0
    held = r["module"] + r["pairs"] + r["after_check"]
    assert held <= HEAP_BUDGET, r
    # the check's module and work come and go after a fit (the solver's far larger work has
    # gone by then): bounded too, so that it stays small beside it
    assert r["check_module"] + r["check_transient"] <= 4 * 1024, r


def test_the_heading_path_never_loads_the_check():
    import ast
    for name in ("app", "compass", "app_setup", "health", "calibration", "axes", "status",
                 "accuracy", "store", "app_persist", "boot"):
        src = open(os.path.join(mp.ROOT, "firmware", name + ".py")).read()
        for node in ast.walk(ast.parse(src)):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [node.module + "." + a.name for a in node.names]
                assert not any(n.startswith(("firmware.calibrate.mounting", "firmware.calibrate.mountcheck"))
                               for n in names), (name, node.lineno)


# --- offline: python -m host_sim calibrate on a log with accelerometer columns -------------------
@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A GY-87's 40 s dance logged as raw counts (ax, ay, az, mx, my, mz), with the HMC5883L
    mounted as the boards' usual maps say and turned against the MPU6050; the wrong one also
    with the accelerometer in m/s^2 under other header names, and without its columns."""
    d = tmp_path_factory.mktemp("mountlogs")
    out = {}
    for name, mount in (("right", M.MOUNT), ("wrong", (2, 1, -3))):
        rows = M.Session("gy87", None, mount=mount, record=True).rows
        out[name] = str(d / (name + ".csv"))
        with open(out[name], "w") as f:
            f.write("ax,ay,az,mx,my,mz\n")
            f.writelines(",".join(str(v) for v in r) + "\n" for r in rows)
        if name == "wrong":
            out["wrong_si"] = str(d / "wrong_si.csv")
            with open(out["wrong_si"], "w") as f:
                f.write("# a phone app's export\ntime;accX (m/s^2);accY (m/s^2);accZ (m/s^2);"
                        "magX;magY;magZ\n")
                for i, r in enumerate(rows):
                    f.write("%d;%s;%d;%d;%d\n" % (i, ";".join("%.4f" % (v * 9.80665 / 16384)
                                                               for v in r[:3]), *r[3:]))
            out["mag_only"] = str(d / "mag_only.csv")
            with open(out["mag_only"], "w") as f:
                f.write("mx,my,mz\n")
                f.writelines(",".join(str(v) for v in r[3:]) + "\n" for r in rows)
    return out


def _calibrate(args, micro=False):
    exe = [mp.MICROPYTHON] if micro else [mp.sys.executable]
    env = dict(os.environ, MICROPYPATH=mp.ROOT, PYTHONPATH=mp.ROOT)
    return subprocess.run(exe + ["-m", "host_sim", "calibrate"] + args, cwd=mp.ROOT, env=env,
                          capture_output=True, text=True, timeout=120)


def test_the_calibrate_command_names_the_mapping_a_log_with_accelerometer_columns_says(logs):
    r = _calibrate([logs["wrong"], "--sensor", "hmc5883l", "--json"])
    assert r.returncode == 0, r.stderr
    m = json.loads(r.stdout)["mounting"]
    assert (m["verdict"], m["mag_axes"], m["mag_axes_given"]) == ("wrong", "y,x,-z", "x,-y,-z")
    assert m["pairs"] >= mountcheck.MIN_BINS and m["accel_columns"] == ["ax", "ay", "az"]
    r = _calibrate([logs["wrong"], "--sensor", "hmc5883l"])
    assert r.returncode == 0
    assert 'the data say MAG_AXES = "y,x,-z"' in r.stdout
    # the setting the data say is confirmed; the right log is confirmed as it is
    r = _calibrate([logs["wrong"], "--sensor", "hmc5883l", "--mag-axes", "y,x,-z", "--json"])
    assert json.loads(r.stdout)["mounting"]["verdict"] == "ok"
    r = _calibrate([logs["right"], "--sensor", "hmc5883l"])
    assert 'mounting       ok: MAG_AXES "x,-y,-z" agrees with ACCEL_AXES "-x,y,z"' in r.stdout


def test_other_units_and_header_names_give_the_same_answer_and_no_columns_no_check(logs):
    r = _calibrate([logs["wrong_si"], "--sensor", "hmc5883l", "--json"])
    m = json.loads(r.stdout)["mounting"]
    assert (m["verdict"], m["mag_axes"]) == ("wrong", "y,x,-z"), m
    r = _calibrate([logs["mag_only"], "--sensor", "hmc5883l", "--json"])
    assert r.returncode == 0 and "mounting" not in json.loads(r.stdout)


def test_the_check_options_refuse_a_mirror_or_a_typo_in_one_line(logs):
    for opt, val in (("--mag-axes", "x,y,-z"), ("--accel-axes", "x,-y,-z"),
                     ("--mag-axes", "x,y")):
        r = _calibrate([logs["wrong"], "--sensor", "hmc5883l", opt, val])
        assert r.returncode == 2 and r.stdout == ""
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and opt in lines[0], r.stderr


def test_the_offline_check_says_the_same_on_micropython(logs):
    a = _calibrate([logs["wrong"], "--sensor", "hmc5883l"])
    b = _calibrate([logs["wrong"], "--sensor", "hmc5883l"], micro=True)
    assert b.returncode == 0, b.stderr
    pick = [ln for ln in a.stdout.splitlines() if ln.startswith("mounting")]
    assert pick and pick == [ln for ln in b.stdout.splitlines() if ln.startswith("mounting")]


# --- the guided check: examples/check_axes.py on the simulator ----------------------------------
_CHECK = ("import sys; sys.path.insert(0, %r); from examples.check_axes import check; "
          "print(sorted(check(mount=%r, accel_mount=%r).items()))")


@pytest.mark.parametrize("mount,accel_mount", [
    (None, None), ((2, 1, -3), None), (None, (-2, -1, -3)), ((-1, -3, -2), (-2, -1, -3))],
    ids=["right", "mag-turned", "accel-turned", "both"])
def test_the_guided_check_names_the_lines_for_board_py(mount, accel_mount):
    code = _CHECK % (mp.ROOT, mount, accel_mount)
    out = mp.parity(["-c", code])
    acc = M.accel_axes(accel_mount or M.MOUNT)
    mag = M.mag_axes(mount or M.MOUNT)
    lines = out.splitlines()
    assert ("pitch and roll move the right way: ACCEL_AXES is right" in lines) == (
        accel_mount is None)
    assert any(ln.startswith("the heading holds through the poses") for ln in lines) == (
        mount is None)
    if mount is None and accel_mount is None:
        assert "put these lines" not in out
    else:
        i = lines.index("put these lines in boards/<board>/board.py:")
        assert lines[i + 1:i + 3] == ['ACCEL_AXES = "%s"' % acc, 'MAG_AXES = "%s"' % mag]
    r = dict(eval(lines[-1]))
    assert (r["accel_axes"], r["mag_axes"]) == (acc, mag)


# --- on the board: the calibration session runs the check ---------------------------------------
def test_on_the_board_a_wrong_setting_is_said_and_the_heading_not_presented_as_good():
    from firmware.app import status_line
    s = M.Session("gy87", None, mount=(2, 1, -3), statuses=True)
    app = s.app
    note = 'check MAG_AXES: the data say "y,x,-z"'
    assert app.mounting[:2] == (mountcheck.WRONG, "y,x,-z")
    assert app.status == note and "| %s |" % note in status_line(app)
    assert app.accuracy == 0 and app.accuracy_reason() == "mag_axes"
    # from the first check that named it, never "ok" again
    first = s.statuses.index(note)
    assert "ok" not in s.statuses[first:]
    # the board put down: the session ends and its modules leave; the note stays
    import sys
    s.board.world.motion = motion.still(30.0, 0.0, 0.0)
    for _ in range(50 * 20):
        app.step()
    assert app.collector is None
    assert "firmware.calibrate.mounting" not in sys.modules and "firmware.calibrate.mountcheck" not in sys.modules
    assert app.status == note and app.accuracy_reason() == "mag_axes"


def test_on_the_board_a_right_setting_is_never_questioned():
    for chip, accel in M.BOARDS:
        s = M.Session(chip, accel, statuses=True)
        assert s.app.mounting[0] == mountcheck.OK, (chip, s.app.mounting)
        assert not any(st.startswith("check MAG_AXES") for st in s.statuses), chip
        assert s.app.status == "ok" and s.app.accuracy_reason() != "mag_axes"


# --- the magnetometers inside an IMU, and handedness -------------------------------------------
@pytest.mark.parametrize("board,breakout_name", [("gy9250", "gy9250"), ("icm20948", "icm20948")])
def test_an_imus_own_magnetometer_is_confirmed_where_its_datasheet_puts_it(board, breakout_name):
    # the AK8963 / AK09916 sit in their package as the datasheets draw them (host_sim/chips.py
    # mountings); boards/breakouts.py's MAG_AXES for them are confirmed, the usual breakout's
    # map is named wrong with the right one in its place
    from boards.breakouts import breakout
    from host_sim import chips
    mount = chips.board(board)[4]
    right = breakout(breakout_name)["mag"]
    assert M.mag_axes(mount) == right
    s = M.Session(board, None, mount=mount, mag_axes=right)
    assert s.verdict[0] == mountcheck.OK, s.checks
    s = M.Session(board, None, mount=mount, mag_axes="x,-y,-z")
    assert s.verdict == (mountcheck.WRONG, right), s.checks


def _mirrored():
    from firmware.qmc5883l import QMC5883L

    class MirroredQMC(QMC5883L):
        MIRROR = True  # as a chip whose datasheet draws its axes as a mirror of its accelerometer's
    return MirroredQMC


def test_a_mirror_map_only_for_a_chip_whose_axes_are_a_mirror():
    from host_sim import motion
    from host_sim.boards import make_board
    from host_sim.world import World
    from firmware.app import CompassApp
    from firmware.qmc5883l import QMC5883L

    def app(cls, axes, mount=(1, -2, 3)):
        w = World(field_ut=50.0, inclination_deg=60.0, hard_iron_ut=(45.0, -35.0, 30.0),
                  motion=motion.figure8())
        b = make_board("qmc5883l", world=w, seed=3, accel=True, mount=mount)
        return b, CompassApp(b.bus, mag=cls(b.bus, delay_us=b.sleep_us), mag_axes=axes,
                             accel_axes="-x,y,z", store=None, delay_us=b.sleep_us,
                             ticks_us=b.clock.ticks_us)
    with pytest.raises(ValueError, match="mirror image: the qmc5883l's axes are right-handed"):
        app(QMC5883L, "x,-y,z")
    with pytest.raises(ValueError, match="rotation: the qmc5883l's axes are a mirror"):
        app(_mirrored(), "x,-y,-z")
    # a left-handed chip (x forward, y left, z down) with its mirror map: a heading, and the
    # check confirms it; a wrong mirror map is named, with the right mirror in its place
    for given, verdict in (("x,-y,z", (mountcheck.OK, "x,-y,z")),
                           ("y,x,z", (mountcheck.WRONG, "x,-y,z"))):
        b, a = app(_mirrored(), given)
        while b.clock.now_us < M.SECONDS * 1000000:
            a.step()
        assert a.mounting[:2] == verdict, a.mounting


def test_the_calibrate_command_takes_a_mirror_map_only_without_a_right_handed_chip(logs):
    from host_sim import chips
    r = _calibrate([logs["wrong"], "--sensor", "ak8963", "--mag-axes", "x,y,-z"])
    assert r.returncode == 2 and "--mag-axes 'x,y,-z' is a mirror image: the ak8963's" in r.stderr
    r = _calibrate([logs["wrong"], "--mag-axes", "x,y,-z", "--json"])   # no chip named
    assert r.returncode in (0, 1) and json.loads(r.stdout)["mounting"]["mag_axes_given"] == \
        "x,y,-z"
    assert M.handedness("x,y,-z", None) is None and M.handedness("x,-y,-z", "hmc5883l") is None
    m = chips.mag("hmc5883l")
    try:
        m["mirror"] = True   # a chip whose datasheet draws a mirror
        assert M.handedness("x,y,-z", "hmc5883l") is None
        assert "is a rotation" in M.handedness("x,-y,-z", "hmc5883l")
    finally:
        m["mirror"] = False
