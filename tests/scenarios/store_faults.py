# Store faults and the history check, through app_world's in-memory filesystem: an
# unreadable newest slot, a directory in slot b (saves go to the spare), a CRC-valid record
# that means nothing valid, an app booting on it, a MemoryError during the app's save, and a
# hard-iron jump judged by firmware.calibrate.history. Prints JSON lines of ints and strings only, so
# CPython and MicroPython print the same (tests/test_store_faults.py compares them).
import json
import struct
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.calibration import Calibration  # noqa: E402
from firmware.errors import StoreError  # noqa: E402
from firmware.calibrate.history import FLAG_ACCEPTED, History  # noqa: E402
from firmware.store import CalStore  # noqa: E402


def store(fs, validate=None):
    return CalStore("/", sensor="qmc5883l", range_code=0, fs=fs, validate=validate)


def cal(fit_error=120, v=(5400, -4200, 3600), field=6000):
    return Calibration(model=10, offset=v, invw=(27000, -2000, 1300, -2000, 29000, -1500,
                                                 1300, -1500, 28000),
                       field=field, field_out=5900, fit_error=fit_error, samples=220,
                       coverage=80)


def bad_payload():
    b = bytearray(cal().to_bytes())
    b[38:42] = struct.pack("<i", -5)   # B < 0: CRC-valid, meaningless
    return bytes(b)


fs = W.MemFs()
store(fs).save(cal(fit_error=110).to_bytes())
store(fs).save(cal(fit_error=100).to_bytes())
fs.bad["/ecompass_b.cal"] = "eio"
st = store(fs)
st.load()
print(json.dumps(["eio_newest", st.seq, st.last_skipped[0][1]]))

fs.bad["/ecompass_b.cal"] = "dir"
seqs = [st.save(cal(fit_error=90 - i).to_bytes()) for i in range(3)]
st2 = store(fs)
st2.load()
print(json.dumps(["dir_saves", seqs, st2.path]))

fs = W.MemFs()
store(fs).save(cal(fit_error=90).to_bytes())
store(fs).save(bad_payload())
st = store(fs, validate=Calibration.from_bytes)
st.load()
print(json.dumps(["bad_payload", st.seq, st.last_skipped[0][1]]))

b = W.make_sim("gy271", m=W.motion.still(30.0, 10.0, -5.0), seed=5)
app = W.make_app(b, store=CalStore("/", fs=fs))
print(json.dumps(["app_boot", app.load_reason, app.calibration.fit_error, app.step()]))

fs = W.MemFs()
fs.nomem = 0
b = W.make_sim("gy271", seed=5)
app = W.make_app(b, store=CalStore("/", fs=fs))
while not app.accepted:
    app.step()
print(json.dumps(["app_nomem", app.save_reason, app.save_errors, app.stored]))

fs = W.MemFs()
h = History(store(fs))
for i in range(5):
    h.check(cal(v=(5400 + 7 * i, -4200 - 3 * i, 3600 + i)))
    h.own = None  # a new session each time
    h.record(cal(v=(5400 + 7 * i, -4200 - 3 * i, 3600 + i)), FLAG_ACCEPTED, 1000 * i)
h2 = History(store(fs))
j = h2.check(cal(v=(7400, -4200, 3600)))
print(json.dumps(["history", j[0], j[1], j[2], j[3], [e[0] for e in h2.entries]]))
try:
    store(W.MemFs()).load()
except StoreError as e:
    print(json.dumps(["empty", e.reason]))
