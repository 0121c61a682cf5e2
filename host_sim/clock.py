"""Simulated time: integer microseconds, advanced only by the bus and by explicit sleeps.

    clock = SimClock()
    clock.advance(5000)      # 5 ms pass
    clock.now_us             # -> 5000

Integers only, so a run is bit-identical on CPython and MicroPython and never drifts.
"""


class SimClock:
    """Monotonic simulated clock. `now_us` is an int; nothing else moves it."""

    def __init__(self, start_us=0):
        self.now_us = int(start_us)

    def advance(self, us):
        """Let `us` microseconds pass (int >= 0); returns the new time."""
        us = int(us)
        if us < 0:
            raise ValueError("SimClock.advance: negative step %d us" % us)
        self.now_us += us
        return self.now_us

    def sleep_us(self, us):
        self.advance(us)

    def sleep_ms(self, ms):
        self.advance(int(ms) * 1000)

    def ticks_us(self):
        return self.now_us

    def ticks_ms(self):
        return self.now_us // 1000

    def seconds(self):
        """Current time in seconds (float), for the world model only."""
        return self.now_us / 1000000
