"""Every measured figure a page quotes agrees with the bench output it comes from.

`make bench` writes its figures between markers (`<!-- bench:begin -->` in docs/benchmarks.md;
`boards`, `by-board`, `logs`, `gyro`, `soak` blocks in other pages; `make run` writes the `run`
block of docs/design.md: WRITERS). Outside those blocks a page points at them or quotes one of
their figures; this test finds each figure quoted with a unit and fails unless (a) a block holds
the same value in the same unit, at the rounding the page shows, or (b) it is not a measurement
of ours (a bound or goal, a setting, a format or datasheet fact, a computed value), told apart
by the rules and the short list below. No bench run: the blocks are bench's recorded output.

What is checked, on every page alike: heap and file sizes (KB, B, bytes), interned names,
times (ms, us, ns), and seconds, angles and percentages quoted with decimals. Whole numbers in
s / deg / % are not checked: they are periods, thresholds and scenario settings (5 s, 5 deg,
+-3 %; every whole number the pages quote was read and is one of those, or was rewritten),
so a page states a measured one with its decimals, or states the limit a test or a
command holds ("within the 5 deg the test allows") and names it. Not checked: MB (third-party
download sizes, docs/install.md). A scenario's one-off result (a soak seed, a test's scenario,
a MotionCal session) is not quoted as a figure: the page names the test or the command that
holds or prints it. CHANGELOG.md is exempt: each entry is a dated record of a past release;
docs/ pages are not (a "what moved it" note says what moved a figure and quotes today's or
points at benchmarks.md).
"""
import glob
import os
import re

from tests import mp

PAGES = ([os.path.join(mp.ROOT, "README.md")] + sorted(glob.glob(os.path.join(mp.ROOT, "docs", "*.md")))
         + sorted(glob.glob(os.path.join(mp.ROOT, "examples", "*.py"))))

# Status and progress lines quoted as code are the board's output, not figures to quote:
# tests/test_readme.py and tests/test_calibration_doc.py hold the first-calibration transcripts
# to a run of the simulated board.
TRANSCRIPT = re.compile(r"`[^`]*\| [^`]*`?|^[^`]*\| [^`]*`|^(heading|calibrating:) .*\|")

UNITS = {"KB": "size", "kB": "size", "B": "size", "bytes": "size", "names": "names",
         "s": "time", "ms": "time", "us": "time", "\u00b5s": "time", "ns": "time", "deg": "angle",
         "\u00b0": "angle", "%": "pct"}
_NUM = r"\d{1,3}(?:,\d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
_UNIT = r"(KB|kB|bytes|B|names|s|ms|us|\u00b5s|ns|deg|\u00b0|%)"
FIGURE = re.compile(r"(?<![\w.\-+/])((?:%s)(?:\s*(?:/|-|->|to|and|or)\s*(?:%s))*)\s*%s(?![\w/])"
                    % (_NUM, _NUM, _UNIT))
NUM = re.compile(_NUM)
# a bound, a goal or an input, not a result: "goal <= 1 KB", "budget 57.0 KB", "+-1.5 %",
# "at most 300 characters", "below 1/8"
BOUND = re.compile(r"(goal|budget|<=|>=|<|>|\+-|\u00b1|\u2264|\u2265|at most|at least|up to|"
                   r"less than|more than|below|above|under|limit|bound|default|every|each|per)"
                   r"\s*$")

