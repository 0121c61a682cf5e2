"""The calibration picture of `make run` (CPython with matplotlib only; never on MicroPython).

    from desktop import plot
    plot.calibration_png("build/calibration.png", setup, calibration, raw_samples)

Three panels, as AN4246 figures 1-3 tell it backwards: the raw samples of the figure-8 on
their ellipsoid (hard iron V moves its centre, soft iron W stretches and tilts it), the same
samples with V removed (a centred ellipsoid), and the samples corrected by the accepted
calibration on a sphere of radius B. Wireframes: the fitted ellipsoid, and the sphere.
Axes in uT, the sensor's own axes, equal scales so a sphere looks like one.
"""
import os

_MAX_POINTS = 2500  # enough to show the surface; more only slows the 3D renderer


def _ellipsoid_mesh(centre, m, radius, n=24):
    """Points centre + m (radius u) for u on a latitude/longitude grid of the unit sphere."""
    import numpy as np
    th = np.linspace(0, np.pi, n // 2 + 1)
    ph = np.linspace(0, 2 * np.pi, n + 1)
    u = np.stack([np.outer(np.sin(th), np.cos(ph)), np.outer(np.sin(th), np.sin(ph)),
                  np.outer(np.cos(th), np.ones_like(ph))])
    p = np.einsum("ij,jkl->ikl", np.asarray(m, float), u) * radius
    return [p[i] + centre[i] for i in range(3)]


def _equal_axes(ax, pts, centre):
    import numpy as np
    r = float(np.max(np.abs(pts - np.asarray(centre)))) * 1.05
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        setter(c - r, c + r)
    try:
        ax.set_box_aspect((1, 1, 1))
    except AttributeError:  # older matplotlib
        pass


def calibration_png(path, setup, cal, raws):
    """Write the three-panel PNG to `path` (directories created). `raws`: the raw samples,
    flat x0 y0 z0 x1 ... (demo.run_session). Raises ImportError when matplotlib or numpy
    is missing."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    raws = [(raws[j], raws[j + 1], raws[j + 2]) for j in range(0, len(raws) - 2, 3)]
    n_all = len(raws)
    if len(raws) > _MAX_POINTS:
        step = (len(raws) + _MAX_POINTS - 1) // _MAX_POINTS
        raws = raws[::step]
    k_ut = 100.0 / setup.cpg                      # counts -> uT
    raw = np.array(raws, dtype=float) * k_ut
    v = np.array(cal.offset, dtype=float) * k_ut
    out = [0, 0, 0]
    corr = []
    for r in raws:
        cal.correct(r, out)                       # the firmware's own Q15 correction
        corr.append((out[0], out[1], out[2]))
    k_out = cal.field / cal.field_out if cal.field_out else 1.0
    corr = np.array(corr, dtype=float) * k_out * k_ut
    b_ut = cal.field * k_ut
    # W, the ellipsoid's shape: the inverse of W^-1 = InvW / 32768 scaled as the corrected
    # samples are (demo.invw_float; computed here, demo imports this module)
    w_fit = np.linalg.inv(np.array(cal.invw, dtype=float).reshape(3, 3) / 32768 * k_out)
    eye = np.eye(3)
    fe = "%d.%02d %%" % (cal.fit_error // 100, cal.fit_error % 100)

    fig = plt.figure(figsize=(15, 5.6))
    zero = np.zeros(3)
    panels = (
        ("1. raw samples on their ellipsoid, centre V:\n|V| = %.1f uT of hard iron "
         "(grey: the sphere without iron)" % float(np.linalg.norm(v)),
         raw, v, w_fit, "tab:red", True),
        ("2. hard iron removed, raw - V:\nsoft iron W stretches and tilts the sphere",
         raw - v, zero, w_fit, "tab:orange", True),
        ("3. corrected, InvW (raw - V): on the sphere\nB = %.1f uT, fit error %s"
         % (b_ut, fe), corr, zero, eye, "tab:blue", False),
    )
    for i, (title, pts, centre, shape, colour, ref) in enumerate(panels):
        ax = fig.add_subplot(1, 3, i + 1, projection="3d")
        mx, my, mz = _ellipsoid_mesh(centre, shape, b_ut)
        ax.plot_wireframe(mx, my, mz, color=colour, linewidth=0.3, alpha=0.35)
        lim = pts
        if ref:  # the ideal locus (AN4246 fig. 1): a sphere of radius B at the origin
            sx, sy, sz = _ellipsoid_mesh(zero, eye, b_ut, n=16)
            ax.plot_wireframe(sx, sy, sz, color="0.55", linewidth=0.4, alpha=0.5)
            lim = np.vstack([pts, [[b_ut] * 3, [-b_ut] * 3]])
        ax.scatter(pts[:, 0], pts[:, 1], pts[:, 2], s=2, c=colour, depthshade=True)
        ax.scatter([centre[0]], [centre[1]], [centre[2]], s=60, c="k", marker="+")
        mid = (lim.max(axis=0) + lim.min(axis=0)) / 2
        _equal_axes(ax, lim, mid)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("x (uT)")
        ax.set_ylabel("y (uT)")
        ax.set_zlabel("z (uT)")
        ax.tick_params(labelsize=7)
    fig.suptitle("%s, seed %d: %d samples of a figure-8 (%d shown); calibration model %s "
                 "(AN4246 eq. 5: raw = W B + V)" % (setup.label, setup.seed, n_all, len(raws),
                                                    cal.model),
                 fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    d = os.path.dirname(path)
    if d:
        os.makedirs(d, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
