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
            "trig_tables", "trig", "compass", "store", "store_slots", "calibrate.history", "health",
            "fieldwatch", "learning", "app", "fast",
            # the app's capabilities, each loaded for its job and dropped after it (boot,
            # construction, the drivers' start-up and error texts, the store's load and save,
            # run()'s loop, the calibration session, calibration mode where the heap holds one job at a
            # time, the status line)
            "boot", "app_setup", "devinit", "app_persist", "calibrate.session", "status", "hints",
            # the calibration program, and what a board's main.py runs
            "calibrate.program", "runner", "runner_program", "runner_heading"]
CALIBRATION_MACHINERY = {"firmware.calibrate.calibrator", "firmware.calibrate.solve", "firmware.calibrate.accum",
                         "firmware.calibrate.samples", "firmware.calibrate.acceptance", "firmware.calibrate.session",
                         "firmware.calibrate.history"}
# what a board booted from a stored calibration holds while it shows headings (docs/design.md)
CORE = {"firmware." + m for m in ("app", "axes", "calibration", "compass", "compat", "errors",
                                  "fieldwatch", "fixedpoint", "health", "i2cdevice", "learning",
                                  "trig_tables", "mpu6050", "qmc5883l", "store", "trig")}


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


def _needed(node, package):
    """The module an optional part's compat.need("field.location", ...) call imports, or
    None."""
    f = node.func if isinstance(node, ast.Call) else None
    if (getattr(f, "id", None) == "need" or getattr(f, "attr", None) == "need") and node.args \
            and isinstance(node.args[0], ast.Constant):
        return package + "." + node.args[0].value
    return None


def _imports(path, package, lazy=True):
    """Every module `path` imports (module level, and inside functions when lazy), as dotted
    names; compat.need() calls too."""
    tree = ast.parse(open(path).read(), path)
    # a module imported by a string held in a name (firmware/app_persist.py, session.py:
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
        if _needed(node, package):
            out.add(_needed(node, package))
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
                                "gyro.attitude_setup", "calibrate.mounting", "calibrate.mountcheck",
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


# CompassApp holds the per-sample path and thin public methods; cold code lives in modules
# loaded for their job (docs/design.md, names). The goal is 400 lines; this bound only goes down.
APP_CLASS_MAX = 400


def test_the_app_class_stays_short():
    tree = ast.parse(open(_path("app")).read())
    (c,) = [n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "CompassApp"]
    assert c.end_lineno - c.lineno + 1 <= APP_CLASS_MAX, c.end_lineno - c.lineno + 1


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


def _host_modules():
    """{dotted name: path} of every module of the simulator (host_sim/) and the desktop tools
    (desktop/); a package by its own name ("desktop.benchmarks")."""
    out = {}
    for top in ("host_sim", "desktop"):
        for d, dirs, files in os.walk(os.path.join(ROOT, top)):
            dirs[:] = [x for x in dirs if not x.startswith((".", "__"))]
            pkg = os.path.relpath(d, ROOT).replace(os.sep, ".")
            for f in files:
                if f.endswith(".py"):
                    out[pkg if f == "__init__.py" else pkg + "." + f[:-3]] = os.path.join(d, f)
    return out


def _host_imports(path):
    """Every dotted name the file imports, at module level or inside a function: `import a.b`,
    `from a import b` (a and a.b: b may be a module), and `__import__(PREFIX + x)` resolved
    through the file's string constants (PREFIX + the text before a dot: chips.py's
    "qmc5883l.QMC5883LSim", desktop/__main__.py's command names)."""
    tree = ast.parse(open(path).read(), path)
    strings = {n.value for n in ast.walk(tree)
               if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0 and node.module, (path, node.lineno)  # absolute imports
            out.add(node.module)
            out.update(node.module + "." + a.name for a in node.names)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id == "__import__" and node.args):
            a = node.args[0]
            if isinstance(a, ast.Constant):
                out.add(a.value)
            elif (isinstance(a, ast.BinOp) and isinstance(a.left, ast.Constant)
                  and isinstance(a.left.value, str)):
                out.update(a.left.value + t.split(".")[0] for t in strings)
            else:
                out.add("?")   # a name this check cannot follow
    return out


