"""The shape of the tree: one job per module, no import cycles, a heading-only runtime that
loads without the calibration machinery, portability shims in one place, no emitter
decorators in plain modules, and a simulator that knows nothing of the firmware."""
import ast
import os
import re

import pytest

from firmware.detect import CHIPS
from tests import mp

ROOT = mp.ROOT
FW = os.path.join(ROOT, "firmware")
# the chip drivers: firmware/detect.py's table names them (docs/chips.md)
DRIVERS = sorted({row.split()[5].decode() for row in CHIPS})
PIPELINE = ["compat", "errors", "fixedpoint", "i2cdevice", "detect"] + DRIVERS + [
            "axes", "calibrate.samples", "calibrate.accum",
            "calibrate.solve", "calibration", "calibrate.acceptance", "calibrate.calibrator",
            "kang_tables", "trig", "compass", "store", "slots", "calibrate.history", "health",
            "fieldwatch", "app", "fast",
            # the app's capabilities, each loaded for its job and dropped after it (boot,
            # construction, the drivers' start-up and error texts, the store's load and save,
            # the calibration session, calibration mode where the heap holds one job at a
            # time, the status line)
            "boot", "appsetup", "devinit", "persist", "calibrate.session", "status", "hints",
            # the calibration program, and what a board's main.py runs
            "calibrate.program", "runner"]
CALIBRATION_MACHINERY = {"firmware.calibrate.calibrator", "firmware.calibrate.solve", "firmware.calibrate.accum",
                         "firmware.calibrate.samples", "firmware.calibrate.acceptance", "firmware.calibrate.session",
                         "firmware.calibrate.history"}
# what a board booted from a stored calibration holds while it shows headings (docs/design.md)
CORE = {"firmware." + m for m in ("app", "axes", "calibration", "compass", "compat", "errors",
                                  "fieldwatch", "fixedpoint", "health", "i2cdevice", "kang_tables",
                                  "mpu6050", "qmc5883l", "store", "trig")}


def _modules(folder):
    """Every module below `folder`, as dotted names relative to it ("app", "calibrate.solve")."""
    out = []
    for d, dirs, files in os.walk(folder):
        dirs[:] = [x for x in dirs if not x.startswith((".", "__"))]
        rel = os.path.relpath(d, folder)
        pre = "" if rel == "." else rel.replace(os.sep, ".") + "."
        out += [pre + f[:-3] for f in files if f.endswith(".py") and f != "__init__.py"]
    return sorted(out)


def _path(m):
    return os.path.join(FW, *m.split(".")) + ".py"


def _imports(path, package, lazy=True):
    """Every module `path` imports (module level, and inside functions when lazy), as dotted
    names."""
    tree = ast.parse(open(path).read(), path)
    # a module imported by a string held in a name (firmware/persist.py, session.py:
    # name = "firmware.mountnote"; __import__(name, ...)): the strings such names hold
    held = {n.targets[0].id: n.value.value for n in ast.walk(tree)
            if isinstance(n, ast.Assign) and isinstance(n.targets[0], ast.Name)
            and isinstance(n.value, ast.Constant) and isinstance(n.value.value, str)
            and n.value.value.startswith(package + ".")}
    out = set()
    for node in (ast.walk(tree) if lazy else tree.body):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id == "__import__" and node.args
                and isinstance(node.args[0], ast.Name) and node.args[0].id in held):
            out.add(held[node.args[0].id])
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
            if node.module.split(".")[0] == package:  # from firmware.calibrate import solve
                out.update(node.module + "." + a.name for a in node.names)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id == "__import__" and node.args
              and isinstance(node.args[0], ast.BinOp)):
            out.add(package + ".*")  # detect.driver_class: a chip driver by name
    return out


def _graph(lazy=True):
    g = {}
    mods = set(_modules(FW))
    for m in mods:
        deps = _imports(_path(m), "firmware", lazy)
        g[m] = sorted(d.split(".", 1)[1] for d in deps
                      if d.startswith("firmware.") and d.split(".", 1)[1] in mods)
    return g


def test_firmware_reads_as_the_pipeline_one_module_per_job():
    # beside the pipeline: the field model, where the board is (location, quick calibration),
    # the accuracy level, the MotionCal codec and mode, importing a calibration file at boot,
    # CircuitPython's bus adapter, the gyro-aided heading's attitude filter, the mounting check
    # and its verdict kept across a reboot
    assert set(_modules(FW)) - {"field.wmm", "motioncal.protocol", "motioncal.mode",
                                "field.location", "field.quickcal", "accuracy",
                                "calfile.calimport", "circuitpython.busio_i2c",
                                "gyro.attitude", "gyro.attitude_plain", "gyro.attitude_fast",
                                "gyro.gyrosetup", "calibrate.mounting", "calibrate.mountcheck",
                                "mountnote"} == set(PIPELINE)


