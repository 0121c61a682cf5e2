"""MicroPython only: desktop/benchmarks/boardrun.py (boards/main.py over a recorded
session) run as it is, then the names interned by the end (micropython.qstr_info()'s line).
A wrapper, so the sweeps' harness carries no code of this test.

    micropython -X heapsize=N board_names.py BOARDRUN SESSION STOREDIR DANCE_S END_S
"""
import sys

_path = sys.argv.pop(1)
sys.argv[0] = _path
with open(_path) as _f:
    exec(compile(_f.read(), _path, "exec"), {"__name__": "__main__"})
import micropython  # noqa: E402

micropython.qstr_info()
