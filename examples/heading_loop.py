"""A heading loop: the app with its status line (calibrates itself while you turn the board).

    python3 examples/heading_loop.py [SECONDS]    # on the host: a simulated figure-8
    from examples.heading_loop import run; run()  # on a board: forever

firmware/app.py does everything: it finds the chips, loads the stored calibration (none
here: store=None), collects and solves in the background, and shows the tilt-compensated
heading. status_line() says what it is doing.
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.app import CompassApp, status_line


def run(seconds=None, seed=1, declination_cdeg=0):
    i2c, delay_us = get_bus(seed)
    if delay_us is None:  # a board: its own clock
        app = CompassApp(i2c, declination_cdeg=declination_cdeg)
        steps = None
    else:  # the simulator: its clock moves when the drivers wait
        # get_bus() imported the simulated board (boards/host/board.py)
        import board
        app = CompassApp(i2c, delay_us=delay_us, ticks_us=board.ticks_us,
                         declination_cdeg=declination_cdeg)
        steps = seconds * 50 if seconds else None  # 50 Hz
    app.run(steps, report=lambda a: print(status_line(a)), every=250)
    return app


if __name__ == "__main__":
    run(int(sys.argv[1]) if len(sys.argv) > 1 else None)
