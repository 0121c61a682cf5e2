"""A CompassApp's calibration in the store: load at boot, save after each change, retry a
failed save. Imported for each of those and dropped again (firmware.compat.drop), with the
store's slot code (firmware/store_slots.py): a running board rarely saves.
"""
# load(app)    -> the stored Calibration, or UNCALIBRATED with the reason in app.load_reason:
#              the newest slot whose record is intact AND whose payload Calibration.from_bytes
#              accepts (the store skips a torn, unreadable or meaningless slot and falls back to
#              an older one).
# save(app, dip_only)  the calibration in force, with the dip it measures when known
#              (firmware/fieldwatch.py DipCheck). A failed save (OSError, StoreError, MemoryError)
#              is counted in app.save_errors, never raises, and is retried every
#              _SAVE_RETRY_US by CompassApp. dip_only: the fit in force again, now with its dip
#              (not counted in app.stored).
#              After the record, the mounting check's verdict kept beside it, when there is one
#              (firmware/mountnote.py: loaded only then, and dropped).
from firmware.calibration import UNCALIBRATED, Calibration
from firmware.compat import drop
from firmware.errors import StoreError
from firmware.learning import LOAD_NO_MEMORY

LOAD_BAD_PAYLOAD = "bad_payload"      # .load_reason: the record is intact, its payload is not
LOAD_IO_ERROR = "io_error"            # .load_reason: the filesystem raised OSError


def load(app):
    """(the stored Calibration or UNCALIBRATED, the reason why not or None): the app keeps
    the reason as .load_reason."""
    st = app.store
    if st is None:
        return UNCALIBRATED, "no_store"
    # records are tied to the sensor and its range: bind the store to the chip found
    st.sensor = app.mag.KIND
    st.range_code = app.mag.range_code
    # a record that is intact but means nothing valid is skipped like a torn one
    st.validate = Calibration.from_bytes
    try:
        cal = Calibration.from_bytes(st.load())
        # the mounting check's verdict kept beside the record (firmware/mountnote.py: NAME,
        # and more bytes than its longest line): its code is loaded only when there is one
        try:
            f = st.fs.open(st.prefix + "_mounting.txt", "rb")
            try:
                note = f.read(80)
            finally:
                f.close()
        except (AttributeError, OSError):  # none, unreadable, or a store without files
            note = None
        if note:
            # imported by a string of more than 10 characters, which MicroPython keeps as a
            # string, where the names of an import statement are interned (qstrs, never
            # freed) when this module loads: a board without the file interns nothing for it
            name = "firmware.mountnote"
            try:  # (a MemoryError: the load is tried again, as the store's)
                if __import__(name, None, None, ("load",)).load(app, note):
                    cal = cal.with_dip(None)  # measured through another MAG_AXES
            finally:
                drop(name[9:])
        return cal, None
    except StoreError as e:
        reason = e.reason
    except ValueError:
        reason = LOAD_BAD_PAYLOAD
    except OSError:
        reason = LOAD_IO_ERROR
    except MemoryError:
        reason = LOAD_NO_MEMORY
    return UNCALIBRATED, reason


def save(app, dip_only):
    """The app's save figures after saving: (stored, dip_unsaved, save_errors, save_wait_us,
    unsaved, save_reason, worst_save_us), which the app assigns; None without a store."""
    if app.store is None:
        return None
    t = app._wall()
    reason = None
    try:
        app.store.save(_record(app))
        if not dip_only and app.learning.session is not None:
            app.learning.session.saved(app)  # the history follows the store
    except StoreError as e:
        reason = e.reason
    except OSError as e:
        reason = "os_error %s" % (e.args[0] if e.args else "?")
    except MemoryError:
        reason = LOAD_NO_MEMORY
    except ValueError as e:  # a payload the store refuses: a bug, never a crash
        reason = "bad_payload %s" % (e,)
    us = app._wall_diff(app._wall(), t)
    if reason is not None:  # retried after CompassApp's _SAVE_RETRY_US
        return (app.stored, False, app.save_errors + 1, 0, True, reason,
                max(us, app.worst_save_us))
    # a fit saved before its dip was learned is saved once more with it (dip_unsaved)
    return (app.stored + (0 if dip_only else 1), app.dip is not None and not app.dip.armed,
            app.save_errors, 0, False, None, max(us, app.worst_save_us))


def _record(app):
    # the payload saved: the calibration in force with the dip it measures, when known
    c = app.calibration
    d = app.dip
    if d is not None and d.armed and c.model is not None and c.dip_kang != d.ref:
        c = c.with_dip(d.ref)
    return c.to_bytes()
