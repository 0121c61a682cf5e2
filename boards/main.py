"""eCompass: runs at boot (main.py). Prints a status line every 0.5 s.

First run (no good stored calibration): the calibration program runs alone. Turn the board
through a figure-8 (every direction: over and around) while its progress line shows coverage,
samples and the fit; once a fit is saved and read back, hold it still: the board restarts into
the heading, which starts from the stored calibration at every boot (docs/calibration.md).
A calibration file (calibration.json) copied beside the store is imported at boot, once.

From the REPL (Ctrl-C stops the compass): calibrate() restarts into the calibration program,
motioncal() streams to PJRC MotionCal. In board.py: MODE = "motioncal" (docs/motioncal.md),
GYRO = True (the MPU6050's gyroscope holds the heading: docs/gyro.md), CALIBRATE = "never"
(the board never calibrates itself). The code is firmware/runner.py.
"""
from firmware.runner import calibrate, motioncal, run  # noqa: F401 - REPL calls

run()