# Facts that are not measurements of ours: (page, figure as written, where it comes from).
ALLOW = [
    ("*", "68 bytes", "MotionCal's calibration packet: its wire format (docs/motioncal.md)"),
    ("*", "3.5 %", "NXP's fit-error threshold for a higher-order fit (docs/references.md)"),
    ("docs/api.md", "0.0055\u00b0", "a KANG's resolution: 360 / 65536 deg (computed)"),
    ("docs/quick_calibration.md", "63.5 deg", "the scenario's place (quickcal.ZURICH): its dip"),
    ("docs/quick_calibration.md", "6.9 deg", "computed: 4 x 0.03 rad across the field"),
    ("docs/design.md", "100 \u00b5s", "busio_i2c.py's _LOCK_POLL_US: a setting"),
    ("docs/field_model.md", "12 bytes", "a table record: 6 int16 (the format)"),
    ("docs/field_model.md", "7.5 deg", "the table's grid step: a design choice"),
    ("docs/field_model.md", "97.5 deg", "the grid's rows: 7.5 deg steps and a pad row"),
    ("docs/field_model.md", "172.5 deg", "the grid's last column: 360 - 7.5 deg"),
    ("docs/field_model.md", "9,104 B", "10 deg grid's table: 32 + 21 x 36 x 12 B (computed)"),
    ("docs/field_model.md", "11,072 B", "9 deg grid's table: 32 + 23 x 40 x 12 B (computed)"),
    ("docs/field_model.md", "0.27 %", "grid study, rejected 10 deg grid: measured once"),
    ("docs/field_model.md", "0.19 %", "grid study, rejected 9 deg grid: measured once"),
    ("docs/api.md", "100 us", "AK8963 datasheet: the wait after a mode change (docs/hardware.md)"),
    ("docs/api.md", "8 ms", "MPU6050 register map, DLPF_CFG table: the 21 Hz setting's delay"),
    ("docs/design.md", "100 us", "AK09916 datasheet: the wait after a mode change"),
    ("docs/design.md", "6.6 ms", "MMC5603 datasheet: the measurement time at BW 0"),
    ("docs/api.md", "1.2 ms", "MMC5603 datasheet: the measurement time at BW 3"),
    ("docs/hardware.md", "1.2 ms", "MMC5603 datasheet: the measurement time at BW 3"),
    ("docs/design.md", "29 us", "2**29 us: the limit of a wait that stays a small int"),
    ("docs/design.md", "23 ms", "computed: 1 KiB x 9 bits at 400 kHz (an SSD1306 frame)"),
    ("docs/design.md", "0.0055 deg", "a KANG's resolution: 360 / 65536 deg (computed)"),
    ("docs/design.md", "7.5 deg", "the field model table's grid step: a design choice"),
    ("docs/design.md", "2.5-3.5 deg", "computed: half of a 5 deg direction error, and the tilt's share"),
    ("docs/faults.md", "2.5-3.5 deg", "computed: half of a 5 deg direction error, and the tilt's share"),
    ("docs/faults.md", "7.3 deg", "computed: the two-step jump limit at 15 Hz, 4 + 25 x 2 / 15 deg"),
    ("docs/faults.md", "30 ms", "computed: three samples at the AKM chips' 100 Hz"),
    ("docs/hardware.md", "20 ms", "MMC5603 datasheet, register details: SW_RST's power-on time"),
    ("docs/hardware.md", "100 us", "AK8963 and AK09916 datasheets: the wait after a mode change"),
    ("docs/motioncal.md", "250 ms", "firmware/motioncal/mode.py's _PACKET_TIMEOUT_US: a setting"),
    ("docs/web.md", "42.84\u00b0", "computed: MotionCal's equal-area bands, asin(0.68) (34 %)"),
    ("docs/web.md", "78.52\u00b0", "computed: MotionCal's equal-area caps, asin(0.98) (1 %)"),
]


# The blocks a command writes, and the command: only these are a source.
WRITERS = {"bench": "make bench (desktop/bench.py)", "soak": "make bench (--soak-only)",
           "boards": "make bench", "by-board": "make bench", "gyro": "make bench",
           "logs": "make bench (desktop/benchmarks/accuracy.py)",
           "run": "make run (desktop/run.py)",
           "soak-run": "make soak (desktop/soak.py --doc)"}


def _rel(path):
    return os.path.relpath(path, mp.ROOT).replace(os.sep, "/")


def blocks(text):
    """(inside, line) for each line: inside is True within a block a command writes."""
    depth = 0
    for line in text.splitlines():
        m = re.search(r"<!-- ([\w-]+):begin -->", line)
        if m:
            assert m.group(1) in WRITERS, "no command writes the block %r" % m.group(1)
            depth += 1
        yield depth > 0, line
        if re.search(r"<!-- [\w-]+:end -->", line):
            depth -= 1


