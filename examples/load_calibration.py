"""Load a calibration file (the desktop tool's --out) into the board's store, once.

    python -m host_sim calibrate mag_log.csv --sensor qmc5883l --out calibration.json
    mpremote cp calibration.json :calibration.json        # then, on the board:
    import examples.load_calibration

    python examples/load_calibration.py FILE [STORE_DIR]  # on the host (simulated board)

firmware/calimport.py checks the file against the chip found (sensor kind, range) and the
record's meaning, stores it, and renames the file to FILE.imported (FILE.rejected when it is
refused: the store is untouched). boards/main.py does the same at every boot.
"""
import sys

from examples.bus import get_bus
from firmware.calimport import import_calibration
from firmware.detect import detect
from firmware.store import CalStore


def load(path="calibration.json", store_dir="/", seed=1):
    i2c, delay_us = get_bus(seed)
    mag = detect(i2c, delay_us=delay_us) if delay_us else detect(i2c)
    store = CalStore(store_dir, sensor=mag.KIND, range_code=mag.range_code)
    r = import_calibration(path, store, mag)
    if r is None:
        print("no calibration file at %s" % path)
    else:
        print("%s: %s" % ("imported" if r[0] else "refused", r[1]))
    return r


if __name__ == "__main__":
    a = sys.argv[1:]
    load(a[0] if a else "calibration.json", a[1] if len(a) > 1 else "/")
