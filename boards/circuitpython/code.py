"""eCompass on CircuitPython: runs at boot (code.py), the same app as boards/main.py.

Prints a status line every 0.5 s; calibrates as you move (turn the board through a figure-8).
The drivers reach busio.I2C through firmware/circuitpython/busio_i2c.py; the clock and the drivers' sleeps
come from firmware/compat.py (CircuitPython has neither machine nor time.ticks_us). An accepted
calibration is saved to CIRCUITPY when boot.py made it writable for code (see boot.py);
otherwise it is used until the next reset and the status line counts the failed saves.
"""
import time

import wiring
from firmware.app import CompassApp, status_line
from firmware.store import CalStore

i2c = wiring.make_i2c()
while True:
    try:
        app = CompassApp(i2c, mag_axes=wiring.MAG_AXES, accel_axes=wiring.ACCEL_AXES,
                         declination_cdeg=wiring.DECLINATION_CDEG,
                         store=CalStore(wiring.STORE_DIR),
                         # None on the board (firmware.compat's clock and sleep); the
                         # simulated board of the tests brings its own clock
                         delay_us=getattr(wiring, "delay_us", None),
                         ticks_us=getattr(wiring, "ticks_us", None))
        break
    except OSError as e:  # SensorNotFound, BusError: wiring or power; say so and retry
        print("eCompass: %s" % e)
        time.sleep(2)
print("eCompass: %s, accelerometer %s, stored calibration: %s" % (
    app.mag.KIND, getattr(app.accel, "NAME", "yes") if app.accel else "no",
    app.load_reason or "loaded"))
app.run(None, report=lambda a: print(status_line(a)), every_us=500000)
