"""Float64 references for the benchmarks and the tests: the same algebraic model fitted with
numpy (least squares on the design matrix, not the normal equations), and the real logs of
../shared/datasets fitted both ways. Host only (numpy)."""
import os

import numpy as np

from firmware.calibrator import Calibrator
from host_sim.cli.calibrate import DESKTOP_CAPACITY, choose_scale, scaled_rows

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(
    __file__)))))
DATASETS = os.path.normpath(os.path.join(ROOT, "..", "shared", "datasets"))
HAVE = os.path.isdir(DATASETS)
LOGS = sorted(f[:-4] for f in os.listdir(DATASETS) if f.endswith(".csv")) if HAVE else []
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
    """(calibrator filled with every row, int rows, evaluated float rows, scale power)."""
    if name not in _cache:
        path = os.path.join(DATASETS, name + ".csv")
        p, _ = choose_scale(path)
        rows = np.array(list(scaled_rows(path, p)), dtype=np.int64)
        cal = Calibrator(model=10, capacity=DESKTOP_CAPACITY, max_fit_error=10000)
        for x, y, z in rows.tolist():
            cal.add(x, y, z)
        data = np.genfromtxt(path, delimiter=",", names=True)
        floats = np.c_[data["mx"], data["my"], data["mz"]]
        skip = STILL_ROWS.get(name, 0)
        _cache[name] = (cal, rows[skip:], floats[skip:], p)
    return _cache[name]


def ours(name, model):
    cal, rows, _, _ = load(name)
    c = cal.solve(model=model, accept=False)
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
