"""`python -m host_sim wmm [--step DEG] [--out FILE]`: write the board's World Magnetic Model table.

`make wmm` runs it. It evaluates the official WMM2025 spherical-harmonic model (the coefficient
file WMM_2025.COF and the float implementation shipped by the PyPI package pygeomag, pinned in
requirements.txt) on a latitude/longitude grid at sea level, and writes firmware/field/wmm2025.bin,
which firmware/field/wmm.py reads a few records at a time. Host only: the board never sees pygeomag.

What each grid node holds (docs/field_model.md has the measurements behind the choices):
  X0, Y0, Z0     north, east, down components at the epoch 2025.0, int16 in units of 4 nT
                 (|Z| reaches 66.9 uT near the south magnetic pole: 2 nT units would overflow)
  SX, SY, SZ     their secular variation, int16 in units of 1/8 nT per year. WMM's Gauss
                 coefficients are linear in time (g(t) = g + (t - 2025) dg/dt), and X, Y, Z are
                 linear in the coefficients, so SV = (B(2030.0) - B(2025.0)) / 5 exactly.
Rows run south to north from -90 - PAD*step to 90 + PAD*step; a row beyond a pole is the
meridian continued over it: the node (90 + d, lon) is the point (90 - d, lon + 180) with X and Y
negated (the local north and east axes turn round there), so the board's 4 x 4 cubic stencil
needs no special case at the poles. Columns run east from -180 in steps of `step` (no repeated
+180 column: the board wraps the index).

File layout (little-endian), version 1:
  0   4  magic b"WMMT"
  4   1  version (1)
  5   1  PAD, rows beyond each pole (1)
  6   2  n_lat (rows, padding included)
  8   2  n_lon (columns)
  10  4  step in 1e-7 deg
  14  4  epoch as decimal year * 1000 (2025000)
  18  2  life in years * 1000 (5000)
  20  1  nT per count of X0, Y0, Z0 (4)
  21  1  counts per nT/year of SX, SY, SZ (8)
  22  1  record bytes (12)
  23  1  reserved (0)
  24  4  CRC-32 (IEEE, as binascii.crc32) of the records
  28  4  model name, ASCII b"2025"
  32  n_lat * n_lon records of 6 int16 (X0 Y0 Z0 SX SY SZ), row by row
"""
import os
import struct
import sys
import zlib

from desktop.args import Parser, UsageError, decimal_text


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUT = os.path.join(ROOT, "firmware", "field", "wmm2025.bin")
DEFAULT_STEP_E7 = 75000000  # 7.5 deg: docs/field_model.md compares 10, 9, 7.5 and 5 deg grids
COF = "wmm/WMM_2025.COF"  # inside the pygeomag package
EPOCH = 2025.0
LIFE = 5.0
PAD = 1
MAIN_NT = 4
SV_PER_NT = 8
RECORD = 12
HEADER = struct.Struct("<4sBBHHIIHBBBBI4s")


def geomag():
    from pygeomag import GeoMag
    return GeoMag(coefficients_file=COF)


def node_xyz(model, lat, lon, t):
    """X, Y, Z in nT at a grid node, rows beyond a pole continued over it (see above)."""
    if lat > 90 or lat < -90:
        x, y, z = node_xyz(model, (180 if lat > 0 else -180) - lat, lon + 180, t)
        return -x, -y, z
    while lon >= 180:
        lon -= 360
    r = model.calculate(glat=lat, glon=lon, alt=0, time=t)
    return r.x, r.y, r.z


def _count(v, what):
    c = int(round(v))
    if not -32768 <= c <= 32767:
        raise ValueError("%s = %d does not fit an int16" % (what, c))
    return c


def build(step_e7=DEFAULT_STEP_E7):
    """The table file's bytes."""
    if step_e7 <= 0 or 1800000000 % step_e7:
        raise UsageError("--step must divide 180 degrees")
    model = geomag()
    n_lat = 1800000000 // step_e7 + 1 + 2 * PAD
    n_lon = 3600000000 // step_e7
    step = step_e7 / 1e7
    recs = bytearray()
    for i in range(n_lat):
        lat = -90 + (i - PAD) * step
        for j in range(n_lon):
            lon = -180 + j * step
            b0 = node_xyz(model, lat, lon, EPOCH)
            b1 = node_xyz(model, lat, lon, EPOCH + LIFE)
            vals = [_count(b0[k] / MAIN_NT, "main field") for k in range(3)]
            vals += [_count((b1[k] - b0[k]) / LIFE * SV_PER_NT, "secular variation")
                     for k in range(3)]
            recs += struct.pack("<6h", *vals)
    head = HEADER.pack(b"WMMT", 1, PAD, n_lat, n_lon, step_e7, int(EPOCH * 1000),
                       int(LIFE * 1000), MAIN_NT, SV_PER_NT, RECORD, 0,
                       zlib.crc32(bytes(recs)) & 0xFFFFFFFF, b"2025")
    return head + bytes(recs)


def parser():
    p = Parser("wmm", "[--step DEG] [--out FILE]",
               "Write the World Magnetic Model table the board's firmware/field/wmm.py reads.")
    p.option("--step", "decimal", default=(DEFAULT_STEP_E7, 7), lo="0.1", hi="180",
             metavar="DEG", help="grid step in degrees, dividing 180 (default 7.5)")
    p.option("--out", "path", default=DEFAULT_OUT, metavar="FILE",
             help="output file (default firmware/field/wmm2025.bin)")
    p.epilog = "exit status: 0 written; 2 bad usage or pygeomag missing."
    return p


def body(opts):
    m, dec = opts["step"]
    if dec > 7:
        raise UsageError("--step %s: finer than 1e-7 deg" % decimal_text(opts["step"]))
    try:
        data = build(m * 10 ** (7 - dec))
    except ImportError as e:
        raise UsageError("%s (pygeomag is in requirements.txt: make venv)" % e)
    with open(opts["out"], "wb") as f:
        f.write(data)
    print("wmm: wrote %s (%d bytes)" % (opts["out"], len(data)))
    return 0


def main(argv):
    return parser().main(argv, body)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
