"""eCompass firmware: magnetometer calibration (AN4246) and tilt-compensated heading (AN4248).

Integer-only, dependency-free, and the same bits on CPython, the MicroPython unix port and a
32-bit board. See README.md for the API.
"""
__version__ = "0.1.0"
