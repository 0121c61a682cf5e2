# Runs a board's main.py (argv[1]) on the simulated desktop board (boards/host/board.py) for
# argv[3] simulated seconds, with the calibration record in directory argv[2]; its output is
# the board's. argv[4], if given: the accelerometer module beside the magnetometer, an IMUS
# kind of host_sim/chips.py (board.ACCEL; the board's GY-521 otherwise). Stops it by raising
# StopRun from the board's delay once the time is up.
# board.restart() (main.py's restart after the calibration program) runs main.py afresh on a
# new simulated board (its clock from 0, the same iron and store), as a reset would: at most
# three times; "restarted at T s" marks each.
import sys

sys.path.insert(0, "boards/host")
import board  # noqa: E402


class StopRun(BaseException):
    # not an Exception: CompassApp.step() turns every Exception into the status "internal
    # error" and goes on, but lets BaseException (KeyboardInterrupt, this) end the loop
    pass


main_py, store_dir, seconds = sys.argv[1], sys.argv[2], int(sys.argv[3])
board.STORE_DIR = store_dir
if len(sys.argv) > 4:
    board.ACCEL = sys.argv[4]
_delay = board.delay_us


def delay_us(us):
    if board.ticks_us() >= seconds * 1000000:
        raise StopRun()
    _delay(us)


class Restart(BaseException):
    pass


def restart():
    raise Restart()


board.delay_us = delay_us
board.restart = restart
for _ in range(4):
    try:
        exec(open(main_py).read(), {"__name__": "__main__"})
    except StopRun:
        print("stopped at %d s" % (board.ticks_us() // 1000000))
        break
    except Restart:
        print("restarted at %d s" % (board.ticks_us() // 1000000))
