"""The mounting check's samples: (magnetometer, accelerometer) pairs spread over orientations,
collected while a calibration session runs; firmware/calibrate/mountcheck.py judges them after a fit.
"""
#     from firmware.calibrate.mounting import Pairs
#     pairs = Pairs(accel.counts_per_g, mag.period_us)   # made by the calibration session
#     pairs.feed(raw, acc)       # each step with a plausible accelerometer: both in chip counts
#
# At most one pair per direction of gravity (BINS = 24), the stillest offered; 342 bytes, feed()
# allocates nothing (tests/scenarios/mounting_heap.py). Why, and how a pair is chosen:
# docs/design.md (module notes, mounting).
from array import array

from firmware.compat import const

BINS = const(24)        # 3 nearest axes x 2 signs x 4 sign pairs of the other two
WIDTH = const(7)        # int16 per bin: mag x, y, z, accel x, y, z, score (-1: empty)
MIN_BINS = const(8)     # bins a check needs (firmware/calibrate/mountcheck.py): a third of the
#                         directions, gravity has left one face of the cube
_PREV = const(168)      # BINS * WIDTH: the previous step's accelerometer
_G_SHIFT = const(4)     # |a|^2 on a >> 4: int16 counts -> < 3 * 2**24
_G2_TOL_PCT = const(20)  # |a|^2 within 20 % of 1 g^2 (|a| within ~10 % of 1 g): little
#                           linear acceleration from the hand
_TURN_US = const(159155)  # 1e6 / 2 pi: a board turning one turn per second moves gravity by
#                            g * period_us / _TURN_US per step (faster than a hand calibrates)
_PERIOD_MAX_US = const(100000)  # 10 Hz, the slowest rate the drivers set
_MOVE_CAP = const(32767)
_OFF_SHIFT = const(4)   # |a|^2 - g^2 >> 4 beside the move: 1 % off 1 g weighs as a 2 deg move


class Pairs:
    """Up to BINS (magnetometer raw, accelerometer raw) pairs, one per direction of gravity
    (see docs/design.md, module notes). counts_per_g: the accelerometer's 1 g; period_us: the sample
    period (firmware.calibrate.mountcheck.check() judges them)."""

    def __init__(self, counts_per_g=16384, period_us=20000):
        if (type(counts_per_g) is not int or type(period_us) is not int
                or not (256 <= counts_per_g <= 32767 and 1000 <= period_us <= 1000000)):
            raise ValueError("Pairs: counts_per_g=%r (counts per g, 256..32767), period_us=%r "
                             "(the sample period, 1000..1000000 us)" % (counts_per_g, period_us))
        d = array("h", bytes(2 * (_PREV + 3)))
        for i in range(BINS):
            d[WIDTH * i + 6] = -1
        self.data = d
        self.count = 0
        g = counts_per_g >> _G_SHIFT
        self.g2 = g * g
        self.g_tol = g * g * _G2_TOL_PCT // 100
        g = g * (period_us if period_us < _PERIOD_MAX_US else _PERIOD_MAX_US) // _TURN_US
        self.step2 = g * g

    def feed(self, raw, acc):
        """Offer one step's magnetometer and accelerometer samples (chip axes, counts); True
        when a bin took the pair (see docs/design.md, module notes)."""
        q = self._moved(acc)
        if q < 0:
            return False
        if q > _MOVE_CAP:
            q = _MOVE_CAP
        d = self.data
        b = WIDTH * _bin(acc)
        if d[b + 6] < 0:
            self.count += 1
        elif q >= d[b + 6]:  # the bin holds a stiller pair
            return False
        d[b] = raw[0]
        d[b + 1] = raw[1]
        d[b + 2] = raw[2]
        d[b + 3] = acc[0]
        d[b + 4] = acc[1]
        d[b + 5] = acc[2]
        d[b + 6] = q
        return True

    def _moved(self, a):
        # the score: |da|^2 (on da >> 4) since the last step plus ||a|^2 - g^2| >> 4; -1 when
        # it moved too far or |a| is not 1 g
        p = self.data
        x = (a[0] - p[_PREV]) >> _G_SHIFT
        y = (a[1] - p[_PREV + 1]) >> _G_SHIFT
        z = (a[2] - p[_PREV + 2]) >> _G_SHIFT
        p[_PREV] = a[0]
        p[_PREV + 1] = a[1]
        p[_PREV + 2] = a[2]
        q = x * x + y * y + z * z
        if q >= self.step2:
            return -1
        x = a[0] >> _G_SHIFT
        y = a[1] >> _G_SHIFT
        z = a[2] >> _G_SHIFT
        x = x * x + y * y + z * z - self.g2
        if x < 0:
            x = -x
        return -1 if x > self.g_tol else q + (x >> _OFF_SHIFT)


def _bin(a):
    # the axis nearest to a, its sign and the signs of the other two: 0..23
    x = a[0]
    y = a[1]
    z = a[2]
    ax = -x if x < 0 else x
    ay = -y if y < 0 else y
    az = -z if z < 0 else z
    if ax >= ay and ax >= az:
        return (x < 0) * 4 + (y < 0) * 2 + (z < 0)
    if ay >= az:
        return 8 + (y < 0) * 4 + (x < 0) * 2 + (z < 0)
    return 16 + (z < 0) * 4 + (x < 0) * 2 + (y < 0)