def figures(line):
    """(text, [values], [decimals], unit, column) for each figure with a unit on the line."""
    for m in FIGURE.finditer(line):
        nums, unit = m.group(1), m.group(2)
        vals = [n.replace(",", "") for n in NUM.findall(nums)]
        if unit == "B" and any("." in v for v in vals):
            continue  # "2.5 B": a multiple of the field B, not bytes
        yield m.group(0), [float(v) for v in vals], [len(v.split(".")[1]) if "." in v else 0
                                                       for v in vals], unit, m.start()


NORM = {"kB": "KB", "bytes": "B", "\u00b5s": "us", "\u00b0": "deg"}


class Source:
    """Bench output: each number with the units its line (or its table's header) names."""

    def __init__(self, texts):
        self.rows = []
        for text in texts:
            header = ""
            for inside, line in blocks(text):
                if not inside:
                    continue
                if not line.startswith("|"):
                    header = ""
                elif not header:
                    header = line
                units = {NORM.get(u, u) for u in
                         re.findall(r"(?<![\w])%s(?![\w])" % _UNIT, line + " " + header)}
                for n in NUM.findall(line):
                    self.rows.append((float(n.replace(",", "")), units))

    def holds(self, value, decimals, unit):
        unit = NORM.get(unit, unit)
        tol = 0.5 * 10 ** -decimals + 1e-9
        for n, units in self.rows:
            if unit in units and abs(n - value) <= tol:
                return True
            # a KB figure may round a figure bench gives in B
            if unit == "KB" and "B" in units and n > 1024 and abs(n / 1024 - value) <= tol:
                return True
        return False


def allowed(page, text, allow, used):
    for entry in allow:
        if entry[0] in ("*", page) and entry[1] == text:
            used.add(entry)
            return True
    return False


def cells(line, header):
    """Figures of a table row whose column header names the unit: | RMS deg | ... | 0.22 |."""
    heads = header.split("|")
    for i, cell in enumerate(line.split("|")):
        m = re.fullmatch(r"\s*\**(%s)\**\s*" % _NUM, cell)
        units = re.findall(r"(?<![\w])%s(?![\w])|\[(B)\]" % _UNIT, heads[i]) \
            if i < len(heads) else []
        if m and units:  # the header's last unit: "95 % of seeds within deg" is in deg
            v = m.group(1).replace(",", "")
            yield (m.group(1), [float(v)], [len(v.split(".")[1]) if "." in v else 0],
                   units[-1][0] or units[-1][1], 0)


def check(pages, source, allow=ALLOW, used=None):
    """Lines "page:line: figure" for each quoted measured figure bench does not hold."""
    bad, used = [], set() if used is None else used
    for page, text in pages:
        header = ""
        for no, (inside, line) in enumerate(blocks(text), 1):
            if inside:
                continue
            table = line.strip().startswith("|") and line.strip().endswith("|")
            header = (header or line) if table else ""
            found = list(figures(line))
            if table and header is not line:
                found += list(cells(line, header))
            for fig, vals, decs, unit, at in found:
                kind = UNITS[unit]
                if (kind in ("angle", "pct") or unit == "s") and not any(decs):
                    continue
                if not table and TRANSCRIPT.search(line):
                    continue
                if BOUND.search(line[:at]) or allowed(page, fig, allow, used):
                    continue
                if all(source.holds(v, d, unit) for v, d in zip(vals, decs)):
                    continue
                bad.append("%s:%d: %s" % (page, no, fig))
    return bad


def _pages():
    return [(_rel(p), open(p, encoding="utf-8").read()) for p in PAGES]


def test_every_quoted_figure_is_what_bench_wrote():
    pages = _pages()
    assert {"README.md", "docs/design.md", "docs/field_model.md"} <= {p for p, _ in pages}
    source = Source(text for _, text in pages)
    assert len(source.rows) > 1000 and source.holds(0.035, 3, "deg")  # bench's tables read
    used = set()
    bad = check(pages, source, used=used)
    assert not bad, "figures no bench block holds (quote it from docs/benchmarks.md, point " \
                    "there, or list a non-measured fact in ALLOW):\n" + "\n".join(bad)
    # the list stays short and current: an entry no page quotes any more goes
    assert not set(ALLOW) - used, sorted(set(ALLOW) - used)


