"""MicroPython only: the live heap each firmware module adds when it is imported, in the order a
board imports them (what a calibrated board needs to show a heading first, then the
calibration machinery). From .py source or .mpy files the module's bytecode is on the heap;
from a ROMFS image (or frozen) it stays in flash and what remains is the module's objects:
its dict, function and class objects, module-level tables, and the names (qstrs) it interns.

python -m desktop.benchmarks.modheap [IMAGE --romfs]   (one JSON line)
"""
import gc
import sys

from desktop.benchmarks import common

# what a calibrated board holds while it shows headings (tests/test_layout.py CORE), then the
# status line it prints, then what it loads for a job and drops after it
HEADING = ("compat", "errors", "fixedpoint", "i2cdevice", "trig", "trig_tables", "axes",
           "calibration", "compass", "health", "fieldwatch", "learning", "store", "mpu6050",
           "qmc5883l", "app")
REPORT = ("status", "accuracy")
MACHINERY = ("boot", "detect", "app_setup", "app_persist", "store_slots", "calibrate.session",
             "calibrate.history", "calibrate.samples", "calibrate.accum", "calibrate.solve",
             "calibrate.acceptance", "calibrate.calibrator", "hmc5883l", "qmc5883p",
             "field.location", "field.wmm", "field.quickcal", "motioncal.protocol",
             "motioncal.mode", "calfile.calimport", "gyro.attitude_setup", "gyro.attitude",
             "calibrate.mounting", "calibrate.mountcheck", "mountnote")


def live():
    gc.collect()
    return gc.mem_alloc()


def main():
    if not hasattr(gc, "mem_alloc"):
        common.emit({"interpreter": common.interpreter(), "skipped": "needs gc.mem_alloc"})
        return
    if "--romfs" in sys.argv:
        import vfs
        with open(sys.argv[1], "rb") as f:
            rom = f.read()
        vfs.mount(vfs.VfsRom(rom), "/rom")
        sys.path.insert(0, "/rom")
    out = {}
    prev = live()
    for name in HEADING + REPORT + MACHINERY:
        __import__("firmware." + name)
        now = live()
        out[name] = now - prev
        prev = now
    common.emit({"interpreter": common.interpreter(), "modules": out,
                 "heading": sum(out[n] for n in HEADING),
                 "report": sum(out[n] for n in REPORT),
                 "machinery": sum(out[n] for n in MACHINERY)})


if __name__ == "__main__":
    main()
