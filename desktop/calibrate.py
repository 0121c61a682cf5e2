"""`python -m host_sim calibrate FILE.csv [options]`: calibrate a logged magnetometer file offline.

Runs the firmware's own Calibrator (firmware/calibrate/calibrator.py) over the file, so the result is
the one a board would compute from the same samples, and prints it, or writes the calibration
file a board loads (--out, desktop/calfile.py).
Also runs under `micropython -m host_sim calibrate ...` (no argparse: desktop/args.py).

Steps: read the log (desktop/logfile.py: separators, BOM, header names, corrupt rows
skipped with a warning) -> choose the conversion into counts (the board's counts when its
sensor and range are stated, else a power of ten into int16) -> leave glitch rows out (all-zero,
at the rails, far outside the others; after a fit, far off it: desktop/glitches.py) ->
feed the Calibrator (the desktop keeps every distinct sample; --board-like thins them as a
board: desktop_plan) -> solve and accept, or refuse (exit 1), or with --force fit without the
acceptance checks (forced_solve: Calibrator.solve(checks=False)) -> report in the file's
units and in counts.
"""
import json
import sys
from array import array

from host_sim import chips
from desktop import calfile, calopts, glitches, logfile, mounting
from desktop.args import (STATUS_OK, STATUS_REFUSED, Parser, UsageError, decimal_text,
                               warn, wrap)
from desktop.args import parse_decimal  # noqa: F401  (its earlier home; tests use it)

# The desktop holds every distinct sample of a log, up to the most a Calibrator holds
# (firmware/calibrate/samples.py MAX_CAPACITY); a board holds 300 (firmware/calibrate/calibrator.py
# DEFAULT_CAPACITY) kept apart by its separation rule (--board-like)
DESKTOP_CAPACITY = 16383
BOARD_CAPACITY = 300
COMMAND = "calibrate"
# --units: file units per gauss (1 G = 100 uT = 1000 mG = 100000 nT)
UNITS_PER_GAUSS = {"uT": 100, "mG": 1000, "G": 1, "nT": 100000}
UNITS = ("counts", "uT", "mG", "G", "nT")
MODEL_CHOICES = ("minmax", "4", "7", "10", "auto")
# What to try after a refusal, per firmware/magcal.py REASON_*
HINTS = {
    "too_few_samples": "log more samples, turning the board through every orientation; or "
                       "--model 4 (40 samples) / --model auto; or --force",
    "planar": "turn the board over, not only around (samples near one plane cannot fix a 3D "
              "fit); or --model 4; or --force",
    "singular": "the samples do not lie on an ellipsoid: check the columns (--columns) and "
                "remove magnets; or --model 4; or --force",
    "low_coverage": "log more orientations (cover the whole sphere); or --force",
    "offset_out_of_range": "the hard iron is beyond int16: check --units / --scale",
    "soft_iron_out_of_range": "the ellipsoid is too flat (more than 5:1): check the columns and "
                              "units; or --force",
    "field_out_of_range": "the field is not 10..90 uT: check --sensor / --range / "
                          "--counts-per-gauss / --units; or --force",
    "fit_error_high": "the samples are not on the fitted shape: --model 10 for a soft-iron "
                      "ellipsoid, --max-fit-error PCT to allow more, or --force",
    "not_better": "a better calibration is already in force; --force",
    "inconsistent_samples": "the start and the end of the log disagree (a magnet moved, a "
                            "motor, a drifting offset): log again away from it, or --skip N "
                            "to leave the start out; or --force",
}


def _date(text):
    return calfile.check_date(text)


