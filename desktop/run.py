"""`python -m host_sim run` (what `make run` shows): the demo on a GY-271 (QMC5883L) with a
separate MPU6050, seed 1, human-readable, with the PNG in build/calibration.png.

Options are the demo's (its defaults are this board and seed), e.g. `--no-plot`, `--seed 7`.
`--update-doc` (what `make run` passes) also rewrites the excerpt of this run that
docs/design.md quotes, between its `<!-- run:begin -->` and `<!-- run:end -->` markers, so the
figures there are the ones the run prints (tests/test_demo.py compares them). It writes only
for the demo's default world (chip, seed, seconds, samples) and on CPython.
"""
import sys

from desktop import demo
from desktop.args import warn

# docs/design.md of this repository (string operations: MicroPython has no os.path; the doc is
# written on CPython only)
DOC = __file__.replace("\\", "/").rsplit("/", 2)[0] + "/docs/design.md"
BEGIN = "<!-- run:begin -->"
END = "<!-- run:end -->"
# the options that change what the run prints; the excerpt is of their defaults
_WORLD = ("chip", "seed", "seconds", "samples")


def excerpt(text):
    """The block docs/design.md quotes from the printed run `text` (markers included): the
    accepted calibration with V and B, the heading table's head, first row and summary."""
    lines = text.splitlines()
    i = [k for k, ln in enumerate(lines) if ln.startswith("Accepted calibration:")][0]
    j = [k for k, ln in enumerate(lines) if ln.startswith("  pitch  roll   true |")][0]
    last = [ln for ln in lines if ln.startswith("  error max / rms")][0]
    body = lines[i:i + 4] + ["  ..."] + lines[j:j + 2] + ["  ...", last]
    return "\n".join([BEGIN, "```"] + [ln.rstrip() for ln in body] + ["```", END])


class _Tee:
    """stdout that also keeps what was written."""

    def __init__(self, out):
        self.out = out
        self.parts = []

    def write(self, s):
        self.parts.append(s)
        return self.out.write(s)

    def flush(self):
        self.out.flush()

    def isatty(self):
        return False  # the progress lines as a log, the way the excerpt shows the run


def body(opts):
    if not opts.get("update_doc"):
        return demo.body(opts)
    p = demo.parser()
    defaults = p.parse([])
    changed = [k for k in _WORLD if opts[k] != defaults[k]]
    if changed or sys.implementation.name != "cpython":
        warn("run", "--update-doc: not written (%s)" % (
            "the excerpt is of the default world; --%s given" % changed[0] if changed
            else "CPython only"))
        return demo.body(opts)
    tee = _Tee(sys.stdout)
    sys.stdout = tee
    try:
        rc = demo.body(opts)
    finally:
        sys.stdout = tee.out
    if rc == 0:
        from desktop.bench import splice_block
        block = excerpt("".join(tee.parts))
        with open(DOC) as f:
            old = f.read()
        if block not in old:
            if splice_block(DOC, BEGIN, END, block):
                print("\ndocs/design.md: its excerpt of this run rewritten")
            else:
                warn("run", "--update-doc: docs/design.md has no %s ... %s block"
                               % (BEGIN, END))
    return rc


def main(argv):
    p = demo.parser("run", "The demo with its defaults (make run): a GY-271 (QMC5883L) and an "
                           "MPU6050, seed 1,\nwith the plot; the options below apply.")
    p.option("--update-doc", "flag",
             help="rewrite docs/design.md's excerpt of this run (make run;\n"
                  "the default world, CPython)")
    return p.main(argv, body)
