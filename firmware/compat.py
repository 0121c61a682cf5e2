"""Portability shims, one home each: const, the microsecond clock, and the fast-path switch.

    from firmware.compat import const, ticks_us, ticks_diff, sleep_us, kernels
"""
# const(x)          micropython.const on MicroPython (the constant costs no RAM); the identity
#                   elsewhere (CPython, or a port built without it).
# ticks_us()        time.ticks_us where the port has it, else None (CPython: the simulator
#                   passes its own clock). ticks_diff(a, b) likewise: the wrapping difference.
#                   CircuitPython (a micropython module, no time.ticks_us): time.monotonic_ns
#                   in microseconds, wrapped to 30 bits as MicroPython's ticks are, with the same
#                   wrapping ticks_diff (its monotonic_ns is a long int: each call allocates).
# sleep_us(us)      time.sleep_us where it exists; on CircuitPython a busy wait on that clock
#                   (its time.sleep takes float seconds); else a no-op (the simulator passes
#                   its own).
# wait_clock(delay_us)  (delay, measured) for a bounded wait (firmware/i2cdevice.py's data-ready
#                   wait, firmware/circuitpython/busio_i2c.py's lock wait): None gives sleep_us, the wait
#                   measured with ticks_us where the port has it; the simulator's delay_us gives
#                   itself, the waited time then being the sum of the delays asked for.
# wall_clock()      (now_us, diff) for measuring real time: ticks_us / ticks_diff on MicroPython,
#                   perf_counter_ns on CPython (used only for stall figures, never for logic).
# kernels()         the fast-path module firmware.fast (viper/native code with the same
#                   functions and signatures as the plain ones) when this port has the native
#                   emitter, else None. Plain modules never carry an emitter decorator: a port
#                   without the emitter (CircuitPython, the WebAssembly port) rejects the emitter's
#                   decorators at compile time, so that code lives in firmware/fast.py
#                   and is only ever imported here, inside try/except. Set FAST = False before
#                   the first call to force the plain path (tests compare the two).
# pick(kn, name, plain)  the function `name` of kernel set kn (None: kernels()), or `plain`
#                   when there is none (kn False or None): a module's use_kernels().
# compiled_here(m)  True when MicroPython compiled module m from its .py source on this board
#                   (not a .mpy file, nor frozen or ROMFS code): loading it again costs a
#                   compile (firmware/calibrate/calibrator.py keeps the solver then; boards/main.py
#                   says a board runs from sources).
# free_bytes()      gc.mem_free() after a collection: the heap a job can have now; None where the
#                   port does not tell (CPython): whether a calibration session fits beside the
#                   heading (firmware/app.py SESSION_ROOM; docs/design.md, memory).
# drop(*names)      forget the firmware modules `names` ("detect", "calibrator", ...): out of
#                   sys.modules and off the firmware package, so their code and tables are
#                   freed at the next collection once nothing else refers to them (a
#                   capability that is done; docs/design.md, memory). The next import loads
#                   the module afresh.
import sys
import time

try:
    from micropython import const
    _MICRO = True
except ImportError:  # CPython, or a port without micropython.const
    _MICRO = False

    def const(x):
        return x

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
    """(delay, measured): see the module's opening comment."""
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
    """gc.mem_free() after a collection, or None (see the module's opening comment)."""
    import gc
    f = getattr(gc, "mem_free", None)
    if f is None:
        return None
    gc.collect()
    return f()

