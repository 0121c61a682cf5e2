"""Load a calibration file (the desktop tool's --out) into the board's store, once.

    python3 -m host_sim calibrate mag_log.csv --out calibration.json  # the log names its chip
    mpremote cp calibration.json :calibration.json        # then, on the board:
    from examples.load_calibration import load; load()

    python3 examples/load_calibration.py FILE [STORE_DIR]  # on the host (simulated board)

STORE_DIR (default /, the board's root) is made when it does not exist (one level).
Exit status as a script: 0 imported; 1 refused (or the store could not save it); 2 no file
at FILE, or no folder for the store. What went wrong is printed on stderr.

firmware/calfile/calimport.py checks the file against the chip found (sensor kind, range) and the
record's meaning, stores it, and renames the file to FILE.imported (FILE.rejected when it is
refused: the store is untouched). boards/main.py does the same at every boot.
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.calfile.calimport import import_calibration
from firmware.detect import detect
from firmware.store import CalStore


def _store_folder(d):
    """None when folder `d` exists or was made now; else what to do, in a line."""
    import os
    try:
        if os.stat(d)[0] & 0o170000 == 0o040000:
            return None
        return "%s is a file, not a folder: give the folder for the store" % d
    except OSError:
        pass
    try:
        os.mkdir(d)
    except OSError as e:
        return "cannot create the store folder %s (%s): create it first" % (d, e)
    print("created the store folder %s" % d)
    return None


def load(path="calibration.json", store_dir="/", seed=1):
    """None (no file), (True, 'imported ...') or (False, 'rejected ...' / 'not imported ...'),
    as firmware.calimport.import_calibration; the message is printed as it comes."""
    why = _store_folder(store_dir)
    if why is not None:
        print("not imported: %s" % why, file=sys.stderr)
        return False, why
    i2c, delay_us = get_bus(seed)
    mag = detect(i2c, delay_us=delay_us) if delay_us else detect(i2c)
    store = CalStore(store_dir, sensor=mag.KIND, range_code=mag.range_code)
    r = import_calibration(path, store, mag)
    if r is None:
        print("no calibration file at %s" % path, file=sys.stderr)
    else:
        print(r[1], file=sys.stdout if r[0] else sys.stderr)
    return r


def status(r):
    """The script's exit status for load()'s result (the module docstring)."""
    if r is not None and r[0]:
        return 0
    if r is not None and r[1].startswith(("rejected ", "not imported ")):
        return 1          # firmware.calimport's refusal, or a save that failed
    return 2              # no file, or no folder for the store


if __name__ == "__main__":
    a = sys.argv[1:]
    sys.exit(status(load(a[0] if a else "calibration.json", a[1] if len(a) > 1 else "/")))
