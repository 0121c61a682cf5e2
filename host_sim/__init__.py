"""host_sim: an independent register-level simulator of the eCompass hardware.

The hardware's mirror, built from the datasheets (docs/hardware.md and each model's docstring), never from the
firmware: clock.py (integer microseconds), prng.py (deterministic noise), bus.py (SimI2C, a
machine.I2C look-alike with bus timing and fault injection), world.py (Earth's field,
gravity, orientation, hard/soft iron, magnets), motion.py (motion scripts), one model per
chip (qmc5883l.py, hmc5883l.py, qmc5883p.py, ak8963.py, ak09916.py, mpu6050.py with the
MPU-9250, icm20948.py), chips.py (the table of them) and boards.py (make_board).
Runs unchanged, bit for bit, on CPython and the MicroPython unix port. It imports nothing of
firmware/ or desktop/ (the desktop tools, which drive it); __main__.py only forwards
`python -m host_sim COMMAND` to desktop/__main__.py.
"""