def _host_graph():
    """{module: [the modules of host_sim and desktop it imports]}; importing a.b.c imports
    the packages a and a.b too (not counted for a module inside them)."""
    mods = _host_modules()
    g = {}
    for m, path in mods.items():
        deps = set()
        for d in _host_imports(path):
            parts = d.split(".")
            for k in range(1, len(parts) + 1):
                p = ".".join(parts[:k])
                if p in mods and p != m and not m.startswith(p + "."):
                    deps.add(p)
        g[m] = sorted(deps)
    return g


def _cycle(g):
    """An import cycle of graph g as a list of modules, or None."""
    state = {}

    def visit(m, path):
        if state.get(m) == 1:
            return path[path.index(m):] + [m]
        if state.get(m) == 2:
            return None
        state[m] = 1
        for d in g.get(m, ()):
            c = visit(d, path + [m])
            if c:
                return c
        state[m] = 2
        return None

    for m in sorted(g):
        c = visit(m, [])
        if c:
            return c
    return None


def test_the_cycle_check_finds_a_cycle():
    assert _cycle({"a": ["b"], "b": ["c"], "c": ["a"], "d": ["a"]}) == ["a", "b", "c", "a"]
    assert _cycle({"a": ["b", "c"], "b": ["c"], "c": []}) is None


def test_no_import_cycles_in_the_simulator_or_the_desktop_tools():
    g = _host_graph()
    # the graph is the real one: function-level and by-name imports are in it
    assert "desktop.plot" in g["desktop.demo"]                    # inside demo's _plot()
    assert "host_sim.qmc5883l" in g["host_sim.chips"]             # chips.model_class
    assert {"desktop.calibrate", "desktop.serve"} <= set(g["desktop.__main__"])
    assert g["host_sim.__main__"] == ["desktop", "desktop.__main__"]
    c = _cycle(g)
    assert c is None, "import cycle: " + " -> ".join(c)


def test_the_simulator_imports_nothing_of_desktop_firmware_boards_or_tests():
    # host_sim models hardware from datasheets; the desktop tools drive it and the firmware.
    # Its __main__.py only forwards `python -m host_sim` to desktop/__main__.py
    mods = _host_modules()
    sim = [m for m in mods if m.split(".")[0] == "host_sim"]
    assert len(sim) >= 15
    for m in sim:
        deps = _host_imports(mods[m])
        assert "?" not in deps, m
        bad = sorted(d for d in deps if d.split(".")[0] in ("desktop", "firmware", "boards",
                                                             "tests"))
        if m == "host_sim.__main__":
            assert bad == ["desktop.__main__", "desktop.__main__.main"], bad
        else:
            assert not bad, (m, bad)


def _cli_files():
    base = os.path.join(ROOT, "desktop")
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


# a function a reader takes in at once: longer ones are split into named steps
TOOL_FUNCTION_MAX = 80


def test_no_function_of_the_desktop_tools_is_over_80_lines():
    long_, n = [], 0
    for path in _cli_files():
        for node in ast.walk(ast.parse(open(path).read(), path)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n += 1
                lines = node.end_lineno - node.lineno + 1
                if lines > TOOL_FUNCTION_MAX:
                    long_.append("%s:%d %s (%d lines)" % (os.path.relpath(path, ROOT),
                                                          node.lineno, node.name, lines))
    assert n > 500   # every tool was read
    assert not long_, long_


def test_every_command_parses_its_arguments_with_the_one_shared_parser():
    from desktop import __main__ as runner
    for cmd in runner._COMMANDS:
        src = open(os.path.join(ROOT, "desktop", cmd + ".py")).read()
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


def _dropped():
    """Every module a drop() call in firmware/ or boards/ names by a string constant."""
    out = set()
    for folder in ("firmware", "boards"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, folder)):
            for f in files:
                if not f.endswith(".py"):
                    continue
                path = os.path.join(dirpath, f)
                for n in ast.walk(ast.parse(open(path).read(), path)):
                    if (isinstance(n, ast.Call) and isinstance(n.func, ast.Name)
                            and n.func.id == "drop"):
                        out.update(a.value for a in n.args
                                   if isinstance(a, ast.Constant) and isinstance(a.value, str))
    return out