def _parser():
    p = Parser(COMMAND, "FILE.csv [options]",
               "Calibrate a magnetometer log with the firmware's Calibrator and print the result.")
    p.positional("file", "FILE.csv", "the log: a header naming the x, y, z columns (mx,my,mz,\n"
                 "x,y,z, magX.. - lines above it are skipped), or --columns;\n"
                 "',' ';' tab or space separated; UTF-8/latin-1, LF/CRLF", kind="path")
    p.option("--model", "choice", default="10", choices=MODEL_CHOICES, metavar="M",
             help="{choices} (default 10)")
    p.option("--json", "flag", help="print one JSON object (keys below); nothing else on stdout")
    p.option("--out", "path", metavar="CAL.json",
             help="write the calibration file a board loads (needs --sensor,\n"
                  "or the log's sensor line; format: desktop/calfile.py)")
    p.option("--force", "flag",
             help="fit even when acceptance refuses (too few samples, planar,\n"
                  "fit error...): the result says forced and why; exit 0")
    p.option("--sensor", calopts.sensor, metavar="CHIP",
             help=wrap("the board's magnetometer: %s, or its breakout %s (any case, '-' "
                       "ignored); the file is then in its counts (or --units) and V, B are "
                       "the board's. Another chip's log: no --sensor, --units or --scale. "
                       "Default: the log's line '# CHIP range_code N ...' (what "
                       "examples/log_csv.py writes); an option that differs wins"
                       % (", ".join(calfile.SENSOR_NAMES), ", ".join(sorted(calopts.BREAKOUTS)))))
    p.option("--range", "str", metavar="G",
             help="its full scale in gauss (%s;\n"
                  "default: the driver's)" % ",\n".join(
                      "%s %s" % (k, "|".join(r[0] for r in calfile.SENSORS[k]["ranges"]))
                      for k in calfile.SENSOR_NAMES))
    p.option("--counts-per-gauss", "int", lo=1, hi=100000, metavar="N",
             help="the board's sensitivity (instead of --sensor/--range):\n"
                  "enables the 10..90 uT field check")
    p.option("--units", calopts.units, metavar="U",
             help="the file's units: counts, uT, mG, G, nT (any case; with a\n"
                  "micro sign, microtesla, gauss, milligauss, nanotesla too);\n"
                  "uT/mG/G/nT files are converted to the board's counts (or\n"
                  "checked against 10..90 uT). Default: the units the header's\n"
                  "names state ('Mag_X (uT)', 'mx_mG', 'x [G]'); a --units that\n"
                  "differs wins, with a warning")
    p.option("--scale", "decimal", lo="0.000001", hi=1000000, metavar="K",
             help="counts per file unit, instead of --units (e.g. 6.6667 for\n"
                  "a log in uT of a chip at 0.15 uT per count)")
    p.option("--columns", parse_columns_opt, metavar="X,Y,Z",
             help="1-based columns of x, y, z (overrides the header)")
    p.option("--skip", "int", default=0, lo=0, hi=10 ** 9, metavar="N",
             help="ignore the first N data rows (e.g. 3000 still samples)")
    p.option("--board-like", "flag",
             help="thin the samples as a board does (a %d-sample buffer, its\n"
                  "separation rule), e.g. to reproduce a board's fit; default:\n"
                  "every distinct sample of the log" % BOARD_CAPACITY)
    p.option("--capacity", "int", lo=12, hi=calopts.MAX_CAPACITY, metavar="N",
             help="samples the buffer holds (default %d, the most a Calibrator\n"
                  "holds; a longer log is offered every k-th row so none is\n"
                  "evicted; --board-like: %d, as a board)" % (DESKTOP_CAPACITY, BOARD_CAPACITY))
    p.option("--separation", "int", lo=1, hi=32767, metavar="N",
             help="counts between kept samples (default 1: every distinct\n"
                  "sample; --board-like: from the sensitivity, else from the\n"
                  "data's range, as a board does)")
    p.option("--max-fit-error", "decimal", lo="0.01", hi=100, metavar="PCT",
             help="refuse fits with a larger fit error (default 15 %)")
    p.option("--date", _date, metavar="ISO",
             help="the date written (YYYY-MM-DDTHH:MM:SSZ; default now, UTC)")
    mounting.options(p)  # --mag-axes, --accel-axes: the mounting check
    p.epilog = EPILOG
    return p


def parse_columns_opt(text):
    return logfile.parse_columns(text)


