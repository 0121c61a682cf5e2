"""PJRC MotionCal's serial protocol, board side, in integers."""
#     from firmware.motioncal import protocol as mc
#     out.write(mc.raw_line(acc_8192, mc.GYRO_NONE, mag_01ut))        # every sample
#     for kind, value in reader.feed(chunk):  # reader = mc.PacketReader(); chunk from stdin
#         if kind == mc.PACKET: fields = mc.calibration_fields(value, cpg); echo = mc.echo(value)
#
# The line and packet formats (MotionCal's serialdata.c, rawdata.c): docs/design.md (module
# notes, protocol). Floats are decoded from their bits into fixed point; the per-sample path
# (raw_line_into, the unit conversions) allocates nothing.
from firmware.compat import const
from firmware.errors import CalibrationRejected
from firmware.fixedpoint import bit_length, icbrt, rdiv, sat16

RAW_LINE_MAX = const(68)        # "Raw:" + 9 x "-32768" + 8 commas + CR LF
PACKET_SIZE = const(68)
_SIG0 = const(117)              # 'u'
_SIG1 = const(84)               # 'T'
_CRC_INIT = const(0xFFFF)       # CRC-16/MODBUS: reflected poly 0xA001, no final XOR
_CRC_POLY = const(0xA001)
ACCEL_PER_G = const(8192)       # MotionCal's G_PER_COUNT = 1/8192
GYRO_NONE = (0, 0, 0)           # no gyro: MotionCal only draws with it, the fit ignores it

# PacketReader events: (kind, value)
PACKET = "packet"               # value: the 68 bytes, signature and CRC checked
BAD_CRC = "bad_crc"             # value: the 68 bytes that failed (a false start, or damage)
TRUNCATED = "truncated"         # value: bytes of the packet held when end() was called
GARBAGE = "garbage"             # value: bytes skipped outside any packet since the last event

# float32 kinds (f32_kind)
F32_ZERO = "zero"
F32_NORMAL = "normal"
F32_DENORMAL = "denormal"       # decoded exactly: below 2**-126, 0 at any sensible scale
F32_INF = "inf"
F32_NAN = "nan"

# calibration_fields() refusals (CalibrationRejected.reason) of its own; the field, offset and
# soft-iron refusals are firmware/calibrate/acceptance.py's REASON_*
REASON_BAD_CRC = "bad_crc"
REASON_NOT_A_NUMBER = "not_a_number"
REASON_NOT_POSITIVE_DEFINITE = "not_positive_definite"

_INVW_FRAC_BITS = const(24)     # invW decoded in Q24: 2**-24 << one Q15 step
_Q16 = const(65536)             # V and B decoded in Q16 uT
_ECHO_SCALE = const(100000)     # echo at 1e-5: within MotionCal's 0.0001 tolerance
# packet byte offsets of the floats
_OFF_V = const(26)
_OFF_B = const(38)
_OFF_DIAG = const(42)
_OFF_OFFDIAG = const(54)


# ---- board -> MotionCal: Raw lines -------------------------------------------------------

def mag_01ut(counts, counts_per_gauss):
    """Magnetometer counts -> MotionCal's 0.1 uT (1 G = 100 uT), rounded half away from 0."""
    return rdiv(counts * 1000, counts_per_gauss)


def accel_8192(counts, counts_per_g):
    """Accelerometer counts -> MotionCal's 1/8192 g, rounded half away from zero."""
    return rdiv(counts * ACCEL_PER_G, counts_per_g)


def mag_01ut_into(raw, counts_per_gauss, out):
    """out[0:3] = mag_01ut of raw[0:3]; allocates nothing."""
    out[0] = rdiv(raw[0] * 1000, counts_per_gauss)
    out[1] = rdiv(raw[1] * 1000, counts_per_gauss)
    out[2] = rdiv(raw[2] * 1000, counts_per_gauss)


def accel_8192_into(raw, counts_per_g, out):
    """out[0:3] = accel_8192 of raw[0:3]; allocates nothing."""
    out[0] = rdiv(raw[0] * ACCEL_PER_G, counts_per_g)
    out[1] = rdiv(raw[1] * ACCEL_PER_G, counts_per_g)
    out[2] = rdiv(raw[2] * ACCEL_PER_G, counts_per_g)


