"""The calibration record: hard iron V, inverse soft iron InvW in Q15, field B; applied with
`>> 15` and serialised for the store.
"""
#     from firmware.calibration import Calibration, UNCALIBRATED
#     cal = Calibration(model=10, offset=(120, -80, 35), invw=invw_q15, field=5800, field_out=5790)
#     cal.correct(raw, out)             # out = InvW (raw - V) >> 15: allocation-free, small ints
#     Calibration.from_bytes(cal.to_bytes()) == cal
#
# The fields and their units: docs/api.md (calibration). Why correct() stays within small ints
# and allocates nothing: docs/design.md (module notes, calibration).
import struct
from array import array

from firmware.compat import const
from firmware.fixedpoint import rdiv

MINMAX = "minmax"
MODELS = (MINMAX, 4, 7, 10)
ORDER = {None: -1, MINMAX: 0, 4: 4, 7: 7, 10: 10}  # which model is "higher"

_IDENTITY_Q15 = (32767, 0, 0, 0, 32767, 0, 0, 0, 32767)
_MODEL_CODE = {None: 0, MINMAX: 1, 4: 4, 7: 7, 10: 10}
_CODE_MODEL = {0: None, 1: MINMAX, 4: 4, 7: 7, 10: 10}
_PAYLOAD_VERSION = const(1)
_PAYLOAD = "<BBBBHH3i9hii"  # version, model, coverage, dip, fit_error, samples, V, InvW, B, B_out
_DIP_UNKNOWN = const(0)     # the dip byte: 0 not known, else whole degrees + 128 (38..218)
_DIP_BIAS = const(128)
PAYLOAD_SIZE = const(46)
# a fit good enough to need no more collecting, in hundredths of a percent: a session and the
# calibration program end with one, boot needs one to skip the program (MotionCal's "good")
GOOD_FIT_ERROR = const(500)
STALE_AGE_S = const(1200000)  # seconds of age that make any fit error "worse" (> 16 doublings)


def correct(k, raw, out):
    """out[0:3] = InvW sat16(raw - V) >> 15, rounded; k = InvW (0..8) then V (9..11).
    The clamp is fixedpoint.sat16 written out: three calls would cost more than the rest."""
    x = raw[0] - k[9]
    x = 32767 if x > 32767 else -32768 if x < -32768 else x
    y = raw[1] - k[10]
    y = 32767 if y > 32767 else -32768 if y < -32768 else y
    z = raw[2] - k[11]
    z = 32767 if z > 32767 else -32768 if z < -32768 else z
    out[0] = (k[0] * x + k[1] * y + k[2] * z + 16384) >> 15
    out[1] = (k[3] * x + k[4] * y + k[5] * z + 16384) >> 15
    out[2] = (k[6] * x + k[7] * y + k[8] * z + 16384) >> 15


