"""The board's field model (firmware/field/wmm.py and its table firmware/field/wmm2025.bin) against the
full float World Magnetic Model 2025 (pygeomag, host only), as docs/field_model.md states it.

Points are area-uniform on the sphere, dates uniform over the model's life 2025.0-2030.0:
10,000 with |lat| <= 60 deg (the goals: declination RMS <= 0.1 deg and max <= 0.5 deg,
inclination max <= 0.3 deg, total field within 0.5 %) and 3,000 in the polar band, where the
declination is also reported where WMM itself trusts a compass (H >= 6000 nT). The errors are
the board's integer answers (centidegrees, nT) minus the float model's.

python -m desktop.benchmarks.fieldacc [--smoke]   (one JSON line)
"""
import math
import os
import random
import sys

from desktop.benchmarks import common

GOALS = {"decl_rms_deg": 0.1, "decl_max_deg": 0.5, "incl_max_deg": 0.3, "field_max_pct": 0.5}
H_TRUSTED_NT = 6000   # WMM's caution zone starts below this horizontal field


def points(rng, n, lat_lo, lat_hi):
    """n (lat_e7, lon_e7, year_e3) area-uniform in lat_lo <= |lat| <= lat_hi (degrees), dates
    uniform over the model's life."""
    s0, s1 = math.sin(math.radians(lat_lo)), math.sin(math.radians(lat_hi))
    pts = []
    for _ in range(n):
        lat = math.degrees(math.asin(rng.uniform(s0, s1))) * rng.choice((-1, 1))
        pts.append((int(round(lat * 1e7)), rng.randint(-1800000000, 1800000000),
                    rng.randint(2025000, 2030000)))
    return pts


def reference():
    """The float model from the coefficients the table is built from."""
    import pygeomag

    from desktop import wmm
    return pygeomag.GeoMag(coefficients_file=wmm.COF)


def errors(model, ref, pts):
    """Per point: (declination error deg, inclination error deg, field error %, reference H
    in nT)."""
    out = []
    for lat_e7, lon_e7, year_e3 in pts:
        d, i, f, _status = model.at(lat_e7, lon_e7, year_e3)
        r = ref.calculate(glat=lat_e7 / 1e7, glon=lon_e7 / 1e7, alt=0, time=year_e3 / 1000)
        dd = (d / 100 - r.d + 180) % 360 - 180
        out.append((dd, i / 100 - r.i, (f - r.f) / r.f * 100, r.h))
    return out


def summary(errs):
    dd = [e[0] for e in errs]
    return {"n": len(errs),
            "decl_rms_deg": math.sqrt(sum(v * v for v in dd) / len(dd)),
            "decl_max_deg": max(abs(v) for v in dd),
            "incl_max_deg": max(abs(e[1]) for e in errs),
            "field_max_pct": max(abs(e[2]) for e in errs)}


def measure(n_mid=10000, n_polar=3000):
    from firmware.field.wmm import FieldModel
    ref = reference()
    with FieldModel() as model:
        mid = errors(model, ref, points(random.Random(2025), n_mid, 0, 60))
        polar = errors(model, ref, points(random.Random(2030), n_polar, 60, 90))
    trusted = [e for e in polar if e[3] >= H_TRUSTED_NT]
    res = {"mid": summary(mid), "polar": summary(polar), "polar_trusted": summary(trusted)}
    from firmware.field import wmm as field
    res["table_bytes"] = os.path.getsize(os.path.join(os.path.dirname(field.__file__),
                                                      field.TABLE_NAME))
    return res


def main():
    smoke = common.smoke()
    res = {"interpreter": common.interpreter()}
    try:
        res.update(measure(1000, 300) if smoke else measure())
    except ImportError as e:  # pygeomag is host-only (requirements.txt)
        res["skipped"] = str(e)
    common.emit(res)


if __name__ == "__main__":
    sys.exit(main())
