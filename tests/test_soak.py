"""A short run of the fault campaign (python -m host_sim soak; make soak runs the long one):
step() never raises, no stored calibration is lost or replaced by a worse one, and no heading
is "ok" while wrong by more than the documented accuracy (docs/faults.md) - except under a
magnet whose field leaves |B| inside the interference window, which the magnitude check
cannot see (docs/faults.md, known limits): those are counted and bounded, not hidden."""
import subprocess
import sys

from host_sim.cli import soak


def test_a_short_fault_campaign_has_no_exception_no_loss_and_no_wrong_but_ok():
    st = soak.campaign(sessions=10, seconds=40, seed=5)
    assert st["steps"] > 10000 and st["total_faults"] >= 20
    assert len(st["faults"]) >= 8          # most classes drawn
    assert st["exceptions"] == 0
    assert st["lost"] == 0
    wrong = {k: v for k, v in st["wrong_by_class"].items() if k != "magnet"}
    assert wrong == {}
    for cls, d in st["detect_ms"].items():
        assert d["max_ms"] < 1000, (cls, d)  # every detected fault within a second


def test_soak_bad_arguments_are_one_line_and_exit_2():
    p = subprocess.run([sys.executable, "-m", "host_sim", "soak", "--sessions", "0"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "--sessions=0" in p.stderr
