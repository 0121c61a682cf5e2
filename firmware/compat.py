"""Portability shims, one home each: const, the microsecond clock, and the fast-path switch.

    from firmware.compat import const, ticks_us, ticks_diff, sleep_us, kernels
"""
# Also wait_clock(), wall_clock(), pick(), room(), compiled_here(), free_bytes(), drop(),
# drop_part(): each function says what it gives. What each shim is on CPython, MicroPython,
# CircuitPython and the WebAssembly port, and why emitter code lives only in firmware/fast.py:
# docs/design.md (module notes, compat).
import sys
import time

try:
    from micropython import const
    _MICRO = True
except ImportError:  # CPython, or a port without micropython.const
    _MICRO = False

    def const(x):
        return x
try:
    from micropython import kbd_intr  # Ctrl-C on or off (MotionCal's packets carry 0x03)
except ImportError:
    kbd_intr = None

_TICKS_MAX = const((1 << 30) - 1)   # MicroPython's ticks wrap at 2**30 (time.ticks_add docs)
_TICKS_HALF = const(1 << 29)

ticks_us = getattr(time, "ticks_us", None)
ticks_diff = getattr(time, "ticks_diff", None)


def _mono_us():
    return (time.monotonic_ns() // 1000) & _TICKS_MAX


def _mono_diff(a, b):
    return ((a - b + _TICKS_HALF) & _TICKS_MAX) - _TICKS_HALF


def _no_sleep(us):
    pass


def _busy_sleep(us):
    # the clock counts whole microseconds: wait until more than `us` have ticked, so the
    # time slept is at least `us` wherever within its first tick the wait began
    t0 = ticks_us()
    while ticks_diff(ticks_us(), t0) <= us:
        pass


sleep_us = getattr(time, "sleep_us", None)
if ticks_us is None and _MICRO and hasattr(time, "monotonic_ns"):  # CircuitPython
    ticks_us = _mono_us
    ticks_diff = _mono_diff
    sleep_us = sleep_us or _busy_sleep
sleep_us = sleep_us or _no_sleep


def wait_clock(delay_us):
    """(delay, measured): see docs/design.md, module notes."""
    if delay_us is None:
        return sleep_us, ticks_us is not None
    return delay_us, False


def _sub(a, b):
    return a - b


def _perf_us():
    return time.perf_counter_ns() // 1000


def wall_clock():
    """(now_us, diff) on the real clock: for stall and save-time figures only."""
    if ticks_us is not None:
        return ticks_us, ticks_diff
    return _perf_us, _sub


FAST = True       # False: always the plain path
_kernels = 0      # 0: not looked up yet


def kernels():
    """firmware.fast when the native emitter exists here (and FAST is True), else None."""
    global _kernels
    if not FAST:
        return None
    if _kernels == 0:
        try:
            from firmware import fast
            _kernels = fast
        except (ImportError, SyntaxError, ValueError, MemoryError):
            # CPython (no micropython module), no emitter (SyntaxError at compile time), an
            # .mpy of another architecture (ValueError), no room for the native code
            _kernels = None
    return _kernels


def need(name, call):
    """The module firmware.<name> of an optional part (docs/design.md, parts), or an
    ImportError that names the package `call` needs."""
    try:
        return __import__("firmware." + name, None, None, ("x",))  # (the leaf module)
    except ImportError:
        part = name[:name.find(".")]
        raise ImportError("%s needs the %s part: install package-%s.json" % (call, part, part))


def pick(kn, name, plain):
    """kn's function `name` (kn None: the port's kernels()), else `plain`."""
    if kn is None:
        kn = kernels()
    return getattr(kn, name) if kn else plain


def drop(*names):
    """Forget the firmware modules `names` ("detect", "calibrate.solve": below firmware); a
    part's folder goes with the last of its modules."""
    for name in names:
        sys.modules.pop("firmware." + name, None)
        i = name.rfind(".")
        pkg = sys.modules.get("firmware." + name[:i] if i > 0 else "firmware")
        if pkg is not None and name[i + 1:] in pkg.__dict__:
            delattr(pkg, name[i + 1:])
        if i > 0:
            prefix = "firmware." + name[:i + 1]
            for k in sys.modules:
                if k.startswith(prefix):
                    break
            else:
                drop(name[:i])


def drop_part(part, keep=()):
    """Forget every loaded module of the part firmware/<part>/ but those named in `keep`."""
    prefix = "firmware." + part + "."
    for name in [n[9:] for n in sys.modules if n.startswith(prefix)]:
        if name not in keep:
            drop(name)
    drop(*(() if keep else (part,)))


# MicroPython's hash-table sizes from 17 on (py/map.c): a table grows only when it is full
_TABLE_SIZES = (17, 23, 29, 37, 47, 59, 73, 97, 127, 167, 223)
# room()'s names: builtins' names, which MicroPython keeps in ROM with its own (a name made
# here would be interned in the heap's name table for good), and no firmware object's
ROOM_NAMES = ("abs", "all", "any", "bin", "chr", "divmod", "hex", "oct", "ord", "pow", "repr",
              "round", "sorted", "sum", "zip", "hash", "iter", "next", "min", "max", "callable",
              "globals", "locals", "delattr", "setattr", "hasattr", "getattr", "issubclass",
              "isinstance", "dir", "len", "print")


def room(obj, pct=85):
    """Spare slots in obj's attribute table, called last in the construction of an object
    whose methods each step calls (docs/design.md, memory: attribute tables)."""
    # A method's name is looked up in the instance's table first, probing until an empty
    # slot, and MicroPython's tables grow only when full: 59 names in 59 slots cost 59
    # probes a call. Over pct % full, names without a value grow the table to the next size.
    d = getattr(obj, "__dict__", ())  # (a copy on MicroPython)
    n = len(d)
    for s in _TABLE_SIZES:
        if n <= s:
            i = 0
            while n * 100 > s * pct and n <= s and i < len(ROOM_NAMES):
                k = ROOM_NAMES[i]
                if k not in d:
                    setattr(obj, k, None)
                    n += 1
                i += 1
            return


def compiled_here(m):
    """True when MicroPython compiled module m from its .py source on this board."""
    # Loading it again would compile it again (solve.py: 17x its import from .mpy on the
    # x86-32 build, docs/benchmarks.md; the sample loop stalls meanwhile, and the compiler's
    # peak is above the module's own size). A frozen module's __file__ names the source it
    # was made from, which is not on the board's filesystem; CPython: False.
    f = getattr(m, "__file__", None) or ""
    if not _MICRO or not f.endswith(".py"):
        return False
    try:
        import os
        os.stat(f)
        return True
    except OSError:
        return False


def free_bytes():
    """gc.mem_free() after a collection, or None (see docs/design.md, module notes)."""
    import gc
    f = getattr(gc, "mem_free", None)
    if f is None:
        return None
    gc.collect()
    return f()