# Modules with a job of their own that one module alone imports: what runner.py boots a board
# with, and the field model location.py evaluates. Every other dropped module that one module
# alone imports is that module's cold companion.
OWN_JOB = {"boot", "field.wmm"}
# The one companion with a shorter name, measured: any i2cdevice_<job> (i2cdevice_init, _boot,
# _up) raised the heap a finished session leaves (tests/test_budgets.py, after_session_slack_mpy)
# from 4.4 to 5.3 KB on the x86-32 build, over its 5 KB budget (docs/design.md, names).
SHORT = {"devinit": "i2cdevice"}


def test_cold_companions_are_named_owner_underscore_job():
    # A module loaded for one job of another module and dropped after it (construction, a
    # save, a chip's start-up) is named <owner>_<job>, beside its owner in its folder
    # (app_setup, app_persist, store_slots, gyro/attitude_setup, and devinit: SHORT; the kernels
    # attitude_plain / attitude_fast and trig_tables follow the same rule): docs/design.md, names.
    g = _graph()
    mods = set(g)
    importers = {m: {o for o in g if m in g[o]} for m in mods}
    dropped = _dropped()
    assert {"app_setup", "app_persist", "store_slots", "gyro.attitude_setup"} | set(SHORT) \
        <= dropped, sorted(dropped)
    for m in sorted(mods):
        folder, _, base = m.rpartition(".")
        owner = (folder + "." if folder else "") + base.split("_")[0]
        if "_" in base and owner in mods:  # named for a sibling: that sibling loads it
            assert owner in importers[m], (m, "is not loaded by", owner)
    for m in sorted(dropped & mods - OWN_JOB - set(DRIVERS)):  # a driver: detect's table names it
        folder = m.rpartition(".")[0]
        only = importers[m]
        if len(only) == 1 and next(iter(only)).rpartition(".")[0] == folder:
            owner = next(iter(only))
            assert m.startswith(owner + "_") or SHORT.get(m) == owner, (m, "companion of", owner)


OPENING_MAX = 15


def _opening_lines(path):
    """Lines of a module's opening block: the comments before its docstring, the docstring, and
    the comments after it up to the first line of code (blank lines not counted)."""
    lines = open(path).read().split("\n")
    n = 0

    def comments(i):
        c = 0
        while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
            c += lines[i].startswith("#")
            i += 1
        return i, c

    i, n = comments(0)
    if i < len(lines) and lines[i].lstrip().startswith(('"""', "'''")):
        q = lines[i].lstrip()[:3]
        j = i
        if not (lines[i].count(q) >= 2 and len(lines[i].strip()) > 3):
            j = i + 1
            while q not in lines[j]:
                j += 1
        n += j - i + 1
        i, c = comments(j + 1)
        n += c
    return n


def test_every_module_opens_with_at_most_15_lines():
    # what it is for, how to use it, where the reasoning is (docs/design.md, module notes;
    # docs/api.md): the reasoning lives once, in docs/
    long_ = {m: _opening_lines(_path(m)) for m in _modules(FW)}
    assert not {m: k for m, k in long_.items() if k > OPENING_MAX}, long_
    assert max(long_.values()) > 5  # the count sees comment lines


def test_the_opening_count_sees_a_docstring_and_the_comments_after_it(tmp_path):
    p = tmp_path / "m.py"
    p.write_text('# one\n"""two\nthree\n"""\n# five\n\n# six\nimport os\n# not counted\n')
    assert _opening_lines(str(p)) == 6


