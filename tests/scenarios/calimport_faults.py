# The boot-time calibration import under faults, on every interpreter: each case writes
# calibration.json (or makes reading it fail), imports it into a store holding a good
# calibration and prints [case, refused, renamed .rejected, the store's calibration kept,
# what the message starts with]; then a good file is imported. import_calibration must
# never raise (tests/test_calimport.py).
import json
import os
import sys

from firmware.calfile import calimport
from firmware.calibration import Calibration
from firmware.store import CalStore

d = "build/calimport_faults_%s" % sys.implementation.name
try:
    os.mkdir("build")
except OSError:
    pass
try:
    os.mkdir(d)
except OSError:
    pass
for n in os.listdir(d):
    os.remove(d + "/" + n)


class Mag:
    KIND, range_code, counts_per_gauss = "qmc5883l", 0, 12000


store = CalStore(d)
old = Calibration(model=4, offset=(1, 2, 3), field=5000, field_out=5000, fit_error=500,
                  samples=90, coverage=50)
store.save(old.to_bytes())
path = d + "/calibration.json"
read = calimport._read


def fail(e):
    def f(p):
        raise e
    return f


def case(name, data, reader=None):
    with open(path, "wb") as f:
        f.write(data)
    calimport._read = reader or read
    try:
        r = calimport.import_calibration(path, store, Mag())
    finally:
        calimport._read = read
    kept = Calibration.from_bytes(store.load()) == old
    renamed = path + ".rejected" in [d + "/" + n for n in os.listdir(d)]
    if renamed:
        os.remove(path + ".rejected")
    print(json.dumps([name, r is not None and r[0] is False, renamed, kept,
                      r[1].split(" ")[0] if r else None]))


case("deep_nesting", b"[" * 200000)
case("not_utf8", b'{"format": "\xff\xfe\x80"}')
case("no_memory", b"{}", fail(MemoryError()))
case("eio", b"{}", fail(OSError(5)))
good = {"format": "ecompass-calibration", "version": 1, "sensor": "qmc5883l", "range_code": 0,
        "model": 10, "offset_counts": [5400, -4200, 3600],
        "invw_q15": [27000, -2000, 1300, -2000, 29000, -1500, 1300, -1500, 28000],
        "field_counts": 6000, "field_out_counts": 5900, "fit_error_x100": 120, "samples": 220,
        "coverage_percent": 80}
with open(path, "w") as f:
    f.write(json.dumps(good))
r = calimport.import_calibration(path, store, Mag())
print(json.dumps(["good", r[0] is False, r[0] is True,
                  Calibration.from_bytes(store.load()) == old, r[1].split(" ")[0]]))
