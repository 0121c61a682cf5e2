# Freeze the eCompass firmware into a custom MicroPython build (bytecode runs from flash: less RAM).
# In a MicroPython checkout:
#   cd ports/rp2   && make BOARD=RPI_PICO   FROZEN_MANIFEST=/abs/path/to/this/manifest.py
#   cd ports/esp32 && make BOARD=ESP32_GENERIC FROZEN_MANIFEST=/abs/path/to/this/manifest.py
# Then copy only boards/<board>/board.py and boards/main.py to the board's filesystem.
# Install what you use: keep in PARTS the parts your board needs ("core" always; README.md's
# install section gives the heap of each). The field part's table (firmware/wmm2025.bin) is a
# data file, not frozen: copy it to the board and pass its path to set_location(table=...).
PARTS = ("core", "calibrate", "motioncal", "field", "import")

# part -> the firmware modules in it (the same files as package-PART.json;
# tests/test_packaging.py checks both against host_sim/cli/packaging.py)
_FILES = {
    'core': ('__init__.py', 'compat.py', 'errors.py', 'fixedpoint.py', 'i2cdevice.py', 'devinit.py', 'detect.py', 'qmc5883l.py', 'qmc5883p.py', 'hmc5883l.py', 'mpu6050.py', 'axes.py', 'calibration.py', 'kang_tables.py', 'trig.py', 'compass.py', 'health.py', 'fieldwatch.py', 'store.py', 'slots.py', 'persist.py', 'appsetup.py', 'app.py', 'status.py', 'accuracy.py', 'boot.py', 'fast.py', 'mountnote.py'),
    'calibrate': ('session.py', 'calibrator.py', 'samples.py', 'accum.py', 'solve.py', 'acceptance.py', 'history.py', 'calmode.py', 'mounting.py', 'mountcheck.py'),
    'motioncal': ('motioncal.py', 'motioncal_mode.py'),
    'field': ('field.py', 'location.py', 'quickcal.py'),
    'import': ('calimport.py',),
    'gyro': ('attitude.py', 'attitude_plain.py', 'attitude_fast.py', 'gyrosetup.py'),
    'circuitpython': ('busio_i2c.py',),
}

include("$(PORT_DIR)/boards/manifest.py")
package("firmware", files=[f for p in PARTS for f in _FILES[p]])
