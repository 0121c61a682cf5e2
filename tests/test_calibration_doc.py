"""docs/calibration.md's transcript of the calibration program is what boards/main.py prints on
the simulated board (boards/host), line for line in the order shown."""
import os

from tests import mp

DOC = os.path.join(mp.ROOT, "docs", "calibration.md")


def test_the_progress_transcript_is_what_the_simulated_board_prints(tmp_path):
    text = open(DOC).read()
    body = text[text.index("### The calibration program's progress line"):]
    body = body[body.index("```\n") + 4:]
    shown = [ln for ln in body[:body.index("```")].splitlines() if not ln.startswith("(")]
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "20"],
                 micro=False).splitlines()
    i = 0
    for ln in shown:  # each line, in order
        while i < len(out) and out[i] != ln:
            i += 1
        assert i < len(out), ln


def test_the_status_line_examples_are_what_the_simulated_app_prints():
    # the example of a session beside the heading and the one of a wrong MAG_AXES: each is a
    # line the app prints on the simulated GY-271 + GY-521 (tests/scenarios/status_examples.py)
    text = open(DOC).read()
    shown = [ln for ln in text.splitlines()
             if ln.startswith("heading ") and ("| saved |" in ln or "check MAG_AXES" in ln)
             and "..." not in ln]
    assert len(shown) == 2, shown
    out = mp.run(["tests/scenarios/status_examples.py"], micro=False).splitlines()
    assert len(out) > 200, out[-3:]
    for ln in shown:
        assert ln in out, ln
