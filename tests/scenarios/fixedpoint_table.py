# Prints isqrt/rdiv results for a fixed integer sequence; run on both interpreters.
import json
from firmware.fixedpoint import isqrt, rdiv, bit_length, sat16

x = 12345
out = []
for i in range(300):
    x = (x * 1103515245 + 12345) % (1 << 31)
    n = x * x * (i + 1) + i
    out.append([isqrt(n), isqrt(x), rdiv(n, -(i + 3)), bit_length(n), sat16(x - (1 << 30))])
print(json.dumps(out))
