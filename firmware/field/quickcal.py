"""Quick calibration: the hard iron V from one pose and a known heading, with the field model's
field vector (PX4's `calibrate mag quick`, ArduPilot's fixed-yaw calibration), integer-only.
"""
#     from firmware.field.quickcal import QuickCal
#     qc = QuickCal(location, counts_per_gauss, mag_map)   # a usable firmware.field.location.Location
#     qc.add(raw_sum, gravity_sum, n, true_heading_kang)  # n samples of one pose, summed
#     cal = qc.result()           # a 4-element-equivalent Calibration, or CalibrationRejected
#
# CompassApp.quick_calibrate(true_heading_cdeg) reads the samples, calls these and puts the
# result in force (docs/quick_calibration.md: measured accuracy). How V follows from AN4248's
# equations read backwards, the result and the refusals: docs/design.md (module notes, quickcal).
from firmware.calibrate import acceptance
from firmware.calibrate.acceptance import REASON_FIELD_MISMATCH, REASON_OFFSET_OUT_OF_RANGE, reject
from firmware.calibration import Calibration
from firmware.compat import const
from firmware.fixedpoint import rdiv
from firmware.trig import ZERO_VECTOR, atan2, cdeg_to_kang, cos, norm14, sin

REASON_NO_LOCATION = "no_location"
REASON_BLACKOUT_ZONE = "blackout_zone"
REASON_NO_SAMPLES = "no_samples"

QUICK_FIT_ERROR = const(1000)  # hundredths of a percent: a quick fit has no residual
POSE_SPREAD_PCT = const(10)    # poses' V within 10 % of |B| of their mean (3 % soft iron
#                                moves a pose's V by <= 3 %, opposite poses apart by <= 6 %)
_MAX_OFFSET_MG = const(1800)   # ArduPilot: offsets <= 1800 mG
_Q15 = const(32768)
_R15 = const(16384)
_BLACKOUT = "blackout zone"  # firmware.field.wmm.STATUS_BLACKOUT (not imported: field loads late)


class QuickCal:
    """Hard iron from poses of known heading; see docs/design.md, module notes.

    location: a firmware.field.location.Location; counts_per_gauss: the magnetometer's; mag_map: the
    app's firmware.axes.AxisMap (chip -> body). .poses: the per-pose V estimates, counts."""

    def __init__(self, location, counts_per_gauss, mag_map):
        if location is None or not location.usable:
            reject(REASON_NO_LOCATION, "no field model here: %s" % (
                "call set_location(lat_e7, lon_e7) first" if location is None
                else location.status))
        if location.status == _BLACKOUT:
            reject(REASON_BLACKOUT_ZONE, "horizontal field %d nT < 2000 nT (WMM blackout "
                   "zone): no magnetic heading here" % location.horizontal_nt)
        if not counts_per_gauss:
            raise ValueError("counts_per_gauss=%r: the magnetometer's sensitivity is needed"
                             % (counts_per_gauss,))
        self.location = location
        self.counts_per_gauss = counts_per_gauss
        self.map = mag_map
        self.h = location.counts(location.horizontal_nt, counts_per_gauss)
        self.z = location.counts(location.down_nt, counts_per_gauss)
        self.field = location.counts(location.field_nt, counts_per_gauss)
        self.poses = []
        self.samples = 0

    def expected(self, gravity, true_heading_kang):
        """The field the board should sense in the chip's axes, counts: (x, y, z)."""
        psi = (true_heading_kang - self.location.declination_kang) & 0xFFFF
        h = self.h
        bfx = (h * cos(psi) + _R15) >> 15
        bfy = -((h * sin(psi) + _R15) >> 15)
        bfz = self.z
        sp, cp, st, ct = _attitude(gravity)
        bx = (bfx * ct - bfz * st + _R15) >> 15
        t = (bfx * st + bfz * ct + _R15) >> 15
        by = (bfy * cp + t * sp + _R15) >> 15
        bz = (t * cp - bfy * sp + _R15) >> 15
        b = (bx, by, bz)
        out = [0, 0, 0]
        m = self.map
        for i in range(3):  # body[i] = sign[i] * chip[axis[i]]: the transpose goes back
            out[m.axis[i]] = m.sign[i] * b[i]
        return out

    def add(self, raw_sum, gravity_sum, n, true_heading_kang):
        """One pose: raw_sum the sum of n raw samples (chip axes, counts), gravity_sum the sum
        of their body-frame gravity vectors (AN4248 sign, +1 g on z when level) or None for
        a level board, the true heading in KANG. Returns this pose's V."""
        if type(n) is not int or n < 1:
            reject(REASON_NO_SAMPLES, "no sample of this pose was read")
        if type(true_heading_kang) is not int:
            raise TypeError("true_heading_kang=%r: expected an int in KANG (65536 per turn)"
                            % (true_heading_kang,))
        raw = [rdiv(raw_sum[i], n) for i in range(3)]
        g = None if gravity_sum is None else [rdiv(gravity_sum[i], n) for i in range(3)]
        e = self.expected(g, true_heading_kang)
        v = (raw[0] - e[0], raw[1] - e[1], raw[2] - e[2])
        self.poses.append(v)
        self.samples += n
        return v

    def offset(self):
        """The mean of the poses' V, counts."""
        k = len(self.poses)
        return tuple(rdiv(sum(p[i] for p in self.poses), k) for i in range(3))

    def result(self):
        """The Calibration (see docs/design.md, module notes), or CalibrationRejected."""
        if not self.poses:
            reject(REASON_NO_SAMPLES, "no pose added")
        v = self.offset()
        acceptance.check_offset(v)
        lim = rdiv(_MAX_OFFSET_MG * self.counts_per_gauss, 1000)
        for i in range(3):
            if not -lim <= v[i] <= lim:
                reject(REASON_OFFSET_OUT_OF_RANGE, "V = (%d, %d, %d) counts: beyond %d counts "
                       "(%d mG) on an axis; a wrong heading, a magnet near, or strong iron"
                       % (v[0], v[1], v[2], lim, _MAX_OFFSET_MG))
        spread = self.spread(v)
        if spread * 100 > POSE_SPREAD_PCT * self.field:
            reject(REASON_FIELD_MISMATCH, "the %d poses' hard iron differs by up to %d counts "
                   "= %d %% of |B| (limit %d %%): a wrong heading, soft iron or a gain error; "
                   "do a full calibration" % (len(self.poses), spread,
                                              rdiv(spread * 100, self.field), POSE_SPREAD_PCT))
        f = self.field
        return Calibration(model=4, offset=v, field=f,
                           field_out=rdiv(f * 32767, _Q15), fit_error=QUICK_FIT_ERROR,
                           samples=self.samples, coverage=0)

    def spread(self, v):
        """The largest distance (counts, per axis) of a pose's V from the mean v."""
        worst = 0
        for p in self.poses:
            for i in range(3):
                d = abs(p[i] - v[i])
                if d > worst:
                    worst = d
        return worst


