"""CompassApp.run()'s loop, loaded for the run and dropped after it (firmware/app.py)."""
from firmware.compat import ticks_diff


def run(app, n, report, every, every_us):
    # step() n times (None: forever, or until .relearn_due: the calibration program is
    # needed); report(app) every `every` steps, or every `every_us` microseconds of the app's
    # clock. Returns the steps with a heading.
    good = 0
    i = 0
    last = app._ticks()
    while (n is None or i < n) and not app.relearn_due:
        if app.step():
            good += 1
        i += 1
        if report is None:
            continue
        if every_us:
            now = app._ticks()
            if (ticks_diff(now, last) if app._wrap else now - last) >= every_us:
                last = now
                report(app)
        elif i % every == 0:
            report(app)
    return good
