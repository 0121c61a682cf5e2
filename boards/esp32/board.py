"""ESP32 DevKit (ESP32-WROOM-32) wiring. Only what differs per board lives here.

GY-271 / GY-273 / GY-87 breakout -> ESP32: VCC 3V3, GND GND, SCL GPIO22, SDA GPIO21
(the pins most ESP32 tutorials use; any free GPIO works with hardware I2C 0).
"""
I2C_ID = 0
SCL_PIN = 22
SDA_PIN = 21
I2C_FREQ = 400000           # Hz; QMC5883L, HMC5883L and MPU6050 are all 400 kHz parts
BREAKOUT = "gy271"          # sensor mounting: see boards/breakouts.py (gy271, gy273, gy87,
#                             gy9250, gy91, icm20948: their MAG_AXES differ)
MAG_AXES = "x,-y,-z"        # sensor -> body of BREAKOUT's magnetometer (boards/breakouts.py;
ACCEL_AXES = "-x,y,z"       # a GY-521 MPU6050 lying the same way; tests/test_app.py checks both)
DECLINATION_CDEG = 0        # local magnetic declination, centidegrees east-positive (NOAA/WMM)
MODE = "compass"            # "compass": headings, self-calibrating; "motioncal": stream to
#                             PJRC MotionCal and take its Send Cal (docs/motioncal.md)
GYRO = False                # True: the MPU6050's gyroscope holds the heading through magnets
#                             and fast turns (docs/gyro.md; package-gyro.json installed)
STORE_DIR = "/"             # where the calibration record lives (LittleFS on the internal flash)


def make_i2c():
    from machine import I2C, Pin
    return I2C(I2C_ID, scl=Pin(SCL_PIN), sda=Pin(SDA_PIN), freq=I2C_FREQ)
