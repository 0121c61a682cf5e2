"""`python -m host_sim field [--date YYYY-MM-DD] [--json] [LAT,LON ...]`: the board's field model.

Computes declination, inclination and total field with the firmware's own integer code and
table (firmware/field/wmm.py, firmware/field/wmm2025.bin), not with a float model, so the figures are the
ones a board prints for the same place and date. Points come as LAT,LON arguments (decimal
degrees, north and east positive: -33.9,151.2 is Sydney; a leading '-' is a point, not an
option) or, with none given, as LAT,LON lines on stdin. Also runs under `micropython -m host_sim`.
"""
import json
import sys

from firmware.fixedpoint import rdiv
from desktop.args import Parser, UsageError, error_line, parse_decimal

COMMAND = "field"


def degrees_e7(text, what, limit):
    """'-33.9' -> -339000000 exactly (1e-7 deg), checked against +-limit degrees."""
    try:
        m, dec = parse_decimal(text)
    except ValueError:
        raise UsageError("%s %r is not a number of degrees" % (what, text))
    v = m * 10 ** (7 - dec) if dec <= 7 else rdiv(m, 10 ** (dec - 7))
    if not -limit * 10000000 <= v <= limit * 10000000:
        raise UsageError("%s %s outside -%d..%d deg" % (what, text.strip(), limit, limit))
    return v


def parse_point(text, where):
    parts = text.split(",")
    if len(parts) != 2:
        raise UsageError("%s: %r is not LAT,LON in degrees" % (where, text.strip()))
    return (degrees_e7(parts[0], where + ": latitude", 90),
            degrees_e7(parts[1], where + ": longitude", 180), text.strip())


def parse_date(text):
    p = text.split("-")
    if len(p) != 3 or not all(s.isdigit() for s in p) or len(p[0]) != 4:
        raise UsageError("--date %r is not YYYY-MM-DD" % text)
    return int(p[0]), int(p[1]), int(p[2])


def parser():
    p = Parser(COMMAND, "[--date YYYY-MM-DD] [--json] [--table FILE] [LAT,LON ...]",
               "The World Magnetic Model 2025 as the board computes it (firmware/field/wmm.py,\n"
               "integer-only). LAT,LON in decimal degrees (north, east positive), e.g. 51.5,-0.13\n"
               "or -33.9,151.2; without arguments, one LAT,LON per line on stdin (blank lines and\n"
               "lines starting with # are skipped).")
    p.positional("points", "LAT,LON", "a place in decimal degrees", required=False, many=True,
                 kind=lambda text: parse_point(text, "LAT,LON %r" % text))
    p.option("--date", "str", metavar="YYYY-MM-DD",
             help="the date (default today); the model covers\n2025-01-01 .. 2030-01-01")
    p.option("--json", "flag", help="print a JSON list: lat, lon, declination_deg (east\n"
             "positive), inclination_deg (down positive), field_nt,\nhorizontal_nt, status")
    p.option("--table", "path", metavar="FILE",
             help="the table file (default firmware/field/wmm2025.bin)")
    p.epilog = ("exit status: 0 done; 1 the date is outside the model's validity; 2 bad usage "
                "or input.")
    return p


def stdin_points():
    pts = []
    n = 0
    for line in sys.stdin:
        n += 1
        s = line.strip()
        if s and not s.startswith("#"):
            pts.append(parse_point(s, "line %d" % n))
    return pts


def run(opts):
    from firmware.field.wmm import STATUS_OUTSIDE, FieldModel, FieldTableError, decimal_year_e3
    if opts["date"] is None:
        import time
        t = time.localtime()
        ymd = (t[0], t[1], t[2])
    else:
        ymd = parse_date(opts["date"])
    try:
        year_e3 = decimal_year_e3(*ymd)
    except ValueError as e:
        raise UsageError("--date %04d-%02d-%02d: %s" % (ymd + (e,)))
    points = opts["points"] or stdin_points()
    try:
        model = FieldModel(opts["table"])
    except FieldTableError as e:
        raise UsageError("field-model table unusable: %s" % e)
    out = []
    with model:
        for lat_e7, lon_e7, text in points:
            d, i, f, status = model.at(lat_e7, lon_e7, year_e3)
            if status == STATUS_OUTSIDE:
                print(error_line(COMMAND, "%04d-%02d-%02d is outside model validity (WMM2025: "
                                          "2025.0 to 2030.0)" % ymd), file=sys.stderr)
                return 1
            out.append({"lat": lat_e7 / 1e7, "lon": lon_e7 / 1e7,
                        "declination_deg": d / 100, "inclination_deg": i / 100,
                        "field_nt": f, "horizontal_nt": model.horizontal_nt, "status": status})
    if opts["json"]:
        print(json.dumps(out))
    else:
        print("%10s %11s %9s %9s %8s  status" % ("lat", "lon", "decl", "incl", "F nT"))
        for r in out:
            print("%10.5f %11.5f %9.2f %9.2f %8d  %s" % (
                r["lat"], r["lon"], r["declination_deg"], r["inclination_deg"], r["field_nt"],
                r["status"]))
    return 0


def main(argv):
    return parser().main(argv, run)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
