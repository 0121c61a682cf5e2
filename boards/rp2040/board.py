"""Raspberry Pi Pico (RP2040) wiring. Only what differs per board lives here.

GY-271 / GY-273 / GY-87 breakout -> Pico: VCC 3V3(OUT) pin 36, GND pin 38,
SDA GP4 (pin 6), SCL GP5 (pin 7) — I2C0's default pins.
"""
I2C_ID = 0
SCL_PIN = 5
SDA_PIN = 4
I2C_FREQ = 400000           # Hz
BREAKOUT = "gy271"          # sensor mounting: see boards/breakouts.py (gy271, gy273, gy87,
#                             gy9250, gy91, icm20948: their MAG_AXES differ)
MAG_AXES = "x,-y,-z"        # sensor -> body of BREAKOUT's magnetometer (boards/breakouts.py;
ACCEL_AXES = "-x,y,z"       # a GY-521 MPU6050 lying the same way; tests/test_app.py checks both)
DECLINATION_CDEG = 0        # local magnetic declination, centidegrees east-positive (NOAA/WMM)
MODE = "compass"            # "compass": headings, self-calibrating; "motioncal": stream to
#                             PJRC MotionCal and take its Send Cal (docs/motioncal.md)
GYRO = False                # True: the MPU6050's gyroscope holds the heading through magnets
#                             and fast turns (docs/gyro.md; package-gyro.json installed)
STORE_DIR = "/"             # LittleFS on the Pico's flash


def make_i2c():
    from machine import I2C, Pin
    return I2C(I2C_ID, scl=Pin(SCL_PIN), sda=Pin(SDA_PIN), freq=I2C_FREQ)
