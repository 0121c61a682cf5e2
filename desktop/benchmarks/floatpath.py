"""The float approach of the heading guide, in Python: the yardstick the integer firmware is timed against.

The heading guide (a hobbyist article, C): a min/max collector per axis, offset = (max + min) / 2 and
scale = mean half-range / half-range (mag_cal_compute), ((float)raw - offset) * scale
(mag_apply_cal), and a tilt-compensated heading from roll = atan2f(ay, az),
pitch = atan2f(-ax, sqrtf(ay^2 + az^2)), sinf/cosf of both, then atan2f(-my_h, mx_h) in
degrees (compute_heading). Translated line for line with math.atan2/sin/cos/sqrt; the reads
decode the same six data bytes by hand (the seed's int16 casts), and the axes are mapped to
the AN4248 body frame with the same signs as the firmware (mag x,-y,-z; accel -x,y,z).
"""
import math

_RAD_TO_DEG = 180.0 / math.pi
_G_PER_COUNT = 1.0 / 16384.0    # MPU6050 at +-2 g


class MinMaxCollector:
    """mag_cal_collector_t + mag_cal_compute of the heading guide."""

    def __init__(self):
        self.lo = [32767, 32767, 32767]
        self.hi = [-32768, -32768, -32768]
        self.n = 0

    def collect(self, x, y, z):
        v = (x, y, z)
        for i in range(3):
            if v[i] < self.lo[i]:
                self.lo[i] = v[i]
            if v[i] > self.hi[i]:
                self.hi[i] = v[i]
        self.n += 1

    def compute(self):
        cal = FloatCal()
        r = [(self.hi[i] - self.lo[i]) / 2.0 for i in range(3)]
        avg = (r[0] + r[1] + r[2]) / 3.0
        cal.ox = (self.hi[0] + self.lo[0]) / 2.0
        cal.oy = (self.hi[1] + self.lo[1]) / 2.0
        cal.oz = (self.hi[2] + self.lo[2]) / 2.0
        cal.sx = avg / r[0] if r[0] > 0.0 else 1.0
        cal.sy = avg / r[1] if r[1] > 0.0 else 1.0
        cal.sz = avg / r[2] if r[2] > 0.0 else 1.0
        return cal


class FloatCal:
    """mag_cal_t: offsets (counts) and scales."""

    def __init__(self):
        self.ox = self.oy = self.oz = 0.0
        self.sx = self.sy = self.sz = 1.0


def mag_apply_cal(cal, raw, out):
    out[0] = (raw[0] - cal.ox) * cal.sx
    out[1] = (raw[1] - cal.oy) * cal.sy
    out[2] = (raw[2] - cal.oz) * cal.sz


def compute_heading(ax, ay, az, mx, my, mz, declination_deg):
    roll = math.atan2(ay, az)
    pitch = math.atan2(-ax, math.sqrt(ay * ay + az * az))
    sin_roll = math.sin(roll)
    cos_roll = math.cos(roll)
    sin_pitch = math.sin(pitch)
    cos_pitch = math.cos(pitch)
    mx_h = mx * cos_pitch + my * sin_roll * sin_pitch + mz * cos_roll * sin_pitch
    my_h = my * cos_roll - mz * sin_roll
    heading = math.atan2(-my_h, mx_h) * _RAD_TO_DEG + declination_deg
    if heading < 0.0:
        heading += 360.0
    if heading >= 360.0:
        heading -= 360.0
    return heading


def read_mag(bus, st, d, raw):
    """qmc5883l_read_mag: status first (DRDY), then the six data bytes, LSB first."""
    bus.readfrom_mem_into(0x0D, 0x06, st)
    if not st[0] & 0x01:
        return False
    bus.readfrom_mem_into(0x0D, 0x00, d)
    v = d[1] << 8 | d[0]
    raw[0] = v - 0x10000 if v & 0x8000 else v
    v = d[3] << 8 | d[2]
    raw[1] = v - 0x10000 if v & 0x8000 else v
    v = d[5] << 8 | d[4]
    raw[2] = v - 0x10000 if v & 0x8000 else v
    return True


def read_accel_g(bus, d, acc):
    """MPU6050 accelerometer in g, MSB first, mapped to AN4248's sign (-x, y, z)."""
    bus.readfrom_mem_into(0x68, 0x3B, d)
    v = d[0] << 8 | d[1]
    acc[0] = -(v - 0x10000 if v & 0x8000 else v) * _G_PER_COUNT
    v = d[2] << 8 | d[3]
    acc[1] = (v - 0x10000 if v & 0x8000 else v) * _G_PER_COUNT
    v = d[4] << 8 | d[5]
    acc[2] = (v - 0x10000 if v & 0x8000 else v) * _G_PER_COUNT
