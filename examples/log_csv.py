"""Log raw magnetometer samples to a CSV file on the board's flash, bounded in size.

    python3 examples/log_csv.py [PATH] [MAX_BYTES]    # on the host (simulated board)
    from examples.log_csv import log; log()           # on a board: writes /mag_log.csv

Turn the board through figure-8s while it logs; copy the file to the desktop
(`mpremote cp :mag_log.csv .`) and fit it there:
`python3 -m host_sim calibrate mag_log.csv --out calibration.json` (the file's first line
names the chip and its range, which calibrate reads).
Stops when the next row would pass MAX_BYTES (default 16 KB, about 900 rows).
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.detect import detect


def log(path="mag_log.csv", max_bytes=16384, every_us=20000, seed=1):
    i2c, delay_us = get_bus(seed)
    mag = detect(i2c, delay_us=delay_us) if delay_us else detect(i2c)
    sleep = delay_us
    if sleep is None:
        import time
        sleep = time.sleep_us
    buf = [0, 0, 0]
    rows = 0
    with open(path, "w") as f:
        head = "# %s range_code %d counts_per_gauss %d\nmx,my,mz\n" % (
            mag.KIND, mag.range_code, mag.counts_per_gauss)
        f.write(head)
        size = len(head)
        while True:
            mag.read_into(buf)
            line = "%d,%d,%d\n" % (buf[0], buf[1], buf[2])
            if size + len(line) > max_bytes:
                break
            f.write(line)
            size += len(line)
            rows += 1
            sleep(every_us)
    print("logged %d rows, %d bytes to %s (%s)" % (rows, size, path, mag.KIND))
    return rows


if __name__ == "__main__":
    a = sys.argv[1:]
    log(a[0] if a else "mag_log.csv", int(a[1]) if len(a) > 1 else 16384)
