"""The I2C bus for the examples: machine.I2C on a board, the simulator on a desktop.

    from examples.bus import get_bus
    i2c, delay_us = get_bus()   # delay_us: None on a board (the drivers use time.sleep_us)

On a board edit the pins below (boards/<board>/board.py has them). On the host the bus is a
simulated GY-271 + GY-521 being turned through figure-8s (boards/host/board.py); delay_us
then advances its clock, so pass it to the drivers.
"""
SCL, SDA, FREQ = 5, 4, 400000   # Raspberry Pi Pico GP5/GP4; ESP32 DevKit: 22, 21


def _repo():
    # the folder holding examples/ (string operations: MicroPython has no os.path)
    f = __file__.replace("\\", "/")
    d = f[:f.rfind("/")] if "/" in f else "."
    return d + "/.."


def get_bus(seed=1):
    try:
        from machine import I2C, Pin
    except ImportError:  # a desktop: the simulated board, boards/host beside examples/
        import sys
        sys.path.insert(0, _repo() + "/boards/host")
        import board
        return board.make_i2c(seed=seed), board.delay_us
    return I2C(0, scl=Pin(SCL), sda=Pin(SDA), freq=FREQ), None