BENCH = """<!-- bench:begin -->
| item | CPython | MicroPython unix | ratio / goal | verdict |
|---|---|---|---|---|
| 8 field model heap, x86-32: open model / per query / import [B] |  | 432 / 372 / 9344 | goal <= 1 KB | met |
| 4 budget: smallest heap, boot + first calibration (.romfs) |  | 82.5 KB | budget <= 100.0 KB | within |
| 3 solve model 10, 300 samples [ms] | 2.92 | 3.70 | goal <= 100 ms (unix) | met |
| 7 quality DB: ingest 10086 records into SQLite [s] | 0.32 |  | goal <= 5 s | met |
<!-- bench:end -->
"""


def test_a_drifted_figure_fails_with_its_page_and_line():
    source = Source([BENCH])
    page = ("the model holds 432 B open and 372 B per query (9.1 KB to import);\n"
            "a first calibration from ROMFS needs 82.5 KB, a solve 3.70 ms, ingest 0.32 s.\n"
            "drifted: 368 B per query and 87.3 KB, a solve 3.9 ms; 96 KB; ingest 0.9 s\n"
            "a goal <= 12 KB and +-1.5 % are not results; about 110 KB free\n")
    bad = check([("docs/x.md", page)], source, allow=[])
    assert bad == ["docs/x.md:3: 368 B", "docs/x.md:3: 87.3 KB", "docs/x.md:3: 3.9 ms",
                   "docs/x.md:3: 96 KB", "docs/x.md:3: 0.9 s", "docs/x.md:4: 110 KB"], bad
    # a fact listed as not ours passes, on its page or on every page
    assert check([("docs/x.md", page)], source, allow=[("*", "110 KB", "nominal")]) == bad[:5]
    # a table's cells take the unit of their column's header
    table = ("| setup | RMS deg | heap [B] |\n|---|---|---|\n"
             "| a | 0.79 | 9344 |\n| b | 0.80 | 9345 |\n")
    more = Source([BENCH.replace("<!-- bench:end", "| q | 0.79 deg |\n<!-- bench:end")])
    assert check([("docs/x.md", table)], more) == ["docs/x.md:4: 0.80", "docs/x.md:4: 9345"]
    # a figure inside a bench block of the page is bench's own
    assert check([("docs/x.md", "<!-- gyro:begin -->\n96 KB\n<!-- gyro:end -->\n")], source) == []
    # a decimal angle is checked on every page; a whole one is a setting or a threshold
    assert check([("docs/x.md", "off by 2.7 deg\n")], source) == ["docs/x.md:1: 2.7 deg"]
    assert check([("docs/faults.md", "off by 2.7 deg\n")], source) == ["docs/faults.md:1: 2.7 deg"]
    assert check([("docs/faults.md", "within 3 deg, every 5 s, +-3 %\n")], source) == []


def test_make_soak_writes_the_table_docs_faults_md_quotes(tmp_path):
    # docs/faults.md's campaign table is the soak-run block `make soak` writes (--doc)
    text = open(os.path.join(mp.ROOT, "docs", "faults.md"), encoding="utf-8").read()
    assert "<!-- soak-run:begin -->\n\n    soak: 600 sessions x 60 s, seed 1\n" in text
    assert "--doc docs/faults.md" in open(os.path.join(mp.ROOT, "Makefile")).read()
    from desktop import soak
    page = tmp_path / "page.md"
    page.write_text("before\n<!-- soak-run:begin -->\nold\n<!-- soak-run:end -->\nafter\n")
    assert soak.main(["--sessions", "2", "--seconds", "5", "--clean", "2",
                      "--doc", str(page)]) == 0
    got = page.read_text()
    assert "old" not in got and got.startswith("before\n") and got.endswith("after\n")
    body = got.split("<!-- soak-run:begin -->\n\n")[1].split("\n\n<!-- soak-run:end -->")[0]
    lines = [ln[4:] for ln in body.splitlines()]
    assert lines[0] == "soak: 2 sessions x 5 s, seed 1" and lines[-1] == "goals: all met", lines
    # a page without the markers is refused before the campaign runs
    page.write_text("no markers\n")
    assert soak.main(["--sessions", "2", "--seconds", "5", "--doc", str(page)]) == 2
