# A pseudo-random generator for the scenario scripts that stays in small ints on a 32-bit port:
# no intermediate reaches 2**30, so a script under heap_lock allocates nothing and a long run
# does not fragment the heap (an LCG multiplying by 1103515245 makes a long int at every step
# there). Two Lehmer generators modulo the prime 65537 (multiplier 75, a primitive root), the
# same integers on every interpreter.


class SmallRand:
    def __init__(self, seed):
        self.s = [seed % 65536 + 1, (seed // 65536) % 65536 + 1]

    def u16(self):
        """0 .. 65535."""
        s = self.s
        s[0] = s[0] * 75 % 65537
        return s[0] & 0xFFFF

    def u30(self):
        """0 .. 2**30 - 1."""
        s = self.s
        s[1] = s[1] * 75 % 65537
        return (self.u16() & 0x7FFF) << 15 | (s[1] & 0x7FFF)
