# How many names each object a GY-87 app holds has in its attribute table, while collecting and
# with the gyro-aided heading: tests/test_tables.py counts them on CPython and asserts that
# MicroPython's count is the same (the tables' sizes are MicroPython's). Last, on MicroPython,
# the names in the table of each class (and its bases) of every firmware object an app holds
# while collecting, on every board, and with the gyro (a method is found there).
import json
import sys

sys.path.insert(0, "tests/scenarios")
from app_world import make_app, make_sim, run_until  # noqa: E402


def counts(app):
    objs = {"app": app, "health": app.health, "watch": app.watch, "dip": app.dip,
            "compass": app.compass, "mag": app.mag, "accel": app.accel}
    if app.collector is not None:
        objs.update(collector=app.collector, calibrator=app.collector.calibrator,
                    session=app.learning.session)
    if app.attitude is not None:
        objs["attitude"] = app.attitude
    return sorted((k, len(o.__dict__)) for k, o in objs.items())


b = make_sim("gy87")
app = make_app(b)
run_until(app, b, 2.0)
print(json.dumps(counts(app)))
app.use_gyro()
run_until(app, b, 20.0)
print(json.dumps(counts(app)))


def firmware_classes():
    # every class a loaded firmware module defines or imports (MicroPython's classes name no
    # module)
    from array import array
    out = set()
    for name, m in sorted(sys.modules.items()):
        if name.startswith("firmware"):
            for k in dir(m):
                v = getattr(m, k)
                if isinstance(v, type) and v not in (array, type(sys)):
                    out.add(v)
    return out


def classes(app, out):
    # the tables of the classes of every firmware object the app holds, and their bases'
    ours, seen, todo = firmware_classes(), set(), [app]
    while todo:
        o = todo.pop()
        c = type(o)
        if id(o) in seen or c not in ours:
            continue
        seen.add(id(o))
        for k in dir(o):  # (instance names and class names: values that are firmware objects)
            if not k.startswith("__"):
                v = getattr(o, k, None)
                if type(v) in ours and not isinstance(v, type):
                    todo.append(v)
        while c is not object:
            out[c.__name__] = len(c.__dict__)
            c = c.__bases__[0]


if sys.implementation.name == "micropython":  # (CPython's class tables are other)
    from app_world import ALL_SETUPS  # noqa: E402
    found = {}
    for setup in sorted(ALL_SETUPS):
        b = make_sim(setup)
        a = make_app(b)
        run_until(a, b, 2.0)  # collecting: the session's objects too
        classes(a, found)
        if setup == "gy87":
            a.use_gyro()
            run_until(a, b, 3.0)
            classes(a, found)
    print(json.dumps(sorted(found.items())))
