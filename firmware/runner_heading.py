"""The heading's loop of a board, for firmware/runner.py: what was found, then app.run() with
the status line every 0.5 s (or MotionCal mode), for good. Loaded once the app is built, so
that neither the calibration program nor the app's construction holds it.
"""
#     from firmware import runner_heading
#     runner_heading.run(app)        # for good (a restart into the program may end it)
#
# What the board prints and why: docs/calibration.md; the memory it saves: docs/design.md#memory.
import sys

import board
from firmware import compat
from firmware.app import status_line, status_view  # (loaded with the app)
from firmware.compat import compiled_here, drop, drop_part, free_bytes

_PY_SHORT_KB = 96  # free heap below which a board running from .py sources is told so
_out = getattr(sys.stdout, "buffer", sys.stdout)


def announce(app, gyro=True):
    """What was found, and what the board will do (one line each)."""
    if app.no_memory is not None:
        print("eCompass: %s" % status_line(app))
    else:
        print("eCompass: %s, accelerometer %s, stored calibration: %s" % (
            app.mag.KIND, getattr(app.accel, "NAME", "yes") if app.accel else "no",
            app.load_reason or "loaded"))
    f = free_bytes()
    kb = f // 1024 if f is not None else -1
    if compiled_here(sys.modules.get("firmware.app")) and kb < _PY_SHORT_KB:
        print("eCompass: running from .py sources, %d KB free: .mpy files (make deploy) or "
              "a frozen build need much less heap (docs/design.md, memory)" % kb)
    if gyro and getattr(board, "GYRO", False):
        try:
            app.use_gyro()  # docs/gyro.md: status "gyro held" while it holds the heading
            print("eCompass: gyro-aided heading on")
        except (ImportError, ValueError, MemoryError) as e:  # no part; no MPU6050; no room
            print("eCompass: no gyro-aided heading: %s" % (e or "out of memory"))


def _report(a):
    # the status line from the buffer firmware/status.py keeps: no garbage every half second
    try:
        _out.write(status_view(a))
        _out.write(b"\n")
    except MemoryError:  # no room to print this one: the next report tries again
        pass


def motioncal(app, rate_hz=50):
    """MotionCal mode on this app until Ctrl-C (firmware/motioncal/mode.py)."""
    MotionCalMode = compat.need("motioncal.mode", "motioncal()").MotionCalMode
    kbd_intr = compat.kbd_intr  # 0x03 in MotionCal's packet is data
    try:
        MotionCalMode(app, rate_hz=rate_hz, mag_axes=board.MAG_AXES, kbd_intr=kbd_intr,
                      ticks_us=getattr(board, "ticks_us", None)).run()
    finally:  # MotionCal mode is done: its code leaves (docs/design.md, memory)
        if app.collector is None:
            drop_part("motioncal")
            drop("calibrate.acceptance", "calibrate.solve")
        else:
            drop_part("motioncal")


def run(app, motioncal_mode=False):
    """What was found, then the heading's loop (or board.MODE "motioncal": MotionCal mode) for
    good."""
    try:
        announce(app, not motioncal_mode)
    except MemoryError:  # the board runs on; its status line says the rest
        pass
    if motioncal_mode:
        motioncal(app)
        return
    while True:
        try:
            app.run(None, report=_report, every_us=500000)
        except MemoryError:  # step() never raises; the loop's own bookkeeping: go on
            pass
        if app.relearn_due and getattr(board, "CALIBRATE", "auto") != "never":
            print("eCompass: the calibration no longer fits the board and no session fits "
                  "beside the heading: restarting into the calibration program")
            from firmware import runner_program
            runner_program.restart_into("relearn")
