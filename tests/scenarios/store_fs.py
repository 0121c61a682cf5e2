# Round trip through the real filesystem of the interpreter, in the directory given as argv[1]:
# save twice, load, corrupt the newest slot, load the older, save again, erase.
# Prints JSON lines without paths, so CPython and MicroPython print the same.
import json
import sys

from firmware.store import CalStore
from firmware.errors import StoreError

d = sys.argv[1]
A = bytes(range(50))
B = bytes(range(60, 10, -1))


def reason_of_load(store):
    try:
        store.load()
        return "loaded"
    except StoreError as e:
        return e.reason


st = CalStore(directory=d, sensor="qmc5883l", range_code=0)
st.erase()
print(json.dumps(["empty", reason_of_load(st)]))
print(json.dumps(["saved", st.save(A), st.save(B)]))
st2 = CalStore(directory=d)
p = st2.load()
print(json.dumps(["load", st2.seq, p == B]))
f = open(st2.path, "rb")
data = bytearray(f.read())
f.close()
data[40] ^= 0x55
f = open(st2.path, "wb")
f.write(data)
f.close()
st3 = CalStore(directory=d)
p = st3.load()
print(json.dumps(["corrupted_newest", st3.seq, p == A, st3.last_skipped[0][1]]))
s3 = st3.save(B)
st4 = CalStore(directory=d)
p = st4.load()
print(json.dumps(["resaved", s3, st4.seq, p == B]))
st4.erase()
print(json.dumps(["erased", reason_of_load(CalStore(directory=d))]))
