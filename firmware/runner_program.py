"""The calibration program's turn at a board's start, for firmware/runner.py: whether it is due
(a request, the stored calibration) and running it, then a restart. The runner loads this at
boot and drops it before the heading's app is built, and loads it again to restart.
"""
#     what = asked()                         # the request file's word, read once
#     why, mag = due(i2c, what, cal_file)    # None: the heading now; mag: the chip it found
#     run(i2c, why)                          # the program alone, then restart()
# The request file: docs/design.md (memory, the calibration program); the program itself:
# firmware/calibrate/program.py.
import sys

import board
from firmware.compat import compiled_here, drop, drop_part, free_bytes

# calibrate(): the calibration program at the next start, even with a good calibration
REQUEST = board.STORE_DIR.rstrip("/") + "/calibrate.req"


def restart():
    """Start afresh: board.restart() where the board module has one (the simulated board),
    else the port's reset."""
    r = getattr(board, "restart", None)
    if r is None:
        import machine
        r = machine.reset
    r()


def restart_into(what):
    """A restart whose start reads `what` ("calibrate", "relearn", "skip": asked())."""
    with open(REQUEST, "w") as f:
        f.write(what)
    restart()


def asked():
    """The request's word, read once (a program cut short by a power cut is not run again)."""
    try:
        import os
        with open(REQUEST) as f:
            what = f.read(16)
        os.remove(REQUEST)
        return what
    except OSError:
        return None


def due(i2c, what, cal_file, mag_options=None, delay_us=None):
    """(why the program runs now or None, the magnetometer the boot check found or None).
    board.CALIBRATE "auto" (the default): when no good calibration is stored; "never": the
    board never calibrates itself (a desktop, MotionCal or browser calibration instead)."""
    if what == "skip":  # the program just said it could not run here: the heading now
        return None, None
    if what:
        return "asked", None
    if getattr(board, "CALIBRATE", "auto") != "auto":
        return None, None
    from firmware.boot import calibrated
    try:
        ok, mag = calibrated(i2c, board.STORE_DIR, cal_file=cal_file, delay_us=delay_us,
                             mag_options=mag_options)
        return (None if ok else "uncalibrated"), mag
    finally:
        calibrated = None
        drop("boot")


def _need_kb():
    try:
        drop_part("calibrate")  # the program's modules leave first, and a collection makes
        free_bytes()            # room for the figure's module (the failed one left it short)
        from firmware.status import PROGRAM_NEED_KB
        return PROGRAM_NEED_KB
    except MemoryError:
        return "?"


def _smaller():
    # what needs less heap than this install: .mpy files than .py sources, and a frozen or
    # ROMFS build (its bytecode in flash) than .mpy files (docs/install.md)
    if compiled_here(sys.modules.get(__name__)):
        return "use .mpy files (make deploy), a frozen or a ROMFS build"
    return "use a frozen or a ROMFS build (docs/install.md)"


def run(i2c, why, delay_us=None):
    """The calibration program alone (firmware/calibrate/program.py), then a restart: into
    the heading with its fit, or, when it could not run (said why), without running it again."""
    # asked for (`why`), any good fit may replace the stored one: a new mounting, new iron
    try:
        from firmware.calibrate.program import Program
        p = Program(i2c, board.STORE_DIR, mag_axes=board.MAG_AXES, accel_axes=board.ACCEL_AXES,
                    ticks_us_=getattr(board, "ticks_us", None), delay_us=delay_us,
                    renew=why == "asked")
        Program = None
        # the accelerometer as its driver names it (firmware/detect.py CHIPS), else yes / no
        print("eCompass: calibrating (%s, accelerometer %s): turn the board through a figure-8, "
              "over and around" % (p.mag.KIND,
                                   getattr(p.accel, "NAME", "yes") if p.accel else "no"))
        if p.run() is not None:
            restart()  # into the heading, with the calibration just saved
        print("eCompass: the calibration program ran out of memory (%s KB free at a solve): "
              "it needs ~%s KB of heap; %s, or calibrate on the desktop or in the browser "
              "(docs/calibration.md)"
              % (p.free_at_solve // 1024 if p.free_at_solve else "?", _need_kb(), _smaller()))
    except ImportError:
        print("eCompass: cannot calibrate on the board: install package-calibrate.json "
              "(or calibrate on the desktop: docs/calibration.md)")
        return
    except MemoryError:
        p = Program = None
        print("eCompass: the calibration program needs ~%s KB of heap, more than this board "
              "has: %s, or calibrate on the desktop or in the browser (docs/calibration.md)"
              % (_need_kb(), _smaller()))
    p = Program = None
    restart_into("skip")  # a clean heap for the heading
