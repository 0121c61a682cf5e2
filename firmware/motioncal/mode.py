"""MotionCal mode: the compass app streaming to PJRC MotionCal and taking its calibration."""
#     from firmware.motioncal.mode import MotionCalMode
#     mode = MotionCalMode(app)          # app: a firmware.app.CompassApp (built with learn=False)
#     mode.run()                         # Raw: lines at 50 Hz; Send Cal installs and stores the fit
#
# step() = the app's step, then _listen, _stream, _echo; it never raises (but a Ctrl-C).
# Options, what goes out, what a packet does and Ctrl-C: docs/design.md (module notes, mode);
# docs/motioncal.md for the user's side.
import sys
from array import array

from firmware.motioncal import protocol as mc
from firmware.axes import AxisMap, apply
from firmware.compat import const, ticks_diff, ticks_us
from firmware.errors import CalibrationRejected

STATUS_STREAMING = "streaming"
STATUS_APPLIED = "applied"
STATUS_REJECTED = "rejected"
STATUS_BAD_CRC = "bad_crc"
STATUS_TRUNCATED = "truncated"
REASON_NOT_A_CALIBRATION = "not_a_calibration"  # .last_reason: the record itself is refused

DEFAULT_RATE_HZ = const(50)
_MAX_RATE_HZ = const(400)          # MotionCal reads 256 bytes / 14 ms: ~400 Raw lines/s
_PACKET_TIMEOUT_US = const(250000)  # 68 bytes take ~6 ms at 115200 baud, < 1 ms on USB
_ECHO_EVERY_US = const(1000000)    # Cal1/Cal2 again every second (harmless, notes section 5)
_POLL_MAX = const(128)             # bytes taken per step: the loop stays bounded
# The record fields MotionCal does not send: the bounds its Send Cal rule guarantees
# (gui.cpp: gaps < 15, fit error < 5 %; magcal.c: 10 elements from 150 points).
MC_FIT_ERROR = const(500)          # hundredths of a percent
MC_SAMPLES = const(150)
MC_COVERAGE = const(86)            # % of 100 regions holding a point: gaps < 15
_CTRL_C = const(3)
_ENDL = b"\r\n"


def stdin_poll():
    """A poll() over the board's USB serial: the bytes waiting on sys.stdin.buffer (at most
    _POLL_MAX), b"" when none; select.poll with a 0 timeout, so it never blocks."""
    import select
    s = sys.stdin.buffer
    p = select.poll()
    p.register(s, select.POLLIN)

    def poll():
        out = b""
        while len(out) < _POLL_MAX and p.poll(0):
            c = s.read(1)
            if not c:
                break
            out += c
        return out
    return poll


def _stdout_write():
    out = getattr(sys.stdout, "buffer", sys.stdout)
    return out.write


def _to_chip(m, force=True):
    # the map body -> this sensor's chip axes: the inverse of the sensor -> body permutation
    # m, for a specific force (+1 g up) negated (AN4248's gravity sign is +1 g down), for a
    # rotation rate not
    inv = [0, 0, 0, 1, 1, 1]
    for i in range(3):
        inv[m[i]] = i
        inv[3 + m[i]] = (0 if m[3 + i] else 1) if force else m[3 + i]
    return bytes(inv)


