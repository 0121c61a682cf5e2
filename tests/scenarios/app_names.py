# How many names each object a GY-87 app holds has in its attribute table, while collecting and
# with the gyro-aided heading: tests/test_tables.py counts them on CPython and asserts that
# MicroPython's count is the same (the tables' sizes are MicroPython's). Last, on MicroPython,
# the names in the table of each of their classes and its bases (a method is found there).
import json
import sys

sys.path.insert(0, "tests/scenarios")
from app_world import make_app, make_sim, run_until  # noqa: E402


def counts(app):
    objs = {"app": app, "health": app.health, "watch": app.watch, "dip": app.dip,
            "compass": app.compass, "mag": app.mag, "accel": app.accel}
    if app.collector is not None:
        objs.update(collector=app.collector, calibrator=app.collector.calibrator,
                    session=app._session)
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


def classes(objs):
    out, todo = {}, [type(o) for o in objs]
    while todo:
        c = todo.pop()
        if c is not object and c.__name__ not in out:
            out[c.__name__] = len(c.__dict__)
            todo.extend(c.__bases__)
    return sorted(out.items())


if sys.implementation.name == "micropython":  # (CPython's class tables are other)
    b = make_sim("gy87")
    app2 = make_app(b)
    run_until(app2, b, 2.0)
    print(json.dumps(classes([app2, app2.health, app2.watch, app2.dip, app2.compass, app2.mag,
                              app2.accel, app2.collector, app2.collector.calibrator,
                              app2._session, app.attitude])))
