"""The history chart of one parameter: every device's values over time (a parts-history /
control chart), the fleet mean, the fleet limits (and fixed limits from a limits file), and
the flagged records marked. matplotlib is imported here only."""
import datetime


def _text(s):
    # matplotlib reads the text between two $ as mathematics: a device name is shown as typed
    return s.replace("$", r"\$")


def draw(rows, parameter, flags, fleet, fixed, out_path, mean=None, title=None):
    """rows: stored rows; flags: check() flags of this parameter; fleet: (low, high, centre)
    or None; fixed: (low or None, high or None); mean: the fleet mean (default: of rows)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def when(r):
        return datetime.datetime.fromtimestamp(r["t_epoch"], datetime.timezone.utc)

    groups = {}
    for r in rows:
        groups.setdefault(r["device"], []).append(r)
    fig, ax = plt.subplots(figsize=(11, 5.5))
    many = len(groups) > 20
    for dev, g in sorted(groups.items()):
        g.sort(key=lambda r: r["t_epoch"])
        ax.plot([when(r) for r in g], [r[parameter] for r in g], "-o",
                lw=0.6 if many else 1.2, ms=1.5 if many else 3,
                alpha=0.35 if many else 0.9, label=None if many else _text(dev))
    if mean is None and rows:
        mean = sum(r[parameter] for r in rows) / len(rows)
    if mean is not None:
        ax.axhline(mean, color="k", lw=1.2, label="fleet mean %.4g" % mean)
    if fleet is not None:
        ax.axhline(fleet[0], color="tab:red", ls="--", lw=1,
                   label="fleet limits %.4g .. %.4g" % (fleet[0], fleet[1]))
        ax.axhline(fleet[1], color="tab:red", ls="--", lw=1)
    for v, name in zip(fixed, ("fixed low", "fixed high")):
        if v is not None:
            ax.axhline(v, color="tab:purple", ls=":", lw=1.2, label="%s %.4g" % (name, v))
    if flags:
        at = {(r["device"], r["time"]): r for r in rows}
        pts = [at[(f["device"], f["time"])] for f in flags if (f["device"], f["time"]) in at]
        ax.plot([when(r) for r in pts], [r[parameter] for r in pts], "x", color="tab:red",
                ms=7, mew=1.5, label="flagged (%d)" % len(pts))
    ax.set_title(_text(title) if title else
                 "%s: %d records, %d devices" % (parameter, len(rows), len(groups)))
    ax.set_xlabel("calibration time (UTC)")
    ax.set_ylabel(parameter)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
