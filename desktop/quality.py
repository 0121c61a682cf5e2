"""`python -m host_sim quality --db DB COMMAND ...`: the calibration quality database.

Keeps every calibration's parameters (the calibrate command's --json record plus device and
time), checks each against limits from a limits file or learned from the device's history and
the fleet, and shows each parameter's history. See docs/quality.md. CPython only.
"""
import csv
import json
import sys
from types import SimpleNamespace

from desktop.args import Parser, UsageError, error_line

USAGE = """usage: python -m host_sim quality --db DB COMMAND [options]

DB is an SQLite file (created by ingest) or postgresql://user@host:port/dbname
(?host=/socket/dir for a unix socket; password in the URL or PGPASSWORD).

commands:
  ingest FILE... [--skip-duplicates]   store JSON-line records (- reads stdin), all or none
  check [--limits FILE] [--k SIGMAS]   print each flagged record as a JSON line
  export --csv FILE [--raw]            every record as CSV (- writes stdout); a text cell that
                                       a spreadsheet would run as a formula gets a leading '
                                       (--raw: as stored)
  plot PARAMETER -o FILE.png [--limits FILE] [--k SIGMAS] [--device D]...
  trend [--device D] [--json]          per parameter: mean, sigma, drift per month

options:
  --wait SECONDS   how long to wait for another writer's lock (default 2)
  -h, --help       this text; COMMAND --help for a command's

exit status: 0 done (check: nothing flagged); 1 check flagged a record; 2 bad usage,
unreadable or invalid input, or a database that cannot be read or written (nothing stored).
"""


COMMANDS = ("ingest", "check", "export", "plot", "trend")


def _seconds(text):
    v = float(text)
    if not v >= 0:
        raise ValueError("expected seconds >= 0")
    return v


def _sigmas(text):
    v = float(text)
    if not v > 0:
        raise ValueError("expected sigmas > 0")
    return v


def _parser(name):
    """The shared parser (desktop/args.py) of one command, with the database options,
    which may also stand before the command."""
    from desktop.qualitydb.records import PARAMETERS
    helps = {"ingest": "store JSON-line calibration records, all or none",
             "check": "check every record against its limits",
             "export": "write every record as CSV",
             "plot": "a parameter's history chart (PNG)",
             "trend": "per parameter: mean, sigma, repeatability, drift per month"}
    p = Parser("quality", "--db DB %s [options]" % name, helps[name])
    p.option("--db", "str", metavar="DB", help="an SQLite file or postgresql://...")
    p.option("--wait", _seconds, default=2.0, metavar="SECONDS",
             help="how long to wait for another writer's lock")
    if name == "ingest":
        p.positional("files", "FILE", "JSON lines; - for stdin", many=True)
        p.option("--skip-duplicates", "flag",
                 help="store the new records and report duplicates\ninstead of refusing")
    elif name in ("check", "plot"):
        if name == "plot":
            p.positional("parameter", "PARAMETER", "one of " + ", ".join(PARAMETERS),
                         kind="choice", choices=PARAMETERS)
            p.option("--output", "path", short="-o", metavar="FILE.png", help="the chart")
            p.option("--device", "str", repeat=True, metavar="D",
                     help="only this device (repeatable)")
        p.option("--limits", "path", metavar="FILE", help="limits file (JSON, or .toml)")
        p.option("--k", _sigmas, metavar="SIGMAS", help="sigmas for learned limits")
    elif name == "export":
        p.option("--csv", "path", metavar="FILE", help="- for stdout")
        p.option("--raw", "flag",
                 help="text cells exactly as stored (no ' before a leading = + - @ tab CR)")
    else:
        p.option("--device", "str", metavar="D", help="only this device")
        p.option("--json", "flag", help="JSON lines instead of a table")
    return p


def _split(argv):
    """(options before the command, the command or None, the words after it)."""
    i = 0
    while i < len(argv):
        w = argv[i]
        if w in ("--db", "--wait"):
            i += 2
        elif w.startswith("--db=") or w.startswith("--wait="):
            i += 1
        elif w.startswith("-") and w != "-":
            return argv, None, []          # help, or an unknown option: parsed below
        else:
            return argv[:i], w, argv[i + 1:]
    return argv, None, []


def _args(argv):
    """The parsed options as attributes, None after printing help, or UsageError."""
    head, name, rest = _split(argv)
    if name is None:
        if not argv or "-h" in head or "--help" in head:
            print(USAGE)
            if not argv:
                raise UsageError("no command (%s)" % ", ".join(COMMANDS))
            return None
        raise UsageError("no command (%s)" % ", ".join(COMMANDS))
    if name not in COMMANDS:
        raise UsageError("unknown command %r (%s)" % (name, ", ".join(COMMANDS)))
    p = _parser(name)
    opts = p.parse(head + rest)
    if opts["help"]:
        print(p.help_text())
        return None
    if not opts["db"]:
        raise UsageError("--db DB is required (an SQLite file or postgresql://...)")
    for req, what in (("csv", "--csv FILE"), ("output", "-o FILE.png")):
        if req in opts and opts[req] is None:
            raise UsageError("%s %s is required" % (name, what))
    opts["cmd"] = name
    return SimpleNamespace(**opts)


def _err(msg):
    sys.stderr.write(error_line("quality", msg) + "\n")


def main(argv):
    from desktop.qualitydb.limits import LimitsError
    from desktop.qualitydb.records import RecordError
    from desktop.qualitydb.store import StoreError
    try:
        a = _args(argv)
        if a is None:
            return 0
        return _COMMANDS[a.cmd](a)
    except UsageError as e:
        _err("%s (try --help)" % e)
        return 2
    except (RecordError, LimitsError, StoreError) as e:
        _err(str(e))
        return 2
    except BrokenPipeError:                # e.g. `check | head`: the reader has gone
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 2
    except KeyboardInterrupt:
        _err("interrupted; nothing was stored by an unfinished ingest")
        return 2


