"""CircuitPython board wiring (Raspberry Pi Pico, or any Feather). Only what differs per board.

Named wiring.py, not board.py as on the MicroPython boards: CircuitPython's own `board` module
(the pin names used below) is built in, and a board.py on CIRCUITPY would not replace it.

GY-271 / GY-273 / GY-87 breakout -> Pico: VCC 3V3(OUT) pin 36, GND pin 38, SDA GP4 (pin 6),
SCL GP5 (pin 7). -> a Feather (RP2040, M4, ESP32-S2/S3...): VCC 3V, GND, SDA and SCL pins (or
the STEMMA QT connector, the same bus). The pins are looked up by name in the `board` module:
SCL_PIN/SDA_PIN when the board has them, else its SCL/SDA.
"""
SCL_PIN = "GP5"             # the Pico's I2C0 pins; a Feather has none, so SCL/SDA are used
SDA_PIN = "GP4"
I2C_FREQ = 400000           # Hz; QMC5883L, HMC5883L and MPU6050 are all 400 kHz parts
LOCK_TIMEOUT_US = 50000     # the longest wait for the bus lock (firmware/circuitpython/busio_i2c.py)
MAG_AXES = "x,-y,-z"        # sensor -> body: a GY-271/273/87 flat, X arrow forward (another
ACCEL_AXES = "-x,y,z"       # mounting: boards/breakouts.py); a GY-521 MPU6050 lying the same way
#                             (GY-9250, GY-91, ICM-20948, LIS2MDL: other MAG_AXES, breakouts.py)
DECLINATION_CDEG = 0        # local magnetic declination, centidegrees east-positive (NOAA/WMM)
STORE_DIR = "/"             # CIRCUITPY; code may write there only when boot.py allows it
STORE_JUMPER = "GP15"       # boot.py: to GND at power-up, code.py may save ("D5" on a Feather)


def pins(board):
    """(scl, sda) of the `board` module: SCL_PIN/SDA_PIN if it has them, else SCL/SDA."""
    if hasattr(board, SCL_PIN) and hasattr(board, SDA_PIN):
        return getattr(board, SCL_PIN), getattr(board, SDA_PIN)
    return board.SCL, board.SDA


def make_i2c():
    import board
    import busio
    from firmware.circuitpython.busio_i2c import BusioI2C
    scl, sda = pins(board)
    return BusioI2C(busio.I2C(scl, sda, frequency=I2C_FREQ), lock_timeout_us=LOCK_TIMEOUT_US)
