"""Acceptance of a new calibration: the thresholds, and a named reason for every refusal.

    from firmware.calibrate import acceptance
    acceptance.check_field(field_counts, counts_per_gauss)   # raises CalibrationRejected(reason)
"""
# Every refusal raises CalibrationRejected(REASON_*, detail) with the numbers in the detail.
# The checks in the order the calibrator runs them, each threshold's source, and the same bar
# for a calibration from anywhere (check_calibration): docs/design.md (module notes,
# acceptance); docs/faults.md lists every refusal.
from firmware.calibration import MINMAX, ORDER
from firmware.compat import const
from firmware.errors import CalibrationRejected
from firmware.fixedpoint import rdiv

REASON_TOO_FEW_SAMPLES = "too_few_samples"
REASON_PLANAR = "planar"
REASON_SINGULAR = "singular"
REASON_LOW_COVERAGE = "low_coverage"
REASON_OFFSET_OUT_OF_RANGE = "offset_out_of_range"
REASON_SOFT_IRON_OUT_OF_RANGE = "soft_iron_out_of_range"
REASON_FIELD_OUT_OF_RANGE = "field_out_of_range"
REASON_FIELD_MISMATCH = "field_mismatch"
REASON_FIT_ERROR_HIGH = "fit_error_high"
REASON_NOT_BETTER = "not_better"
REASON_INCONSISTENT = "inconsistent_samples"

# Minimum held samples, in units of one great circle at the default separation (~33):
# more than one circle for min/max and 4 elements, than two for 7, than three for 10
# (Judd: a 3D ellipsoid needs data from more than two independent planes).
MIN_SAMPLES = {MINMAX: 40, 4: 40, 7: 70, 10: 100}
MIN_SAMPLES_GEOMETRY = const(12)  # enough to tell a flat spin from a start (4-element fit)
# Coverage (% of 100 equal-area regions around V; one great circle crosses ~20 of them);
# min/max needs both extremes of every axis.
MIN_COVERAGE = {MINMAX: 40, 4: 30, 7: 40, 10: 50}
# Degeneracy ratios rho (firmware/calibrate/solve.py; parts per million). A fully covered sphere gives
# 333333 for the centre, 66667 (dx dy) and 200000 (dx^2 - dz^2) for the shape; soft iron
# lowers them as the ellipsoid flattens (roughly as 1 / axis ratio^2), so each threshold is
# half the value measured on a fully covered ellipsoid with 5:1 axes, the most anisotropic
# one accepted (_MAX_SOFT_IRON_COND_X100). The planar wind-vane log gives 1/10 of these.
_MIN_RHO_CENTRE_PPM = const(17000)  # all models (5:1 ellipsoid: 34000)
_MIN_RHO_SHAPE_7_PPM = const(12500)  # 7 elements (5:1 ellipsoid: 25000)
_MIN_RHO_SHAPE_10_PPM = const(1400)  # 10 elements (5:1 ellipsoid: 2870)
_MAX_SOFT_IRON_COND_X100 = const(500)  # W^-1 eigenvalues within 5:1 (ArduPilot: 0.2 .. 5)
_MIN_FIELD_UT = const(10)           # NXP: plausible geomagnetic field 10 .. 90 uT
_MAX_FIELD_UT = const(90)
_MIN_FIELD_COUNTS = const(16)       # unknown sensitivity: 1 count is then >= 6 % of B
# |B_fit - B_model| / B_model limit, %: a gain step of the HMC5883L (1370 / 1090 = 1.26) or a
# wrong range (x4) is refused; a few % of sensitivity error, WMM's crustal-field omission and
# a building's steel pass.
FIELD_MATCH_PCT = const(20)
# NXP's 15 %: the definition is NXP's, so its limit carries over. It refuses a sphere fit to a
# 2:1 ellipsoid (~20 %); real 10-element fits here give 0.6-3.7 %, 9.5 % on a noisy QMC log.
DEFAULT_MAX_FIT_ERROR = const(1500)  # hundredths of a percent
_FIT_ERROR_UPGRADE = const(350)     # NXP: a higher-order model is accepted at <= 3.5 %
_COVERAGE_GAIN = const(15)          # points of coverage that make a wider fit "better"...
_COVERAGE_FIT_NUM = const(3)        # ...if its fit error is within 3/2 of the current's:
_COVERAGE_FIT_DEN = const(2)        # a fit over part of the sphere looks better than it is
# inconsistent_samples: the hard iron changed by more than 3 % of B between the halves where
# they saw the same directions, with a chi-square above 16 against the noise (3 degrees of
# freedom: 16.3 is exceeded once in 1000 by chance), unless the change is within the fit's RMS
# residual and that residual is the noise (mean square within _MIXED_RESIDUAL times the
# noise's: a mix of two states spreads the samples about any one fit); shared directions
# flatter than det < (trace / 3)^3 / 20, or a change over 3 % within the noise, give no
# verdict, and no fit while the residual is beyond the noise's (check_comparable). Noise:
# sigma = sqrt(pi) / 2 mean|d| over consecutive samples' differences d (variance 2 sigma^2),
# which a few jumps (a switching iron, a glitch) do not inflate as a mean square; pi/4 ~ 355/452.
CONSISTENCY_PCT = const(3)
_CHI2 = const(16)
_FLAT_HALF = const(20)
_MIXED_RESIDUAL = const(2)
PI4_NUM = const(355)
PI4_DEN = const(452)