def test_no_import_cycles_in_firmware():
    g = _graph()
    state = {}

    def visit(m, path):
        if state.get(m) == 1:
            raise AssertionError("import cycle: " + " -> ".join(path + [m]))
        if state.get(m) == 2:
            return
        state[m] = 1
        for d in g.get(m, ()):
            visit(d, path + [m])
        state[m] = 2

    for m in g:
        visit(m, [])


def _app_assignments(src):
    """(line, text) of each assignment into a CompassApp in the source src: `app.x = ...`,
    `app.x += ...`, a tuple target holding app.x, setattr(app, ...)."""
    out = []
    tree = ast.parse(src)

    def into_app(t):
        if isinstance(t, (ast.Tuple, ast.List)):
            return any(into_app(e) for e in t.elts)
        return (isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name)
                and t.value.id == "app")

    for n in ast.walk(tree):
        if isinstance(n, ast.Assign):
            hit = any(into_app(t) for t in n.targets)
        elif isinstance(n, (ast.AugAssign, ast.AnnAssign)):
            hit = into_app(n.target)
        elif isinstance(n, ast.Call) and isinstance(n.func, ast.Name):
            hit = (n.func.id == "setattr" and n.args and isinstance(n.args[0], ast.Name)
                   and n.args[0].id == "app")
        else:
            continue
        if hit:
            out.append((n.lineno, ast.unparse(n).split("\n")[0]))
    return out


def test_no_module_but_the_app_assigns_into_the_app():
    # CompassApp's state has owners: the app itself, or the objects it holds (the session,
    # the compass, the field watch, health); another module returns what the app assigns
    found = {}
    for m in _modules(FW):
        if m != "app":
            with open(_path(m)) as f:
                hits = _app_assignments(f.read())
            if hits:
                found[m] = hits
    assert found == {}


def test_the_assignment_finder_sees_every_form():
    src = "app.a = 1\napp.b += 1\nx, app.c = 1, 2\nsetattr(app, 'd', 1)\napp.e.f = 1\nself.g = 1\n"
    assert [t for n, t in _app_assignments(src)] == [
        "app.a = 1", "app.b += 1", "x, app.c = (1, 2)", "setattr(app, 'd', 1)"]


def test_chip_drivers_import_only_the_device_base_and_errors():
    g = _graph()
    for chip in DRIVERS:
        assert set(g[chip]) <= {"compat", "errors", "i2cdevice"} | set(DRIVERS), (chip, g[chip])


def test_the_heading_only_modules_do_not_import_the_calibration_machinery():
    g = _graph(lazy=False)  # module level: what importing them loads
    seen = set()
    todo = ["app", "store", "compass", "calibration", "qmc5883l"]
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo.extend(g[m])
    assert not {"firmware." + m for m in seen} & CALIBRATION_MACHINERY, sorted(seen)


@pytest.mark.parametrize("micro", [False, True], ids=["cpython", "micropython"])
def test_a_board_booted_from_a_stored_calibration_loads_no_calibration_machinery(micro):
    out = mp.json_lines(mp.run(["tests/scenarios/app_modules.py"], micro=micro))
    first, second, third, fourth = out
    assert first[0] == "heading_only" and first[2] == 100
    assert not first[3]
    # the core and nothing else: no machinery, no boot-time code (detect, construction, the
    # store's slot code), no field model (set_location() / quick_calibrate() load it)
    assert set(first[1]) == CORE, sorted(set(first[1]) ^ CORE)
    # collecting imports the machinery, lazily, and the heading goes on
    assert second[3] and second[2] == 100
    # (the solver comes with the first solve, the history with the first accepted fit)
    assert CALIBRATION_MACHINERY - {"firmware.calibrate.history", "firmware.calibrate.solve"} <= set(second[1])
    # the board rests: a solve on what was kept, nothing new for 3 s, and the good
    # calibration in force stays: the session ends and its modules leave
    assert third[0] == "ended" and not third[3] and third[2] == third[4]
    assert set(third[1]) == CORE, sorted(set(third[1]) ^ CORE)
    # a location: its figures stay (firmware/field/location.py), the model's table code leaves
    assert fourth[0] == "located" and fourth[4] == "ok" and fourth[2] == 100
    assert set(fourth[1]) == CORE | {"firmware.field", "firmware.field.location"}, sorted(set(fourth[1]) ^ CORE)


def test_the_field_model_is_imported_by_set_location_only():
    g = _graph(lazy=False)
    seen = set()
    todo = ["app", "compass", "calibration", "store", "calibrate.calibrator", "accuracy"]
    while todo:
        m = todo.pop()
        if m not in seen:
            seen.add(m)
            todo.extend(g[m])
    assert not seen & {"field.wmm", "field.location", "field.quickcal"}, sorted(seen)
    lazy = _graph(lazy=True)
    assert "field.location" in lazy["app"] and "field.wmm" in lazy["field.location"]


