"""README.md's first-calibration steps are what boards/main.py prints on the simulated board:
every quoted line of that section is a piece of one line of the run's output."""
import os
import re

from tests import mp

README = os.path.join(mp.ROOT, "README.md")


def _quoted(section):
    text = open(README).read()
    body = text[text.index("## " + section):]
    body = body[:body.index("\n## ", 4)]
    # the quotes of a transcript: a status or progress line, or an announcement
    quotes = [re.sub(r"\s+", " ", q) for q in re.findall(r"`([^`]+)`", body, re.S)]
    return [q for q in quotes if " | " in q or q.startswith(("eCompass:", "saved and read back"))]


def test_the_first_calibration_transcript_is_what_the_simulated_board_prints(tmp_path):
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "20"],
                 micro=False).splitlines()
    quotes = _quoted("First calibration on a board")
    assert len(quotes) >= 5, quotes
    for q in quotes:
        q = q.rstrip(".")
        assert any(q in ln for ln in out), (q, out[:30])
    assert any(ln.startswith("restarted at ") for ln in out)


def test_the_wiring_table_lists_every_chip_detect_finds_at_each_of_its_addresses():
    # firmware/detect.py CHIPS is the one list of the chips a board finds: each magnetometer
    # and IMU is in README's wiring table with every address detect() looks at
    from firmware.detect import CHIPS
    text = open(README).read()
    table = text[text.index("## Wiring"):]
    rows = [r for r in table[:table.index("\n## ", 4)].splitlines() if r.startswith("| ")]
    for entry in CHIPS:
        addrs, label = entry.decode().split()[1], entry.decode().split()[6]
        for a in addrs.split(","):
            addr = "0x" + a
            assert any(label in r and addr in r for r in rows), (label, addr)
