"""Limits for each calibration parameter, and the check of every stored record against them.

Three kinds of limit (the `basis` of a flag):
  fixed   low / high written in a limits file (e.g. a field window for the factory site);
  device  the device's own earlier records (the last `window` of them): their mean
          +- k * sigma * sqrt(1 + 1/n), the prediction interval of one more record. sigma is
          the calibration repeatability of the fleet (below); once the device has
          `min_history` earlier records its own standard deviation is used when larger;
  fleet   every record of the parameter: median +- k * 1.4826 * MAD (1.4826 * MAD estimates
          sigma of a normal distribution; median and MAD ignore the few changed devices).
Repeatability: the spread of the difference between a device's consecutive calibrations,
1.4826 * median(|differences|) / sqrt(2) over the fleet (a difference of two records has sqrt(2)
times one record's noise; a component change or a slow drift moves only a few differences,
which the median ignores). A control chart's moving-range sigma, made robust.

A limits file (JSON, or TOML when its name ends in .toml) looks like docs/quality.md shows:
  {"k": 4.5, "min_history": 5, "window": 8,
   "parameters": {"offset_x": {}, "field": {"low": 25, "high": 65, "learned": ["device"]}}}
Only the parameters it lists are checked. Per parameter: `learned` (a list of "device",
"fleet"; default both, or none when low/high are given), `low`, `high`, `k`.
"""
import json
import math

from desktop.qualitydb.records import DEFAULT_PARAMETERS, PARAMETERS

DEFAULT_K = 4.5          # sigmas; a normal value is outside +-4.5 sigma once in 150,000
DEFAULT_MIN_HISTORY = 5  # earlier records before a device's own sigma is trusted
DEFAULT_WINDOW = 8       # earlier records a device's limits are learned from (follows drift)
MIN_FLEET_DEVICES = 10   # fewer devices than this: no fleet limits
MAD_TO_SIGMA = 1.4826    # sigma / MAD of a normal distribution
BASES = ("device", "fleet")
_TOP_KEYS = ("k", "min_history", "window", "parameters")
_PARAM_KEYS = ("learned", "low", "high", "k")


class LimitsError(ValueError):
    """A limits file that cannot be used; the message names the file and the key."""


class Limits:
    """k, min_history, window and per parameter {"learned": [...], "low", "high", "k"}."""

    def __init__(self, k=DEFAULT_K, min_history=DEFAULT_MIN_HISTORY, window=DEFAULT_WINDOW,
                 parameters=None):
        self.k = k
        self.min_history = min_history
        self.window = window
        if parameters is None:
            parameters = {p: {"learned": list(BASES)} for p in DEFAULT_PARAMETERS}
        self.parameters = parameters

    def k_for(self, p):
        return self.parameters[p].get("k", self.k)


