"""The accuracy level (firmware/accuracy.py): every row of the table, state by state, then the
app's .accuracy and status line through the simulator."""
import pytest

from firmware import accuracy
from firmware.accuracy import HIGH, LOW, MEDIUM, UNRELIABLE, level
from firmware.app import status_line
from tests import location_world as L
from tests.location_world import W

GOOD = dict(model=10, fit_error=120, coverage=80, tilt=True)

# (state, expected level, expected reason): one per row of the table, in its order, each
# the best state except for the one thing that row is about
ROWS = [
    (dict(GOOD, heading=False), UNRELIABLE, "no_heading"),
    (dict(GOOD, model=None), UNRELIABLE, "uncalibrated"),
    (dict(GOOD, interference=True), UNRELIABLE, "interference"),
    (dict(GOOD, zone="blackout zone"), UNRELIABLE, "blackout_zone"),
    (dict(GOOD, model="minmax"), LOW, "minmax"),
    (dict(GOOD, fit_error=501), LOW, "fit_error_high"),
    (dict(GOOD, mismatch=True), LOW, "field_mismatch"),
    (dict(GOOD, model=4, coverage=0, fit_error=1000), MEDIUM, "quick"),
    (dict(GOOD, coverage=34), LOW, "low_coverage"),
    (dict(GOOD, model=4), MEDIUM, "hard_iron_only"),
    (dict(GOOD, tilt=False), MEDIUM, "no_tilt"),
    (dict(GOOD, extreme=True), MEDIUM, "tilt_extreme"),
    (dict(GOOD, zone="caution zone"), MEDIUM, "caution_zone"),
    (dict(GOOD, fit_error=351), MEDIUM, "fit_error_fair"),
    (dict(GOOD, coverage=59), MEDIUM, "coverage_fair"),
    (dict(GOOD), HIGH, "high"),
    (dict(GOOD, model=7, fit_error=350, coverage=60, zone="ok"), HIGH, "high"),
]


@pytest.mark.parametrize("state, lvl, why", ROWS, ids=[r[2] + "-" + str(i)
                                                         for i, r in enumerate(ROWS)])
def test_each_row_of_the_table(state, lvl, why):
    assert level(**state) == (lvl, why)


def test_the_documented_table_lists_every_reason_in_order():
    # one copy of the table: docs/accuracy.md (firmware/accuracy.py's opening comment points
    # there)
    import os
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        "docs", "accuracy.md")
    with open(path, encoding="utf-8") as f:
        doc = f.read()
    pos = [doc.index("| %d | %s |" % (lvl, why)) for _, lvl, why in ROWS[:-1]]
    assert pos == sorted(pos)


def test_worse_inputs_never_raise_the_level():
    # monotone: each degradation applied to every state keeps or lowers the level
    bad = [dict(heading=False), dict(interference=True), dict(tilt=False), dict(extreme=True),
           dict(mismatch=True), dict(zone="caution zone"), dict(zone="blackout zone")]
    for state, _, _ in ROWS:
        for b in bad:
            if "zone" in b and state.get("zone") not in (None, "ok"):
                continue  # a zone replaces the state's own zone: not a degradation
            assert level(**dict(state, **b))[0] <= level(**state)[0], (state, b)


def test_app_accuracy_through_the_simulator():
    b = L.board(L.world_at(L.ZURICH, W.HARD_IRON_UT, W.SOFT_IRON), seed=3)
    b.world.motion = W.motion.figure8()
    app = L.app_on(b)
    app.step()
    assert app.accuracy == UNRELIABLE and "accuracy 0 unreliable (uncalibrated)" in \
        status_line(app)
    W.run_until(app, b, 40)
    assert app.calibration.model == 10
    assert app.accuracy == HIGH and "accuracy 3 high" in status_line(app)
    # a magnet near the board: unreliable while it is there
    b.world.add_magnet((40.0, 0.0, 0.0), 41, 45, frame="world")
    W.run_until(app, b, 43)
    assert app.compass.interference and app.accuracy == UNRELIABLE
    assert app.accuracy_reason() == "interference"
