"""Every object an app holds keeps spare slots in its attribute table (firmware/compat.py room,
docs/design.md, memory: attribute tables).

MicroPython's tables (py/map.c) grow through fixed sizes and only when full, and a method call
looks its name up in the instance's table first, probing until an empty slot: a full table of
59 names made each of the app's method calls probe all 59 (a fifth of the step's time on the
unix port: make bench's app-step rows, docs/benchmarks.md). The sizes are MicroPython's and
the names are counted here on CPython (the unix port holds the same: checked below), and no
firmware object deletes an attribute (checked below), whose marker slot probes would pass over.
"""
import ast
import pathlib

import pytest

from firmware.compat import ROOM_NAMES
from tests.scenarios import app_world

ROOT = pathlib.Path(__file__).resolve().parent.parent
# py/map.c hash_allocation_sizes: the table an instance holds after n names is the first >= n
SIZES = (0, 2, 4, 6, 8, 10, 12, 17, 23, 29, 37, 47, 59, 73, 97, 127, 167, 223, 293)
SMALL = 12     # a table this small costs at most 12 probes: not checked
FULL_PCT = 85  # the most a checked table may be filled


def slots(n):
    return next(s for s in SIZES if s >= n)


def held(app):
    """(path, object) of every firmware object reachable from the app (instances only)."""
    seen, out, todo = set(), [], [("app", app)]
    while todo:
        path, o = todo.pop()
        if id(o) in seen or not type(o).__module__.startswith("firmware"):
            continue
        seen.add(id(o))
        d = getattr(o, "__dict__", None)
        if d is None or isinstance(o, type):
            continue
        out.append((path, o))
        for k, v in d.items():
            if k not in ROOM_NAMES:
                todo.append((path + "." + k, v))
    return out


def crowded(app):
    bad = []
    for path, o in held(app):
        n = len(vars(o))
        if n > SMALL and n * 100 > FULL_PCT * slots(n):
            bad.append("%s (%s): %d names in %d slots" % (path, type(o).__name__, n, slots(n)))
    return bad


@pytest.mark.parametrize("setup", sorted(app_world.ALL_SETUPS))
def test_the_objects_an_app_holds_keep_room(setup):
    b = app_world.make_sim(setup)
    app = app_world.make_app(b)
    assert app.collector is not None  # uncalibrated: a session beside the heading line
    app_world.run_until(app, b, 2.0)
    assert crowded(app) == []
    if getattr(app.accel, "gyro_ready", None) is not None or setup == "gy87":
        app.use_gyro()
    app_world.run_until(app, b, 120.0)
    assert app.collector is None, app.status  # the session ended
    assert crowded(app) == []


def test_the_rule_sees_a_full_table():
    class Full:
        pass
    from firmware.compat import room
    o = Full()
    for i in range(59):
        setattr(o, "a%d" % i, i)
    assert slots(len(vars(o))) == 59
    room(o)
    assert len(vars(o)) == 60 and slots(60) == 73  # grown: 60 of 73 slots
    room(o)  # again: nothing to do
    assert len(vars(o)) == 60
    for n, grown in ((12, 12), (14, 14), (15, 18), (40, 48), (50, 50), (73, 74)):
        o = Full()
        for i in range(n):
            setattr(o, "a%d" % i, i)
        room(o)
        assert len(vars(o)) == grown, n
        assert len(vars(o)) <= SMALL or len(vars(o)) * 100 <= FULL_PCT * slots(len(vars(o)))


def test_no_firmware_object_deletes_an_attribute():
    # a deleted name leaves a marker slot that probes pass over like a name: the counts
    # above would not be the table's
    found = []
    for p in sorted((ROOT / "firmware").rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Delete) and any(isinstance(t, ast.Attribute)
                                                    for t in node.targets):
                found.append("%s:%d" % (p.relative_to(ROOT), node.lineno))
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "delattr" \
                    and p.name != "compat.py":  # (compat.drop: a module's name)
                found.append("%s:%d" % (p.relative_to(ROOT), node.lineno))
    assert found == []


def test_micropython_holds_the_same_names_and_the_classes_keep_room():
    # the counts above are CPython's: the unix port's must be the same, object by object
    from tests import mp
    argv = ["tests/scenarios/app_names.py"]
    collecting, gyro = mp.json_lines(mp.run(argv, micro=False))
    assert dict(collecting)["calibrator"] > SMALL and dict(gyro)["attitude"] > SMALL
    on_mp = mp.json_lines(mp.run(argv, micro=True))
    assert on_mp[:2] == [collecting, gyro]
    # a method call that misses the instance's table finds the method in its class's
    # (or a base's): the same probing, so a class's table keeps the same room (room(cls));
    # the unix port's last line (CPython's class tables are other)
    classes = on_mp[2]
    names = dict(classes)
    assert {"CompassApp", "SampleBuffer", "Calibrator", "Attitude", "LIS3MDL", "AK8963",
            "MMC5603"} <= set(names) and names["CompassApp"] > SMALL
    bad = ["%s: %d names in %d slots" % (c, n, slots(n)) for c, n in classes
           if n > SMALL and n * 100 > FULL_PCT * slots(n)]
    assert bad == []


def test_no_firmware_object_has_an_attribute_named_as_room_fills_its_table():
    # room()'s spare slots take builtins' names (firmware/compat.py ROOM_NAMES): set on an
    # object that uses one of them, a spare slot would overwrite it
    found = []
    for p in sorted((ROOT / "firmware").rglob("*.py")):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in ROOM_NAMES:
                found.append("%s:%d .%s" % (p.relative_to(ROOT), node.lineno, node.attr))
            elif isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name in ROOM_NAMES:
                found.append("%s:%d %s" % (p.relative_to(ROOT), node.lineno, node.name))
    assert found == []
