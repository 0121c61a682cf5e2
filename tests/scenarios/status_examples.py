# The status lines docs/calibration.md shows as examples, from a run of the simulated GY-271
# + GY-521 board: a first calibration beside the heading (a board with room for it), then the
# same board with a wrong magnetometer map. Prints every status line of each run, one a line,
# after a line "# run NAME". Run by tests/test_calibration_doc.py.
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402

from firmware.app import CompassApp, status_line  # noqa: E402
from firmware.store import CalStore  # noqa: E402


def run(name, seconds, mag_axes=W.MAG_AXES):
    print("# run " + name)
    b = W.make_sim("gy271", seed=3)
    app = CompassApp(b.bus, mag_axes=mag_axes, accel_axes=W.ACCEL_AXES,
                     declination_cdeg=W.DECLINATION_CDEG, store=CalStore("/", fs=W.MemFs()),
                     delay_us=b.sleep_us, ticks_us=b.clock.ticks_us)
    t = [0]

    def each(a):
        if b.clock.now_us - t[0] >= 500000:
            t[0] = b.clock.now_us
            print(status_line(a))
    W.run_until(app, b, seconds, each)


run("session", 60)
run("wrong_map", 60, mag_axes="y,x,-z")
