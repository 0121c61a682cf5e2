"""What the calibrate command makes of the words a user types, and what it says when a log does
not fit the options given.

    sensor("GY-271")   -> ("qmc5883l", note)   a chip in any case, or a breakout's name
    units("µT")        -> "uT"                 a unit in any spelling the docs use
    logged_board("mag_log.csv") -> ("qmc5883l", "2", line)   examples/log_csv.py's first line
    range_advice(...)                          most rows outside the stated chip's output
    value_columns(fields, cols)                'Mx 34 My -292 Mz 420': --columns 2,4,6

Each refusal raises ValueError with one line saying what to give instead (args.py turns it into
`host_sim calibrate: error: --sensor X: ...`, exit 2). Also runs under MicroPython.
"""
from firmware.calibrate.samples import MAX_CAPACITY  # noqa: F401  (--capacity's bound: the Calibrator's)
from host_sim import chips
from desktop import calfile
from desktop.args import parse_decimal

# Breakouts by their silkscreen name (README's wiring table, boards/breakouts.py): the chip the
# calibration is for, and what to give when that breakout carries another chip
# (host_sim/chips.py BREAKOUTS).
BREAKOUTS = dict(chips.BREAKOUTS)
NO_MAGNETOMETER = {"gy521": "the GY-521 carries an MPU6050 (accelerometer and gyroscope), "
                            "no magnetometer"}
GENERIC = ("for another chip's log leave out --sensor and give the file's units (--units uT, "
           "mG, G, nT or counts) or --scale COUNTS_PER_UNIT: the fit is the same, reported in "
           "the file's units (--out needs one of these chips)")


def _key(text):
    return text.strip().lower().replace("-", "").replace("_", "").replace(" ", "")


def sensor(text):
    """--sensor: (chip, note or None); ValueError naming what the firmware drives."""
    k = _key(text)
    if k in calfile.SENSOR_NAMES:
        return k, None
    if k in BREAKOUTS:
        chip, other = BREAKOUTS[k]
        note = "%s read as its %s%s" % (text, chip, "; " + other if other else "")
        return chip, note
    known = "%s (breakouts %s)" % (", ".join(calfile.SENSOR_NAMES),
                                   ", ".join(sorted(BREAKOUTS)))
    if k in NO_MAGNETOMETER:
        raise ValueError("%s: give the magnetometer's chip: %s" % (NO_MAGNETOMETER[k], known))
    raise ValueError("not a chip this firmware drives: %s; %s" % (known, GENERIC))


# --units: every spelling -> the one the converter knows (UNITS_PER_GAUSS in calibrate.py)
UNIT_NAMES = {
    "counts": "counts", "count": "counts", "raw": "counts", "lsb": "counts",
    "ut": "uT", "microtesla": "uT", "microteslas": "uT",
    "mg": "mG", "milligauss": "mG", "mgauss": "mG",
    "g": "G", "gauss": "G", "gs": "G",
    "nt": "nT", "nanotesla": "nT", "nanoteslas": "nT",
}
UNITS_HELP = ("counts, uT (microtesla; a micro sign reads as u), mG (milligauss), G (gauss), "
              "nT (nanotesla), in any case")


def units(text):
    """--units: 'µT', 'uT', 'ut', 'microtesla', 'gauss', 'mG', ... -> 'uT', 'G', 'mG', ..."""
    k = text.strip()
    for micro in ("\u00b5", "\u03bc"):     # the micro sign and the Greek mu
        k = k.replace(micro, "u")
    k = k.lower()
    if k in UNIT_NAMES:
        return UNIT_NAMES[k]
    raise ValueError("expected %s" % UNITS_HELP)


def value_columns(fields, cols):
    """The 1-based columns of the values when a line reads `Mx 34 My -292 Mz 420` and its
    labels were taken for a header's names (0-based columns `cols`): the column after each
    label holds a number. None otherwise."""
    out = []
    for c in cols:
        if c + 1 >= len(fields):
            return None
        try:
            parse_decimal(fields[c + 1])
        except ValueError:
            return None
        out.append(c + 2)
    return tuple(out)


def named_sensor(path):
    """The chip a comment line at the top of the log names (examples/log_csv.py writes
    `# qmc5883l range_code 0 ...`), or None."""
    try:
        with open(path, "rb") as f:
            head = f.read(2048)
    except OSError:
        return None
    for line in head.split(b"\n")[:20]:
        s = line.strip().lower()
        if s[:1] == b"#":
            for name in calfile.SENSOR_NAMES:
                if name.encode() in s:
                    return name
    return None


def logged_board(path):
    """(chip, range in gauss as text, the line) from the comment line examples/log_csv.py writes
    above its header, `# qmc5883l range_code 0 counts_per_gauss 12000`, or None when the log's
    first lines hold none. ValueError when the line names a range or sensitivity the chip
    does not have."""
    try:
        with open(path, "rb") as f:
            head = f.read(2048)
    except OSError:
        return None
    for raw in head.split(b"\n")[:20]:
        line = raw.strip()
        if line[:1] != b"#":
            continue
        text = "".join([chr(c) if c < 128 else "?" for c in line])   # any bytes, any port
        w = text[1:].split()
        if len(w) < 3 or w[0].lower() not in calfile.SENSOR_NAMES or w[1] != "range_code":
            continue
        chip = w[0].lower()
        for rng, code, cpg in calfile.SENSORS[chip]["ranges"]:
            if w[2] == str(code):
                if len(w) >= 5 and w[3] == "counts_per_gauss" and w[4] != str(cpg):
                    raise ValueError("%r: %s's range code %s is %s G at %d counts/G, not %s"
                                     % (text, chip, code, rng, cpg, w[4]))
                return chip, rng, text
        raise ValueError("%r: %s has no range code %s (%s)" % (text, chip, w[2], ", ".join(
            ["%d: %s G" % (c, r) for r, c, _ in calfile.SENSORS[chip]["ranges"]])))
    return None


def range_advice(board, opts, outside, rows, peak, named):
    """One line: `outside` of `rows` rows beyond the stated chip's output, and what to give."""
    lo, hi = board.output
    tips = []
    if named is not None and named != board.sensor:
        tips.append("the file's comment names %s: --sensor %s" % (named, named))
    converted = opts["units"] not in (None, "counts") or opts["scale"] is not None
    if converted:
        tips.append("check --units / --scale, or a larger --range (fewer counts per gauss)")
    else:
        if board.sensor == "hmc5883l" and peak <= 32767 and named is None:
            tips.append("int16 counts like these are a QMC5883L's or QMC5883P's: --sensor "
                        "qmc5883l or qmc5883p")
        tips.append("a file in uT, mG, G or nT: --units")
    tips.append("another magnetometer's log: leave out --sensor")
    return ("%d of %d rows (%d %%) are outside %s's output %d..%d counts at %s G (values reach "
            "%d): not this chip's counts at this range; %s" % (
                outside, rows, outside * 100 // rows, board.sensor, lo, hi, board.range_gauss,
                peak, "; ".join(tips)))
