"""How much of the solve (and of a kept sample) is long-int work on a 32-bit
board. CPython only: the arithmetic is counted, not timed, so any interpreter gives the same
counts (the firmware's results are the same bits everywhere).

The unix port is 64-bit: its small ints reach 2**62, a 32-bit board's only 2**30. An int
operation whose operands or result lie in [2**30, 2**62) is therefore a heap-allocated long
int on the board but free on the unix port, so scaling unix times by an interpreter
yardstick misses its cost. Counting: the Calibrator's moment sums (and so everything the
solve derives from them) are replaced by a subclass of int that counts each arithmetic
operation by the magnitude of max(|operands|, |result|):
  small  < 2**30   small int everywhere
  mid    < 2**62   long int on a 32-bit board only
  big    >= 2**62  long int on both
Comparisons are not counted (they allocate nothing). Operations between plain ints that
never touch a counted value (loop counters, table lookups) are not counted either: they
are small ints by construction.
"""
from desktop.benchmarks import common

_S = 1 << 30
_M = 1 << 62
COUNTS = [0, 0, 0]


def _rec(a, b, r):
    m = abs(int(r))
    x = abs(int(a))
    if x > m:
        m = x
    if b is not None:
        x = abs(int(b))
        if x > m:
            m = x
    COUNTS[0 if m < _S else (1 if m < _M else 2)] += 1


def _binary(name):
    op = getattr(int, name)

    def f(self, other):
        if not isinstance(other, int) or isinstance(other, bool):
            return NotImplemented
        r = op(int(self), int(other))
        if r is NotImplemented:
            return r
        _rec(self, other, r)
        return TInt(r)
    return f


def _unary(name):
    op = getattr(int, name)

    def f(self):
        r = op(int(self))
        _rec(self, None, r)
        return TInt(r)
    return f


class TInt(int):
    """An int that counts the arithmetic done with it (see the module docstring)."""

    def __int__(self):
        return int.__int__(self)

    def __index__(self):
        return int.__index__(self)

    def __repr__(self):
        return "TInt(%d)" % int(self)


for _n in ("__add__", "__radd__", "__sub__", "__rsub__", "__mul__", "__rmul__",
           "__floordiv__", "__rfloordiv__", "__mod__", "__rmod__", "__lshift__",
           "__rlshift__", "__rshift__", "__rrshift__", "__and__", "__rand__", "__or__",
           "__ror__", "__xor__", "__rxor__"):
    setattr(TInt, _n, _binary(_n))
for _n in ("__neg__", "__pos__", "__abs__", "__invert__"):
    setattr(TInt, _n, _unary(_n))


def _pow(self, other, mod=None):
    r = int.__pow__(int(self), int(other)) if mod is None else pow(int(self), int(other), mod)
    _rec(self, other, r)
    return TInt(r)


def _rpow(self, other):
    r = int.__pow__(int(other), int(self))
    _rec(self, other, r)
    return TInt(r)


TInt.__pow__ = _pow
TInt.__rpow__ = _rpow


def snapshot():
    return list(COUNTS)


def delta(a):
    return [COUNTS[i] - a[i] for i in range(3)]


def instrument(cal):
    """Make the Calibrator's moment sums counted (their values unchanged)."""
    m = cal.moments
    if m.c is not None:
        m.c = tuple(TInt(v) for v in m.c)
    m.s = [TInt(v) for v in m.s]


def main():
    from desktop.benchmarks import solver
    from firmware.calibrate.calibrator import Calibrator
    smoke = common.smoke()
    res = {"interpreter": common.interpreter()}
    # the solve on the buffer solver.py times (same session, same Calibrator)
    cal = solver.full_calibrator()
    instrument(cal)
    res["held"] = cal.count
    res["solve"] = {}
    for m in ("minmax", 4, 7, 10):
        a = snapshot()
        c = cal.solve(model=m, accept=False)
        res["solve"][str(m)] = delta(a)
        res["solve_fit_error_x100_" + str(m)] = c.fit_error
    steps = []
    job = cal.solve_steps(model=10, accept=False, group=1)  # as solver.py's sliced_10
    while True:
        a = snapshot()
        try:
            next(job)
        except StopIteration:
            steps.append(delta(a))
            break
        steps.append(delta(a))
    res["sliced_10_per_step"] = steps
    # add(): ops per kept / replaced sample on the collector's stream
    mag, _ = common.session(1500 if smoke else 6000, dt_us=20000 if smoke else 5000,
                            accel=False)
    raw = common.raw_triples(mag)
    cal = Calibrator(model=10, capacity=100 if smoke else 300, separation=900,
                     counts_per_gauss=common.QMC_CPG)
    cal.add(*raw[0])
    instrument(cal)
    paths = {"rejected": [0, 0, 0, 0], "kept": [0, 0, 0, 0], "replaced": [0, 0, 0, 0]}
    for r in raw[1:]:
        n0 = cal.count
        a = snapshot()
        kept = cal.add(r[0], r[1], r[2])
        d = delta(a)
        p = paths["rejected" if not kept else ("kept" if cal.count > n0 else "replaced")]
        p[0] += 1
        for i in range(3):
            p[i + 1] += d[i]
    res["add_per_path"] = {k: {"count": v[0], "small": v[1] / v[0] if v[0] else 0,
                               "mid": v[2] / v[0] if v[0] else 0,
                               "big": v[3] / v[0] if v[0] else 0} for k, v in paths.items()}
    common.emit(res)


if __name__ == "__main__":
    main()
