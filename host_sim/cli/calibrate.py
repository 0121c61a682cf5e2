"""`python -m host_sim calibrate FILE.csv [options]`: calibrate a logged magnetometer file offline.

Runs the firmware's own Calibrator (firmware/magcal.py) over the file, so the result is the
one a board would compute from the same samples (with the desktop's larger buffer).
Also runs under `micropython -m host_sim calibrate ...` (no argparse).
"""
import json

USAGE = """usage: python -m host_sim calibrate FILE.csv [options]

Calibrate a magnetometer log with the firmware's Calibrator and print the result.
FILE.csv has a header line naming columns mx,my,mz (other columns are ignored; lines before
the header are skipped). Values are integer counts, or decimals (e.g. uT), which are scaled
by the largest power of ten that keeps every value in int16; results are reported back in
the file's units.

options:
  --model M            minmax, 4, 7, 10 or auto (default 10)
  --json               print one JSON object: model, offset, invw (W^-1, det 1), invw_q15,
                       field, fit_error_percent, samples_used, coverage_percent, scale
  --skip N             ignore the first N data rows (e.g. 3000 still samples); a still
                       period is harmless anyway: distance separation keeps one or two
  --capacity N         samples the buffer holds (default %d; a board uses %d: the desktop
                       can afford more, which lowers the separation and keeps more samples)
  --separation N       counts between kept samples, in scaled counts (default: derived
                       from the data's range, as the board does without counts_per_gauss)
  --counts-per-gauss N the sensor's sensitivity in the file's units (integer files):
                       enables the 10..90 uT field check and sets the default separation
  --max-fit-error PCT  refuse fits with a larger fit error (default %s %%)
  -h, --help           this text

exit status: 0 calibrated; 2 the calibration was refused (the reason is printed, as
{"rejected": "<reason>", "detail": ...} with --json); 1 bad usage or unreadable file.
"""

DESKTOP_CAPACITY = 1000


class UsageError(Exception):
    pass


def parse_decimal(text):
    """'-22.800001' -> (-22800001, 6): the exact value as mantissa / 10**decimals.
    Accepts an optional exponent ('1.5e-3'). Raises ValueError on anything else."""
    t = text.strip()
    exp = 0
    for e in ("e", "E"):
        if e in t:
            t, ex = t.split(e, 1)
            exp = int(ex)
    neg = t.startswith("-")
    if t[:1] in "+-":
        t = t[1:]
    if "." in t:
        whole, frac = t.split(".", 1)
    else:
        whole, frac = t, ""
    if not (whole + frac) or not (whole + frac).isdigit():
        raise ValueError("not a number: %r" % text)
    m = int(whole + frac)
    dec = len(frac) - exp
    if dec < 0:
        m *= 10 ** (-dec)
        dec = 0
    return (-m if neg else m), dec


def iter_rows(path, skip=0):
    """Yield [(m, dec)] * 3 exact values per data row of a file with an mx,my,mz header
    (streamed: a 22k-row log must fit MicroPython's heap)."""
    cols = None
    lineno = 0
    n = 0
    with open(path) as f:
        for line in f:
            lineno += 1
            line = line.strip()
            if not line:
                continue
            parts = [p.strip() for p in line.split(",")]
            if cols is None:
                names = [p.lower() for p in parts]
                if "mx" in names and "my" in names and "mz" in names:
                    cols = (names.index("mx"), names.index("my"), names.index("mz"))
                continue
            n += 1
            if n <= skip:
                continue
            try:
                yield [parse_decimal(parts[c]) for c in cols]
            except (ValueError, IndexError):
                raise UsageError("%s:%d: expected numbers in columns mx,my,mz, got %r"
                                 % (path, lineno, line))
    if cols is None:
        raise UsageError("%s: no header line with columns mx,my,mz" % path)


