"""Boot a compass: find the chips, import a calibration file once, open the store, make the app.
boards/main.py calls it; the memory benchmarks boot through it the same way.

    from firmware.boot import start
    app, note = start(i2c, "/", mag_axes="x,-y,-z", declination_cdeg=150)
"""
# start(i2c, store_dir, cal_file=None, mag_options=None, delay_us=None, **app_options)
#   store_dir  the directory of the calibration store (firmware/store.py); None: no store
#   cal_file   a calibration file to import once (firmware/calfile/calimport.py); None:
#              store_dir + "/calibration.json"
#   returns (CompassApp, note): note is None, or what the calibration import said
# Exceptions: the drivers' OSError (SensorNotFound, BusError): wiring or power, the caller
# retries. What only boot needs (the chip scan, the import of a file) is dropped again
# (compat.drop), so a running board holds only what it runs (docs/design.md, memory).
import os

from firmware.compat import drop


def _exists(path):
    try:
        os.stat(path)
        return True
    except OSError:
        return False


def _import(cal_file, store, mag):
    try:
        from firmware.calfile.calimport import import_calibration
    except ImportError:  # package-calfile.json not installed: the file waits for it
        return "%s found, but firmware.calfile.calimport is not installed" % cal_file
    imported = import_calibration(cal_file, store, mag)  # never raises
    import_calibration = None
    drop("calfile.calimport")
    return imported[1] if imported is not None else None


def calibrated(i2c, store_dir, cal_file=None, mag_options=None, delay_us=None, model=10):
    """(ok, mag): ok when the heading can start (a calibration file waits, or the store holds
    a good-enough fit for the chip found), else boards/main.py runs the calibration program;
    mag: the driver found, which start(mag=...) takes."""
    from firmware import detect
    from firmware.calibration import Calibration
    from firmware.store import CalStore
    opts = dict(mag_options or {})
    if delay_us is not None:
        opts["delay_us"] = delay_us
    mag = detect.detect(i2c, **opts)
    detect = None
    drop("detect", "devinit")
    if cal_file is None:
        cal_file = store_dir.rstrip("/") + "/calibration.json"
    if _exists(cal_file):
        return True, mag
    st = CalStore(store_dir, sensor=mag.KIND, range_code=mag.range_code,
                  validate=Calibration.from_bytes)
    try:
        cal = Calibration.from_bytes(st.load())
    except Exception:  # noqa: BLE001 - none, torn, unreadable: not calibrated
        return False, mag
    finally:
        drop("store_slots")
    return cal.good_for(model), mag


def start(i2c, store_dir, cal_file=None, mag_options=None, delay_us=None, **app_options):
    # one step at a time, each step's code let go before the next loads (docs/design.md,
    # memory): the chips, the store, a calibration file, then the app
    from firmware import detect
    opts = dict(mag_options or {})
    if delay_us is not None:
        opts["delay_us"] = delay_us
    mag = app_options.pop("mag", None) or detect.detect(i2c, **opts)  # (found by calibrated())
    if "accel" not in app_options:
        acc = detect.detect_accel(i2c)
        if acc:  # (absent: the app looks for one again now and then)
            app_options["accel"] = acc
    detect = None
    drop("detect", "devinit")
    store = None
    note = None
    if store_dir is not None:
        from firmware.store import CalStore
        store = CalStore(store_dir)
        if cal_file is None:
            cal_file = store_dir.rstrip("/") + "/calibration.json"
        if _exists(cal_file):  # the importer (and its JSON parser) only when there is a file
            note = _import(cal_file, store, mag)
    from firmware.app import CompassApp
    app = CompassApp(i2c, mag=mag, store=store, delay_us=delay_us, **app_options)
    return app, note
