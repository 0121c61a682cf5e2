"""Sample selection for calibration: a bounded buffer of raw int16 samples, kept apart by distance."""
#     buf = SampleBuffer(capacity=300, separation=separation_for(6000, 300))
#     if buf.offer(x, y, z) == REPLACED: ...  # buf.evicted holds the sample that left
#     pct = buf.coverage(vx, vy, vz)          # % of 100 equal-area sphere regions seen from V
#
# A sample is kept only if no held one is closer than the separation (at most 27 hash look-ups,
# no scan); a full buffer replaces its oldest. Why distance, the slot order and the hash table:
# docs/design.md (module notes, samples). offer() allocates nothing (tests/test_samples.py).
from array import array

from firmware.fixedpoint import isqrt

from firmware.compat import const, pick, room

REJECTED = const(0)  # offer(): too close to a held sample, or its cell is taken
KEPT = const(1)      # offer(): stored in a free slot
REPLACED = const(2)  # offer(): stored over the oldest sample, now in .evicted
NOT_INT = const(3)   # offer(): x, y or z is not an int within 32 bits; nothing changed
                     # (bad_sample() says which)

MAX_CAPACITY = const(16383)     # table entries are uint16 slot+1; the table is 3-6x capacity
MAX_SEPARATION = const(16384)   # counts: keeps 3*s**2 < 2**30 (small int on 32-bit boards)
N_REGIONS = const(100)          # equal-area sphere regions for coverage(), as MotionCal uses
COVERAGE_CHUNK = const(4)       # coverage_steps(): samples per slice (~10 us on the unix port)

# Spatial hash: odd multipliers < 2**14 keep |c * m| < 2**29 for cell coordinates |c| <= 2**15,
# and the xor of three such values stays below 2**29 too; a fold, a second multiply on 15 bits
# and a fold spread neighbouring cells over the table (mean probes match ideal linear probing).
_HX = const(0x2F1B)
_HY = const(0x1D4F)
_HZ = const(0x3A95)
_HMIX = const(0x5BD1)

_FAR = const(0)     # _probe(): cell empty and no sample within s met on the way
_TAKEN = const(1)   # _probe(): the cell holds a sample, not within s
_NEAR = const(2)    # _probe(): a held sample within s was met

# MotionCal gap weights (docs/motioncal.md, what each gauge means): empty region 1.0, one sample 0.2, two 0.01, in hundredths
_GAP_EMPTY = const(100)
_GAP_ONE = const(20)
_GAP_TWO = const(1)

# Coverage regions. Area on a sphere is uniform in z (Archimedes), so each hemisphere is cut
# into latitude bands whose height in z/|r| is 0.02 per region (z/|r| boundaries 49/50, 43/50,
# 32/50, 17/50, 0), and each band into equal longitude sectors: 1 + 6 + 11 + 15 + 17 = 50
# regions per hemisphere, all of area 4*pi/100 and about 20 degrees across.
_Z_FIFTIETHS = (49, 43, 32, 17, 0)    # lower z/|r| limit of each band, in 1/50
_BAND_SECTORS = (1, 6, 11, 15, 17)
_BAND_FIRST = (0, 1, 7, 18, 33)       # region index of each band's sector 0 (upper hemisphere)
# Sector boundaries: (cos, sin) of 2*pi*k/n in Q14 for k = 0 .. n-1, per band.
_BOUNDS = (
    (),
    (16384, 0, 8192, 14189, -8192, 14189, -16384, 0, -8192, -14189, 8192, -14189),
    (16384, 0, 13783, 8858, 6806, 14903, -2332, 16217, -10729, 12382, -15720, 4616,
     -15720, -4616, -10729, -12382, -2332, -16217, 6806, -14903, 13783, -8858),
    (16384, 0, 14968, 6664, 10963, 12176, 5063, 15582, -1713, 16294, -8192, 14189,
     -13255, 9630, -16026, 3406, -16026, -3406, -13255, -9630, -8192, -14189,
     -1713, -16294, 5063, -15582, 10963, -12176, 14968, -6664),
    (16384, 0, 15278, 5919, 12108, 11038, 7303, 14666, 1512, 16314, -4484, 15759,
     -9874, 13075, -13930, 8625, -16105, 3011, -16105, -3011, -13930, -8625,
     -9874, -13075, -4484, -15759, 1512, -16314, 7303, -14666, 12108, -11038,
     15278, -5919),
)
_NORM_HI = const(0x4000)  # region(): the largest component is scaled into [2**13, 2**14)
_NORM_LO = const(0x2000)

