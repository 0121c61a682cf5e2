"""CircuitPython boot.py: may code.py write the calibration to CIRCUITPY?

CIRCUITPY is writable by the computer over USB or by code.py, never both (two writers would
corrupt it). With wiring.STORE_JUMPER tied to GND at power-up, code.py may write (and the
computer sees the drive read-only); without the jumper the drive stays the computer's, and a
calibration lasts until the next reset.
"""
import board
import digitalio
import storage

import wiring

jumper = digitalio.DigitalInOut(getattr(board, wiring.STORE_JUMPER))
jumper.switch_to_input(pull=digitalio.Pull.UP)
storage.remount("/", readonly=jumper.value)  # pulled up (no jumper): read-only for code.py
jumper.deinit()