def _code_lines(path):
    return [ln for ln in open(path).read().splitlines() if not ln.lstrip().startswith("#")]


NATIVE = ("fast", "gyro.attitude_fast")  # the viper mirrors: imported only inside try/except


def test_no_plain_module_carries_an_emitter_decorator():
    for m in _modules(FW):
        if m in NATIVE:
            continue
        src = "\n".join(_code_lines(_path(m)))
        assert not re.search(r"@micropython\.(native|viper)", src), m
    # and each native module is imported in one place only, inside try/except (compat for
    # the compass's, attitude for the filter's; the filter's own mirrors call fast's atan2)
    for m in _modules(FW):
        deps = _imports(_path(m), "firmware")
        if m not in ("compat", "gyro.attitude_fast"):
            assert "firmware.fast" not in deps, m
        if m != "gyro.attitude":
            assert "firmware.gyro.attitude_fast" not in deps, m


def test_portability_shims_have_one_home():
    # const, the clock and the emitter switch come from firmware.compat only
    for m in _modules(FW):
        if m in ("compat",) + NATIVE:
            continue
        path = _path(m)
        deps = _imports(path, "firmware")
        assert not deps & {"micropython", "time", "utime"}, (m, deps)
        for node in ast.walk(ast.parse(open(path).read())):
            if isinstance(node, ast.FunctionDef):
                assert node.name != "const", m  # no local fallback copy


def test_test_only_reference_code_lives_under_tests():
    # the solver steps run to completion and the exact references are tests' business
    from firmware.calibrate import accum
    from firmware.calibrate import solve
    for name in ("fit", "invw_from_a2", "q15_from_invw", "field_q16", "minmax_fit",
                 "sqrtm_sym3", "back_substitute", "fit_error_x100", "_run"):
        assert not hasattr(solve, name), name
    assert not hasattr(accum, "batch")


def test_the_simulator_imports_nothing_of_firmware_boards_or_tests():
    sim = os.path.join(ROOT, "host_sim")
    for f in os.listdir(sim):
        if f.endswith(".py"):
            deps = _imports(os.path.join(sim, f), "host_sim")
            bad = [d for d in deps if d.split(".")[0] in ("firmware", "boards", "tests")]
            assert not bad, (f, bad)


def _cli_files():
    base = os.path.join(ROOT, "host_sim", "cli")
    for dirpath, _, files in os.walk(base):
        for f in files:
            if f.endswith(".py"):
                yield os.path.join(dirpath, f)


def test_commands_never_import_tests_and_load_numpy_matplotlib_only_where_needed():
    for path in _cli_files():
        if path.endswith(os.path.join("benchmarks", "reference.py")):
            continue  # the float64 references themselves, imported by the bench when it runs
        tree = ast.parse(open(path).read(), path)
        deps = _imports(path, "host_sim")
        assert not [d for d in deps if d.split(".")[0] == "tests"], path
        top = set()
        for node in tree.body:  # module level only: a command imports them when it runs
            if isinstance(node, ast.Import):
                top.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module:
                top.add(node.module.split(".")[0])
        assert not top & {"numpy", "matplotlib"}, path


def test_every_command_parses_its_arguments_with_the_one_shared_parser():
    from host_sim import __main__ as runner
    for cmd in runner._COMMANDS:
        src = open(os.path.join(ROOT, "host_sim", "cli", cmd + ".py")).read()
        assert "parser(" in src or "Parser(" in src, cmd      # args.Parser, or demo.parser
        assert "sys.argv" not in src.replace('sys.argv[1:]', ''), cmd
    for path in _cli_files():
        assert "argparse" not in _imports(path, ""), path


def test_comments_cite_what_a_reader_can_follow():
    pat = re.compile(r"\bseed[ -]00\d|\bissue \d+\b|STYLE\.md|style guide", re.I)
    for folder in ("firmware", "host_sim", "boards"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, folder)):
            for f in files:
                if f.endswith(".py"):
                    text = open(os.path.join(dirpath, f)).read()
                    assert not pat.search(text), (f, pat.search(text).group(0))


# A board that installs the sources (mip) compiles each module on its own heap, and the parser
# holds every docstring of a module as a string until the module is compiled: the 12.5 KB of
# docstrings firmware/app.py had made importing it from source need a 100 KB heap on the
# x86-32 build, 75 KB once they were comments (which the lexer skips). Longer text is a
# comment, or in docs/.
DOCSTRING_MAX = 300


def test_firmware_docstrings_are_short_longer_text_is_comments():
    long_ = []
    for m in _modules(FW):
        path = _path(m)
        for n in ast.walk(ast.parse(open(path).read(), path)):
            if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef)):
                d = ast.get_docstring(n, clean=False)
                if d is not None and len(d) > DOCSTRING_MAX:
                    long_.append("%s:%s (%d chars)" % (m, getattr(n, "lineno", 1), len(d)))
    assert not long_, long_
