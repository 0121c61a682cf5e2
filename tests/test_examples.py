"""The examples run against the simulator, on CPython and on the MicroPython unix port."""
import os
import re
import shutil
import subprocess
import sys

import pytest

from tests import mp


def test_log_csv_writes_a_bounded_file_the_same_on_both_interpreters(tmp_path):
    path = str(tmp_path / "log.csv")
    out = mp.parity(["examples/log_csv.py", path, "3000"])
    assert out.startswith("logged ") and "qmc5883l" in out
    size = os.path.getsize(path)
    assert 2950 <= size <= 3000            # stops before the next row would pass the bound
    lines = open(path).read().splitlines()
    assert lines[1] == "mx,my,mz" and len(lines) - 2 == int(out.split()[1])
    assert all(-32768 <= int(v) <= 32767 for ln in lines[2:] for v in ln.split(","))


def test_read_raw_prints_the_chip_and_its_samples_the_same_on_both_interpreters():
    out = mp.parity(["examples/read_raw.py", "4"])
    lines = out.splitlines()
    assert lines[0].startswith("qmc5883l at 0x0D, 12000 counts/G; accelerometer: MPU6050")
    assert len(lines) == 5 and all(ln.startswith("mag ") for ln in lines[1:])


def test_calibrate_at_the_repl_gives_a_ten_element_fit_the_same_on_both_interpreters():
    out = mp.parity(["examples/calibrate_repl.py", "30"])
    assert "model 10:" in out and "refused" not in out
    # the simulated board's hard iron is (40, -30, 25) uT = (4800, -3600, 3000) counts
    v = out.split("V = (")[1].split(")")[0]
    x, y, z = (int(t) for t in v.split(","))
    assert abs(x - 4800) < 60 and abs(y + 3600) < 60 and abs(z - 3000) < 60


def test_heading_loop_reports_a_calibrated_heading_on_both_interpreters():
    out = mp.parity(["examples/heading_loop.py", "30"])
    last = out.strip().splitlines()[-1]
    assert "| ok |" in last and "model 10" in last and "accuracy 3" in last


def test_a_log_fitted_on_the_desktop_is_loaded_onto_the_board_once(tmp_path):
    import subprocess
    import sys
    log = str(tmp_path / "log.csv")
    cal = str(tmp_path / "calibration.json")
    mp.run(["examples/log_csv.py", log, "12000"], micro=True)
    # no --sensor: the log's first line names the chip and its range
    p = subprocess.run([sys.executable, "-m", "host_sim", "calibrate", log, "--out", cal],
                       cwd=mp.ROOT, capture_output=True, text=True)
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert "board          qmc5883l at 2 G (range code 0, 12000 counts/G); the log's line " \
        "'# qmc5883l range_code 0 counts_per_gauss 12000'" in p.stdout
    store = tmp_path / "store"
    store.mkdir()
    out = mp.run(["examples/load_calibration.py", cal, str(store)], micro=True)
    assert out.startswith("imported"), out
    assert os.path.exists(cal + ".imported") and not os.path.exists(cal)
    assert any(f.endswith(".cal") for f in os.listdir(store))
    # imported once: a second run finds no file, says so on stderr and exits 2
    again = subprocess.run([mp.MICROPYTHON, "examples/load_calibration.py", cal, str(store)],
                           cwd=mp.ROOT, env=mp._env(True), capture_output=True, text=True)
    assert again.returncode == 2 and again.stdout == "", again
    assert again.stderr.startswith("no calibration file") and "Traceback" not in again.stderr


