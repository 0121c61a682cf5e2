"""Sensor axes -> AN4248 body frame (x forward, y right, z down): a signed permutation."""
#     from firmware.axes import AxisMap
#     mag_map = AxisMap("x,-y,-z")      # body x = sensor x, body y = -sensor y, body z = -sensor z
#     mag_map.apply(corrected, b)        # allocation-free; src and dst may be the same buffer
#     apply(mag_map.m, corrected, b)     # the same, as a function (firmware.fast has its mirror)
#
# A spec names, for body x, y and z in turn, the sensor axis (and sign) that points that way;
# parsing raises ValueError naming it. .det: +1 rotation, -1 mirror. Specs per board: boards/;
# why an accelerometer's map is a mirror: docs/design.md (module notes, axes).
from array import array

AXES = "xyz"


def apply(m, src, dst):
    # dst (body) <- src (sensor) for the map m = AxisMap.m: the source axes of body x, y, z,
    # then 1 where that axis is negated. A negated -32768 saturates to 32767 so an int16 buffer
    # can hold it (the reading was at the rail already). src and dst may be the same buffer.
    # Allocates nothing; firmware.fast.apply is its viper mirror.
    x = src[m[0]]
    y = src[m[1]]
    z = src[m[2]]
    if m[3]:
        x = 32767 if x == -32768 else -x
    if m[4]:
        y = 32767 if y == -32768 else -y
    if m[5]:
        z = 32767 if z == -32768 else -z
    dst[0] = x
    dst[1] = y
    dst[2] = z


class AxisMap:
    """Body-frame vector from a sensor vector: dst[i] = sign[i] * src[axis[i]]."""

    def __init__(self, spec):
        if isinstance(spec, AxisMap):
            spec = spec.spec
        if isinstance(spec, str):
            parts = spec.split(",")
        else:
            parts = list(spec)
        if len(parts) != 3:
            raise ValueError("axis map %r: need 3 comma-separated axes, got %d"
                             % (spec, len(parts)))
        axis = []
        neg = []
        for p in parts:
            if not isinstance(p, str):
                raise ValueError("axis map %r: %r is not an axis name" % (spec, p))
            p = p.strip().lower()
            n = p[:1] == "-"
            if p[:1] in "+-":
                p = p[1:].strip()
            if len(p) != 1 or p not in AXES:
                raise ValueError("axis map %r: %r is not one of x, y, z (with an optional sign)"
                                 % (spec, p))
            if AXES.index(p) in axis:
                raise ValueError("axis map %r: sensor axis %s used twice" % (spec, p))
            axis.append(AXES.index(p))
            neg.append(n)
        self.axis = tuple(axis)
        self.sign = tuple(-1 if n else 1 for n in neg)
        self.spec = ",".join(("-" if n else "") + AXES[a] for a, n in zip(axis, neg))
        self.m = array("b", (axis[0], axis[1], axis[2], 1 if neg[0] else 0, 1 if neg[1] else 0,
                             1 if neg[2] else 0))  # apply()'s argument
        # determinant of a signed permutation: product of signs times the permutation's parity
        inversions = (axis[0] > axis[1]) + (axis[0] > axis[2]) + (axis[1] > axis[2])
        self.det = self.sign[0] * self.sign[1] * self.sign[2] * (-1 if inversions & 1 else 1)

    def apply(self, src, dst):
        """dst (body) <- src (sensor); see apply()."""
        apply(self.m, src, dst)

    def matrix(self):
        """3x3 ints, rows body axes, columns sensor axes: body = matrix * sensor."""
        rows = []
        for i in range(3):
            row = [0, 0, 0]
            row[self.axis[i]] = self.sign[i]
            rows.append(tuple(row))
        return tuple(rows)

    def inverse(self):
        """The map body -> sensor (the transpose)."""
        parts = ["", "", ""]
        for i in range(3):
            parts[self.axis[i]] = ("-" if self.sign[i] < 0 else "") + AXES[i]
        return AxisMap(",".join(parts))

    def __eq__(self, other):
        return isinstance(other, AxisMap) and other.spec == self.spec

    def __ne__(self, other):
        return not self.__eq__(other)

    def __hash__(self):
        return hash(self.spec)

    def __repr__(self):
        return "AxisMap(%r)" % self.spec
