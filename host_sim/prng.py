"""Deterministic pseudo-random numbers, identical on CPython and MicroPython.

`random` differs between the interpreters, so the simulator brings its own generator:
Marsaglia's xorshift128 (32-bit words, period 2**128 - 1), seeded through the murmur3
32-bit finaliser so that nearby seeds give unrelated streams. Gaussian values use the
Box-Muller transform (math.log/sqrt/cos give the same bits on both interpreters; the
parity scenario tests/scenarios/sim_parity.py checks it).

    g = Prng(seed=1)
    g.next_u32(); g.uniform(); g.gauss(2.5)
    Prng(seed, stream=k)   # an independent stream per (seed, k): the noise of sample k
"""
import math

_M32 = 0xFFFFFFFF
_TWO_PI = 6.283185307179586
_INV_2_32 = 1.0 / 4294967296.0


def mix32(x):
    """murmur3 fmix32: a bijective 32-bit hash (avalanche for seeding)."""
    x &= _M32
    x ^= x >> 16
    x = (x * 0x85EBCA6B) & _M32
    x ^= x >> 13
    x = (x * 0xC2B2AE35) & _M32
    x ^= x >> 16
    return x


class Prng:
    """xorshift128 generator. `seed` and `stream` are any ints (negative ones are folded in)."""

    def __init__(self, seed=1, stream=0):
        h = mix32(seed ^ 0x9E3779B9)
        h = mix32(h ^ ((seed >> 32) & _M32) ^ 0x7F4A7C15)
        h = mix32(h + (stream & _M32) * 0x632BE5AB)
        h = mix32(h ^ ((stream >> 32) & _M32))
        s = []
        for i in range(4):
            h = mix32(h + 0x9E3779B9 + i)
            s.append(h)
        if s[0] | s[1] | s[2] | s[3] == 0:  # the one state xorshift cannot leave
            s[0] = 1
        self._x, self._y, self._z, self._w = s
        self._spare = None

    def next_u32(self):
        t = self._x ^ ((self._x << 11) & _M32)
        self._x = self._y
        self._y = self._z
        self._z = self._w
        w = self._w
        self._w = (w ^ (w >> 19)) ^ (t ^ (t >> 8))
        return self._w

    def uniform(self):
        """Float in the open interval (0, 1)."""
        return (self.next_u32() + 0.5) * _INV_2_32

    def randrange(self, n):
        """Int in [0, n), n >= 1 (rejection sampling: no modulo bias)."""
        if n <= 0:
            raise ValueError("Prng.randrange: n must be >= 1, got %d" % n)
        if n == 1:
            return 0
        limit = (0x100000000 // n) * n
        while True:
            r = self.next_u32()
            if r < limit:
                return r % n

    def gauss(self, sigma=1.0):
        """Normal(0, sigma) by Box-Muller; the pair's second value serves the next call."""
        if self._spare is not None:
            z = self._spare
            self._spare = None
            return z * sigma
        r = math.sqrt(-2.0 * math.log(self.uniform()))
        a = _TWO_PI * self.uniform()
        self._spare = r * math.sin(a)
        return r * math.cos(a) * sigma
