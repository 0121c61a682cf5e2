# Calibration mode: one job in RAM at a time. Where the heap cannot hold the heading line and a
# calibration session together, CompassApp calibrates in this mode: it lets go of what showing a
# heading needs (the Compass, the field watch, the fast kernels and their tables, the status
# line's heading part) and holds only what calibrating needs (the drivers, their sample checks,
# the collector, the solver, the acceptance, the store); once a fit is saved and the session
# ends, the heading line is made again without the session's code. Imported for that and
# dropped after it (firmware.compat.drop).
#
#     app.mode          "heading", or "calibrating" while this mode runs (no heading: the
#                       status is "calibrating", the status line shows the session's progress)
#
# CompassApp enters it from calibrate() (at construction with no good stored calibration, from
# relearning when the iron changed, or when called) when compat.free_bytes() is below
# SESSION_ROOM, or when a session started beside the heading line ran out of memory. When even
# this mode finds no room, the heading line is made again, app.no_memory says what could not be
# done and what to do instead, and the app tries again after RETRY_US. docs/design.md (memory)
# has the figures; make bench measures them (docs/benchmarks.md).
from firmware.compat import const, drop, drop_part, free_bytes

# free heap (bytes, after a collection) a calibration session needs beside the heading line
# for the board to keep both: below it the board calibrates in this mode. Measured on the
# x86-32 build with boards/main.py (docs/benchmarks.md): the background session completes
# reliably from about 196 KB of heap, ~128 KB free after boot; at 112 KB it sometimes ran
# out saving (a heap of 192 KB).
SESSION_ROOM = const(128 * 1024)
# the smallest heap from which a first calibration completes at every heap (.mpy, x86-32
# build, boards/main.py with its status line; docs/benchmarks.md): what the status line says
# a board needs when even this mode fails (firmware/status.py holds the same figure)
MODE_NEED_KB = const(140)
RETRY_US = const(60000000)  # a session that found no room is tried again after 60 s
MODE_HEADING = "heading"
MODE_CALIBRATING = "calibrating"
# the heading line's modules: dropped while this mode runs (their objects let go first)
HEADING_LINE = ("compass", "fieldwatch", "fast", "kang_tables", "trig", "accuracy", "status",
                "field.location", "field.wmm", "gyro.attitude", "gyro.attitude_fast",
                "gyro.attitude_plain")


def room():
    """True when a session fits beside the heading line (always, where the port does not
    say how much is free)."""
    f = free_bytes()
    return f is None or f >= SESSION_ROOM


def enter(app):
    """Let go of the heading line and start the session; the collector, or None when even
    that did not fit (then the heading line is back and app.no_memory says so)."""
    from firmware import compat, i2cdevice
    try:
        # The status line's names interned now, before the session's: MicroPython never frees
        # a name, and its table of names grows by doubling, in one block (~9 KB on a 32-bit
        # port past 1260 names). Interned first, at most a small growth happens here; interned
        # once the session has fragmented the heap, the status line could not load again
        # (its accuracy part too, though this mode does not show it: left for leave(), its
        # names made the growth come after the session, and the block then found no room).
        import firmware.status  # noqa: F401
        import firmware.accuracy  # noqa: F401
    except MemoryError:
        pass  # (the status line says what it cannot do, and tries at each report)
    app.mode = MODE_CALIBRATING
    app._decl_kang = app.compass.declination_kang
    app.compass = app.watch = app.dip = app.attitude = None
    app._correct = app._apply = None
    app.heading_kang = -1
    i2cdevice.use_kernels(False)  # the drivers' plain decode: firmware.fast goes, and
    app._fast_was = compat.FAST   # no module imported meanwhile brings it back
    compat.FAST = False
    compat._kernels = 0
    drop(*HEADING_LINE)
    free_bytes()
    try:
        from firmware.calibrate import session
        app._session = session
        app.collector = session.start(app, False)
        return app.collector
    except MemoryError:
        app._session = app.collector = None
        session = None
        drop_part("calibrate", KEEP)
        app.no_memory = "calibrate"
        try:
            leave(app)
        except MemoryError:  # not even the heading line: CompassApp retries it
            app.mode = MODE_CALIBRATING
            app.no_memory = "heading"
        return None


def leave(app):
    """The session is over (its machinery dropped): the heading line again."""
    free_bytes()
    from firmware import appsetup, compat
    compat.FAST = app._fast_was
    app.mode = MODE_HEADING
    appsetup.heading_line(app, app._decl_kang)  # MemoryError: the app says so and retries
    appsetup = None
    drop("appsetup", "devinit")
    app._use(app.calibration)
    if app._gyro_options is not None:  # the gyro-aided heading it had, made again
        try:
            opts = app._gyro_options
            if opts:
                app.use_gyro(**opts)
            else:
                app.use_gyro()
        except MemoryError:
            app._gyro_options = None  # (status line: no "gyro:" part; use_gyro() again)


# what stays of the calibrate part when a session's machinery goes: this mode itself
KEEP = ("calibrate.calmode",)