def gyro_16_into(raw, counts_per_dps_x10, out):
    """out[0:3] = raw[0:3] gyroscope counts in 1/16 deg/s (MotionCal's DEG_PER_SEC_PER_COUNT),
    counts_per_dps_x10 the MPU6050's 10 x counts per deg/s (1310 .. 164); allocates nothing."""
    out[0] = rdiv(raw[0] * 160, counts_per_dps_x10)
    out[1] = rdiv(raw[1] * 160, counts_per_dps_x10)
    out[2] = rdiv(raw[2] * 160, counts_per_dps_x10)


def _put_int(buf, n, v):
    # decimal digits of sat16(v) at buf[n:], returns the new end
    v = sat16(v)
    if v < 0:
        buf[n] = 45  # '-'
        n += 1
        v = -v
    d = 10000
    while d > v and d > 1:
        d //= 10
    while d:
        buf[n] = 48 + v // d
        v %= d
        d //= 10
        n += 1
    return n


def _put3(buf, n, v):
    n = _put_int(buf, n, v[0])
    buf[n] = 44  # ','
    n = _put_int(buf, n + 1, v[1])
    buf[n] = 44
    return _put_int(buf, n + 1, v[2])


def raw_line_into(buf, acc, gyro, mag_01ut):
    """Write `Raw:ax,ay,az,gx,gy,gz,mx,my,mz\\r\\n` into buf (>= RAW_LINE_MAX bytes), each value
    clamped to int16 (MotionCal would wrap it); returns the length. Allocates nothing.
    acc in 1/8192 g, gyro in 1/16 deg/s (GYRO_NONE without one), mag in 0.1 uT."""
    buf[0] = 82  # 'R'
    buf[1] = 97  # 'a'
    buf[2] = 119  # 'w'
    buf[3] = 58  # ':'
    n = _put3(buf, 4, acc)
    buf[n] = 44
    n = _put3(buf, n + 1, gyro)
    buf[n] = 44
    n = _put3(buf, n + 1, mag_01ut)
    buf[n] = 13  # CR ends the record for MotionCal; LF only for terminals
    buf[n + 1] = 10
    return n + 2


def raw_line(acc, gyro, mag_01ut, buf=None):
    """The Raw line as bytes; with buf (a bytearray(RAW_LINE_MAX) to reuse) a memoryview of
    it instead (one small object; raw_line_into allocates nothing)."""
    if buf is None:
        b = bytearray(RAW_LINE_MAX)
        return bytes(b[:raw_line_into(b, acc, gyro, mag_01ut)])
    return memoryview(buf)[:raw_line_into(buf, acc, gyro, mag_01ut)]


# ---- MotionCal -> board: the packet --------------------------------------------------------

def crc16(data, n):
    """CRC-16/MODBUS of data[0:n] (MotionCal's crc16(): init 0xFFFF, reflected 0xA001)."""
    crc = _CRC_INIT
    for i in range(n):
        crc ^= data[i]
        for _ in range(8):
            crc = (crc >> 1) ^ _CRC_POLY if crc & 1 else crc >> 1
    return crc


def packet_ok(data):
    """True for 68 bytes with the signature and a matching CRC (low byte first at 66)."""
    return (len(data) == PACKET_SIZE and data[0] == _SIG0 and data[1] == _SIG1
            and crc16(data, 66) == data[66] | (data[67] << 8))


