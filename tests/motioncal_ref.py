"""Host-side re-implementation of what PJRC MotionCal does with the board's serial stream, for
tests only (floats allowed): written from MotionCal's behaviour as its source implements it
(serialdata.c ascii_parse(), rawdata.c send_calibration() / crc16() / cal1_data() /
cal2_data() / is_float_ok()), independently of firmware/motioncal/protocol.py.

    p = MotionCal()
    p.send(build_packet(V, B, invw))     # what Send Cal writes; arms the confirmation
    p.read(board_bytes)                  # in reads of at most 256 bytes, like read_serial_data()
    p.raw      -> accepted Raw records (9 int16 each)
    p.confirmed -> True once a matching Cal1 and Cal2 arrived after the send
"""
import struct

READ_SIZE = 256  # read_serial_data(): at most 256 bytes per read()


def f32(x):
    """x rounded to float32 (float32 arithmetic: each +, -, *, / in double then rounded
    once is correctly rounded, double having more than 2 x 24 + 2 bits)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _int32(n):
    return (n + 2 ** 31) % 2 ** 32 - 2 ** 31


def _int16(n):
    return (n + 2 ** 15) % 2 ** 16 - 2 ** 15


def _crc_table():
    # table of the reflected polynomial 0xA001, one entry per byte value
    t = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0xA001 if c & 1 else c >> 1
        t.append(c)
    return t


_TABLE = _crc_table()


def crc16_modbus(data):
    crc = 0xFFFF
    for b in data:
        crc = (crc >> 8) ^ _TABLE[(crc ^ b) & 0xFF]
    return crc


def symmetric(invw):
    """The 6 packet entries (d0, d1, d2, o01, o02, o12) from a 3x3 or a 6-sequence."""
    if len(invw) == 3:
        return (invw[0][0], invw[1][1], invw[2][2], invw[0][1], invw[0][2], invw[1][2])
    return tuple(invw)


def build_packet(V, B, invw, accel=(0.0, 0.0, 0.0), gyro=(0.0, 0.0, 0.0)):
    """The 68 bytes send_calibration() writes: 117, 84, 16 float32 LE, CRC-16/MODBUS LE."""
    body = struct.pack("<BB16f", 117, 84, *(tuple(accel) + tuple(gyro) + tuple(V) + (B,)
                                            + symmetric(invw)))
    return body + struct.pack("<H", crc16_modbus(body))


def sent_values(packet):
    """cal_data_sent[0..18] for a packet: Cal1's 10 values, then invW row-major (float32)."""
    f = struct.unpack_from("<16f", packet, 2)
    d0, d1, d2, o01, o02, o12 = f[10:16]
    return list(f[0:10]) + [d0, o01, o02, o01, d1, o12, o02, o12, d2]


def is_float_ok(actual, expected):
    err = f32(abs(f32(actual - expected)))
    maxerr = f32(f32(0.0001) + f32(abs(expected) * f32(0.00003)))
    return err <= maxerr


_WORD, _RAW, _CAL1, _CAL2 = 0, 1, 2, 3


class MotionCal:
    """ascii_parse()'s state machine with its static state, and the Cal confirmation."""

    def __init__(self):
        self.state = _WORD
        self.num = 0
        self.neg = False
        self.count = 0
        self.nvals = 0
        self.raw_vals = [0] * 9
        self.cal_vals = [0.0] * 10  # static: a number without '.' adds to the old slot
        self.raw = []
        self.cal1 = []
        self.cal2 = []
        self.failures = 0
        self.sent = None
        self.confirm_needed = 0
        self.confirmed = False

    def send(self, packet):
        self.sent = sent_values(packet)
        self.confirm_needed = 3
        self.confirmed = False

    def read(self, data, size=READ_SIZE):
        """The stream as read_serial_data() delivers it: consecutive reads of `size` bytes."""
        for i in range(0, len(data), size):
            self.parse(data[i:i + size])

    def _reset(self):
        self.state = _WORD
        self.nvals = 0
        self.num = 0
        self.neg = False
        self.count = 0

    def parse(self, chunk):
        for c in bytes(chunk):
            if not self._char(chr(c)):
                self.failures += 1
                self._reset()
                return  # a failure drops the rest of this read

    def _word(self, ch):
        # looks for "Raw:", "Cal1:", "Cal2:"; a mismatch consumes the character
        k = self.count
        if k == 0:
            if ch == "R":
                self.num, self.count = _RAW, 1
            elif ch == "C":
                self.num, self.count = _CAL1, 1
            return
        want = {1: {"a": None}, 2: {"w": _RAW, "l": _CAL1}, 3: None, 4: None}[k]
        if k == 1 and ch == "a":
            self.count = 2
        elif k == 2 and want.get(ch) == self.num:
            self.count = 3
        elif k == 3 and ch == ":" and self.num == _RAW:
            self.state, self.nvals, self.num, self.count = _RAW, 0, 0, 0
        elif k == 3 and ch in "12" and self.num == _CAL1:
            self.num, self.count = (_CAL1 if ch == "1" else _CAL2), 4
        elif k == 4 and ch == ":":
            self.state, self.nvals, self.num, self.count = self.num, 0, 0, 0
        else:
            self.num, self.count = 0, 0

    def _char(self, ch):
        if self.state == _WORD:
            self._word(ch)
            return True
        if ch == "-":
            if self.count > 0:
                return False
            self.neg = True
        elif ch.isdigit():
            self.num = _int32(self.num * 10 + ord(ch) - 48)
            self.count += 1
        elif ch == "\n":
            pass
        elif self.state == _RAW:
            return self._raw_char(ch)
        else:
            return self._cal_char(ch)
        return True

    def _raw_char(self, ch):
        if ch not in ",\r":
            return False
        v = -self.num if self.neg else self.num
        if ch == ",":
            if self.nvals >= 8:
                return False
            self.raw_vals[self.nvals] = _int16(v)
            self.nvals += 1
        else:
            if self.nvals != 8:
                return False
            self.raw_vals[8] = _int16(v)
            self.raw.append(tuple(self.raw_vals))
            self._reset()
            return True
        self.num, self.neg, self.count = 0, False, 0
        return True

    def _cal_char(self, ch):
        if ch == ".":
            if self.nvals > 9:
                return False
            self.cal_vals[self.nvals] = f32(float(self.num))
            self.num, self.count = 0, 0
            return True
        if ch not in ",\r":
            return False
        if ch == "\r":
            last = 9 if self.state == _CAL1 else 8
            if self.nvals != last:
                return False
        elif self.nvals > 9:
            return False
        i = self.nvals
        self.cal_vals[i] = f32(self.cal_vals[i] + f32(f32(float(self.num))
                                                      / f32(10.0 ** self.count)))
        if self.neg:
            self.cal_vals[i] = -self.cal_vals[i]
        if ch == ",":
            self.nvals += 1
            self.num, self.neg, self.count = 0, False, 0
            return True
        if self.state == _CAL1:
            self._cal_line(self.cal_vals[:10], 0, 1)
            self.cal1.append(self.cal_vals[:10])
        else:
            self._cal_line(self.cal_vals[:9], 10, 2)
            self.cal2.append(self.cal_vals[:9])
        self._reset()
        return True

    def _cal_line(self, vals, first, bit):
        if not self.confirm_needed:
            return
        if all(is_float_ok(v, self.sent[first + i]) for i, v in enumerate(vals)):
            self.confirm_needed &= ~bit
            if self.confirm_needed == 0:
                self.confirmed = True
