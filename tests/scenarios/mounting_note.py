# CPython and MicroPython: the mounting check's verdict kept beside the store and read back at
# boot (firmware/mountnote.py save, load), on an in-memory filesystem with a stand-in app: the
# line written, what each setting reads back, and what torn or corrupt lines read back (none).
# tests/test_mounting_reboot.py compares the output of both interpreters.
import json
import sys

from firmware import app_persist, mountnote
from firmware.health import Health
from firmware.calibration import Calibration
from firmware.axes import AxisMap
from firmware.store_slots import crc32
from firmware.store import CalStore
from desktop.memfs import MemFs


class Mag:
    KIND = "hmc5883l"
    range_code = 0


class App:
    def __init__(self, store, mag_axes, accel_axes="-x,y,z"):
        self.health = Health()  # what keeps a verdict (Health.mounted)
        self.store = store
        self.mag = Mag()
        self._mag_map = AxisMap(mag_axes)
        self._acc_map = AxisMap(accel_axes)

    @property
    def mounting(self):  # as CompassApp reads it
        return self.health.mounting


def recall(fs, mag_axes, accel_axes="-x,y,z"):
    a = App(CalStore("/", fs=fs), mag_axes, accel_axes)
    if path in fs.files:
        mountnote.load(a, fs.files[path][:80])  # as firmware/app_persist.py reads it
    return [a.mounting and list(a.mounting), a.health.axes_status]


fs = MemFs()
path = "/ecompass_mounting.txt"
a = App(CalStore("/", fs=fs), "x,-y,-z")
a.health.mounting = ("wrong", "y,x,-z")
mountnote.save(a)
line = fs.files[path]
print(json.dumps(["line", line.decode()]))
for axes in ("x,-y,-z", "y,x,-z", "-y,-x,-z"):
    print(json.dumps(["setting", axes, recall(fs, axes)]))
print(json.dumps(["other accel", recall(fs, "x,-y,-z", "y,x,z")]))
for n in range(len(line)):
    fs.files[path] = line[:n]
    r = recall(fs, "x,-y,-z")
    if r != [None, None]:
        print(json.dumps(["torn", n, r]))
for i in range(len(line)):
    for bit in (1, 4, 64):
        fs.files[path] = line[:i] + bytes([line[i] ^ bit]) + line[i + 1:]
        r = recall(fs, "x,-y,-z")
        if r != [None, None]:
            print(json.dumps(["flipped", i, bit, r]))
for text in (b"wrong hmc5883l x,y,z -x,y,z y,x,-z", b"wrong hmc5883l x,-y,-z -x,y,z y,\xff,-z",
             b"wrong hmc5883l x,-y,-z -x,y,z x,-y,-z", b"ok hmc5883l x,-y,-z -x,y,z y,x,-z",
             b"wrong hmc5883l x,-y,-z x,y,z y,x,-z", b"wrong hmc5883l  x,-y,-z -x,y,z y,x,-z"):
    fs.files[path] = text + ("%08x\n" % crc32(text)).encode()
    print(json.dumps(["line", len(text), recall(fs, "x,-y,-z")]))
# through the store's load at boot (firmware/app_persist.py: the code loaded by its name, dropped)
a.health.mounting = ("wrong", "y,x,-z")
mountnote.save(a)
CalStore("/", sensor="hmc5883l", fs=fs).save(Calibration(
    model=10, offset=(100, -200, 300), invw=(30000, 0, 0, 0, 30000, 0, 0, 0, 30000), field=600,
    field_out=590, fit_error=100, samples=200, coverage=80, dip_kang=10923).to_bytes())
for axes in ("x,-y,-z", "y,x,-z", "-y,-x,-z"):
    b = App(CalStore("/", fs=fs), axes)
    cal, why = app_persist.load(b)  # (the app keeps why as .load_reason)
    print(json.dumps(["boot", axes, why, cal.model, cal.dip_kang,
                      b.mounting and list(b.mounting), b.health.axes_status,
                      "firmware.mountnote" in sys.modules]))
a.health.mounting = ("ok", "x,-y,-z")
mountnote.save(a)
print(json.dumps(["after ok", path in fs.files, recall(fs, "x,-y,-z")]))