def _num(v, where, positive=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise LimitsError("%s: expected a number, got %s" % (where, json.dumps(v)))
    if positive and v <= 0:
        raise LimitsError("%s: expected a number > 0, got %s" % (where, v))
    return float(v)


def parse(obj, name="limits"):
    """A parsed limits document -> Limits; LimitsError names the offending key."""
    if not isinstance(obj, dict):
        raise LimitsError("%s: expected an object with keys %s" % (name, ", ".join(_TOP_KEYS)))
    for key in obj:
        if key not in _TOP_KEYS:
            raise LimitsError("%s: unknown key %r (expected %s)" % (name, key,
                                                                   ", ".join(_TOP_KEYS)))
    lim = Limits()
    if "k" in obj:
        lim.k = _num(obj["k"], "%s: k" % name, positive=True)
    for key in ("min_history", "window"):
        if key in obj:
            v = obj[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise LimitsError("%s: %s: expected a whole number >= 1, got %s"
                                  % (name, key, json.dumps(v)))
            setattr(lim, key, v)
    params = obj.get("parameters")
    if not isinstance(params, dict) or not params:
        raise LimitsError("%s: parameters: expected an object naming at least one of %s"
                          % (name, ", ".join(PARAMETERS)))
    out = {}
    for p, spec in params.items():
        if p not in PARAMETERS:
            raise LimitsError("%s: unknown parameter %r (expected one of %s)"
                              % (name, p, ", ".join(PARAMETERS)))
        where = "%s: parameters.%s" % (name, p)
        if not isinstance(spec, dict):
            raise LimitsError("%s: expected an object with keys %s" % (where,
                                                                      ", ".join(_PARAM_KEYS)))
        for key in spec:
            if key not in _PARAM_KEYS:
                raise LimitsError("%s: unknown key %r (expected %s)"
                                  % (where, key, ", ".join(_PARAM_KEYS)))
        s = {}
        for key in ("low", "high"):
            if key in spec:
                s[key] = _num(spec[key], "%s.%s" % (where, key))
        if "low" in s and "high" in s and s["low"] >= s["high"]:
            raise LimitsError("%s: low %s is not below high %s" % (where, s["low"], s["high"]))
        if "k" in spec:
            s["k"] = _num(spec["k"], where + ".k", positive=True)
        learned = spec.get("learned", [] if s else list(BASES))
        if not isinstance(learned, list) or any(b not in BASES for b in learned):
            raise LimitsError("%s.learned: expected a list of %s, got %s"
                              % (where, " / ".join(BASES), json.dumps(learned)))
        if not learned and not s:
            raise LimitsError("%s: no limit (give low, high or learned)" % where)
        s["learned"] = learned
        out[p] = s
    lim.parameters = out
    return lim


def load(path):
    """Read a limits file: TOML if the name ends in .toml, else JSON."""
    try:
        if path.endswith(".toml"):
            import tomllib
            with open(path, "rb") as f:
                try:
                    obj = tomllib.load(f)
                except tomllib.TOMLDecodeError as e:
                    raise LimitsError("%s: not TOML: %s" % (path, e))
        else:
            with open(path) as f:
                try:
                    obj = json.load(f)
                except ValueError as e:
                    raise LimitsError("%s: not JSON: %s" % (path, e))
    except OSError as e:
        raise LimitsError("%s: cannot read: %s" % (path, e.strerror or e))
    return parse(obj, path)


# --- statistics ---------------------------------------------------------------------------
def median(xs):
    s = sorted(xs)
    n = len(s)
    if not n:
        return None
    return s[n // 2] if n % 2 else (s[n // 2 - 1] + s[n // 2]) / 2


def robust_sigma(xs):
    """(median, 1.4826 * MAD), or (median, None) for fewer than 2 values."""
    m = median(xs)
    if len(xs) < 2:
        return m, None
    return m, MAD_TO_SIGMA * median([abs(x - m) for x in xs])


def by_device(rows):
    """{device: [rows by time]} (rows come sorted by device and time from the store)."""
    out = {}
    for r in rows:
        out.setdefault(r["device"], []).append(r)
    for g in out.values():
        g.sort(key=lambda r: r["t_epoch"])
    return out


def repeatability(groups, p):
    """The fleet's calibration-to-calibration sigma of parameter p, or None.
    Differences are taken as centred on zero (a slow drift moves them little):
    1.4826 * median |d| / sqrt(2); when more than half of them are exactly zero (a parameter
    that repeats bit for bit), their root mean square / sqrt(2) instead."""
    diffs = []
    for g in groups.values():
        diffs.extend(b[p] - a[p] for a, b in zip(g, g[1:]))
    if not diffs:
        return None
    s = MAD_TO_SIGMA * median([abs(d) for d in diffs])
    if s == 0:
        s = math.sqrt(sum(d * d for d in diffs) / len(diffs))
    return s / math.sqrt(2)


def fleet_limits(rows, groups, p, k):
    """(low, high, centre) from the fleet's records of p, or None (too few devices)."""
    if len(groups) < MIN_FLEET_DEVICES:
        return None
    m, s = robust_sigma([r[p] for r in rows])
    if not s:
        return None
    return m - k * s, m + k * s, m


def device_limits(earlier, p, k, sigma_r, min_history):
    """(low, high) for the next record of a device from its earlier records, or None."""
    n = len(earlier)
    if n == 0:
        return None
    xs = [r[p] for r in earlier]
    mean = sum(xs) / n
    sigma = sigma_r
    if n >= min_history:
        own = math.sqrt(sum((x - mean) ** 2 for x in xs) / (n - 1))
        sigma = own if sigma is None else max(own, sigma)
    if sigma is None:
        return None
    half = k * sigma * math.sqrt(1 + 1 / n)
    return mean - half, mean + half


def check(rows, limits):
    """Every record against every limit: a list of flag dicts (device, time, parameter,
    value, low, high, basis), by device, time and parameter."""
    groups = by_device(rows)
    flags = []
    for p, spec in limits.parameters.items():
        k = limits.k_for(p)
        learned = spec["learned"]
        if "low" in spec or "high" in spec:
            lo, hi = spec.get("low", -math.inf), spec.get("high", math.inf)
            for r in rows:
                if not lo <= r[p] <= hi:
                    flags.append(_flag(r, p, spec.get("low"), spec.get("high"), "fixed"))
        if "fleet" in learned:
            fl = fleet_limits(rows, groups, p, k)
            if fl is not None:
                for r in rows:
                    if not fl[0] <= r[p] <= fl[1]:
                        flags.append(_flag(r, p, fl[0], fl[1], "fleet"))
        if "device" in learned:
            sr = repeatability(groups, p)
            for g in groups.values():
                for i, r in enumerate(g):
                    dl = device_limits(g[max(0, i - limits.window):i], p, k, sr,
                                       limits.min_history)
                    if dl is not None and not dl[0] <= r[p] <= dl[1]:
                        flags.append(_flag(r, p, dl[0], dl[1], "device"))
    order = {p: i for i, p in enumerate(PARAMETERS)}
    flags.sort(key=lambda f: (f["device"], f["t_epoch"], order[f["parameter"]], f["basis"]))
    for f in flags:
        del f["t_epoch"]
    return flags


def _flag(r, p, lo, hi, basis):
    return {"device": r["device"], "time": r["time"], "parameter": p, "value": r[p],
            "low": lo, "high": hi, "basis": basis, "t_epoch": r["t_epoch"]}
