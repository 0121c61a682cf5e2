# MicroPython only: what one Attitude.update() allocates (firmware/gyro/attitude.py), over the
# integer inputs of attitude_inputs (every path: corrections, rejections, recovery, still
# windows, a slow loop's chunks). Prints one JSON object: bytes (micropython.mem_total delta
# over all the updates, call frames on the heap included) and locked (updates run under
# heap_lock).
import json
from array import array

import micropython

from firmware.gyro import attitude
from tests.scenarios import attitude_inputs as I

N = 1500
a, gyro, grav, field, c = I.filter()
a.update(20000, 7)
# the inputs first (their generator allocates), 10 ints a sample
tab = array("i", bytearray(4 * 10 * N))
for i in range(N):
    I.step(i, gyro, grav, field)
    j = 10 * i
    for k in range(3):
        tab[j + k] = gyro[k]
        tab[j + 3 + k] = grav[k]
        tab[j + 6 + k] = field[k]
    tab[j + 9] = I.flags(i)
upd = a.update
own = attitude.gravity
st = a.st
mt = micropython.mem_total


def feed(j):
    gyro[0] = tab[j]
    gyro[1] = tab[j + 1]
    gyro[2] = tab[j + 2]
    grav[0] = tab[j + 3]
    grav[1] = tab[j + 4]
    grav[2] = tab[j + 5]
    field[0] = tab[j + 6]
    field[1] = tab[j + 7]
    field[2] = tab[j + 8]


i = 0
m0 = mt()
while i < N:
    feed(10 * i)
    upd(20000 if i % 7 else 70000, tab[10 * i + 9])
    own(st, grav)  # the app's predict(): the filter's gravity in place of a bumped one
    i += 1
m1 = mt()
locked = 0
micropython.heap_lock()
try:
    i = 0
    while i < N:
        feed(10 * i)
        upd(20000, tab[10 * i + 9])
        own(st, grav)
        i += 1
        locked += 1
except MemoryError:
    pass
micropython.heap_unlock()
print(json.dumps({"bytes": m1 - m0, "updates": N, "locked": locked}))