EPILOG = """Counts. With --sensor (and --range) or --counts-per-gauss, values are the board's
counts: a counts file as is, a uT/mG/G/nT file (--units) or any file (--scale) converted and
rounded; a value outside the sensor's output (int16, HMC5883L -2048..2047) is a corrupt row.
Without them, a decimal file is scaled by the largest power of ten that keeps its rows
within int16 (rows beyond 4x the median row's magnitude are not counted: corrupt) and the
results are reported back in the file's units.

Corrupt rows (text, nan, inf, 1e30000, out of range, short or empty) are skipped with a
warning naming the line, on stderr; errors and warnings always go to stderr. Glitch rows
(all-zero, at the rails, far outside the others, or more than 6 robust spreads off the fit)
are left out of the fit, said in one line (docs/calibration.md).

JSON: model, offset, field, invw (W^-1, det 1; file units), scale (counts per file unit),
invw_q15, offset_counts, field_counts, field_out_counts (the magnitude the compass checks),
fit_error_x100, fit_error_percent, samples_used, coverage_percent, date, rows, skipped_rows,
units (the file's: --units, else the header's, else null), glitch_rows, forced, refusal,
warnings, and sensor, range_gauss, range_code, counts_per_gauss, field_ut when known; mounting
(a log with accelerometer columns: the mounting check, its verdict and the MAG_AXES the data
say; docs/calibration.md, troubleshooting); after a refusal {"rejected", "detail", "hint",
rows, samples_held}.

--sensor takes a chip or its breakout in any case (GY-271 is read as its QMC5883L, with a
warning naming the other chip it may carry). A log of a chip the firmware does not drive
(BMM150, LSM303DLHC, ...) is fitted without --sensor: give its units (--units uT) or
--scale; the result is in the file's units (--out needs a supported chip).

exit status: 0 calibrated (or forced); 1 the data was read but the calibration was refused
(the reason and what to try are printed); 2 bad usage or unreadable input; 3 an internal
error (a bug; one line on stderr, please report it)."""


# ---- the board and the conversion --------------------------------------------------------

class Board:
    """What the options say about the target: sensor, range, counts per gauss (or None)."""

    def __init__(self, opts):
        s = opts["sensor"]  # (chip, note): calopts.sensor; a breakout's name says which chip
        self.sensor, self.note = (s, None) if s is None or isinstance(s, str) else s
        self.range_gauss = None
        self.range_code = None
        self.cpg = opts["counts_per_gauss"]
        self.output = (-32768, 32767)
        self.overflow = None
        if opts["range"] is not None and self.sensor is None:
            raise UsageError("--range %s needs --sensor (%s)"
                             % (opts["range"], ", ".join(calfile.SENSOR_NAMES)))
        if self.sensor is not None:
            rng = opts["range"]
            if rng is None:
                rng = calfile.SENSORS[self.sensor]["default_range"]
            try:
                self.range_gauss, self.range_code, cpg = calfile.range_entry(self.sensor, rng)
            except ValueError as e:
                raise UsageError("--range %s: %s" % (rng, e))
            if self.cpg is not None and self.cpg != cpg:
                raise UsageError("--counts-per-gauss %d: %s at %s G has %d counts/G (give one "
                                 "or the other)" % (self.cpg, self.sensor, self.range_gauss, cpg))
            self.cpg = cpg
            self.output = calfile.SENSORS[self.sensor]["output"]
            self.overflow = chips.mag(self.sensor)["overflow"]  # the HMC5883L's -4096
        wrong = mounting.handedness(opts.get("mag_axes"), self.sensor)
        if wrong is not None:
            raise UsageError("--mag-axes %s" % wrong)
        if opts["out"] is not None and self.sensor is None:
            raise UsageError("--out %s needs --sensor (and --range), or a log whose first "
                             "lines name them ('# qmc5883l range_code 0', as "
                             "examples/log_csv.py writes): a board checks both before it "
                             "loads a calibration" % opts["out"])


def conversion(opts, board, mag, path):
    """(num, den, per_unit_text, cpg for the Calibrator or None, p or None): a file value v
    becomes round(v * num / den) counts."""
    units = opts["units"]
    scale = opts["scale"]
    if scale is not None and units not in (None, "counts"):
        raise UsageError("--scale %s and --units %s: give one (--scale is counts per file unit)"
                         % (decimal_text(scale), units))
    if scale is not None:
        num, den = scale[0], 10 ** scale[1]
        p = None
    elif board.cpg is not None:
        p = None
        if units in UNITS_PER_GAUSS:
            num, den = board.cpg, UNITS_PER_GAUSS[units]
        else:
            if units is None and mag.decimals:
                raise UsageError("%s: values have decimals but the board counts are integers: "
                                 "give the file's units (--units uT, mG, G, nT), or --scale "
                                 "COUNTS_PER_UNIT, or --units counts to round them" % path)
            num, den = 1, 1
    else:
        p = mag.power()
        num, den = (10 ** p, 1) if p >= 0 else (1, 10 ** (-p))
    cpg = board.cpg
    if cpg is None and units in UNITS_PER_GAUSS:
        # counts per gauss of the scaled counts: enables the field check
        c = logfile.rdiv(num * UNITS_PER_GAUSS[units], den)
        cpg = c if c >= 1 else None
    return num, den, cpg, p


# ---- forced fit: the firmware's own solve with its acceptance checks turned into notes ------