def _attitude(g):
    """(sin phi, cos phi, sin theta, cos theta) in Q15 from body gravity (AN4248 eqs. 13,
    15), exact 1.0 and 0 for a level board (g None), as firmware.compass."""
    if g is None:
        return 0, _Q15, 0, _Q15
    v = [0, 0, 0]
    if norm14(g, v, 0) == ZERO_VECTOR:
        reject(REASON_NO_SAMPLES, "the accelerometer read (0, 0, 0): no tilt")
    a = atan2(v[1], v[2])  # roll phi
    sp = sin(a)
    cp = cos(a)
    t = (v[1] * sp + v[2] * cp + _R15) >> 15
    a = atan2(-v[0], t)  # pitch theta
    return sp, cp, sin(a), cos(a)


def quick_calibrate(app, true_heading_cdeg, refine=False, samples=32):
    # CompassApp.quick_calibrate: hard iron from this pose and its known true heading
    # (centidegrees, 0..35999, clockwise from true north) with the field model's field: reads
    # `samples` samples (the board held still; tilt from the accelerometer, or level without
    # one), puts the result in force and saves it. refine=True adds this pose to those of the
    # previous calls and averages them (poses at opposite headings cancel most soft-iron
    # error). Returns (the QuickCal, the Calibration); raises CalibrationRejected (.reason: no_location,
    # blackout_zone, no_samples, offset_out_of_range, field_mismatch) and keeps the
    # calibration in force; TypeError / ValueError for bad arguments. Needs
    # app.set_location() first.
    if type(true_heading_cdeg) is not int:
        raise TypeError("true_heading_cdeg=%r: expected an int in hundredths of a degree "
                        "(e.g. 9000 for east)" % (true_heading_cdeg,))
    if not 0 <= true_heading_cdeg < 36000:
        raise ValueError("true_heading_cdeg=%d: expected 0..35999 hundredths of a degree"
                         % true_heading_cdeg)
    if type(samples) is not int or not 1 <= samples <= 128:
        raise ValueError("samples=%r: expected an int in 1..128 (samples averaged)"
                         % (samples,))
    qc = app.quick
    if not refine or qc is None or qc.location is not app.location:
        qc = QuickCal(app.location, app.mag.counts_per_gauss, app._mag_map)
    n, raw, g = _still_samples(app, samples)
    qc.add(raw, g, n, cdeg_to_kang(true_heading_cdeg))
    cal = qc.result()
    acceptance.check_calibration(cal, app.mag.counts_per_gauss)  # the board's own bar
    app._use(cal)
    if app.collector is not None:
        app.collector.calibrator.current = cal  # a later full fit must beat it
    app._save()
    return qc, cal  # (the app keeps qc as .quick: refine=True adds to it)


def _still_samples(app, n):
    """Sum of n good raw samples (chip axes) and of their body gravity (None without an
    accelerometer), read through app.step(); at most 4n tries."""
    raw = [0, 0, 0]
    g = [0, 0, 0] if app.accel is not None else None
    k = 0
    tries = 0
    while k < n and tries < 4 * n:
        tries += 1
        if not app.step():
            continue
        k += 1
        for i in range(3):
            raw[i] += app.raw[i]
            if g is not None:
                g[i] += app.gravity[i]
    return k, raw, g