class Calibration:
    """One calibration: V (offset, counts), InvW (9 Q15 ints, row-major), B (field, counts)."""
    # correct(raw, out) writes InvW * sat16(raw - V) >> 15 (rounded) into out[0:3]; its
    # magnitude on the calibrated sphere is .field_out counts (= .field scaled by the Q15
    # normalisation of InvW). .fit_error: hundredths of a percent. .model: None
    # (uncalibrated identity), 'minmax', 4, 7 or 10. .samples, .coverage (%) at solve time.

    def __init__(self, model=None, offset=(0, 0, 0), invw=_IDENTITY_Q15, field=0, field_out=0,
                 fit_error=0, samples=0, coverage=0, dip_kang=None):
        if model not in _MODEL_CODE:
            raise ValueError("unknown calibration model %r" % (model,))
        if len(offset) != 3 or len(invw) != 9:
            raise ValueError("offset needs 3 ints and invw 9, got %d and %d"
                             % (len(offset), len(invw)))
        for v in tuple(offset) + tuple(invw):
            if not isinstance(v, int) or not -32768 <= v <= 32767:
                raise ValueError("offset and invw take int16 ints, got %r" % (v,))
        for i in range(3):
            t = abs(invw[3 * i]) + abs(invw[3 * i + 1]) + abs(invw[3 * i + 2])
            if t > 32767:  # the small-int bound of correct() rests on this
                raise ValueError("invw row %d absolute sum %d > 32767" % (i, t))
        for name, v, lo, hi in (("field", field, 0, 0x3FFFFFFF), ("field_out", field_out, 0,
                                0x3FFFFFFF), ("fit_error", fit_error, 0, 0x3FFFFFFF),
                                ("samples", samples, 0, 0x3FFFFFFF), ("coverage", coverage, 0, 100)):
            if not isinstance(v, int) or not lo <= v <= hi:
                raise ValueError("calibration %s=%r: expected an int in %d..%d" % (name, v, lo, hi))
        if dip_kang is not None and (type(dip_kang) is not int or not -16384 <= dip_kang <= 16384):
            raise ValueError("calibration dip_kang=%r: expected None or an int in -16384..16384 "
                             "(KANG, +-90 deg)" % (dip_kang,))
        if model is not None and (field == 0 or field_out == 0):
            raise ValueError("calibration model %s with field %d, field_out %d counts: a fitted "
                             "field is never 0" % (model, field, field_out))
        self.model = model
        self.offset = (offset[0], offset[1], offset[2])
        self.invw = tuple(invw)
        self.k = array("h", self.invw + self.offset)  # correct()'s argument: InvW 0..8, V 9..11
        self.field = field
        self.field_out = field_out
        self.fit_error = fit_error
        self.samples = samples
        self.coverage = coverage
        self.dip_kang = dip_kang

    def correct(self, raw, out):
        """out[0:3] = InvW sat16(raw - V) >> 15, rounded (AN4246 section 3); see correct()."""
        correct(self.k, raw, out)

    def good_for(self, model):
        """No collecting needed for `model` (10, 7, 4, "minmax"; "auto": any but "minmax"):
        its fit, within GOOD_FIT_ERROR."""
        return (self.model is not None and self.fit_error <= GOOD_FIT_ERROR
                and (self.model == model or model == "auto" and self.model != "minmax"))

    def with_dip(self, dip_kang):
        """The same fit with the dip it measures (KANG, or None)."""
        return Calibration(self.model, self.offset, self.invw, self.field, self.field_out,
                           self.fit_error, self.samples, self.coverage, dip_kang)

    def to_bytes(self):
        """The 46-byte little-endian payload (storage adds its own header and CRC)."""
        fe = self.fit_error if self.fit_error < 65535 else 65535
        n = self.samples if self.samples < 65535 else 65535
        d = self.dip_kang
        d = _DIP_UNKNOWN if d is None else rdiv(d * 45, 8192) + _DIP_BIAS  # KANG -> deg
        return struct.pack(_PAYLOAD, _PAYLOAD_VERSION, _MODEL_CODE[self.model], self.coverage,
                           d, fe, n, self.offset[0], self.offset[1], self.offset[2],
                           *(self.invw + (self.field, self.field_out)))

    @classmethod
    def from_bytes(cls, b):
        """Inverse of to_bytes; raises ValueError naming what is wrong."""
        if len(b) != PAYLOAD_SIZE:
            raise ValueError("calibration payload is %d bytes, expected %d"
                             % (len(b), PAYLOAD_SIZE))
        f = struct.unpack(_PAYLOAD, b)
        if f[0] != _PAYLOAD_VERSION:
            raise ValueError("calibration payload version %d, expected %d"
                             % (f[0], _PAYLOAD_VERSION))
        if f[1] not in _CODE_MODEL:
            raise ValueError("calibration payload model code %d unknown" % f[1])
        d = f[3]
        if d != _DIP_UNKNOWN:
            d -= _DIP_BIAS
            if not -90 <= d <= 90:
                raise ValueError("calibration payload dip byte %d: expected 0 or 38..218"
                                 % f[3])
            d = rdiv(d * 8192, 45)  # whole degrees -> KANG (65536 / 360 = 8192 / 45)
        else:
            d = None
        return cls(model=_CODE_MODEL[f[1]], offset=f[6:9], invw=f[9:18], field=f[18],
                   field_out=f[19], fit_error=f[4], samples=f[5], coverage=f[2], dip_kang=d)

    def __eq__(self, other):
        # the same fit: the payload but its dip byte (an observation of the place)
        if not isinstance(other, Calibration):
            return False
        a = self.to_bytes()
        b = other.to_bytes()
        return a[:3] == b[:3] and a[4:] == b[4:]

    def __repr__(self):
        return ("Calibration(model=%r, offset=%r, invw=%r, field=%d, field_out=%d, "
                "fit_error=%d, samples=%d, coverage=%d%s)" % (
                    self.model, self.offset, self.invw, self.field, self.field_out,
                    self.fit_error, self.samples, self.coverage,
                    "" if self.dip_kang is None else ", dip_kang=%d" % self.dip_kang))


UNCALIBRATED = Calibration()