def forced_solve(cal, model):
    """The Calibration the firmware's solver gives past every acceptance check
    (Calibrator.solve(checks=False): sample count, degeneracy, coverage, soft iron, field, fit
    error, better-than-current become notes in cal.overridden). 'auto' tries 10, 7, then 4.
    Raises CalibrationRejected when even that is impossible (a singular system, V outside
    int16, too few samples to solve at all)."""
    from firmware.errors import CalibrationRejected

    if model == "auto":
        err = None
        for m in (10, 7, 4):
            try:
                return forced_solve(cal, m)
            except CalibrationRejected as e:
                err = e
        raise err
    return cal.solve(model=model, accept=False, checks=False)


# ---- run ---------------------------------------------------------------------------------

def desktop_plan(rows, capacity=None, separation=None, board_like=False):
    """(capacity, separation, step) for a log of `rows` data rows; every step-th row is offered.

    Default, the desktop: separation 1 count, so every distinct sample is held, in a buffer of
    `capacity` (default DESKTOP_CAPACITY) but no larger than the log; a log of more rows than
    that is offered every step-th row, step = ceil(rows / capacity): nothing is evicted and
    the rows keep the log's own weighting in time (the float64 fit of every row weights them
    so too; tests/test_datasets.py holds the fits together).
    board_like: a board's buffer (BOARD_CAPACITY unless `capacity`) and separation rule (None:
    from the sensitivity, else from the data's range), every row offered."""
    if board_like:
        return capacity or BOARD_CAPACITY, separation, 1
    cap = capacity or DESKTOP_CAPACITY
    step = max(1, -(-rows // cap))
    return max(12, min(cap, -(-rows // step))), 1 if separation is None else separation, step


def _model(text):
    return text if text in ("minmax", "auto") else int(text)


def _feed(cal, pts, keep, step):
    # every step-th row of the log (desktop_plan), but those left out
    for i in range(0, len(keep), step):
        if keep[i]:
            cal.add(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2])


def _solve(cal, model):
    """(fit, refusal, failure): the accepted fit (refusal None), or the refused one with the
    fit forced_solve gives past the checks (None, and why in failure, when not even that)."""
    from firmware.errors import CalibrationRejected
    try:
        return cal.solve(model=model, accept=False), None, None
    except CalibrationRejected as e:
        rej = e
    except MemoryError:
        raise UsageError("out of memory solving %d samples: give a smaller --capacity"
                         % cal.count)
    try:
        return forced_solve(cal, model), rej, None
    except CalibrationRejected as e:
        return None, rej, e


def run(opts):
    """Read, convert, calibrate. Returns (calibration or None, rejection or None, info);
    UsageError for unusable input."""
    from firmware.calibrate.acceptance import DEFAULT_MAX_FIT_ERROR
    from firmware.calibrate.calibrator import Calibrator

    path = opts["file"]
    opts, board_note = logged_board(opts, path)
    board = Board(opts)
    log, mag = _read_log(opts, path)
    opts, units_note = header_units(opts, log)
    num, den, cpg, p = conversion(opts, board, mag, path)
    capacity, separation, step = desktop_plan(log.rows_read, opts["capacity"],
                                              opts["separation"], opts["board_like"])
    mfe = opts["max_fit_error"]
    mfe = DEFAULT_MAX_FIT_ERROR if mfe is None else logfile.scale_value(mfe[0], mfe[1], 2)
    model = _model(opts["model"])

    def calibrator(plan):
        try:
            return Calibrator(model=model, capacity=plan[0], separation=plan[1],
                              counts_per_gauss=cpg, max_fit_error=mfe,
                              overflow=board.overflow)
        except MemoryError:
            raise UsageError("--capacity %d: out of memory; give a smaller one" % plan[0])
    t = _take_rows(log, board, num, den)
    used, outside = t["used"], t["outside"]
    keep = bytearray(b"\x01" * used)
    far = glitches.box_outliers(t["pts"], keep)   # before any fit: rows far outside the others
    for i in far:
        keep[i] = 0
    # rows: every data row once (log.skipped counts the reader's corrupt rows and, since
    # log.bad, those outside the output, which log.rows_read counted as read already)
    rows = log.rows_read + log.skipped - outside
    note = None
    if board.sensor is not None and outside * 2 > rows:
        note = calopts.range_advice(board, opts, outside, rows, t["peak"],
                                    calopts.named_sensor(path))
        board_note = None   # the advice names the log's chip already
    info = {"rows": rows, "range_note": note, "units": opts["units"], "units_note": units_note,
            "board_note": board_note, "logged_board": opts.get("logged_board"),
            "outside": outside, "used": used, "railed": t["railed"] + t["markers"],
            "skipped": log.skipped,
            "warnings": log.warnings, "num": num, "den": den, "p": p, "cpg": cpg,
            "held": 0, "separation": separation, "step": step, "board": board,
            "log": log, "zeros": t["zeros"], "far": far, "off": [], "lines": t["lines"]}
    if used == 0:
        olo, ohi = board.output
        if note is not None:
            raise UsageError("%s: no row within %d..%d counts: %s" % (path, olo, ohi, note))
        _print_warnings(log)
        raise UsageError("%s: no row within %d..%d counts after conversion (x %s / %s): check "
                         "--units, --scale, --sensor and --range" % (path, olo, ohi, num, den))
    plan = (capacity, separation, step)
    cal, c, rej, fail = _fit(calibrator, model, t["pts"], keep, plan, opts["board_like"], info)
    info.update({"off": sorted(info["off"]), "railed": cal.railed + t["railed"] + t["markers"],
                 "held": cal.count, "separation": cal.separation})
    return _outcome(c, rej, fail, info, opts["force"])


def _read_log(opts, path):
    """(log, mag): the log opened and its rows' magnitudes read; UsageError when it holds
    no data row."""
    log = logfile.Log(path, opts["columns"], opts["skip"])
    mag = logfile.Magnitude()
    for _, row in log.rows():
        mag.add(row)
    if log.rows_read:
        return log, mag
    if log.skipped:
        ln, msg = log.warnings[0]
        vals = None
        if log.names is not None and opts["columns"] is None:
            vals = calopts.value_columns(log.names, log.columns)
        raise UsageError("%s: no valid data row (%d corrupt; line %d: %s)%s"
                         % (path, log.skipped, ln, msg, "" if vals is None else
                            "; each value follows its label (%s): --columns %d,%d,%d "
                            "reads them" % ((" ".join(log.names[:6]),) + vals)))
    if opts["skip"]:
        raise UsageError("%s: no data rows left after --skip %d" % (path, opts["skip"]))
    raise UsageError("%s: no data rows%s" % (path, " after the header (line %d)"
                                             % log.header_line if log.header_line else ""))


def _take_rows(log, board, num, den):
    """The rows a fit may use, in counts: {"pts": row i at 3i..3i+2, "lines": their line
    numbers, "used": how many}, and the counts of those left out: "markers" (the HMC5883L's
    overflow marker: dropped, not "corrupt"), "railed" (an axis at an int16 rail: a clipping
    chip; Calibrator.add), "zeros" (all-zero: a failed read, glitches.py), "outside" (beyond
    the stated chip's output: its counts they are not; logged by log.bad) and "peak" (the
    largest |value| of those, in counts)."""
    olo, ohi = board.output
    t = {"used": 0, "markers": 0, "railed": 0, "outside": 0, "peak": 0, "zeros": 0,
         "pts": array("h", bytes(6 * log.rows_read)),
         "lines": array("i", bytes(4 * log.rows_read))}
    pts = t["pts"]
    names = None
    used = 0
    for lineno, row in log.rows():
        v = [logfile.convert(m, d, num, den) for m, d in row]
        if board.overflow is not None and board.overflow in v:
            t["markers"] += 1
            continue
        bad = -1
        for k in range(3):
            if not olo <= v[k] <= ohi:
                bad = k
        if bad >= 0:
            t["outside"] += 1
            t["peak"] = max(t["peak"], max([abs(x) for x in v]))
            if names is None:
                names = log.column_names()
            log.bad(lineno, "%s = %s is %d counts, outside %d..%d%s" % (
                names[bad], decimal_text(row[bad]), v[bad], olo, ohi,
                " (%s at %s G)" % (board.sensor, board.range_gauss) if board.sensor else ""))
            continue
        if v[0] == 0 and v[1] == 0 and v[2] == 0:
            t["zeros"] += 1
            continue
        if 32767 in v or -32768 in v:
            t["railed"] += 1
            continue
        pts[3 * used] = v[0]
        pts[3 * used + 1] = v[1]
        pts[3 * used + 2] = v[2]
        t["lines"][used] = lineno
        used += 1
    t["used"] = used
    return t


def _fit(calibrator, model, pts, keep, plan, board_like, info):
    """(calibrator, fit, refusal, failure) of the rows `keep` marks: the rows far off the fit
    (glitches.py) are found on every row the desktop holds, even for --board-like, whose
    thinned buffer a row far off can bend more; those found go to info["off"]."""
    screen = desktop_plan(len(keep)) if board_like else plan   # len(keep): the rows used
    fits = 0
    while True:
        cal = calibrator(screen)
        _feed(cal, pts, keep, screen[2])
        c, rej, fail = _solve(cal, model)
        fits += 1
        if c is None or fits == glitches.ROUNDS or (rej is not None and rej.reason in (
                "planar", "too_few_samples")):
            break  # (a fit the samples do not determine says nothing of a row's distance)
        off = glitches.radius_outliers(c, pts, keep)
        if not off:
            break
        for i in off:
            keep[i] = 0
        info["off"] += off
    if screen != plan:
        cal = calibrator(plan)
        _feed(cal, pts, keep, plan[2])
        c, rej, fail = _solve(cal, model)
    return cal, c, rej, fail


def _outcome(c, rej, fail, info, force):
    """run()'s answer: the accepted fit; or, refused, the refusal, or with --force the
    forced fit (the refusal kept in info["forced"])."""
    if rej is None:
        return c, None, info
    if not force:
        return None, rej, info
    if c is None:
        info["force_failed"] = fail
        return None, rej, info
    info["forced"] = rej
    return c, None, info


def logged_board(opts, path):
    """(opts, note): the sensor and range a log's comment line names (examples/log_csv.py:
    `# qmc5883l range_code 0 ...`, the board's counts) are the board's when no option says
    what the numbers are (--sensor, --counts-per-gauss, --units other than counts, --scale);
    an option that differs from the line wins, with a note."""
    try:
        named = calopts.logged_board(path)
    except ValueError as e:
        raise UsageError("%s: %s" % (path, e))
    if named is None:
        return opts, None
    chip, rng, line = named
    opts = dict(opts)
    given = opts["sensor"]
    units = opts["units"] not in (None, "counts")
    if given is None and opts["counts_per_gauss"] is None and not units \
            and opts["scale"] is None:
        opts["logged_board"] = line
        opts["sensor"] = (chip, None)
        if opts["range"] is None:
            opts["range"] = rng
        elif _entry(chip, opts["range"])[1] != calfile.range_entry(chip, rng)[1]:
            return opts, _differs("--range %s" % opts["range"], line)
        return opts, None
    why = None
    if given is not None:
        g = given if isinstance(given, str) else given[0]
        rg = opts["range"] or calfile.SENSORS[g]["default_range"]
        if g != chip or _entry(g, rg)[0] != rng:
            why = "--sensor %s%s" % (g, "" if opts["range"] is None
                                     else " --range %s" % opts["range"])
    elif units:
        why = "--units %s" % opts["units"]
    elif opts["counts_per_gauss"] is not None \
            and opts["counts_per_gauss"] != calfile.range_entry(chip, rng)[2]:
        why = "--counts-per-gauss %d" % opts["counts_per_gauss"]
    return opts, _differs(why, line)


def _differs(why, line):
    if why is None:
        return None
    return "%s differs from the log's line %r: read as %s says (the options win)" % (
        why, line, why)


def _entry(chip, rng):
    try:
        return calfile.range_entry(chip, rng)
    except ValueError as e:
        raise UsageError("--range %s: %s" % (rng, e))


def header_units(opts, log):
    """(opts, note): the units the header's column names state ('Mag_X (uT)', 'mx_mG', 'x [G]')
    are the file's when neither --units nor --scale says; an explicit --units that differs
    from them wins, with a note (one warning line) saying so."""
    said = log.header_units()
    if said is None:
        return opts, None
    if opts["units"] is None and opts["scale"] is None:
        opts = dict(opts)
        opts["units"] = said
        return opts, None
    if opts["units"] is not None and opts["units"] != said:
        return opts, ("--units %s differs from the header's units, %s (%s): the file is read "
                      "as %s (--units wins)" % (opts["units"], said,
                                                ", ".join(log.column_names()), opts["units"]))
    return opts, None


def _unit(v, num, den):
    """counts -> file units."""
    return v * den / num


def calibration_fields(c, info, date):
    """The calfile keys (sensor keys None when no sensor was stated)."""
    b = info["board"]
    rej = info.get("forced")
    return {"format": calfile.FORMAT, "version": calfile.FORMAT_VERSION,
            "sensor": b.sensor, "range_gauss": b.range_gauss, "range_code": b.range_code,
            "counts_per_gauss": b.cpg, "model": c.model, "offset_counts": list(c.offset),
            "invw_q15": list(c.invw), "field_counts": c.field, "field_out_counts": c.field_out,
            "fit_error_x100": c.fit_error, "samples": c.samples,
            "coverage_percent": c.coverage, "date": date, "forced": rej is not None,
            "refusal": rej.reason if rej is not None else ""}


def report(c, info, date):
    """The JSON-able dict: the calibration in counts (calfile keys) and in file units."""
    num, den = info["num"], info["den"]
    r = calibration_fields(c, info, date)
    k = c.field / c.field_out if c.field_out else 1.0
    r.update({
        "offset": [_unit(v, num, den) for v in c.offset],
        "invw": [[c.invw[3 * i + j] / 32768 * k for j in range(3)] for i in range(3)],
        "field": _unit(c.field, num, den),
        "scale": num / den,
        "fit_error_percent": c.fit_error / 100,
        "samples_used": c.samples,
        "rows": info["rows"], "skipped_rows": info["skipped"], "rail_samples": info["railed"],
        "units": info["units"], "glitch_rows": glitch_rows(info), "warnings": warning_list(info),
    })
    if info["cpg"]:
        r["field_ut"] = c.field * 100 / info["cpg"]
    if info.get("forced") is not None:
        r["refusal_detail"] = info["forced"].detail
    return r


def glitch_rows(info):
    """The JSON's glitch_rows: the rows left out of the fit, by kind (glitches.py)."""
    return {"all_zero": info.get("zeros", 0), "rails": info["railed"],
            "outside_range": len(info.get("far", ())), "off_ellipsoid": len(info.get("off", ()))}


def warning_list(info):
    """The JSON's warnings: the rows skipped (the first few, by line), then what the options
    and the log say together (a breakout read as its chip; most rows outside the chip)."""
    out = ["line %d: %s" % w for w in info["warnings"]]
    g = glitch_line(info)
    if g:
        out.append(g)
    for w in (info["board"].note, info.get("board_note"), info.get("range_note"),
              info.get("units_note")):
        if w:
            out.append(w)
    return out


def _print_notes(info):
    for w in (info["board"].note, info.get("board_note"), info.get("range_note"),
              info.get("units_note")):
        if w:
            warn(COMMAND, w)


def _line_list(info, idx):
    return ", ".join(["%d" % info["lines"][i] for i in idx[:3]]) + (", ..." if len(idx) > 3
                                                                     else "")


def glitch_line(info):
    """The one line that says which glitch rows were left out of the fit, of which kind and
    how many (glitches.py), or None."""
    parts = []
    if info.get("zeros"):
        parts.append("%d all-zero row(s) (a failed read)" % info["zeros"])
    if info.get("railed"):
        parts.append("%d sample(s) at the sensor's rails dropped (int16 limits or an overflow "
                     "marker: a clipping or overflowing chip)" % info["railed"])
    far = info.get("far")
    if far:
        parts.append("%d row(s) far outside the others' range (line %s)"
                     % (len(far), _line_list(info, far)))
    off = info.get("off")
    if off:
        parts.append("%d row(s) far off the fitted ellipsoid (line %s: corrected radius over "
                     "%d robust spreads from the median)"
                     % (len(off), _line_list(info, off), glitches.SPREADS))
    if not parts:
        return None
    return "%s: left out of the fit: %s%s" % (info["log"].path, "; ".join(parts),
                                              "; docs/calibration.md" if far or off else "")


def _print_warnings(log, info=None, outside=0):
    g = glitch_line(info) if info else None
    if g:
        warn(COMMAND, g)
    for ln, msg in log.warnings:
        warn(COMMAND, "%s: line %d skipped: %s" % (log.path, ln, msg))
    more = log.skipped - len(log.warnings)
    if more > 0:
        warn(COMMAND, "%s: %d more %s skipped" % (log.path, more, "corrupt rows" if not outside
                                                   else "rows (corrupt or outside the output)"))


def hint_for(reason, model):
    """What to try after a refusal for `reason` with --model `model` (text)."""
    if reason == "too_few_samples" and model in ("4", "minmax"):
        return "log more samples, turning the board through every orientation; or --force"
    return HINTS.get(reason, "--force to fit anyway")


def _refused(opts, rej, info):
    hint = hint_for(rej.reason, opts["model"])
    if info.get("range_note"):  # the refusal follows from it: most rows were left out
        hint = "most rows are outside the chip's output (warning above): --sensor, --range, " \
               "--units"
    fail = info.get("force_failed")
    if fail is not None:
        hint = "even --force cannot fit: %s: %s" % (fail.reason, fail.detail)
    # once, on stderr (stdout carries only a result: the JSON record with --json)
    print("%s %s: calibration refused (%s): %s (%d rows, %d skipped; %d samples held, "
          "separation %d counts); try: %s"
          % ("host_sim", COMMAND, rej.reason, rej.detail, info["rows"], info["skipped"],
             info["held"], info["separation"], hint), file=sys.stderr)
    if opts["json"]:
        print(json.dumps({"rejected": rej.reason, "detail": rej.detail, "hint": hint,
                          "rows": info["rows"], "skipped_rows": info["skipped"],
                          "rail_samples": info["railed"], "glitch_rows": glitch_rows(info),
                          "samples_held": info["held"], "warnings": warning_list(info)}))
    return STATUS_REFUSED


def body(opts):
    date = opts["date"] or calfile.iso_date()
    c, rej, info = run(opts)
    _print_warnings(info["log"], info, info["outside"])
    _print_notes(info)
    if rej is not None:
        return _refused(opts, rej, info)
    forced = info.get("forced")
    if forced is not None:
        warn(COMMAND, "forced: acceptance refused this fit (%s: %s); it is written as forced"
             % (forced.reason, forced.detail))
    r = report(c, info, date)
    check = mounting.offline(opts, c, info)  # a log with accelerometer columns
    if check is not None:
        r["mounting"] = check
    if opts["out"] is not None:
        try:
            calfile.write(opts["out"], dict([(k, r[k]) for k in calfile.KEYS]))
        except calfile.CalFileError as e:
            raise UsageError("--out: %s" % e)
    if opts["json"]:
        print(json.dumps(r))
        return STATUS_OK
    _print_text(r, c, info, opts)
    if check is not None:
        print("\n".join(mounting.offline_lines(check)))
    return STATUS_OK


def _print_text(r, c, info, opts):
    b = info["board"]
    print("model          %s%s" % (r["model"], "   (FORCED past: %s)" % r["refusal"]
                                   if r["forced"] else ""))
    print("offset V       %s %s %s   (file units)" % tuple(["%.4g" % v for v in r["offset"]]))
    print("W^-1 (det 1)   %s" % " ".join(["%8.5f" % v for v in r["invw"][0]]))
    print("               %s" % " ".join(["%8.5f" % v for v in r["invw"][1]]))
    print("               %s" % " ".join(["%8.5f" % v for v in r["invw"][2]]))
    print("V (counts)     %d %d %d" % tuple(c.offset))
    print("InvW (Q15)     %s" % " ".join(["%d" % v for v in c.invw]))
    print("field B        %.5g   (file units; %d counts; correct() outputs %d counts)"
          % (r["field"], c.field, c.field_out))
    if "field_ut" in r:
        print("               %.1f uT at %d counts/G" % (r["field_ut"], info["cpg"]))
    print("fit error      %.2f %%" % r["fit_error_percent"])
    print("samples        %d held of %d rows used (%d rows, %d skipped; %sseparation %d counts; "
          "1 file unit = %.6g counts)" % (c.samples, info["used"], r["rows"], r["skipped_rows"],
                                           "every %d rows offered; " % info["step"]
                                           if info["step"] > 1 else "",
                                           info["separation"], r["scale"]))
    print("coverage       %d %%" % c.coverage)
    if b.sensor:
        print("board          %s at %s G (range code %d, %d counts/G)%s"
              % (b.sensor, b.range_gauss, b.range_code, b.cpg,
                 "; the log's line %r" % info["logged_board"] if info["logged_board"] else ""))
    if opts["out"]:
        print("written        %s" % opts["out"])


def main(argv):
    return _parser().main(argv, body)


# ---- helpers kept for callers of the earlier interface -----------------------------------

def choose_scale(path, skip=0):
    """(p, rows): the power of ten the calibrate command scales a file's values by when no
    board is stated (logfile.Magnitude.power), and the valid data rows."""
    log = logfile.Log(path, None, skip)
    mag = logfile.Magnitude()
    for _, row in log.rows():
        mag.add(row)
    return mag.power(), log.rows_read


def scaled_rows(path, p, skip=0):
    """The rows of a file scaled by 10**p, rounded (corrupt rows left out)."""
    for _, r in logfile.Log(path, None, skip).rows():
        yield [logfile.scale_value(m, d, p) for m, d in r]
