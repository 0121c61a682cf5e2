"""Reference loops whose times on the boards are published, run here.

Source of the board figures: shaoziyang/micropython_benchmarks, README.md (github.com,
commit 48360b7d6b7220a1bcbf252e1ce7b121e24f8902), MicroPython v1.23.0 on an RP2040 at
125 MHz and an ESP32 at 160 MHz (MicroPython's default ESP32 clock). Its loops, re-written
here to do the same operations (a function given a list p, p[0] iterations):
  int_add    C = p[1] + p[2] with 12345678 + 56781234: a small int everywhere
  int_mul    C = p[1] * p[2] with 12345678 * 56781234 = 7.0e14: a small int on a 64-bit
             port, a LONG int (a heap object) on the 32-bit boards - so (mul - add) there
             is the cost of one long-int result, allocation and collection included
  float_add  C = p[1] + p[2] with two floats (boxed on every port here)
  pi_1000    1000 decimal digits of pi from a series of exact long-int steps
             (t = t * n // d; n, d and their increments grow by 8 and 32): long ints on
             every port (x64 uses 32-bit digits, the boards 16-bit ones)
Printed: milliseconds per loop as the source counts them (1e6 iterations; pi: one run).
"""
import gc

from desktop.benchmarks import common

SMOKE = common.smoke()
ITER = 100000 if SMOKE else 1000000
REPEAT = 1 if SMOKE else 3

# Published milliseconds (source above): per 1e6 iterations, pi_1000 per run.
PUBLISHED_MS = {
    "rp2040_125mhz": {"int_add": 7984, "int_mul": 28283, "float_add": 13447,
                      "pi_1000": 868},
    "esp32_160mhz": {"int_add": 6112, "int_mul": 19363, "float_add": 9462,
                     "pi_1000": 660},
}
SOURCE = ("shaoziyang/micropython_benchmarks README.md (commit 48360b7d), MicroPython "
          "v1.23.0: RP2040 @125 MHz and ESP32 @160 MHz columns")


def add_loop(p):
    for i in range(p[0]):
        C = p[1] + p[2]  # noqa: F841


def mul_loop(p):
    for i in range(p[0]):
        C = p[1] * p[2]  # noqa: F841


def pi_digits(digits):
    # sum of the series pi = 3 (1 + 1/24 + 9/640 + ...): each term from the previous one by
    # an exact multiply and floor division, on 10**(digits+8) fixed point
    guard = 8
    one = 10 ** (digits + guard)
    term = 3 * one
    total = term
    n, dn, d, dd = 1, 0, 0, 24
    while term > 1:
        n += dn
        dn += 8
        d += dd
        dd += 32
        term = term * n // d
        total += term
    return total // 10 ** guard


def best_ms(fn, arg):
    best = None
    for _ in range(REPEAT):
        gc.collect()
        t0 = common.clock()
        fn(arg)
        dt = common.since_us(t0) / 1000
        best = dt if best is None or dt < best else best
    return best


def main():
    scale = 1000000 // ITER
    res = {"interpreter": common.interpreter(), "iterations": ITER, "ms": {
        "int_add": best_ms(add_loop, [ITER, 12345678, 56781234]) * scale,
        "int_mul": best_ms(mul_loop, [ITER, 12345678, 56781234]) * scale,
        "float_add": best_ms(add_loop, [ITER, 12345678.1234, 56781234.5678]) * scale,
        "pi_1000": best_ms(pi_digits, 1000)}}
    res["pi_1000_check"] = str(pi_digits(30))
    common.emit(res)


if __name__ == "__main__":
    main()
