"""Calibrate at the REPL: collect samples while you turn the board, then solve.

    python3 examples/calibrate_repl.py [SECONDS]                # on the host: a figure-8
    from examples.calibrate_repl import calibrate; calibrate()  # on a board: turn it 30 s

Every raw sample goes to a Calibrator (firmware/calibrate/calibrator.py), which keeps the ones that are
new information; solve() returns a Calibration or says why not (too few samples, planar: turn
the board over, ...). The result is the record the app stores (hard iron V, InvW in Q15).
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.calibrate.calibrator import Calibrator
from firmware.detect import detect
from firmware.errors import CalibrationRejected


def calibrate(seconds=30, seed=1, every_us=20000):
    i2c, delay_us = get_bus(seed)
    mag = detect(i2c, delay_us=delay_us) if delay_us else detect(i2c)
    sleep = delay_us
    if sleep is None:
        import time
        sleep = time.sleep_us
    cal = Calibrator(model=10, counts_per_gauss=mag.counts_per_gauss)
    buf = [0, 0, 0]
    for _ in range(seconds * 1000000 // every_us):
        mag.read_into(buf)
        cal.add(buf[0], buf[1], buf[2])
        sleep(every_us)
    print("%d samples held, %d %% of the sphere covered" % (cal.count, cal.coverage()))
    try:
        c = cal.solve()
    except CalibrationRejected as e:
        print("refused: %s" % e)
        return None
    print("model %s: V = %s counts, field %d counts, fit error %d.%02d %%" % (
        c.model, c.offset, c.field, c.fit_error // 100, c.fit_error % 100))
    return c


if __name__ == "__main__":
    calibrate(int(sys.argv[1]) if len(sys.argv) > 1 else 30)