class PacketReader:
    """Finds MotionCal's packets in a byte stream, fed in pieces of any size, never blocking."""
    #     r = PacketReader()
    #     for kind, value in r.feed(data):   # () when nothing happened (no allocation)
    #         ...                            # PACKET, BAD_CRC, TRUNCATED or GARBAGE events
    #     r.end()                            # the caller's timeout: a partial packet -> TRUNCATED
    #
    # A candidate starts at 117, 84 and runs 68 bytes. When its CRC fails the candidate may
    # have been a false start (the signature is two ordinary bytes, also inside floats), so
    # the search resumes at the next 117, 84 inside it: a packet behind a false start is
    # still found. Totals: .packets, .bad_crc, .truncated, .skipped (bytes).

    def __init__(self):
        self.buf = bytearray(PACKET_SIZE)
        self.n = 0             # bytes of the current candidate
        self.pending = 0       # garbage bytes not yet reported
        self.packets = 0
        self.bad_crc = 0
        self.truncated = 0
        self.skipped = 0

    def _skip(self, k):
        self.pending += k
        self.skipped += k

    def _flush(self, ev):
        if self.pending:
            ev.append((GARBAGE, self.pending))
            self.pending = 0

    def feed(self, data):
        """Take the bytes that arrived; returns a list of (kind, value) events, or ().
        One small step per byte, so no frame leaves the C stack: garbage and a partial
        packet allocate nothing."""
        self._ev = None
        i = 0
        k = len(data)
        while i < k:
            self._byte(data[i])
            i += 1
        return self._ev if self._ev else ()

    def _byte(self, b):
        n = self.n
        if n >= 2:
            self.buf[n] = b
            n += 1
            if n == PACKET_SIZE:
                if self._ev is None:
                    self._ev = []
                n = self._complete(self._ev)
        elif n == 0:
            if b == _SIG0:
                self.buf[0] = b
                n = 1
            else:
                self._skip(1)
        elif b == _SIG1:
            self.buf[1] = b
            n = 2
        elif b == _SIG0:
            self._skip(1)  # the earlier 117 was garbage; this one may start a packet
        else:
            self._skip(2)
            n = 0
        self.n = n

    def _complete(self, ev):
        # a full candidate in buf: report it; returns how many bytes stay held
        buf = self.buf
        self._flush(ev)
        if crc16(buf, 66) == buf[66] | (buf[67] << 8):
            self.packets += 1
            ev.append((PACKET, bytes(buf)))
            return 0
        self.bad_crc += 1
        ev.append((BAD_CRC, bytes(buf)))
        for i in range(1, PACKET_SIZE):  # resume at the next signature inside the candidate
            if buf[i] == _SIG0 and (i == PACKET_SIZE - 1 or buf[i + 1] == _SIG1):
                k = PACKET_SIZE - i
                for j in range(k):
                    buf[j] = buf[i + j]
                return k
        return 0

    def end(self):
        """The stream ended or timed out: report a partial packet and any garbage; reset."""
        ev = []
        if self.n == 1:
            self._skip(1)
        self._flush(ev)
        if self.n >= 2:
            self.truncated += 1
            ev.append((TRUNCATED, self.n))
        self.n = 0
        return ev


# ---- float32 bits -> fixed point, in integers ---------------------------------------------

def f32_kind(bits):
    """F32_ZERO, F32_NORMAL, F32_DENORMAL, F32_INF or F32_NAN for IEEE-754 binary32 bits."""
    e = (bits >> 23) & 0xFF
    f = bits & 0x7FFFFF
    if e == 0xFF:
        return F32_NAN if f else F32_INF
    if e == 0:
        return F32_DENORMAL if f else F32_ZERO
    return F32_NORMAL


def f32_fixed(bits, scale):
    """round(value * scale) of the binary32 `bits` (scale: a positive int, e.g. 1 << 16 or
    10 ** 4), halves away from zero, exact: value = +-m 2**(e - 150) from the IEEE-754
    fields (m with its implicit bit; a denormal has e = 1 and none). Raises ValueError for
    an infinity or a NaN."""
    e = (bits >> 23) & 0xFF
    m = bits & 0x7FFFFF
    if e == 0xFF:
        raise ValueError("float32 0x%08x is %s: no fixed-point value"
                         % (bits, F32_NAN if m else F32_INF))
    if e:
        m |= 0x800000
        e -= 150
    else:
        e = -149  # denormal: no implicit bit
    n = m * scale
    if e >= 0:
        n <<= e
    else:
        k = -e
        if bit_length(n) < k:  # below one half
            n = 0
        else:
            n = (n + (1 << (k - 1))) >> k
    return -n if bits >> 31 else n


def f32_bits_at(data, offset):
    """The little-endian float32 at data[offset:offset + 4], as an unsigned int."""
    return (data[offset] | (data[offset + 1] << 8) | (data[offset + 2] << 16)
            | (data[offset + 3] << 24))


def _fixed_at(data, offset, scale, name):
    bits = f32_bits_at(data, offset)
    k = f32_kind(bits)
    if k == F32_NAN or k == F32_INF:
        raise CalibrationRejected(REASON_NOT_A_NUMBER, "%s is %s (float32 0x%08x)"
                                  % (name, k, bits))
    return f32_fixed(bits, scale)