def _constants(m):
    """{NAME: (value, comment)} of the module-level constants of firmware module m: NAME =
    literal or NAME = const(literal), NAME in capitals (a leading _ allowed)."""
    path = _path(m)
    src = open(path).read()
    lines = src.split("\n")
    out = {}
    for node in ast.parse(src, path).body:
        if not (isinstance(node, ast.Assign) and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name)):
            continue
        name, v = node.targets[0].id, node.value
        if not re.fullmatch(r"_?[A-Z][A-Z0-9_]*", name):
            continue
        if (isinstance(v, ast.Call) and isinstance(v.func, ast.Name) and v.func.id == "const"
                and len(v.args) == 1):
            v = v.args[0]
        try:
            value = ast.literal_eval(v)
        except ValueError:
            continue  # computed, or a name of another module
        if value is None:
            continue  # module state set later (a kernel set)
        comment = lines[node.lineno - 1].partition("#")[2]
        out[name] = (value, comment)
    return out


# Copies kept on purpose, each with its reason; the test holds every copy equal to the others.
KEPT_COPIES = {
    # const() is inlined only where it is declared: imported, a number becomes a dictionary
    # look-up at every use, in per-sample code (the heading's and the filter's state slots)
    "_KANG_90": "inlined per sample", "_ROUND15": "inlined per sample",
    # a heading-only board must not load the calibrator for its defaults (tests above)
    "SOLVE_EVERY": "calibrator not loaded",
    # the same word in the vocabularies of different things: the WMM table file's, the
    # calibration record's and MotionCal's packet refusals; the app's status and the field
    # model's; a MotionCal packet and a stored record each 'bad_crc'
    "REASON_BAD_CRC": "own vocabulary", "REASON_BAD_MAGIC": "own vocabulary",
    "REASON_MISSING": "own vocabulary", "REASON_TRUNCATED": "own vocabulary",
    "REASON_UNKNOWN_VERSION": "own vocabulary", "STATUS_OK": "own vocabulary",
    "_OK": "own vocabulary",
    # each module's own shift for its own bound (health: |a|^2 < 3 * 2**22; mounting: of a
    # difference, < 3 * 2**24), equal by chance
    "_G_SHIFT": "own bound",
    # the field model's status word, where the field part is not loaded (accuracy, quickcal)
    "_BLACKOUT": "field part not loaded",
}
# the gyro-aided heading's state slots: declared in each of its modules so that they are
# inlined (tests/test_attitude.py checks the numbers agree)
ATTITUDE = {"gyro.attitude", "gyro.attitude_plain", "gyro.attitude_setup"}


def test_no_constant_is_declared_twice():
    where = {}
    for m in _modules(FW):
        for name, (value, _) in _constants(m).items():
            where.setdefault(name, []).append((m, value))
    copies = []
    for name, decl in sorted(where.items()):
        mods = {m for m, _ in decl}
        if len(mods) < 2:
            continue
        values = [v for _, v in decl]
        if name in KEPT_COPIES:
            assert all(v == values[0] for v in values), (name, decl)  # the copies agree
            continue
        same = [m for m, v in decl if values.count(v) > 1]
        if len(same) < 2 or set(same) <= set(DRIVERS) or set(same) <= ATTITUDE:
            continue  # a different value: another thing; drivers: each chip's datasheet
        copies.append((name, decl))
    assert not copies, copies


def test_a_constant_that_names_its_home_agrees_with_it():
    # `_X = "..."  # firmware.app.STATUS_X`: a copy where importing the home would load it
    # (a cold module, or an import cycle); it must equal the home's value
    consts = {m: _constants(m) for m in _modules(FW)}
    checked = 0
    for m, table in consts.items():
        for name, (value, comment) in table.items():
            for home, other in re.findall(r"firmware\.([a-z_.]+)\.([A-Z][A-Z0-9_]*)\b", comment):
                if home in consts and other in consts[home]:
                    assert consts[home][other][0] == value, (m, name, home, other)
                    checked += 1
    assert checked >= 4
