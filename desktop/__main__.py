"""Command-line runner: `python -m desktop COMMAND ...`, also `python -m host_sim COMMAND ...`
(host_sim/__main__.py forwards here) and `micropython -m desktop ...` / `-m host_sim ...`.

The only place, with the command modules of desktop/, where the simulator (host_sim/) and the
firmware meet. COMMANDS says what each command does (`python -m host_sim --help` prints it).

Exit status of every command: 0 done; 1 refused (the data was read, the answer is no: a
calibration refused, no 10-element calibration accepted, ...); 2 bad usage or an input that
cannot be used (desktop/args.py: one line on stderr); 3 an internal error, a bug (one
line on stderr, `host_sim COMMAND: internal error: ...`). main() is the last resort: nothing
a command raises reaches the user as a traceback (HOST_SIM_TRACEBACK=1 shows it, to debug).
"""
import sys

COMMANDS = (
    ("run", "what `make run` shows: demo with its defaults (GY-271 + MPU6050, seed 1), "
            "the plot; --update-doc rewrites docs/design.md's excerpt"),
    ("demo", "the same simulated session for any --chip and --seed; --json for scripts"),
    ("calibrate", "fit a CSV log of raw magnetometer readings; --out writes the file a board "
                  "loads"),
    ("bench", "speed, memory and accuracy on CPython and MicroPython; writes "
              "docs/benchmarks.md"),
    ("quality", "the calibration quality database: ingest, check, export, plot, trend "
                "(CPython)"),
    ("wmm", "write the board's World Magnetic Model table, firmware/field/wmm2025.bin (make wmm)"),
    ("field", "the board's field model: declination, inclination, field at LAT,LON"),
    ("web", "serve the browser calibrator (docs/web.md); --vendor makes web/vendor"),
    ("soak", "a seeded fault campaign against the simulated board (make soak)"),
    ("serve", "a simulated board speaking MotionCal's protocol on stdin/stdout or a pty"),
)
_COMMANDS = tuple(c for c, _ in COMMANDS)
STATUS_USAGE = 2
STATUS_INTERNAL = 3


def help_text():
    lines = ["usage: python3 -m host_sim COMMAND [options]   (COMMAND --help: its options)",
             "       (python3 -m desktop COMMAND ... is the same)", "", "commands:"]
    for name, text in COMMANDS:
        lines.append("  %-10s %s" % (name, text))
    lines += ["", "exit status: 0 done; 1 refused (the reason is printed); 2 bad usage or "
              "unusable input;", "3 internal error (a bug: please report the command line)."]
    return "\n".join(lines)


def _line(cmd, kind, message):
    # one line, however long or multi-line the exception's text
    text = " ".join(str(message).split())
    print("host_sim %s: %s: %s" % (cmd, kind, text), file=sys.stderr)


def main(argv):
    if argv and argv[0] in ("-h", "--help", "help"):
        print(help_text())
        return 0
    cmd = argv[0] if argv else None
    if cmd not in _COMMANDS:
        print("host_sim: error: %s; expected one of %s (python3 -m host_sim --help says what each "
              "does)" % ("unknown command %r" % cmd if argv else "no command",
                         ", ".join(_COMMANDS)), file=sys.stderr)
        return STATUS_USAGE
    try:
        mod = __import__("desktop." + cmd, None, None, ["main"])
        return mod.main(argv[1:])
    except KeyboardInterrupt:
        _line(cmd, "error", "interrupted")
        return 130
    except Exception as e:  # noqa: BLE001 - the last resort: a line, never a traceback
        import os
        if os.getenv("HOST_SIM_TRACEBACK"):
            raise
        return _last_resort(cmd, e)


def _last_resort(cmd, e):
    """The exit status and one line for exception `e` a command let through."""
    from desktop.args import UsageError
    name = type(e).__name__
    if isinstance(e, UsageError):
        _line(cmd, "error", e)
        return STATUS_USAGE
    if isinstance(e, MemoryError):
        _line(cmd, "error", "out of memory (a smaller input or option, or CPython)")
        return STATUS_USAGE
    if isinstance(e, OSError):  # a file or device the command could not use
        _line(cmd, "error", "%s: %s" % (name, e))
        return STATUS_USAGE
    _line(cmd, "internal error", "%s: %s (a bug: please report the command line)" % (name, e))
    return STATUS_INTERNAL


if __name__ == "__main__":
    # MicroPython: sys.argv == ['desktop', ...]; CPython: [path/to/__main__.py, ...]
    sys.exit(main(sys.argv[1:]) or 0)