def _open(a, write=False):
    from desktop.qualitydb.store import Store
    return Store(a.db, write=write, wait=a.wait)


# --- commands -----------------------------------------------------------------------------
def cmd_ingest(a):
    from desktop.qualitydb import records
    from desktop.qualitydb.store import DuplicateError
    rows = []
    for name in a.files:
        if name == "-":
            rows.extend(_tag(records.iter_file(sys.stdin, "<stdin>"), "<stdin>"))
            continue
        try:
            with open(name) as f:
                rows.extend(_tag(records.iter_file(f, name), name))
        except OSError as e:
            raise UsageError("cannot read %s: %s" % (name, e.strerror or e))
        except UnicodeDecodeError as e:
            raise UsageError("%s: not text (%s)" % (name, e.reason))
    store = _open(a, write=True)
    try:
        new, dups = store.ingest(rows, skip_duplicates=a.skip_duplicates)
    except DuplicateError as e:
        first = e.rows[0]
        _err("%s: duplicate of a stored record (device %s, time %s, same parameters); %d "
             "duplicate(s) in all, nothing stored (--skip-duplicates stores the rest)"
             % (first["_where"], first["device"], first["time"], len(e.rows)))
        return 2
    finally:
        store.close()
    for r in dups:
        _err("%s: duplicate (device %s, time %s), not stored again"
             % (r["_where"], r["device"], r["time"]))
    print("stored %d record(s), %d duplicate(s) skipped" % (len(new), len(dups)))
    return 0


def _tag(it, name):
    for n, row in it:
        row["_where"] = "%s:%d" % (name, n)
        yield row


def _limits(a):
    from desktop.qualitydb import limits
    lim = limits.load(a.limits) if a.limits else limits.Limits()
    if a.k is not None:
        lim.k = a.k
    return lim


def _rows(a, device=None):
    store = _open(a)
    try:
        return store.rows(device)
    finally:
        store.close()


def cmd_check(a):
    from desktop.qualitydb import limits
    lim = _limits(a)
    flags = limits.check(_rows(a), lim)
    for f in flags:
        print(json.dumps(f))
    return 1 if flags else 0


# A text cell starting with one of these is a formula to a spreadsheet (OWASP: CSV injection):
# the export writes it with a leading ' so Excel and LibreOffice Calc show it as text
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_text(v):
    """v for a CSV cell a spreadsheet opens: a str that a spreadsheet would take for a formula
    gets a leading '; numbers (and None) stay as they are."""
    if isinstance(v, str) and v.startswith(FORMULA_START):
        return "'" + v
    return v


def cmd_export(a):
    from desktop.qualitydb.records import PARAMETERS
    cols = ("device", "time", "source", "model") + PARAMETERS + ("samples",)
    rows = _rows(a)
    cell = (lambda v: v) if a.raw else spreadsheet_text
    try:
        f = sys.stdout if a.csv == "-" else open(a.csv, "w", newline="")
    except OSError as e:
        raise UsageError("cannot write %s: %s" % (a.csv, e.strerror or e))
    try:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            w.writerow([("" if r[c] is None else cell(r[c])) for c in cols])
    finally:
        if f is not sys.stdout:
            f.close()
    if a.csv != "-":
        print("wrote %d record(s) to %s" % (len(rows), a.csv))
    return 0


def cmd_plot(a):
    from desktop.qualitydb import chart, limits
    lim = _limits(a)
    p = a.parameter
    rows = _rows(a)
    groups = limits.by_device(rows)
    spec = lim.parameters.get(p, {"learned": list(limits.BASES)})
    fleet = None
    if "fleet" in spec.get("learned", ()):
        fleet = limits.fleet_limits(rows, groups, p, spec.get("k", lim.k))
    one = limits.Limits(lim.k, lim.min_history, lim.window, {p: spec})
    flags = limits.check(rows, one)
    mean = sum(r[p] for r in rows) / len(rows) if rows else None
    if a.device:
        missing = [d for d in a.device if d not in groups]
        if missing:
            raise UsageError("--device %s: no records of that device" % missing[0])
        keep = set(a.device)
        rows = [r for r in rows if r["device"] in keep]
        flags = [f for f in flags if f["device"] in keep]
    try:
        chart.draw(rows, p, flags, fleet, (spec.get("low"), spec.get("high")), a.output,
                   mean=mean)
    except OSError as e:
        raise UsageError("cannot write %s: %s" % (a.output, e.strerror or e))
    print("wrote %s (%d records, %d flagged)" % (a.output, len(rows), len(flags)))
    return 0


def cmd_trend(a):
    from desktop.qualitydb import trend
    rows = _rows(a, a.device)
    if a.device and not rows:
        raise UsageError("--device %s: no records of that device" % a.device)
    out = trend.summary(rows)
    if a.json:
        for s in out:
            print(json.dumps(s))
        return 0

    def g(v):
        return "-" if v is None else "%.5g" % v
    print("%-10s %7s %7s %11s %11s %11s %13s" % ("parameter", "records", "devices", "mean",
                                                 "sigma", "repeat", "drift/month"))
    for s in out:
        print("%-10s %7d %7d %11s %11s %11s %13s" % (
            s["parameter"], s["records"], s["devices"], g(s["mean"]), g(s["sigma"]),
            g(s["repeatability"]), g(s["drift_per_month"])))
    return 0


_COMMANDS = {"ingest": cmd_ingest, "check": cmd_check, "export": cmd_export,
             "plot": cmd_plot, "trend": cmd_trend}


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