_MAX_SCALE_DOWN = const(8)   # InvW shrinks |B| by at most 8 (cube root of det >= 1/8): a fit
#                              within 5:1 soft iron scales it by >= 1/5.2 (Q15 rows <= 1)
_MIN_DET_SHIFT = const(36)   # det(InvW) in Q15^3 >= 2**45 / 2**9: the same 1/8, cubed


def reject(reason, detail):
    raise CalibrationRejected(reason, detail)


def _pct(x100):
    return "%d.%02d %%" % (x100 // 100, x100 % 100)


def check_samples(n, model):
    """too_few_samples unless `n` held samples meet the model's minimum."""
    need = MIN_SAMPLES[model]
    if n < need:
        reject(REASON_TOO_FEW_SAMPLES, "%d samples held, model %s needs %d" % (n, model, need))


def flat_spin(n, model, need):
    """The refusal for a buffer that never filled because the samples lie near a plane."""
    reject(REASON_PLANAR, "%d samples held (model %s needs %d), all near a plane: turn the "
           "board over, not only around" % (n, model, need))


def rho_limit(centre, model):
    """The smallest acceptable degeneracy ratio (ppm) of a centre or a shape parameter."""
    if centre:
        return _MIN_RHO_CENTRE_PPM
    return _MIN_RHO_SHAPE_7_PPM if model == 7 else _MIN_RHO_SHAPE_10_PPM


def check_rho(rho_ppm, centre, model, name):
    """planar when the least determined parameter's rho is below its limit."""
    lim = rho_limit(centre, model)
    if rho_ppm < lim:
        reject(REASON_PLANAR, "%s is undetermined (rho %d ppm < %d, %d-element fit): samples "
               "confined near a plane, or two?" % (name, rho_ppm, lim, model))


def check_offset(v):
    """offset_out_of_range unless V fits int16 (Calibration.correct's domain)."""
    for i in range(3):
        if not -32768 <= v[i] <= 32767:
            reject(REASON_OFFSET_OUT_OF_RANGE, "V = (%d, %d, %d) counts is outside int16"
                   % (v[0], v[1], v[2]))


def check_coverage(cov, model):
    if cov < MIN_COVERAGE[model]:
        reject(REASON_LOW_COVERAGE, "%d %% of sphere regions covered around V, model %s needs "
               "%d %%" % (cov, model, MIN_COVERAGE[model]))


def check_soft_iron(cond_x100, field_out):
    """soft_iron_out_of_range unless InvW is positive definite with eigenvalues within 5:1."""
    if cond_x100 is None or cond_x100 > _MAX_SOFT_IRON_COND_X100 or field_out <= 0:
        reject(REASON_SOFT_IRON_OUT_OF_RANGE, "W^-1 eigenvalue ratio %s/100 > %d/100"
               % (cond_x100, _MAX_SOFT_IRON_COND_X100))


def field_ok(field, counts_per_gauss, scale=1):
    """True when B (counts x `scale`) is a plausible geomagnetic field for this sensitivity."""
    if counts_per_gauss:
        # B [uT] = field * 100 / (cpg * scale)
        cs = counts_per_gauss * scale
        return _MIN_FIELD_UT * cs <= field * 100 <= _MAX_FIELD_UT * cs
    return field >= _MIN_FIELD_COUNTS * scale


def check_field(field, counts_per_gauss, scale=1):
    """field_out_of_range unless B (counts x `scale`, e.g. 65536 for Q16) is plausible."""
    if field_ok(field, counts_per_gauss, scale):
        return
    if counts_per_gauss:
        reject(REASON_FIELD_OUT_OF_RANGE, "B = %d counts = %d uT at %d counts/G, not in %d..%d "
               "uT" % (rdiv(field, scale), rdiv(field * 100, counts_per_gauss * scale),
                       counts_per_gauss, _MIN_FIELD_UT, _MAX_FIELD_UT))
    reject(REASON_FIELD_OUT_OF_RANGE, "B = %d counts < %d: too coarse to calibrate"
           % (rdiv(field, scale), _MIN_FIELD_COUNTS))


def field_matches(field, expected):
    """True when B (counts) is within FIELD_MATCH_PCT of the expected |B| (counts, > 0)."""
    d = field - expected
    return -expected * FIELD_MATCH_PCT <= d * 100 <= expected * FIELD_MATCH_PCT


def check_expected_field(field, expected):
    """field_mismatch unless B (counts) is within FIELD_MATCH_PCT of the field model's |B|
    in the same counts (firmware/field/location.py converts nT with the driver's counts_per_gauss)."""
    if field_matches(field, expected):
        return
    reject(REASON_FIELD_MISMATCH, "B = %d counts is %d %% of the %d counts the field model "
           "expects here (limit +-%d %%): wrong gain or range, or a magnet near"
           % (field, rdiv(field * 100, expected), expected, FIELD_MATCH_PCT))


def check_fit_error(fe, max_fit_error):
    if fe > max_fit_error:
        reject(REASON_FIT_ERROR_HIGH, "fit error %s > %s" % (_pct(fe), _pct(max_fit_error)))


def check_better(model, fe, cov, current, aged):
    """not_better unless the new fit beats `current` (whose fit error aged to `aged`)."""
    if current.model is None:
        return
    upgrade = ORDER[model] > ORDER[current.model] and fe <= _FIT_ERROR_UPGRADE
    # A fit over more of the sphere is worth a somewhat higher fit error: the first fit, on
    # ~100 samples from part of it, would otherwise never be replaced.
    wider = (cov >= current.coverage + _COVERAGE_GAIN and ORDER[model] >= ORDER[current.model]
             and fe * _COVERAGE_FIT_DEN <= aged * _COVERAGE_FIT_NUM)
    if fe >= aged and not upgrade and not wider:
        reject(REASON_NOT_BETTER, "fit error %s at %d %% coverage is not better than the "
               "current calibration's %s (aged) at %d %% (model %s)"
               % (_pct(fe), cov, _pct(aged), current.coverage, current.model))


def half_is_flat(det, tr):
    """True when a normal matrix of samples (sums of b b^T: determinant det, trace tr) is too
    flat to place a centre: det < (tr / 3)^3 / _FLAT_HALF."""
    return tr <= 0 or 27 * _FLAT_HALF * det < tr * tr * tr


def mixed_residual(n, ee, spread):
    """True when the fit's mean square residual ee / n (ee: the sum of the n samples'
    (|b|^2 - B^2)^2) is more than _MIXED_RESIDUAL times the noise's, sigma^2 =
    spread / (PI4_DEN (n - 1)^2)."""
    return ee * PI4_DEN * (n - 1) * (n - 1) > _MIXED_RESIDUAL * spread * n


def check_comparable(n, ee, spread):
    """too_few_samples when the halves cannot tell one hard iron from two (too few shared
    directions, or a change over the limit within the noise) and the fit's residual is beyond
    the noise (mixed_residual): wait for more samples, do not accept."""
    if mixed_residual(n, ee, spread):
        reject(REASON_TOO_FEW_SAMPLES, "%d samples: one hard iron or two? keep turning" % n)


def check_consistency(d2, den2, field, n, chi, noise, ee, spread):
    # inconsistent_samples when the hard-iron change between the halves, |c|^2 = d2 / den2 (in
    # the units of `field`, the fit's |B| in those units), is more than CONSISTENCY_PCT of B,
    # beyond the noise of the n samples (its chi-square chi / noise above _CHI2), and either
    # more than twice the fit's RMS residual, sqrt(ee / n) / (2 B) (a mix moves the fit's
    # centre by |c| / 2), or with a residual beyond the noise (mixed_residual; spread: its
    # sigma^2 times PI4_DEN (n - 1)^2).
    f2 = field * field * den2
    if d2 * 10000 <= CONSISTENCY_PCT * CONSISTENCY_PCT * f2:
        return
    if chi <= _CHI2 * noise:
        # within the noise: no verdict, as for halves that cannot be compared
        check_comparable(n, ee, spread)
        return
    if d2 * n * field * field <= ee * den2 and not mixed_residual(n, ee, spread):
        return  # |c| / 2 within the RMS residual, and that residual is the noise
    from firmware.fixedpoint import isqrt
    pct = isqrt(d2 * 100000000 // f2)  # hundredths of a percent
    reject(REASON_INCONSISTENT, "the older and newer halves of the %d samples put the hard "
           "iron %s of B apart where they saw the same directions (limit %d %%): the field "
           "changed while collecting (a magnet, a motor, a drifting offset)"
           % (n, _pct(pct), CONSISTENCY_PCT))


def check_output_field(field, field_out):
    """field_out_of_range unless the correction's output field (counts) is at least 1/8 of B
    and _MIN_FIELD_COUNTS, and at most 2 B: an InvW that scales the field away would switch
    the interference check off."""
    if field_out < _MIN_FIELD_COUNTS or field_out * _MAX_SCALE_DOWN < field or \
            field_out > 2 * field:
        reject(REASON_FIELD_OUT_OF_RANGE, "the output field %d counts is not within 1/%d .. 2 "
               "of B = %d counts: InvW would scale the field away"
               % (field_out, _MAX_SCALE_DOWN, field))


def check_calibration(cal, counts_per_gauss):
    """The plausibility gate (docs/design.md, module notes): CalibrationRejected(reason, detail) unless
    `cal` (a Calibration with a model) could be put in force on a sensor of
    counts_per_gauss (None: not known)."""
    if cal.model is None:
        return
    check_offset(cal.offset)
    f = cal.field
    fo = cal.field_out
    check_field(f, counts_per_gauss)
    check_output_field(f, fo)
    q = cal.invw
    if q[1] != q[3] or q[2] != q[6] or q[5] != q[7]:
        reject(REASON_SOFT_IRON_OUT_OF_RANGE, "InvW %r is not symmetric" % (tuple(q),))
    from firmware.calibrate import solve  # the gate's own: a board showing headings never loads it
    r = [None]
    for _ in solve.cond_steps(q, r):
        pass
    check_soft_iron(r[0], fo)
    det = solve.det3([q[0:3], q[3:6], q[6:9]])
    if det < 1 << _MIN_DET_SHIFT:
        reject(REASON_SOFT_IRON_OUT_OF_RANGE, "det(InvW) = %d (Q15^3) < 2**%d: InvW shrinks "
               "the field more than %d times" % (det, _MIN_DET_SHIFT, _MAX_SCALE_DOWN))
