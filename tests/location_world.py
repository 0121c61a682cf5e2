"""Simulated boards whose world is the field model's at a place: the world's field, dip and
declination are the table's, so the heading the app reports can be compared with the truth.
Shared by tests/test_location.py and tests/test_quickcal.py (host only: floats). The harness
itself is the quick-calibration benchmark's (desktop/benchmarks/quickcal.py)."""
import sys

sys.path.insert(0, "tests/scenarios")
import app_world as W  # noqa: E402,F401

from desktop.benchmarks import quickcal as Q  # noqa: E402
from desktop.benchmarks.quickcal import (  # noqa: E402,F401
    SAO_PAULO, SYDNEY, YEAR_E3, ZURICH, board, hold, mean_error_deg, quick_cal_errors,
    soft_iron, true_heading_cdeg, world_at)


def app_on(b, accel=True, **kw):
    kw.setdefault("declination_cdeg", W.DECLINATION_CDEG)
    return Q.app_on(b, accel, **kw)
