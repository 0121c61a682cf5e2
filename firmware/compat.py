"""Portability shims, one home each: const, the microsecond clock, and the fast-path switch.

    from firmware.compat import const, ticks_us, ticks_diff, sleep_us, kernels

const(x)          micropython.const on MicroPython (the constant costs no RAM); the identity
                  elsewhere (CPython, or a port built without it).
ticks_us()        time.ticks_us where the port has it (CircuitPython: from time.monotonic_ns),
                  else None (CPython: the simulator passes its own clock). ticks_diff(a, b)
                  likewise: the wrapping difference.
sleep_us(us)      time.sleep_us where it exists (CircuitPython: a wait on monotonic_ns), else
                  a no-op (the simulator passes its own).
wall_clock()      (now_us, diff) for measuring real time: ticks_us / ticks_diff on MicroPython,
                  perf_counter_ns on CPython (used only for stall figures, never for logic).
kernels()         the fast-path module firmware.fast (viper/native code with the same
                  functions and signatures as the plain ones) when this port has the native
                  emitter, else None. Plain modules never carry an emitter decorator: a port
                  without the emitter (CircuitPython, the WebAssembly port) rejects the emitter's
                  decorators at compile time, so that code lives in firmware/fast.py
                  and is only ever imported here, inside try/except. Set FAST = False before
                  the first call to force the plain path (tests compare the two).
"""
import time

try:
    from micropython import const
except ImportError:  # CPython, or a port without micropython.const
    def const(x):
        return x

ticks_us = getattr(time, "ticks_us", None)
ticks_diff = getattr(time, "ticks_diff", None)


def _no_sleep(us):
    pass


sleep_us = getattr(time, "sleep_us", None) or _no_sleep

# CircuitPython has no ticks_us/sleep_us: its integer monotonic_ns gives both (it never
# wraps, so the difference is a plain subtraction; the sleep waits on it, no float needed)
try:
    import sys
    _CIRCUITPY = sys.implementation.name == "circuitpython"
except (ImportError, AttributeError):
    _CIRCUITPY = False
if ticks_us is None and _CIRCUITPY:
    _mono = time.monotonic_ns

    def ticks_us():
        return _mono() // 1000

    def ticks_diff(a, b):
        return a - b

    def sleep_us(us):
        end = _mono() + us * 1000
        while _mono() < end:
            pass


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