# separation_for(): a sphere of radius R saturates at about 8.2 * (R / s)**2 samples under this
# rule (measured over 2e5 uniformly spread offers; tests/test_samples.py checks it within 25 %).
_FILL_Q8 = const(2100)


def _hash(c, j):
    # the cell c[j], c[j + 1], c[j + 2]
    h = (c[j] * _HX) ^ (c[j + 1] * _HY) ^ (c[j + 2] * _HZ)
    h = (h ^ (h >> 13)) & 0x7FFF
    h *= _HMIX  # < 2**15 * 2**15: still a small int
    return h ^ (h >> 15)


def separation_for(radius_counts, samples):
    """Separation (counts) at which a whole sphere of `radius_counts` saturates at about
    `samples` held samples.
    """
    # radius_counts is the geomagnetic field in counts (50 uT = 6000 counts on a QMC5883L at
    # +-2 G, 545 on an HMC5883L at 1090 counts/G). Ask for fewer samples than the capacity
    # (about 3/4): if a whole sphere needs more than the capacity, the FIFO evicts the start of
    # a slow rotation before its end arrives and coverage never completes.
    if radius_counts <= 0 or samples <= 0:
        raise ValueError("separation_for(%d, %d): both must be > 0" % (radius_counts, samples))
    s = isqrt(radius_counts * radius_counts * _FILL_Q8 // (256 * samples))
    if s < 1:
        return 1
    return s if s < MAX_SEPARATION else MAX_SEPARATION


def region(dx, dy, dz):
    """Equal-area sphere region 0 .. N_REGIONS-1 of the direction (dx, dy, dz), or -1 for zero."""
    # Regions 0 .. 49 have dz >= 0: 0 is the cap around +z, then bands of 6, 11, 15 and 17
    # longitude sectors down to the equator (sector 0 starts at +x and runs towards +y);
    # 50 .. 99 mirror them for dz < 0.
    ax = -dx if dx < 0 else dx
    ay = -dy if dy < 0 else dy
    az = -dz if dz < 0 else dz
    m = ax if ax > ay else ay
    if az > m:
        m = az
    if m == 0:
        return -1
    # Normalise so that r**2 < 3 * 2**28 stays a small int and the direction keeps 13 bits.
    while m >= _NORM_HI:
        dx >>= 1
        dy >>= 1
        az >>= 1
        m >>= 1
    while m < _NORM_LO:
        dx <<= 1
        dy <<= 1
        az <<= 1
        m <<= 1
    r = isqrt(dx * dx + dy * dy + az * az)
    band = 0
    while 50 * az < _Z_FIFTIETHS[band] * r:
        band += 1
    first = _BAND_FIRST[band] if dz >= 0 else N_REGIONS // 2 + _BAND_FIRST[band]
    n = _BAND_SECTORS[band]
    if n == 1:
        return first
    # Largest k with angle(dx, dy) >= 2*pi*k/n, by bisection; each test is one cross product
    # with the boundary's unit vector, valid because both angles lie in the same half-turn.
    bounds = _BOUNDS[band]
    upper = dy > 0 or (dy == 0 and dx >= 0)   # angle in [0, pi)
    lo = 0
    hi = n
    while hi - lo > 1:
        k = (lo + hi) >> 1
        if 2 * k < n:  # boundary in [0, pi)
            past = (not upper) or bounds[2 * k] * dy - bounds[2 * k + 1] * dx >= 0
        else:          # boundary in [pi, 2*pi)
            past = (not upper) and bounds[2 * k] * dy - bounds[2 * k + 1] * dx >= 0
        if past:
            lo = k
        else:
            hi = k
    return first + lo


def bad_sample(x, y, z):
    """The error for a sample offer() called NOT_INT: TypeError naming the argument that is not
    an int, or ValueError for an int outside int16 (CPython refuses one beyond 32 bits)."""
    for name, v in (("x", x), ("y", y), ("z", z)):
        if not isinstance(v, int) or isinstance(v, bool):
            return TypeError("sample %s = %r: expected an int (raw int16 counts)" % (name, v))
    return ValueError("sample (%d, %d, %d) is not int16" % (x, y, z))


def screen(b):
    """SampleBuffer.offer's rejection test for the candidate in b._q[0..2]: 1 when a held
    sample closer than the separation, or a sample in its own cell, forbids keeping it, else
    0 (its cell then in q[3..5]); counts b.last_cells and b.last_probes. firmware/fast.py
    mirrors it (use_kernels)."""
    # The newest sample is the usual reason to reject at 50 Hz: test it before hashing.
    if b._last >= 0 and b._near(3 * b._last):
        return 1
    if b._own_cell() != _FAR:
        return 1  # own cell taken (or a close sample met on its chain)
    if b._neighbours():
        return 1
    return 0


_screen = screen  # offer()'s: this function or its fast mirror, module-wide (use_kernels)


def use_kernels(kn=None):
    """SampleBuffer.offer's rejection test from the kernel set `kn` (as
    firmware.compass.use_kernels): None picks firmware.fast where the native emitter exists,
    False the plain function."""
    global _screen
    _screen = pick(kn, "screen", screen)


class SampleBuffer:
    """Bounded, distance-separated buffer of raw int16 magnetometer samples (see module doc)."""
    # Attributes: data (array 'h', 3*capacity; slots 0..count-1 hold samples), count, capacity,
    # separation (counts), evicted (array 'h', 3: the sample the last REPLACED pushed out),
    # next_slot, last_cells / last_probes (hash cells looked up / table entries read by the
    # last offer), region_counts (bytearray, per region, filled by coverage()), gaps_x100.

    def __init__(self, capacity=300, separation=50):
        if not 1 <= capacity <= MAX_CAPACITY:
            raise ValueError("capacity %d not in 1..%d" % (capacity, MAX_CAPACITY))
        self.capacity = capacity
        self.data = array('h', bytearray(6 * capacity))
        self.evicted = array('h', bytearray(6))
        self._cells = array('h', bytearray(6 * capacity))  # cell coordinates of each slot
        size = 4
        while size < 3 * capacity:  # load <= 1/3: about 1.6 probes per unsuccessful look-up
            size <<= 1
        self._table = array('H', bytearray(2 * size))     # slot + 1, 0 = empty
        self._mask = size - 1
        self.regions = N_REGIONS
        self.region_counts = bytearray(N_REGIONS)
        self.gaps_x100 = N_REGIONS * _GAP_EMPTY
        self.last_cells = 0
        self.last_probes = 0
        # offer()'s scratch: the candidate x, y, z, its cell, the cell being probed (and, for
        # firmware/fast.py's screen, 9..13: separation, its square, table mask, cells and
        # entries counted); and the squared gaps to the neighbour cells on each side of each
        # axis (low x, high x, ...)
        self._q = array("i", bytearray(4 * 14))
        self._gap = array("i", (0, 0, 0, 0, 0, 0))
        self._check_separation(separation)
        self.separation = separation
        self._s2 = separation * separation
        self.clear()

    @staticmethod
    def _check_separation(d):
        if not 1 <= d <= MAX_SEPARATION:
            raise ValueError("separation %d counts not in 1..%d" % (d, MAX_SEPARATION))

    def clear(self):
        """Forget every sample (the caller's sums must be reset too)."""
        self.count = 0
        self.next_slot = 0
        self._last = -1
        t = self._table
        for i in range(len(t)):
            t[i] = 0

    def sample(self, i, out):
        """Copy slot i (0 <= i < count) into out[0:3]."""
        if not 0 <= i < self.count:
            raise IndexError("slot %d not in 0..%d" % (i, self.count - 1))
        j = 3 * i
        d = self.data
        out[0] = d[j]
        out[1] = d[j + 1]
        out[2] = d[j + 2]

    def slot_by_age(self, k):
        """Slot of the k-th oldest held sample (k = 0 is the oldest)."""
        if not 0 <= k < self.count:
            raise IndexError("age %d not in 0..%d" % (k, self.count - 1))
        if self.count < self.capacity:
            return k
        k += self.next_slot
        return k - self.capacity if k >= self.capacity else k

    def offer(self, x, y, z):
        """Offer one raw sample (int16 counts); returns REJECTED, KEPT or REPLACED, or NOT_INT
        (nothing changed) when x, y or z is not an int within 32 bits. ValueError for an int
        outside int16.
        """
        # As named steps, each small enough that its frame stays on the C stack (11 words,
        # MicroPython's py/objfun.c): nothing is allocated for a rejected sample.
        try:  # the int array refuses a float or a str (CPython: also an int beyond 32 bits)
            self._q[0] = x
            self._q[1] = y
            self._q[2] = z
        except:  # noqa: E722 - a matching class or a call here would put the frame on the heap
            return NOT_INT
        if not (-32768 <= x <= 32767 and -32768 <= y <= 32767 and -32768 <= z <= 32767):
            raise bad_sample(x, y, z)
        self.last_cells = 0
        self.last_probes = 0
        if _screen(self):
            return REJECTED
        return self._keep()

    def _near(self, j):
        # True when the held sample data[j..j+2] is closer than s to the candidate
        q = self._q
        s = self.separation
        a = self.data[j] - q[0]
        if -s < a < s:
            b = self.data[j + 1] - q[1]
            if -s < b < s:
                j = self.data[j + 2] - q[2]
                return -s < j < s and a * a + b * b + j * j < self._s2
        return False

    def _own_cell(self):
        q = self._q
        s = self.separation
        q[3] = q[6] = q[0] // s
        q[4] = q[7] = q[1] // s
        q[5] = q[8] = q[2] // s
        return self._probe()

    def _probe(self):
        # Walk the chain of cell q[6..8] until its occupant or an empty entry. Any entry met
        # that is within s of the candidate decides at once: such a sample forbids keeping.
        t = self._table
        i = _hash(self._q, 6) & self._mask
        self.last_cells += 1
        while True:
            self.last_probes += 1
            e = t[i]
            if e == 0:
                return _FAR
            e = 3 * (e - 1)
            if self._near(e):
                return _NEAR
            if self._in_probed_cell(e):
                return _TAKEN
            i = (i + 1) & self._mask

    def _in_probed_cell(self, j):
        c = self._cells
        q = self._q
        return c[j] == q[6] and c[j + 1] == q[7] and c[j + 2] == q[8]

    def _neighbours(self):
        # Neighbour cells, skipping those whose nearest integer point is already >= s away
        # (at most 26 look-ups; 19.6 on average). True when a close sample is met.
        self._gaps()
        g = self._gap
        for a in range(-1, 2):
            ga = g[0] if a < 0 else g[1] if a > 0 else 0
            if ga < self._s2:
                self._q[6] = self._q[3] + a
                if self._plane(ga):
                    return True
        return False

    def _gaps(self):
        # per axis the gap to cell c-1 is (offset in cell + 1), to cell c+1 it is (s - offset)
        q = self._q
        g = self._gap
        s = self.separation
        for k in range(3):
            u = q[k] - q[3 + k] * s + 1
            g[2 * k] = u * u
            u = s + 1 - u
            g[2 * k + 1] = u * u

    def _plane(self, ga):
        g = self._gap
        for b in range(-1, 2):
            gb = ga + (g[2] if b < 0 else g[3] if b > 0 else 0)
            if gb < self._s2:
                self._q[7] = self._q[4] + b
                if self._row(gb):
                    return True
        return False

    def _row(self, gb):
        g = self._gap
        for c in range(-1, 2):
            gc = gb + (g[4] if c < 0 else g[5] if c > 0 else 0)
            # every gap is >= 1, so gc == 0 is the candidate's own cell, probed already
            if gc < self._s2 and gc != 0:
                self._q[8] = self._q[5] + c
                if self._probe() == _NEAR:
                    return True
        return False

    def _keep(self):
        slot = self.next_slot
        if self.count < self.capacity:
            self.count += 1
            result = KEPT
        else:
            self._evict(slot)
            result = REPLACED
        self._store(slot)
        self.next_slot = slot + 1 if slot + 1 < self.capacity else 0
        self._last = slot
        return result

    def _evict(self, slot):
        self._unlink(slot)
        j = 3 * slot
        ev = self.evicted
        data = self.data
        ev[0] = data[j]
        ev[1] = data[j + 1]
        ev[2] = data[j + 2]

    def _store(self, slot):
        # the candidate q[0..2] and its cell q[3..5] into `slot`, and the slot into the hash
        j = 3 * slot
        q = self._q
        data = self.data
        cells = self._cells
        for k in range(3):
            data[j + k] = q[k]
            cells[j + k] = q[3 + k]
        table = self._table
        i = _hash(q, 3) & self._mask
        while table[i]:
            i = (i + 1) & self._mask
        table[i] = slot + 1

    def _home(self, e):
        return _hash(self._cells, 3 * (e - 1)) & self._mask

    def _unlink(self, slot):
        # Linear-probing deletion by backward shift (Knuth 6.4 Algorithm R): no tombstones,
        # so chains never lengthen with churn.
        table = self._table
        mask = self._mask
        i = self._home(slot + 1)
        while table[i] != slot + 1:
            if table[i] == 0:
                raise RuntimeError("sample slot %d missing from its hash chain" % slot)
            i = (i + 1) & mask
        table[i] = 0
        j = i
        while True:
            j = (j + 1) & mask
            e = table[j]
            if e == 0:
                return
            k = self._home(e)
            if i <= j:
                stays = i < k <= j
            else:
                stays = k > i or k <= j
            if not stays:
                table[i] = e
                table[j] = 0
                i = j

    def set_separation(self, d):
        """Change the separation and rebuild the hash from the held samples (rare; allocates)."""
        # Samples that break the new rule are dropped, the newer of a conflicting pair kept;
        # the survivors stay in age order. Returns how many were dropped. The caller must
        # recompute any sums over the held samples afterwards.
        self._check_separation(d)
        old = [self.data[3 * s:3 * s + 3] for s in
               [self.slot_by_age(k) for k in range(self.count)]]
        self.separation = d
        self._s2 = d * d
        self.clear()
        kept = []
        for v in reversed(old):      # newest first: they win conflicts
            if self.offer(v[0], v[1], v[2]) != REJECTED:
                kept.append(v)
        self.clear()
        for v in reversed(kept):     # oldest first again; all compatible, so all kept
            self.offer(v[0], v[1], v[2])
        return len(old) - len(kept)

    def coverage(self, cx, cy, cz):
        """Percent (0..100) of the N_REGIONS equal-area regions holding a sample, seen from
        the centre (cx, cy, cz) in counts (the current hard-iron estimate V).
        """
        # Also fills region_counts (saturating at 255) and gaps_x100, MotionCal's gaps figure
        # times 100 (0 .. 10000; MotionCal calls gaps < 15, i.e. gaps_x100 < 1500, good).
        counts = self.region_counts
        for i in range(N_REGIONS):
            counts[i] = 0
        self._tally(0, 3 * self.count, cx, cy, cz)
        self.gaps_x100 = 0
        return self._score(0, N_REGIONS) * 100 // N_REGIONS

    def _tally(self, j0, j1, cx, cy, cz):
        # classify the held samples data[j0:j1] (j in steps of 3) into region_counts
        counts = self.region_counts
        data = self.data
        for j in range(j0, j1, 3):
            r = region(data[j] - cx, data[j + 1] - cy, data[j + 2] - cz)
            if r >= 0 and counts[r] < 255:
                counts[r] += 1

    def _score(self, i0, i1):
        # regions i0..i1-1: add MotionCal's gap weights to gaps_x100, return how many are held
        counts = self.region_counts
        occupied = 0
        for i in range(i0, i1):
            c = counts[i]
            if c == 0:
                self.gaps_x100 += _GAP_EMPTY
            else:
                occupied += 1
                if c == 1:
                    self.gaps_x100 += _GAP_ONE
                elif c == 2:
                    self.gaps_x100 += _GAP_TWO
        return occupied

    def coverage_steps(self, cx, cy, cz, out, chunk=COVERAGE_CHUNK):
        # coverage() as a generator for a time-sliced solve: each next() clears or tallies
        # at most 4 * chunk regions or classifies at most `chunk` held samples (region() is
        # the cost: ~40 bytecode lines a sample). Sets out[0] to the percent coverage() would
        # return, with region_counts and gaps_x100 filled the same way. Samples offered
        # meanwhile may land in the slots not yet visited: the count covers the buffer as each
        # slot is reached (as coverage() would at that moment).
        if chunk < 1:
            raise ValueError("coverage chunk %d < 1" % chunk)
        counts = self.region_counts
        step = 4 * chunk
        for i0 in range(0, N_REGIONS, step):
            for i in range(i0, i0 + step if i0 + step < N_REGIONS else N_REGIONS):
                counts[i] = 0
            yield
        j = 0
        while j < 3 * self.count:
            end = j + 3 * chunk
            if end > 3 * self.count:
                end = 3 * self.count
            self._tally(j, end, cx, cy, cz)
            j = end
            yield
        self.gaps_x100 = 0
        occupied = 0
        for i0 in range(0, N_REGIONS, step):
            occupied += self._score(i0, i0 + step if i0 + step < N_REGIONS else N_REGIONS)
            if i0 + step < N_REGIONS:
                yield
        out[0] = occupied * 100 // N_REGIONS


room(SampleBuffer)  # its methods' table too (firmware/compat.py room)


use_kernels()
