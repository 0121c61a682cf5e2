"""eCompass: runs at boot (main.py). Prints a status line every 0.5 s; calibrates as you move.

At boot a calibration file CAL_FILE (calibration.json) is imported into the store, once.
First run: no stored calibration, so the heading is raw until you turn the board through a
figure-8 (every direction: over and around); the line shows coverage and samples grow, then
"model 4" or "model 10" once a calibration is accepted - it is saved and used at every boot.

board.MODE = "motioncal": stream to PJRC MotionCal instead and take its Send Cal
(docs/motioncal.md). From the REPL (Ctrl-C stops the compass loop): motioncal().
board.GYRO = True: the MPU6050's gyroscope holds the heading through magnets and fast turns
(docs/gyro.md).
"""
import time

import board
from firmware.app import status_line
from firmware.boot import start
from firmware.compat import drop

# A calibration fitted on the desktop (python -m host_sim calibrate LOG --sensor ... --out
# calibration.json) copied here is imported once at boot (docs/calibration.md).
CAL_FILE = getattr(board, "CALIBRATION_FILE", None) or (
    board.STORE_DIR.rstrip("/") + "/calibration.json")

MOTIONCAL = getattr(board, "MODE", "compass") == "motioncal"
i2c = board.make_i2c()
# None on a real board (time.sleep_us, time.ticks_us); the simulated board (boards/host)
# brings its own clock
delay_us = getattr(board, "delay_us", None)
while True:
    try:
        # MotionCal mode: an HMC5883L at 75 Hz for 50 Raw lines/s (the QMC chips take no rate)
        app, note = start(i2c, board.STORE_DIR, cal_file=CAL_FILE,
                          mag_options={"rate": 75} if MOTIONCAL else None, delay_us=delay_us,
                          mag_axes=board.MAG_AXES, accel_axes=board.ACCEL_AXES,
                          declination_cdeg=board.DECLINATION_CDEG,
                          ticks_us=getattr(board, "ticks_us", None),
                          # MotionCal mode: its calibration, not the app's own
                          learn=False if MOTIONCAL else None)
        if note is not None:
            print("eCompass: %s" % note)
        break
    except OSError as e:  # SensorNotFound, BusError: wiring or power; say so and retry
        print("eCompass: %s" % e)
        time.sleep(2)
start = None
drop("boot")  # a running board holds only what it runs (docs/design.md, memory)
print("eCompass: %s, accelerometer %s, stored calibration: %s" % (
    app.mag.KIND, "yes" if app.accel else "no", app.load_reason or "loaded"))
if getattr(board, "GYRO", False) and not MOTIONCAL:
    try:
        app.use_gyro()  # docs/gyro.md: status "gyro held" while it holds the heading
        print("eCompass: gyro-aided heading on")
    except (ImportError, ValueError) as e:  # the gyro part not installed; no MPU6050
        print("eCompass: no gyro-aided heading: %s" % e)


def motioncal(rate_hz=50):
    """MotionCal mode on this app until Ctrl-C (firmware/motioncal_mode.py)."""
    from firmware.motioncal_mode import MotionCalMode
    try:
        from micropython import kbd_intr  # 0x03 in MotionCal's packet is data
    except ImportError:
        kbd_intr = None
    try:
        MotionCalMode(app, rate_hz=rate_hz, mag_axes=board.MAG_AXES, kbd_intr=kbd_intr,
                      ticks_us=getattr(board, "ticks_us", None)).run()
    finally:  # MotionCal mode is done: its code leaves (docs/design.md, memory)
        if app.collector is None:
            drop("motioncal_mode", "motioncal", "acceptance", "solve")
        else:
            drop("motioncal_mode", "motioncal")


if MOTIONCAL:
    motioncal()
else:
    app.run(None, report=lambda a: print(status_line(a)), every_us=500000)
