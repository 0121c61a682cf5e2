# Parity: MotionCal mode (firmware/motioncal/mode.py) on the simulated GY-87, on CPython and
# MicroPython alike: 3 s of Raw lines with packets arriving on the way (garbage, a good one, a
# damaged one, one whose first float holds 0x03, a lone Ctrl-C). Packets are built from
# float32 bit patterns, so no float is involved. Prints one JSON list per event (tenths of a
# second, status, applied, bad CRCs, V) and a
# summary (lines, bytes and a CRC of everything the board wrote, the tenths of a second at
# the Ctrl-C, kbd_intr calls, garbage, the calibration, saves, the store's file sizes).
# Lists only: the two interpreters order a dict's keys differently.
import json
import sys

sys.path.append("tests/scenarios")
from app_world import MemFs, make_app, make_sim  # noqa: E402

from firmware.motioncal import protocol as mc  # noqa: E402
from firmware.motioncal.mode import MotionCalMode  # noqa: E402
from firmware.store import CalStore  # noqa: E402

ONE = 0x3F800000


def packet(v_bits, b_bits, diag=(ONE, ONE, ONE), off=(0, 0, 0)):
    words = [0] * 6 + list(v_bits) + [b_bits] + list(diag) + list(off)
    p = bytearray(68)
    p[0] = 117
    p[1] = 84
    for i in range(16):
        for k in range(4):
            p[2 + 4 * i + k] = (words[i] >> (8 * k)) & 0xFF
    c = mc.crc16(p, 66)
    p[66] = c & 0xFF
    p[67] = c >> 8
    return bytes(p)


GOOD = packet((0x41480000, 0xC0E80000, 0x41F00000), 0x42400000)   # 12.5, -7.25, 30; 48 uT
CTRL_C = packet((0x40400003, 0, 0), 0x42400000)                   # V x = 3.0000002 uT
DAMAGED = bytearray(GOOD)
DAMAGED[40] ^= 1
SCHEDULE = ((0.5, b"junk\r\n" + GOOD[:20]), (0.6, GOOD[20:]), (1.5, bytes(DAMAGED)),
            (2.0, CTRL_C), (2.5, b"\x03"))

b = make_sim("gy87", seed=5)
fs = MemFs()
app = make_app(b, store=CalStore("/", fs=fs), learn=False)
out = bytearray()
inbox = []
kbd = []
mode = MotionCalMode(app, write=out.extend, poll=lambda: inbox.pop(0) if inbox else b"",
                     ticks_us=b.clock.ticks_us, kbd_intr=kbd.append)
mode.start()
todo = list(SCHEDULE)
interrupted = None
while b.clock.now_us < 3000000:
    if todo and b.clock.now_us >= int(todo[0][0] * 1000000):
        inbox.append(todo.pop(0)[1])
    last = (mode.applied, mode.bad_crc)
    try:
        mode.step()
    except KeyboardInterrupt:
        interrupted = b.clock.now_us // 100000
        break
    if (mode.applied, mode.bad_crc) != last:
        print(json.dumps([b.clock.now_us // 100000, mode.status, mode.applied, mode.bad_crc,
                          list(app.calibration.offset)]))
cal = app.calibration
print(json.dumps([mode.lines, len(out), mc.crc16(out, len(out)), interrupted, kbd,
                  mode.garbage, cal.model, list(cal.invw), cal.field, cal.field_out,
                  app.stored, sorted([len(v) for v in fs.files.values()])]))