class MotionCalMode:
    """See docs/design.md, module notes. Attributes: app, status, last_reason, last_detail, lines,
    applied, rejected, bad_crc, truncated, garbage (bytes skipped), cal_packet (the last
    applied packet)."""

    def __init__(self, app, write=None, poll=None, rate_hz=DEFAULT_RATE_HZ,
                 mag_axes="x,-y,-z", ticks_us=None, kbd_intr=None, viewer=False,
                 echo_every_us=_ECHO_EVERY_US):
        if type(rate_hz) is not int or not 1 <= rate_hz <= _MAX_RATE_HZ:
            raise ValueError("rate_hz=%r: expected an int in 1..%d (Raw lines per second)"
                             % (rate_hz, _MAX_RATE_HZ))
        self.app = app
        self.write = write if write is not None else _stdout_write()
        self.poll = poll if poll is not None else stdin_poll()
        self.period_us = 1000000 // rate_hz
        self.echo_every_us = echo_every_us
        self.viewer = viewer
        self._cpg = app.mag.counts_per_gauss
        self._cpg_acc = app.accel.counts_per_g if app.accel is not None else 0
        self._to_chip = _to_chip(AxisMap(mag_axes).m)
        self._gyro = None
        acc = app.accel
        if acc is not None and hasattr(acc, "gyro_into"):  # an MPU6050: its gyroscope too,
            g = acc.gyro_into  # read in the accelerometer's burst (use_gyro()'s array, or one
            if g is None:      # of its own)
                g = acc.gyro_into = array("h", (0, 0, 0))
            self._graw = g
            m = app._am  # the accelerometer's map negated: a rate keeps its sign
            self._gmap = bytes((m[0], m[1], m[2], 1 - m[3], 1 - m[4], 1 - m[5]))
            self._grate = _to_chip(AxisMap(mag_axes).m, False)
            self._gbody = array("h", (0, 0, 0))
            self._gyro = [0, 0, 0]
            self._cpd = acc.counts_per_dps_x10
        if ticks_us is None:
            self._ticks = _port_ticks()
            self._wrap = True
        else:
            self._ticks = ticks_us
            self._wrap = False
        self._kbd = kbd_intr
        self.reader = mc.PacketReader()
        self.line = bytearray(mc.RAW_LINE_MAX)
        self._mv = memoryview(self.line)
        self._mag = [0, 0, 0]
        self._acc = [0, 0, 0]
        self._acc_chip = [0, 0, 0]
        self._t_last = self._ticks()
        self._due_us = 0            # us until the next Raw line
        self._idle_us = 0           # us since the last byte while a packet is incomplete
        self._echo_us = 0
        self.echo_lines = None
        self.cal_packet = None
        self.status = STATUS_STREAMING
        self.last_reason = None
        self.last_detail = None
        self.lines = 0
        self.applied = 0
        self.rejected = 0
        self.bad_crc = 0
        self.truncated = 0
        self.garbage = 0
        self.steps = 0

    # --- lifecycle --------------------------------------------------------------------
    def start(self):
        """Listen: 0x03 in a packet must not raise KeyboardInterrupt (micropython.kbd_intr)."""
        if self._kbd is not None:
            self._kbd(-1)

    def stop(self):
        """Give Ctrl-C back to the REPL."""
        if self._kbd is not None:
            self._kbd(_CTRL_C)

    def run(self, n=None):
        """step() n times (None: until Ctrl-C); kbd_intr is restored whatever happens."""
        self.start()
        try:
            i = 0
            while n is None or i < n:
                self.step()
                i += 1
        finally:
            self.stop()

    # --- the loop ---------------------------------------------------------------------
    def step(self):
        """The app's step, then the serial line's work; True when the app made a heading."""
        ok = self.app.step()
        self.steps += 1
        dt = self._clock()
        self._listen(dt)
        self._stream(dt)
        if self.echo_lines is not None:
            self._echo(dt)
        return ok

    def _clock(self):
        now = self._ticks()
        dt = ticks_diff(now, self._t_last) if self._wrap else now - self._t_last
        self._t_last = now
        return dt if dt > 0 else 0

    def _listen(self, dt):
        data = self.poll()
        r = self.reader
        if not data:
            if r.n:
                self._idle_us += dt
                if self._idle_us >= _PACKET_TIMEOUT_US:
                    self._events(r.end())
            return
        self._idle_us = 0
        if self._interrupted(data):
            self.stop()
            raise KeyboardInterrupt
        ev = r.feed(data)
        if ev:
            self._events(ev)

    def _interrupted(self, data):
        # a 0x03 outside any packet: the user's Ctrl-C (docs/design.md, module notes)
        if self.reader.n:
            return False
        i = data.find(b"\x03")
        return i >= 0 and data.find(b"u", 0, i) < 0

    def _stream(self, dt):
        self._due_us -= dt
        if self._due_us > 0:
            return
        # steady rate: the next line is due one period after this one was due; a loop that
        # fell a whole period behind starts afresh
        self._due_us += self.period_us
        if self._due_us <= 0:
            self._due_us = self.period_us
        self._raw_line()
        if self.viewer:
            self._viewer_lines()

    def _raw_line(self):
        app = self.app
        mc.mag_01ut_into(app.raw, self._cpg, self._mag)
        if self._cpg_acc:
            apply(self._to_chip, app.gravity, self._acc_chip)
            mc.accel_8192_into(self._acc_chip, self._cpg_acc, self._acc)
        g = self._gyro
        if g is None:
            g = mc.GYRO_NONE
        else:  # the gyroscope in the magnetometer's chip axes, as the accelerometer
            apply(self._gmap, self._graw, self._gbody)
            apply(self._grate, self._gbody, self._gbody)
            mc.gyro_16_into(self._gbody, self._cpd, g)
        n = mc.raw_line_into(self.line, self._acc, g, self._mag)
        self.write(self._mv[:n])
        self.lines += 1

    def _viewer_lines(self):
        app = self.app
        h = app.heading_kang
        from firmware.trig import kang_to_cdeg
        self.write(mc.orientation_line(kang_to_cdeg(h) if h >= 0 else 0, 0, 0))
        cal = app.calibration
        self.write(mc.calibration_line(0, 0, 3 if app.accel is not None else 0,
                                       mc.mag_level(cal.model, cal.fit_error)))

    def _echo(self, dt):
        self._echo_us += dt
        if self._echo_us >= self.echo_every_us:
            self._echo_us = 0
            self.write(self.echo_lines[0])
            self.write(self.echo_lines[1])

    # --- packets ----------------------------------------------------------------------
    def _events(self, ev):
        for kind, value in ev:
            if kind == mc.PACKET:
                self.apply_packet(value)
            elif kind == mc.BAD_CRC:
                self.bad_crc += 1
                self._refused(STATUS_BAD_CRC, mc.REASON_BAD_CRC,
                              "a 68-byte packet whose CRC does not match")
            elif kind == mc.TRUNCATED:
                self.truncated += 1
                self._refused(STATUS_TRUNCATED, STATUS_TRUNCATED,
                              "%d of 68 bytes, then nothing for %d ms"
                              % (value, _PACKET_TIMEOUT_US // 1000))
            elif kind == mc.GARBAGE:
                self.garbage += value

    def apply_packet(self, packet):
        """Check a 68-byte packet and, when it passes, install, save and echo it.
        Returns the Calibration installed, or None (status and reason say why)."""
        try:
            cal = self._calibration(packet)
            lines = mc.echo(packet)
        except CalibrationRejected as e:
            self.rejected += 1
            self._refused(STATUS_REJECTED, e.reason, e.detail)
            return None
        except ValueError as e:  # a record Calibration refuses: refused, never a crash
            self.rejected += 1
            self._refused(STATUS_REJECTED, REASON_NOT_A_CALIBRATION, str(e))
            return None
        app = self.app
        stored = app.stored
        app.use_calibration(cal, collect=False)  # the user's choice stands (the module's opening comment)
        self.applied += 1
        self.cal_packet = bytes(packet)
        self.status = STATUS_APPLIED
        self.last_reason = None
        self.last_detail = None
        self.echo_lines = lines
        self._echo_us = 0
        self.write(("mcmode: applied: V (%d, %d, %d) counts, B %d counts, stored: %s"
                    % (cal.offset[0], cal.offset[1], cal.offset[2], cal.field,
                       "yes" if app.stored > stored else "no")).encode() + _ENDL)
        self.write(lines[0])
        self.write(lines[1])
        return cal

    def _calibration(self, packet):
        from firmware.calibration import Calibration
        from firmware.calibrate.acceptance import check_calibration
        f = mc.calibration_fields(packet, self._cpg)
        cal = Calibration(model=f["model"], offset=f["offset"], invw=f["invw"],
                          field=f["field"], field_out=f["field_out"],
                          fit_error=MC_FIT_ERROR, samples=MC_SAMPLES, coverage=MC_COVERAGE)
        check_calibration(cal, self._cpg)  # the board's own bar (firmware/calibrate/acceptance.py)
        return cal

    def _refused(self, status, reason, detail):
        self.status = status
        self.last_reason = reason
        self.last_detail = detail
        self.write(("mcmode: rejected %s: %s" % (reason, detail)).encode() + _ENDL)


def _port_ticks():
    if ticks_us is None:
        raise ValueError("ticks_us is needed off MicroPython (the simulator's clock)")
    return ticks_us
