"""Command-line runner: `python -m host_sim COMMAND ...` (also `micropython -m host_sim ...`).

The only place, with host_sim/cli/, where the simulator and the firmware meet.
Commands: run (the compass on the simulated board), calibrate (offline calibration of a CSV
log), demo (the end-to-end story, JSON with --json), bench (make bench), quality (the
calibration quality database, docs/quality.md; CPython only), wmm (write the board's
field-model table: make wmm), field (the board's field model at given points), web (serve the browser
calibrator, docs/web.md), soak (a seeded fault campaign, make soak; docs/faults.md), serve (the
simulated board speaking MotionCal's protocol on stdin/stdout or a pty: docs/motioncal.md).
"""
import sys

_COMMANDS = ("run", "calibrate", "demo", "bench", "quality", "wmm", "field", "web", "soak",
             "serve")


def main(argv):
    if not argv or argv[0] in ("-h", "--help", "help"):
        print("usage: python -m host_sim {%s} [options]   (COMMAND --help for its options)"
              % ",".join(_COMMANDS))
        return 0 if argv else 2
    cmd = argv[0]
    if cmd not in _COMMANDS:
        print("host_sim: error: unknown command %r; expected one of %s"
              % (cmd, ", ".join(_COMMANDS)), file=sys.stderr)
        return 2
    mod = __import__("host_sim.cli." + cmd, None, None, ["main"])
    return mod.main(argv[1:])


if __name__ == "__main__":
    # MicroPython: sys.argv == ['host_sim', ...]; CPython: [path/to/__main__.py, ...]
    sys.exit(main(sys.argv[1:]) or 0)
