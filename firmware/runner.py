"""What boards/main.py runs: the calibration program or the heading, and the calls a REPL
user makes (calibrate(), motioncal()). Its code is a module of the firmware, so a board loads
it as bytecode instead of compiling a long main.py at every boot."""
# run()        boot: a board without a good stored calibration runs the calibration program
#              (firmware/calibrate/program.py, launched by firmware/runner_program.py) and
#              restarts; otherwise the app shows headings (its status line every 0.5 s) or,
#              board.MODE = "motioncal", streams to MotionCal (firmware/runner_heading.py).
# calibrate()  from the REPL: restart into the calibration program.
# motioncal()  from the REPL: MotionCal mode on the running app until Ctrl-C.
# `board` is the board's own module (boards/<board>/board.py): pins, axes, STORE_DIR, and on
# the simulated board its clock and restart().
import board
from firmware import compat
from firmware.compat import drop, free_bytes, sleep_us

app = None  # the CompassApp, once the heading runs
_mag = None  # the magnetometer the boot check found: the app takes it over

# A calibration fitted on the desktop (python -m host_sim calibrate LOG --sensor ... --out
# calibration.json) copied here is imported once at boot (docs/calibration.md).
CAL_FILE = getattr(board, "CALIBRATION_FILE", None) or (
    board.STORE_DIR.rstrip("/") + "/calibration.json")

MOTIONCAL = getattr(board, "MODE", "compass") == "motioncal"
# None on a real board (time.sleep_us, time.ticks_us); the simulated board (boards/host)
# brings its own clock
delay_us = getattr(board, "delay_us", None)


def wait_s(s):
    if delay_us is not None:
        delay_us(s * 1000000)
    else:
        sleep_us(s * 1000000)


def free_kb():
    f = free_bytes()  # after a collection; None where the port does not tell
    return f // 1024 if f is not None else -1


def calibrate():
    """From the REPL (Ctrl-C stops the compass): restart into the calibration program."""
    from firmware import runner_program  # (the program's turn: firmware/runner_program.py)
    runner_program.restart_into("calibrate")


def _boot():
    # the heading's app (or the calibration program first, which restarts the board)
    global app, _mag
    from firmware import runner_program as rp  # the program's turn: gone before the app
    what = rp.asked()
    checked = MOTIONCAL  # the program is considered once a start (the boot loop retries)
    while True:
        try:
            i2c = board.make_i2c()
            if not checked:
                # the boot check and the program run the plain kernels (same bits):
                # firmware.fast and its tables stay out of the program's heap
                compat.FAST = False
                why, _mag = rp.due(i2c, what, CAL_FILE, {"rate": 75} if MOTIONCAL else None,
                                   delay_us)
                checked = True
                if why:
                    _mag = None
                    rp.run(i2c, why, delay_us)  # restarts, unless calibrate is not installed
                    i2c = board.make_i2c()
                compat.FAST = True
            rp = None
            drop("runner_program")
            from firmware.boot import start
            # MotionCal mode: an HMC5883L at 75 Hz for 50 Raw lines/s (the QMC chips take no rate)
            app, note = start(i2c, board.STORE_DIR, cal_file=CAL_FILE,
                              mag_options={"rate": 75} if MOTIONCAL else None, delay_us=delay_us,
                              mag_axes=board.MAG_AXES, accel_axes=board.ACCEL_AXES,
                              declination_cdeg=board.DECLINATION_CDEG,
                              ticks_us=getattr(board, "ticks_us", None),
                              # MotionCal mode: its calibration, not the app's own
                              learn=False if MOTIONCAL else None, mag=_mag)
            _mag = None
            if note is not None:  # (said before a retry: the file is imported once)
                print("eCompass: %s" % note)
            if app.no_memory == "start":  # the app did not fit: again from a clean heap
                app = None
                raise MemoryError
            break
        except OSError as e:  # SensorNotFound, BusError: wiring or power; say so and retry
            print("eCompass: %s" % e)
            wait_s(2)
        except MemoryError:  # not even the app fits: say so, and what to do, and try again
            start = None
            drop("app", "boot", "detect", "app_setup", "devinit", "store", "app_persist", "store_slots")
            print("eCompass: out of memory at boot (%d KB free): use the .mpy or frozen "
                  "install (docs/design.md, memory)" % free_kb())
            wait_s(5)
        except Exception as e:  # noqa: BLE001 - a board keeps running and says why
            print("eCompass: cannot start: %s %s" % (type(e).__name__, e))
            wait_s(5)
    start = None
    drop("boot")  # a running board holds only what it runs (docs/design.md, memory)


def motioncal(rate_hz=50):
    """MotionCal mode on the running app until Ctrl-C (firmware/motioncal/mode.py)."""
    from firmware import runner_heading
    runner_heading.motioncal(app, rate_hz)


def run():
    """Boot, then the heading's loop (or MotionCal mode) for good."""
    _boot()
    from firmware import runner_heading  # (once the app is built: firmware/runner_heading.py)
    runner_heading.run(app, MOTIONCAL)
