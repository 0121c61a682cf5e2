"""CircuitPython boards (Raspberry Pi Pico, Adafruit Feather RP2040 / ESP32-S3): the wiring.

CircuitPython has its own `board` module (the pin map), so this file goes onto the CIRCUITPY
drive as ecompass_board.py, firmware/ into lib/, and boards/main.py as code.py with its
`import board` changed to `import ecompass_board as board` (docs/design.md, CircuitPython).
Only what differs per board lives here.

GY-271 / GY-273 / GY-87 breakout -> Pico: VCC 3V3(OUT) pin 36, GND pin 38, SDA GP4 (pin 6),
SCL GP5 (pin 7). Feather (STEMMA QT / the SDA, SCL pins): board.SDA, board.SCL.
"""
import board as _pins

BREAKOUT = "gy271"          # sensor mounting: see boards/breakouts.py (gy271, gy273, gy87)
MAG_AXES = "x,-y,-z"        # the same mounting table as boards/rp2040/board.py
ACCEL_AXES = "-x,y,z"
DECLINATION_CDEG = 0        # local magnetic declination, centidegrees east-positive
STORE_DIR = "/"             # the drive must be writable by code: see docs/design.md
I2C_FREQ = 400000


def _pin(names):
    for n in names:
        p = getattr(_pins, n, None)
        if p is not None:
            return p
    raise ValueError("no pin named %s on this board" % " or ".join(names))


def make_i2c():
    """busio.I2C on the board's I2C pins, wrapped so the drivers see machine.I2C's calls."""
    import busio
    from firmware.busio_i2c import BusioI2C
    scl = _pin(("SCL", "GP5"))
    sda = _pin(("SDA", "GP4"))
    return BusioI2C(busio.I2C(scl, sda, frequency=I2C_FREQ))