@pytest.mark.parametrize("micro", [False, True])
def test_a_refused_calibration_file_is_said_once_and_exits_1(tmp_path, micro):
    # a file written for another chip than the one the board finds (the simulator's QMC5883L)
    import json
    from desktop import calfile
    log = str(tmp_path / "log.csv")
    cal = str(tmp_path / "calibration.json")
    mp.run(["examples/log_csv.py", log, "12000"], micro=True)
    p = subprocess.run([sys.executable, "-m", "host_sim", "calibrate", log, "--sensor",
                        "qmc5883l", "--out", cal], cwd=mp.ROOT, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    d = calfile.read(cal)
    d.update(sensor="hmc5883l", range_code=1, range_gauss=1.3, counts_per_gauss=1090)
    with open(cal, "w") as f:
        json.dump(d, f)
    store = tmp_path / "store"
    store.mkdir()
    exe = [mp.MICROPYTHON] if micro else [sys.executable]
    r = subprocess.run(exe + ["examples/load_calibration.py", cal, str(store)], cwd=mp.ROOT,
                       env=mp._env(micro), capture_output=True, text=True)
    assert r.returncode == 1 and r.stdout == "", r
    line = r.stderr.strip()
    assert "\n" not in line and line.startswith("rejected %s: " % cal), line
    why = line[len("rejected %s: " % cal):]
    assert "hmc5883l" in why and "refused" not in why and "rejected" not in why  # said once
    assert os.path.exists(cal + ".rejected") and os.listdir(str(store)) == []


def test_gyro_heading_holds_through_the_magnet_the_same_on_both_interpreters():
    out = mp.parity(["examples/gyro_heading.py", "50"])
    lines = out.strip().splitlines()
    held = [ln for ln in lines if "| gyro held |" in ln]
    assert len(held) >= 5 and all("gyro: held" in ln for ln in held)   # the 5 s pass
    assert not any("| interference |" in ln for ln in lines[-12:])  # never left unvouched
    assert "| ok |" in lines[-1] and "gyro: on field" in lines[-1]


# ---- every example's own usage lines, run as they are written -------------------------------
# No PYTHONPATH / MICROPYPATH: `python examples/X.py ...` from the repository root and from
# another folder, `python -m examples.X ...` from the root, on CPython and the unix port; the
# board line (`from examples.X import f; f()`) at the unix port's prompt, where get_bus() gives
# the simulator as it gives machine.I2C on a board.

EXAMPLES = sorted(f[:-3] for f in os.listdir(os.path.join(mp.ROOT, "examples"))
                  if f.endswith(".py") and f not in ("__init__.py", "bus.py"))
FOREVER = ("heading_loop", "gyro_heading")      # their board line loops until reset


def usage_lines(name):
    """(host line, board line) from the docstring of examples/<name>.py."""
    doc = open(os.path.join(mp.ROOT, "examples", name + ".py")).read().split('"""')[1]
    host = [ln.split("#")[0].strip() for ln in doc.splitlines()
            if ln.strip().startswith("python3 examples/%s.py" % name)]
    board = [ln.split("#")[0].strip() for ln in doc.splitlines()
             if ln.strip().startswith("from examples.%s import " % name)]
    assert len(host) == 1 and len(board) == 1, (name, host, board)
    return host[0], board[0]


def host_argv(line, tmp):
    """The usage line's words, its [OPTIONAL] / PLACEHOLDER arguments given values."""
    cal = str(tmp / "calibration.json")
    values = {"[SECONDS]": "6", "[N]": "2", "[PATH]": str(tmp / "log.csv"),
              "[MAX_BYTES]": "2000", "FILE": cal, "[STORE_DIR]": str(tmp / "new_store")}
    words = line.split()[1:]                     # without "python3"
    return [values.get(w, w) for w in words]


def clean_env():
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    env.pop("MICROPYPATH", None)
    return env


def run_line(exe, argv, cwd):
    p = subprocess.run(exe + argv, cwd=cwd, env=clean_env(), capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0 and "Traceback" not in p.stderr and p.stdout.strip(), (
        exe + argv, cwd, p.returncode, p.stdout[-2000:], p.stderr[-2000:])
    return p.stdout


@pytest.fixture
def calibration_file(tmp_path):
    """A desktop fit the load_calibration usage line loads."""
    log = str(tmp_path / "fit.csv")
    run_line([sys.executable], ["examples/log_csv.py", log, "12000"], mp.ROOT)
    p = subprocess.run([sys.executable, "-m", "host_sim", "calibrate", log, "--sensor",
                        "qmc5883l", "--out", str(tmp_path / "calibration.json")], cwd=mp.ROOT,
                       env=clean_env(), capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    shutil.copy(str(tmp_path / "calibration.json"), str(tmp_path / "calibration.json.fit"))
    return str(tmp_path / "calibration.json")


@pytest.mark.parametrize("name", EXAMPLES)
@pytest.mark.parametrize("interp", ["cpython", "unix"])
def test_the_usage_line_runs_as_written(name, interp, tmp_path, calibration_file):
    exe = [sys.executable] if interp == "cpython" else [mp.MICROPYTHON]
    host, _ = usage_lines(name)
    where = tmp_path / "elsewhere"
    where.mkdir()
    outs = []
    for form, cwd in (("script", mp.ROOT), ("script", str(where)), ("module", mp.ROOT)):
        if name == "load_calibration":          # the file is imported once: a fresh copy each
            shutil.copy(calibration_file + ".fit", calibration_file)
        argv = host_argv(host, tmp_path)
        if form == "script" and cwd != mp.ROOT:
            argv[0] = os.path.join(mp.ROOT, argv[0])
        elif form == "module":
            argv = ["-m", "examples." + name] + argv[1:]
        outs.append(run_line(exe, argv, cwd))
    if name == "load_calibration":
        assert outs[0].startswith("created the store folder") and "imported" in outs[0]
        assert all(o.strip().splitlines()[-1].startswith("imported") for o in outs), outs
    else:
        assert outs[0] == outs[1] == outs[2]     # the same simulated run whichever way


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_board_line_runs_at_the_micropython_prompt(name, tmp_path, calibration_file):
    _, board = usage_lines(name)
    m = re.match(r"from examples\.(\w+) import (\w+); (\w+)\(\)$", board)
    assert m and m.group(1) == name and m.group(2) == m.group(3), board
    if name == "load_calibration":               # the board's root: the temporary folder
        board = board.replace("load()", "load(%r, %r)" % (calibration_file, str(tmp_path)))
    if name == "log_csv":
        board = board.replace("log()", "log(%r)" % str(tmp_path / "mag_log.csv"))
    if name not in FOREVER:
        out = run_line([mp.MICROPYTHON], ["-c", board], mp.ROOT)
        assert "Traceback" not in out
        return
    # a loop until reset: its first status line, then stop it
    p = subprocess.Popen([mp.MICROPYTHON, "-c", board], cwd=mp.ROOT, env=clean_env(),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = p.stdout.readline()
    finally:
        p.kill()
        p.wait()
    assert first.startswith("heading "), (first, p.stderr.read())
