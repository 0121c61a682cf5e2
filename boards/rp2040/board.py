"""Raspberry Pi Pico (RP2040) wiring. Only what differs per board lives here.

GY-271 / GY-273 / GY-87 breakout -> Pico: VCC 3V3(OUT) pin 36, GND pin 38,
SDA GP4 (pin 6), SCL GP5 (pin 7) — I2C0's default pins.
"""
I2C_ID = 0
SCL_PIN = 5
SDA_PIN = 4
I2C_FREQ = 400000           # Hz
MAG_AXES = "x,-y,-z"        # sensor -> body: a GY-271/273/87 flat, X arrow forward (another
ACCEL_AXES = "-x,y,z"       # mounting: boards/breakouts.py); a GY-521 MPU6050 lying the same way
#                             (GY-9250, GY-91, ICM-20948, LIS2MDL: other MAG_AXES, breakouts.py)
DECLINATION_CDEG = 0        # local magnetic declination, centidegrees east-positive (NOAA/WMM)
MODE = "compass"            # "compass": headings, self-calibrating; "motioncal": stream to
#                             PJRC MotionCal and take its Send Cal (docs/motioncal.md)
GYRO = False                # True: the MPU6050's gyroscope holds the heading through magnets
#                             and fast turns (docs/gyro.md; package-gyro.json installed)
CALIBRATE = "auto"          # "auto": a board without a good stored calibration runs the
#                             calibration program at boot; "never": it never calibrates itself
STORE_DIR = "/"             # LittleFS on the Pico's flash


def make_i2c():
    from machine import I2C, Pin
    return I2C(I2C_ID, scl=Pin(SCL_PIN), sda=Pin(SDA_PIN), freq=I2C_FREQ)
