"""MicroPython only: how long importing a firmware module takes, from wherever the path finds
it (.py sources: compiled here; .mpy files: loaded). Calibration mode lets the solver go
between solves where loading it again is cheap (firmware.compat.compiled_here).

    micropython -m desktop.benchmarks.importtime [MODULE ...]   (default: calibrate.solve)

Each module imported REPEATS times, dropped in between (firmware.compat.drop): the median, in
microseconds, and where it came from.
"""
import sys

from desktop.benchmarks import common

REPEATS = 5


def main():
    if not common.IS_MP:
        common.emit({"interpreter": common.interpreter(), "skipped": "needs time.ticks_us"})
        return
    import time
    from firmware.compat import drop
    names = [a for a in sys.argv[1:] if not a.startswith("-")] or ["calibrate.solve"]
    out = {}
    for name in names:
        us = []
        src = None
        for _ in range(REPEATS):
            t0 = time.ticks_us()
            m = __import__("firmware." + name, None, None, (name,))
            us.append(time.ticks_diff(time.ticks_us(), t0))
            src = getattr(m, "__file__", "")
            m = None
            drop(name)
        us.sort()
        out[name] = {"us": us[len(us) // 2], "from": src}
    common.emit({"interpreter": common.interpreter(), "modules": out})


if __name__ == "__main__":
    main()
