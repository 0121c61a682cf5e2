"""Gyro-aided heading: the MPU6050's gyroscope holds the heading while a magnet passes.

    python3 examples/gyro_heading.py [SECONDS]    # on the host: the simulated board
    from examples.gyro_heading import run; run()  # on a board: forever

On a board this is the heading loop with app.use_gyro() (docs/gyro.md): bring a magnet or a
motor near the sensor and the status says "gyro held" (with how long and how well) instead of
"interference", and the heading stays right. On the host the simulated GY-271 + GY-521 turns
through figure-8s and calibrates itself (~25 s), lies still for 5 s (the gyro's bias is
measured), then turns slowly while a magnet fixed in the room comes within range from 40 to
45 s; one line a second.
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.app import CompassApp, status_line


def run(seconds=None, seed=1):
    i2c, delay_us = get_bus(seed)
    if delay_us is None:  # a board: its own clock, forever
        app = CompassApp(i2c)
        app.use_gyro()
        app.run(None, report=lambda a: print(status_line(a)), every_us=1000000)
        return app
    # get_bus() imported the simulated board (boards/host/board.py)
    import board
    from host_sim import motion
    w = board.sim.world
    # the figure-8 until 30 s (it ends level), still until 35 s, then a slow turn (2 deg/s)
    yaw = w.motion.at(30000000)[0]
    w.motion = motion.sequence([(30, w.motion), (5, motion.still(yaw=yaw)),
                                (600, motion.arc(yaw, yaw + 1200, 600))])
    w.add_magnet((6.0, 6.0, 3.0), 40, 45, ramp_s=0.5, frame="world")  # ~9 uT
    app = CompassApp(i2c, delay_us=delay_us, ticks_us=board.ticks_us)
    app.use_gyro()
    app.run(seconds * 50 if seconds else None, report=lambda a: print(status_line(a)),
            every_us=1000000)
    return app


if __name__ == "__main__":
    run(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
