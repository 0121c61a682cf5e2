"""The examples run against the simulator, on CPython and on the MicroPython unix port."""
import os

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
    p = subprocess.run([sys.executable, "-m", "host_sim", "calibrate", log, "--sensor",
                        "qmc5883l", "--out", cal], cwd=mp.ROOT, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    store = tmp_path / "store"
    store.mkdir()
    out = mp.run(["examples/load_calibration.py", cal, str(store)], micro=True)
    assert out.startswith("imported"), out
    assert os.path.exists(cal + ".imported") and not os.path.exists(cal)
    assert any(f.endswith(".cal") for f in os.listdir(store))
    again = mp.run(["examples/load_calibration.py", cal, str(store)], micro=True)
    assert again.startswith("no calibration file")  # imported once


def test_gyro_heading_holds_through_the_magnet_the_same_on_both_interpreters():
    out = mp.parity(["examples/gyro_heading.py", "50"])
    lines = out.strip().splitlines()
    held = [ln for ln in lines if "| gyro held |" in ln]
    assert len(held) >= 5 and all("gyro: held" in ln for ln in held)   # the 5 s pass
    assert not any("| interference |" in ln for ln in lines[-12:])  # never left unvouched
    assert "| ok |" in lines[-1] and "gyro: on field" in lines[-1]
