"""A simulated fleet of calibration records with known truth, for the detection test and the
ingest benchmark (records are generated directly; no simulator run is needed).

Each device has nominal parameters drawn once (the spread between boards) and each calibration
adds small noise (the spread of repeated calibrations of one board). Units are those of a
calibrate run on a uT log. Figures (one sigma):
  hard iron V        fleet 15 uT per axis,        repeat 0.4 uT
  field B            fleet 1.5 uT around 50 uT,   repeat 0.3 uT
  InvW diagonal      fleet 0.03 around 1,         repeat 0.004
  fit error          fleet 0.3 % around 1.5 %,    repeat 0.1 %
A device is calibrated every 20..40 days, 6..14 times, from a start in the first half of
2024. DRIFT_SHARE of the devices drift slowly (hard iron up to 0.12 uT/month per axis, field
up to 0.05 uT/month: a third of a repeat sigma per month at most). CHANGE_SHARE have a
component changed before one of their calibrations after the first: a hard-iron jump of
3.5..12 uT on one axis, a soft-iron change of 0.035..0.10 on one InvW diagonal element, or a
field change of 2.5..8 uT; the smallest of each is about 8 repeat sigmas.
"""
import datetime
import random

DRIFT_SHARE = 0.20
CHANGE_SHARE = 0.05
_START = datetime.datetime(2024, 1, 1, tzinfo=datetime.timezone.utc)
_MONTH_DAYS = 30.436875          # 365.2425 / 12


def generate(devices=500, seed=1):
    """(records, truth): records as JSON-able dicts in time order per device; truth[device] =
    {"changed": kind or None, "change_time": ISO text or None, "drift": bool}."""
    rnd = random.Random(seed)
    records = []
    truth = {}
    n_changed = round(devices * CHANGE_SHARE)
    changed = set(rnd.sample(range(devices), n_changed))
    for d in range(devices):
        name = "dev%05d" % d
        off = [rnd.gauss(0, 15) for _ in range(3)]
        field = rnd.gauss(50, 1.5)
        diag = [rnd.gauss(1, 0.03) for _ in range(3)]
        offdiag = [rnd.gauss(0, 0.01) for _ in range(3)]
        fit = max(0.3, rnd.gauss(1.5, 0.3))
        drift = rnd.random() < DRIFT_SHARE
        d_off = [rnd.uniform(-0.12, 0.12) for _ in range(3)] if drift else [0.0] * 3
        d_field = rnd.uniform(-0.05, 0.05) if drift else 0.0
        n = rnd.randint(6, 14)
        t = _START + datetime.timedelta(days=rnd.uniform(0, 182))
        t0 = t
        kind = change_at = None
        if d in changed:
            kind = rnd.choice(("hard_iron", "soft_iron", "field"))
            change_at = rnd.randint(1, n - 1)
            axis = rnd.randrange(3)
            sign = rnd.choice((-1, 1))
        info = {"changed": kind, "change_time": None, "drift": drift}
        for i in range(n):
            if i:
                t += datetime.timedelta(days=rnd.uniform(20, 40))
            if i == change_at:
                info["change_time"] = t.strftime("%Y-%m-%dT%H:%M:%SZ")
                if kind == "hard_iron":
                    off[axis] += sign * rnd.uniform(3.5, 12)
                elif kind == "soft_iron":
                    diag[axis] += sign * rnd.uniform(0.035, 0.10)
                else:
                    field += sign * rnd.uniform(2.5, 8)
            months = (t - t0).total_seconds() / 86400 / _MONTH_DAYS
            o = [off[j] + d_off[j] * months + rnd.gauss(0, 0.4) for j in range(3)]
            w = [diag[j] + rnd.gauss(0, 0.004) for j in range(3)]
            x = [offdiag[j] + rnd.gauss(0, 0.002) for j in range(3)]
            records.append({
                "device": name, "time": t.strftime("%Y-%m-%dT%H:%M:%SZ"), "source": "cli",
                "model": 10,
                "offset": [round(v, 3) for v in o],
                "invw": [[round(w[0], 5), round(x[0], 5), round(x[1], 5)],
                         [round(x[0], 5), round(w[1], 5), round(x[2], 5)],
                         [round(x[1], 5), round(x[2], 5), round(w[2], 5)]],
                "field": round(field + d_field * months + rnd.gauss(0, 0.3), 3),
                "fit_error_percent": round(max(0.05, fit + rnd.gauss(0, 0.1)), 2),
                "samples_used": rnd.randint(150, 400),
                "coverage_percent": rnd.randint(75, 100),
            })
        truth[name] = info
    return records, truth


def score(flags, truth):
    """Detection figures: a changed device counts as found when a record at or after its
    change is flagged; an unchanged device with any flag is a false alarm."""
    first = {}
    for f in flags:
        first.setdefault(f["device"], []).append(f["time"])
    changed = [d for d, t in truth.items() if t["changed"]]
    unchanged = [d for d, t in truth.items() if not t["changed"]]
    found = [d for d in changed
             if any(tm >= truth[d]["change_time"] for tm in first.get(d, ()))]
    false = [d for d in unchanged if d in first]
    return {"devices": len(truth), "changed": len(changed), "detected": len(found),
            "detection_rate": len(found) / len(changed) if changed else None,
            "unchanged": len(unchanged), "false_alarms": len(false),
            "false_alarm_rate": len(false) / len(unchanged) if unchanged else None,
            "missed": sorted(set(changed) - set(found)), "false_alarm_devices": false}