_NAMES = ("accel offset x", "accel offset y", "accel offset z", "gyro offset x",
          "gyro offset y", "gyro offset z", "V x", "V y", "V z", "B", "invW 00", "invW 11",
          "invW 22", "invW 01", "invW 02", "invW 12")


def packet_values(packet, scale):
    """The 16 floats of a packet, each round(value * scale), in packet order; raises
    CalibrationRejected(not_a_number) naming the first NaN or infinity."""
    return [_fixed_at(packet, 2 + 4 * i, scale, _NAMES[i]) for i in range(16)]


# ---- the packet -> our Calibration's fields -------------------------------------------------

def _reject(reason, detail):
    raise CalibrationRejected(reason, detail)


def _run(steps, out):
    # a solver generator (firmware/calibrate/solve.py) run to completion; it leaves its result in out[0]
    for _ in steps:
        pass
    return out[0]


def calibration_fields(packet, counts_per_gauss):
    # Our calibration from MotionCal's packet, for a sensor of `counts_per_gauss`:
    # a dict for firmware.calibration.Calibration(**fields): model 10, offset V (counts, int16), invw (9 Q15
    # ints, row-major, each row's absolute sum <= 32767), field B (counts) and field_out
    # (|InvW (raw - V)| >> 15 on the calibrated sphere, counts).
    #
    # MotionCal's model is Bc = invW (raw 0.1 uT - V) with |Bc| = B (uT); in counts
    # (x uT = x cpg / 100 counts) the same invW maps raw - V to a sphere of B cpg / 100
    # counts. InvW = s invW in Q15 with s from the row sums (solve.q15_steps), so
    # field_out = s B = B cbrt(det(InvW / 2**15) / det(invW)) counts.
    #
    # Raises CalibrationRejected with .reason bad_crc, not_a_number, not_positive_definite,
    # soft_iron_out_of_range, field_out_of_range or offset_out_of_range, checked in that
    # order. The accel and gyro offsets (always 0 from MotionCal) are not used.
    from firmware.calibrate import acceptance  # loaded only when a packet arrives
    from firmware.calibrate import solve

    cpg = counts_per_gauss
    if not isinstance(cpg, int) or cpg <= 0:
        raise ValueError("counts_per_gauss %r: expected a positive int (counts/G)" % (cpg,))
    if not packet_ok(packet):
        _reject(REASON_BAD_CRC, "not a 68-byte packet with signature 117, 84 and its CRC")
    v = [_fixed_at(packet, _OFF_V + 4 * i, _Q16, _NAMES[6 + i]) for i in range(3)]
    b_q16 = _fixed_at(packet, _OFF_B, _Q16, "B")
    d = [_fixed_at(packet, _OFF_DIAG + 4 * i, 1 << _INVW_FRAC_BITS, _NAMES[10 + i])
         for i in range(3)]
    o = [_fixed_at(packet, _OFF_OFFDIAG + 4 * i, 1 << _INVW_FRAC_BITS, _NAMES[13 + i])
         for i in range(3)]
    # rebuild the symmetric invW from its 6 entries (packet: diagonal, then 01 02 12)
    w = [[d[0], o[0], o[1]], [o[0], d[1], o[2]], [o[1], o[2], d[2]]]
    # Sylvester's criterion: every leading principal minor > 0
    dw = solve.det3(w)
    if d[0] <= 0 or d[0] * d[1] - o[0] * o[0] <= 0 or dw <= 0:
        _reject(REASON_NOT_POSITIVE_DEFINITE, "invW (Q%d) %r is not positive definite"
                % (_INVW_FRAC_BITS, w))
    r = [None]
    invw = _run(solve.q15_steps(w, _INVW_FRAC_BITS, r), r)
    cond = _run(solve.cond_steps(invw, r), r)
    if cond is None:
        _reject(REASON_NOT_POSITIVE_DEFINITE, "invW %r in Q15 is not positive definite"
                % (invw,))
    # the calibrator's own limits (firmware/calibrate/acceptance.py): W^-1 within 5:1, B 10..90 uT
    acceptance.check_soft_iron(cond, 1)
    bc_q16 = rdiv(b_q16 * cpg, 100)  # B in Q16 counts
    acceptance.check_field(bc_q16, cpg, _Q16)  # in Q16 counts: no rounding at the limits
    offset = [rdiv(v[i] * cpg, 100 * _Q16) for i in range(3)]
    acceptance.check_offset(offset)
    dq = solve.det3([invw[0:3], invw[3:6], invw[6:9]])
    # field_out in Q17 = cbrt(bc_q16**3 * 8 * dq 2**-45 / (dw 2**-72)), then rounded
    r = icbrt((bc_q16 ** 3 * dq << (3 + 3 * _INVW_FRAC_BITS - 45)) // dw)
    field = rdiv(bc_q16, _Q16)
    field_out = (r + (1 << 16)) >> 17
    # a huge invW is scaled down to Q15: its output field would be ~0, the check off
    acceptance.check_output_field(field, field_out)
    return {"model": 10, "offset": tuple(offset), "invw": invw,
            "field": field, "field_out": field_out}


# ---- board -> MotionCal: the Cal1/Cal2 echo ---------------------------------------------------

def _num_e5(v):
    # 1e-5 fixed point -> "-12.34567": MotionCal's number form (a '.', no exponent, no '+')
    s = "-" if v < 0 else ""
    v = -v if v < 0 else v
    return "%s%d.%05d" % (s, v // _ECHO_SCALE, v % _ECHO_SCALE)


def cal_echo(v_e5, b_e5, invw_e5, offsets_e5=(0, 0, 0, 0, 0, 0)):
    """(Cal1 line, Cal2 line) as bytes, CR LF ended, every value in 1e-5 units:
    Cal1: accel x3, gyro x3 (offsets_e5), V x3 (uT), B (uT); Cal2: invW, 9 row-major."""
    c1 = ",".join([_num_e5(x) for x in tuple(offsets_e5) + tuple(v_e5) + (b_e5,)])
    c2 = ",".join([_num_e5(x) for x in invw_e5])
    return (("Cal1:%s\r\n" % c1).encode(), ("Cal2:%s\r\n" % c2).encode())


def echo(packet):
    """cal_echo of a packet's values as received (decoded to 1e-5 from the float bits), so
    that MotionCal confirms; raises CalibrationRejected(not_a_number) for a NaN/infinity."""
    x = packet_values(packet, _ECHO_SCALE)
    d0, d1, d2, o01, o02, o12 = x[10:16]
    return cal_echo(x[6:9], x[9], (d0, o01, o02, o01, d1, o12, o02, o12, d2), x[0:6])


# ---- Adafruit's WebSerial 3D model viewer ------------------------------------------------
# Its read loop (adafruit/Adafruit_WebSerial_3DModelViewer, js/script.js) splits the stream at
# LF, trims each line and reads "Orientation:" (heading, pitch, roll in degrees, used in its
# Euler mode), "Quaternion:" and "Calibration:" (system, gyro, accelerometer, magnetometer,
# each 0 uncalibrated .. 3 fully calibrated; any other value breaks its display). MotionCal
# skips both lines without a failure (neither is "Raw:", "Cal1:" or "Cal2:").

def _cdeg(v):
    s = "-" if v < 0 else ""
    v = -v if v < 0 else v
    return "%s%d.%02d" % (s, v // 100, v % 100)


def orientation_line(heading_cdeg, pitch_cdeg, roll_cdeg):
    """`Orientation: h,p,r` CR LF, angles in centidegrees (trig.kang_to_cdeg)."""
    return ("Orientation: %s,%s,%s\r\n" % (_cdeg(heading_cdeg), _cdeg(pitch_cdeg),
                                           _cdeg(roll_cdeg))).encode()


def mag_level(model, fit_error):
    """The viewer's magnetometer level for a calibration: 0 none, 1 min/max or 4 elements,
    2 a 7/10-element fit above 5 % fit error (hundredths), 3 a 10-element fit at or below
    5 % (MotionCal's own Send Cal limit)."""
    if model is None:
        return 0
    if model == 10 and fit_error <= 500:
        return 3
    return 2 if model in (7, 10) else 1


def calibration_line(system, gyro, accel, mag):
    """`Calibration: s,g,a,m` CR LF, each level clamped to 0..3."""
    v = [x if 0 <= x <= 3 else (0 if x < 0 else 3) for x in (system, gyro, accel, mag)]
    return ("Calibration: %d,%d,%d,%d\r\n" % (v[0], v[1], v[2], v[3])).encode()
