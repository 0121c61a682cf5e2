"""Float64 references for the benchmarks and the tests: the same algebraic model fitted with
numpy (least squares on the design matrix, not the normal equations), and the real logs
(datasets/README.md) fitted both ways. Host only (numpy).

The logs: those the repository ships, in datasets/, and those whose licences keep them out
of it, which `make datasets` fetches pinned into build/datasets (tools/fetch_datasets.py;
their provenance is in datasets/fetched/). LOGS is what is here, MISSING what is not."""
import json
import os

import numpy as np

from firmware.calibrate.calibrator import Calibrator
from desktop.calibrate import choose_scale, desktop_plan, scaled_rows

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHIPPED = os.path.join(ROOT, "datasets")
FETCHED = os.path.join(ROOT, "build", "datasets")
FETCH = "make datasets"


def _names(folder, ext):
    try:
        return set(f[:-len(ext)] for f in os.listdir(folder) if f.endswith(ext))
    except OSError:
        return set()


def log_path(name):
    """The log's CSV (its provenance NAME.json beside it), or None when it is not here."""
    for folder in (SHIPPED, FETCHED):
        path = os.path.join(folder, name + ".csv")
        if os.path.exists(path) and os.path.exists(path[:-4] + ".json"):
            return path
    return None


def meta(name):
    with open(log_path(name)[:-4] + ".json") as f:
        return json.load(f)


def missing_reason(names):
    """A skip message for logs that are not here (more than two: counted, not named)."""
    return "%s: not in this clone (not shipped: datasets/README.md); `%s` fetches %s" % (
        ", ".join(names) if len(names) <= 2 else "%d real logs" % len(names), FETCH,
        "it" if len(names) == 1 else "them")


ALL_LOGS = sorted(_names(SHIPPED, ".csv") | _names(os.path.join(SHIPPED, "fetched"), ".json"))
LOGS = [n for n in ALL_LOGS if log_path(n)]
MISSING = [n for n in ALL_LOGS if not log_path(n)]
PLANAR = "hmc5883l_nliaudat_windvane_planar"
STILL_ROWS = {"qmc5883l_tomisuarez_filtered": 3000, "qmc5883l_tomisuarez_noisy": 3000}

_cache = {}


def numpy_fit(pts, model):
    """Float64 reference of the same algebraic model on the same samples (lstsq on X,
    not the normal equations), then V, W^-1 = (A / det^(1/3))^1/2 and B as in AN4246."""
    p = np.array(pts, dtype=float)
    c = p.mean(axis=0)
    d = p - c
    x, y, z = d.T
    if model == 4:
        X = np.c_[x, y, z, np.ones_like(x)]
    elif model == 7:
        X = np.c_[x * x - z * z, y * y - z * z, x, y, z, np.ones_like(x)]
    else:
        X = np.c_[x * x - z * z, y * y - z * z, x * y, x * z, y * z, x, y, z, np.ones_like(x)]
    Y = x * x + y * y + z * z
    b = np.linalg.lstsq(X, Y, rcond=None)[0]
    if model == 4:
        S = np.zeros((3, 3))
        lin = b[0:3]
        e = b[3]
    elif model == 7:
        S = np.diag([b[0], b[1], -b[0] - b[1]])
        lin, e = b[2:5], b[5]
    else:
        S = np.array([[b[0], b[2] / 2, b[3] / 2], [b[2] / 2, b[1], b[4] / 2],
                      [b[3] / 2, b[4] / 2, -b[0] - b[1]]])
        lin, e = b[5:8], b[8]
    A = np.eye(3) - S
    d0 = np.linalg.solve(A, lin) / 2
    K = d0 @ A @ d0 + e
    det = np.linalg.det(A)
    An = A / np.cbrt(det)
    w, v = np.linalg.eigh(An)
    invw = v @ np.diag(np.sqrt(w)) @ v.T
    B = (K ** 3 / det) ** (1 / 6)
    return c + d0, invw, B


def sphericity(m):
    r = np.sqrt((m.astype(float) ** 2).sum(axis=1))
    return r.std() / r.mean()


def load(name):
    """(calibrator filled as the calibrate command fills it at its default settings
    (desktop_plan), int rows, evaluated float rows, scale power)."""
    if name not in _cache:
        path = log_path(name)
        p, _ = choose_scale(path)
        rows = np.array(list(scaled_rows(path, p)), dtype=np.int64)
        capacity, separation, step = desktop_plan(len(rows))
        cal = Calibrator(model=10, capacity=capacity, separation=separation,
                         max_fit_error=10000)
        for x, y, z in rows[::step].tolist():
            cal.add(x, y, z)
        data = np.genfromtxt(path, delimiter=",", names=True)
        floats = np.c_[data["mx"], data["my"], data["mz"]]
        skip = STILL_ROWS.get(name, 0)
        _cache[name] = (cal, rows[skip:], floats[skip:], p)
    return _cache[name]


def ours(name, model):
    cal, rows, _, _ = load(name)
    c = cal.solve(model=model, accept=False, checks=False)   # the fit, whatever acceptance says
    out = np.zeros_like(rows)
    buf = [0, 0, 0]
    for i, r in enumerate(rows.tolist()):
        c.correct(r, buf)
        out[i] = buf
    return sphericity(out), c


def reference(name, model):
    _, _, f, _ = load(name)
    if model == "minmax":
        lo, hi = f.min(axis=0), f.max(axis=0)
        h = (hi - lo) / 2
        return sphericity((f - (hi + lo) / 2) * (h.mean() / h))    # the min/max article
    v, invw, _ = numpy_fit(f, model)
    return sphericity((f - v) @ invw.T)


def default_command(name):
    """`python -m host_sim calibrate LOG` at its default settings (model 10, every distinct
    sample: calibrate.desktop_plan) against a float64 fit of the same model to every row:
    {"ours", "float64", "ratio"} - the corrected-radius spreads std(|out|) / mean(|out|)
    over every row of the file - and "refused" (the reason) when the command refuses the
    log, whose figures are then those of the fit --force gives. None when not even --force
    fits (the planar log)."""
    from desktop import calibrate
    path = log_path(name)
    c, rej, info = calibrate.run(calibrate._parser().parse([path, "--force"]))
    if c is None:
        return {"refused": rej.reason, "forced": None}
    rows = np.array(list(scaled_rows(path, info["p"])), dtype=np.int64)
    out = np.zeros_like(rows)
    buf = [0, 0, 0]
    for i, r in enumerate(rows.tolist()):
        c.correct(r, buf)
        out[i] = buf
    data = np.genfromtxt(path, delimiter=",", names=True)
    f = np.c_[data["mx"], data["my"], data["mz"]]
    v, invw, _ = numpy_fit(f, 10)
    ours, ref = sphericity(out), sphericity((f - v) @ invw.T)
    res = {"ours": ours, "float64": ref, "ratio": ours / ref, "held": c.samples,
           "rows": len(rows)}
    if info.get("forced") is not None:
        res["refused"] = info["forced"].reason
    return res