def _rdiv(n, d):
    # n / d rounded half away from zero (d > 0)
    if n >= 0:
        return (n + d // 2) // d
    return -((-n + d // 2) // d)


def scale_value(m, d, p):
    """m / 10**d times 10**p, rounded to an int."""
    k = p - d
    return m * 10 ** k if k >= 0 else _rdiv(m, 10 ** (-k))


def choose_scale(path, skip=0):
    """(p, rows): the largest power of ten p that keeps every value of the file within
    int16 after rounding (p = 0 for an integer file that fits; negative if it does not)."""
    decimals = 0
    big_m, big_d = 0, 0    # the largest |value|, exactly
    rows = 0
    for r in iter_rows(path, skip):
        rows += 1
        for m, d in r:
            if d > decimals:
                decimals = d
            a = -m if m < 0 else m
            if a * 10 ** big_d > big_m * 10 ** d:
                big_m, big_d = a, d
    p = 0
    if decimals:
        while scale_value(big_m, big_d, p + 1) <= 32767 and p < 12:
            p += 1
    while scale_value(big_m, big_d, p) > 32767:
        p -= 1
    return p, rows


def scaled_rows(path, p, skip=0):
    for r in iter_rows(path, skip):
        yield [scale_value(m, d, p) for m, d in r]


def parse_args(argv):
    opts = {"model": 10, "json": False, "skip": 0, "capacity": DESKTOP_CAPACITY,
            "separation": None, "counts_per_gauss": None, "max_fit_error": None, "file": None}
    i = 0
    ints = {"--skip": "skip", "--capacity": "capacity", "--separation": "separation",
            "--counts-per-gauss": "counts_per_gauss"}
    while i < len(argv):
        a = argv[i]
        if a in ("-h", "--help"):
            opts["help"] = True
            return opts
        if a == "--json":
            opts["json"] = True
        elif a in ints or a in ("--model", "--max-fit-error"):
            if i + 1 >= len(argv):
                raise UsageError("%s needs a value" % a)
            val = argv[i + 1]
            i += 1
            if a == "--model":
                if val not in ("minmax", "4", "7", "10", "auto"):
                    raise UsageError("--model %s: expected minmax, 4, 7, 10 or auto" % val)
                opts["model"] = val if val in ("minmax", "auto") else int(val)
            elif a == "--max-fit-error":
                m, d = parse_decimal(val)  # percent -> hundredths
                opts["max_fit_error"] = m * 100 // 10 ** d
            else:
                try:
                    opts[ints[a]] = int(val)
                except ValueError:
                    raise UsageError("%s %s: expected an integer" % (a, val))
        elif a.startswith("-"):
            raise UsageError("unknown option %s" % a)
        elif opts["file"] is None:
            opts["file"] = a
        else:
            raise UsageError("more than one input file (%s)" % a)
        i += 1
    if opts["file"] is None:
        raise UsageError("no input file")
    return opts


def run(opts):
    """Calibrate; returns (calibration or None, rejection or None, info dict)."""
    from firmware.errors import CalibrationRejected
    from firmware.acceptance import DEFAULT_MAX_FIT_ERROR
    from firmware.calibrator import Calibrator

    p, nrows = choose_scale(opts["file"], opts["skip"])
    kw = {}
    if opts["max_fit_error"] is not None:
        kw["max_fit_error"] = opts["max_fit_error"]
    else:
        kw["max_fit_error"] = DEFAULT_MAX_FIT_ERROR
    cpg = opts["counts_per_gauss"]
    if cpg is not None and p:
        cpg = cpg * 10 ** p if p > 0 else cpg // 10 ** (-p)
    cal = Calibrator(model=opts["model"], capacity=opts["capacity"],
                     separation=opts["separation"], counts_per_gauss=cpg, **kw)
    for r in scaled_rows(opts["file"], p, opts["skip"]):
        cal.add(r[0], r[1], r[2])
    info = {"rows": nrows, "scale": p, "held": cal.count, "separation": cal.separation}
    try:
        return cal.solve(), None, info
    except CalibrationRejected as e:
        return None, e, info


def _unit(v, p):
    return v / 10 ** p if p >= 0 else v * 10 ** (-p)


def report(c, p):
    """The JSON-able dict for a Calibration `c` in file units (10**p counts per unit)."""
    k = c.field / c.field_out if c.field_out else 1.0
    invw = [[c.invw[3 * i + j] / 32768 * k for j in range(3)] for i in range(3)]
    return {"model": c.model,
            "offset": [_unit(v, p) for v in c.offset],
            "invw": invw,
            "invw_q15": list(c.invw),
            "field": _unit(c.field, p),
            "fit_error_percent": c.fit_error / 100,
            "samples_used": c.samples,
            "coverage_percent": c.coverage,
            "scale": 10 ** p if p >= 0 else 1 / 10 ** (-p)}


def main(argv):
    try:
        opts = parse_args(argv)
        if opts.get("help"):
            from firmware.acceptance import DEFAULT_MAX_FIT_ERROR
            from firmware.calibrator import DEFAULT_CAPACITY
            print(USAGE % (DESKTOP_CAPACITY, DEFAULT_CAPACITY,
                           "%d.%02d" % (DEFAULT_MAX_FIT_ERROR // 100, DEFAULT_MAX_FIT_ERROR % 100)))
            return 0
        c, rej, info = run(opts)
    except UsageError as e:
        print("calibrate: %s (try --help)" % e)
        return 1
    except OSError as e:
        print("calibrate: cannot read %s: %s" % (opts["file"], e))
        return 1
    p = info["scale"]
    if rej is not None:
        if opts["json"]:
            print(json.dumps({"rejected": rej.reason, "detail": rej.detail,
                              "rows": info["rows"], "samples_held": info["held"]}))
        else:
            print("calibration refused: %s" % rej.reason)
            print("  %s" % rej.detail)
            print("  %d rows, %d samples held (separation %d counts)"
                  % (info["rows"], info["held"], info["separation"]))
        return 2
    r = report(c, p)
    if opts["json"]:
        print(json.dumps(r))
        return 0
    print("model          %s" % r["model"])
    print("offset V       %s %s %s   (file units)" % tuple("%.4g" % v for v in r["offset"]))
    print("W^-1 (det 1)   %s" % " ".join("%8.5f" % v for v in r["invw"][0]))
    print("               %s" % " ".join("%8.5f" % v for v in r["invw"][1]))
    print("               %s" % " ".join("%8.5f" % v for v in r["invw"][2]))
    print("InvW (Q15)     %s" % " ".join("%d" % v for v in c.invw))
    print("field B        %.5g   (file units; correct() outputs %d counts)"
          % (r["field"], c.field_out))
    print("fit error      %.2f %%" % r["fit_error_percent"])
    print("samples        %d of %d rows (separation %d counts, 1 unit = %s counts)"
          % (c.samples, info["rows"], info["separation"], r["scale"]))
    print("coverage       %d %%" % c.coverage)
    return 0
