"""The per-sample path with viper kernels: the same bits as the plain firmware, faster.

    from firmware.fast import Pipeline
    pipe = Pipeline(cal, "x,-y,-z", "-x,y,z", field=cal.field_out)
    h = pipe.update(raw, araw, b, g)    # raw mag, raw accel -> body b, g; heading KANG or -1
    pipe.compass.flags, pipe.compass.pitch_kang ...   # a heading.Compass, updated in place

Pipeline(cal, mag_axes, accel_axes=None, compass=None, **compass_options) does, in one call,
    cal.correct(raw, b); AxisMap(mag_axes).apply(b, b); AxisMap(accel_axes).apply(araw, g)
    return compass.update(b, g)          # accel_axes None: compass.update(b), araw/g unused
set_calibration(cal) swaps the calibration (e.g. one the Calibrator just accepted), and its
pieces exist alone: Corrector(cal).correct(raw, out), FastAxisMap(spec).apply(src,
dst) (an AxisMap), FastCompass(...).update(b, g=None) (a Compass).

On MicroPython with the native emitter (the unix port, RP2040, ESP32) these run as
@micropython.viper kernels (firmware/_fastv.py); elsewhere (CPython, a port built without the
emitter) they ARE the plain methods. Either way the outputs, the return value and the public
attributes are those of the plain firmware for int16 inputs (tests/test_fast.py compares them
on MicroPython). FastCompass keeps only the public attributes current, not Compass's private
scratch. VIPER says which implementation is in use. Nothing allocates per sample.
Why: on the MicroPython unix port correct + axes + heading cost ~4x seed 004's float
offset/scale + atan2 heading as bytecode, ~0.7x as these kernels (make bench, README
"Benchmarks").
"""
from array import array

from firmware.axes import AxisMap
from firmware.heading import Compass

try:
    from firmware import _fastv
    VIPER = True
except (ImportError, SyntaxError, ValueError):  # CPython; no emitter; .mpy of another arch
    _fastv = None
    VIPER = False


def _map_bytes(m):
    return [m.axis[0], m.axis[1], m.axis[2],
            1 if m.sign[0] < 0 else 0, 1 if m.sign[1] < 0 else 0, 1 if m.sign[2] < 0 else 0]


def _invw_v(cal):
    return array("h", tuple(cal.invw) + tuple(cal.offset))  # InvW 0..8, then V 9..11


class Corrector:
    """Calibration.correct(raw, out) of `cal` (make a new one when the calibration changes)."""

    def __init__(self, cal):
        self.cal = cal
        self._k = _invw_v(cal)
        if not VIPER:
            self.correct = cal.correct

    def correct(self, raw, out):
        _fastv.correct(self._k, raw, out)


class FastAxisMap(AxisMap):
    """An AxisMap whose apply() is the viper kernel."""

    def __init__(self, spec):
        super().__init__(spec)
        self._m = array("b", _map_bytes(self))

    if VIPER:
        def apply(self, src, dst):
            _fastv.apply(self._m, src, dst)


class FastCompass(Compass):
    """A Compass whose update() is the viper kernel."""

    if VIPER:
        def update(self, b, g=None):
            if g is None:
                return _fastv.heading(self, b, b, 1)
            return _fastv.heading(self, b, g, 0)


class Pipeline(_fastv.PipelineKernel if VIPER else object):
    """correct -> axes -> heading for one sample in one call (see the module docstring)."""

    def __init__(self, cal, mag_axes, accel_axes=None, compass=None, **compass_options):
        self.cal = cal
        self.mag_map = AxisMap(mag_axes)
        self.accel_map = AxisMap(accel_axes) if accel_axes is not None else None
        self.compass = compass if compass is not None else FastCompass(**compass_options)
        self._k = _invw_v(cal)
        self._mm = array("b", _map_bytes(self.mag_map))
        self._am = array("b", _map_bytes(self.accel_map or self.mag_map))
        self._level = 1 if self.accel_map is None else 0

    def set_calibration(self, cal):
        """Use another Calibration from the next update() on (e.g. one just accepted)."""
        self.cal = cal
        self._k = _invw_v(cal)

    if not VIPER:
        def update(self, raw, araw, b, g):
            """Heading in KANG (or -1, see Compass.update); b and g receive the body-frame
            field and gravity (g untouched without an accelerometer)."""
            self.cal.correct(raw, b)
            self.mag_map.apply(b, b)
            if self._level:
                return self.compass.update(b)
            self.accel_map.apply(araw, g)
            return self.compass.update(b, g)
