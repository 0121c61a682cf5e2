# Runs a board's main.py (argv[1]) on the simulated desktop board (boards/host/board.py) for
# argv[3] simulated seconds, with the calibration record in directory argv[2]; its output is
# the board's. Stops it by raising StopRun from the board's delay once the time is up.
import sys

sys.path.insert(0, "boards/host")
import board  # noqa: E402


class StopRun(BaseException):
    # not an Exception: CompassApp.step() turns every Exception into the status "internal
    # error" and goes on, but lets BaseException (KeyboardInterrupt, this) end the loop
    pass


main_py, store_dir, seconds = sys.argv[1], sys.argv[2], int(sys.argv[3])
board.STORE_DIR = store_dir
_delay = board.delay_us


def delay_us(us):
    if board.ticks_us() >= seconds * 1000000:
        raise StopRun()
    _delay(us)


board.delay_us = delay_us
try:
    exec(open(main_py).read())
except StopRun:
    print("stopped at %d s" % (board.ticks_us() // 1000000))
