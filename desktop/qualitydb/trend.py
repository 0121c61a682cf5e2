"""Per-parameter summary over the stored records: mean, sigma, repeatability and drift.

Drift is the least-squares slope of value over time within devices, pooled over the fleet
(each device measured from its own mean value and mean time, so the spread between devices
does not pass for a trend): sum (t - t_d)(x - x_d) / sum (t - t_d)^2. A month is
365.2425 / 12 days.
"""
import math

from desktop.qualitydb.limits import by_device, repeatability
from desktop.qualitydb.records import PARAMETERS

MONTH_S = 365.2425 / 12 * 86400


def summary(rows, parameters=PARAMETERS):
    """[{parameter, records, devices, mean, sigma, repeatability, drift_per_month}]."""
    groups = by_device(rows)
    out = []
    for p in parameters:
        xs = [r[p] for r in rows]
        n = len(xs)
        mean = sum(xs) / n if n else None
        sigma = math.sqrt(sum((x - mean) ** 2 for x in xs) / (n - 1)) if n > 1 else None
        sxy = sxx = 0.0
        for g in groups.values():
            tm = sum(r["t_epoch"] for r in g) / len(g)
            xm = sum(r[p] for r in g) / len(g)
            for r in g:
                dt = (r["t_epoch"] - tm) / MONTH_S
                sxy += dt * (r[p] - xm)
                sxx += dt * dt
        out.append({"parameter": p, "records": n, "devices": len(groups), "mean": mean,
                    "sigma": sigma, "repeatability": repeatability(groups, p),
                    "drift_per_month": sxy / sxx if sxx > 0 else None})
    return out
