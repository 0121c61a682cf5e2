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
