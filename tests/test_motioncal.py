"""firmware/motioncal/protocol.py against a host re-implementation of MotionCal (tests/motioncal_ref.py)
and against CPython's own float32 decoding (struct), exact rational arithmetic (fractions)
and float64 linear algebra (numpy)."""
import math
import random
import struct
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from firmware.calibrate import acceptance
from firmware.motioncal import protocol as mc
from firmware.errors import CalibrationRejected
from firmware.calibration import Calibration
from tests import motioncal_ref as ref
from tests.mp import json_lines, parity, run

I16 = st.integers(-32768, 32767)
VEC16 = st.tuples(I16, I16, I16)
CPG_MAG = (12000, 3000, 1370, 1090, 820, 660, 440, 390, 330, 230, 1000, 2500, 3750, 15000)


def half_away(fr):
    """Fraction -> nearest int, halves away from zero (the firmware's rounding rule)."""
    n = abs(fr)
    r = math.floor(n + Fraction(1, 2))
    return r if fr >= 0 else -r


def bits_of(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


# ---- Raw lines -------------------------------------------------------------------------------

def test_raw_line_exact_bytes_with_cr_lf_and_int16_clamp():
    line = mc.raw_line((1, -2, 40000), mc.GYRO_NONE, (-40000, 0, -32768))
    assert line == b"Raw:1,-2,32767,0,0,0,-32768,0,-32768\r\n"
    assert len(mc.raw_line((-32768,) * 3, (-32768,) * 3, (-32768,) * 3)) == mc.RAW_LINE_MAX


@given(VEC16, VEC16, st.tuples(*[st.integers(-10 ** 6, 10 ** 6)] * 3))
def test_raw_line_is_one_motioncal_record_of_the_clamped_values(acc, gyro, mag):
    buf = bytearray(mc.RAW_LINE_MAX)
    line = bytes(mc.raw_line(acc, gyro, mag, buf))
    assert line == mc.raw_line(acc, gyro, mag)
    p = ref.MotionCal()
    p.read(line)
    clamp = tuple(max(-32768, min(32767, v)) for v in acc + gyro + mag)
    assert p.raw == [clamp] and p.failures == 0


def test_board_stream_is_accepted_by_motioncal_in_256_byte_reads():
    # >= 99.9 % of Raw lines accepted when interleaved with the echo and status text, read
    # in MotionCal's 256-byte pieces and in random pieces (records span reads)
    rng = random.Random(5)
    sent = []
    stream = bytearray(b"eCompass ready, heading 151.3 deg\r\n")
    cal1, cal2 = mc.echo(ref.build_packet((12.5, -3.25, 40.0), 48.5, np.eye(3)))
    for i in range(3000):
        v = tuple(rng.randint(-32768, 32767) for _ in range(9))
        sent.append(v)
        stream += mc.raw_line(v[0:3], v[3:6], v[6:9])
        if i % 200 == 0:
            stream += cal1 + cal2 + b"Calibration: fit 2.31 %, 86 % covered\r\n"
    for size in (256, None):
        p = ref.MotionCal()
        if size:
            p.read(bytes(stream), size)
        else:
            i = 0
            while i < len(stream):
                k = rng.randint(1, 300)
                p.parse(stream[i:i + k])
                i += k
        assert p.failures == 0
        assert len(p.raw) >= 0.999 * len(sent)
        assert p.raw == sent
        assert len(p.cal1) == len(p.cal2) == 15


def test_reference_parser_rejects_what_motioncal_rejects():
    # the reference can fail: LF-only lines give no sample, a '+' loses the rest of the read
    p = ref.MotionCal()
    p.read(b"Raw:1,2,3,4,5,6,7,8,9\nRaw:1,2,3,4,5,6,7,8,9\n")
    assert p.raw == [] and p.failures == 1
    p = ref.MotionCal()
    p.read(b"Raw:+1,2,3,4,5,6,7,8,9\rRaw:1,2,3,4,5,6,7,8,9\r")
    assert p.raw == []
    p = ref.MotionCal()
    p.read(b"RRaw:1,2,3,4,5,6,7,8,9\rheading 1 Raw:1,2,3,4,5,6,7,8,40000\r")
    assert p.raw == [(1, 2, 3, 4, 5, 6, 7, 8, 40000 - 65536)]


@pytest.mark.parametrize("cpg", CPG_MAG)
def test_mag_01ut_is_counts_times_1000_over_counts_per_gauss_rounded(cpg):
    for c in list(range(-3000, 3001, 7)) + [-32768, 32767, 0, 1, -1]:
        want = half_away(Fraction(c * 1000, cpg))
        assert mc.mag_01ut(c, cpg) == want
    out = [0, 0, 0]
    mc.mag_01ut_into((cpg, -cpg // 2, 3), cpg, out)
    assert out[0] == 1000 and out[1] == mc.mag_01ut(-cpg // 2, cpg)


@given(I16, st.sampled_from((16384, 8192, 4096, 2048, 1000)))
def test_accel_8192_is_counts_in_1_8192_g_rounded(c, cpg):
    assert mc.accel_8192(c, cpg) == half_away(Fraction(c * 8192, cpg))
    out = [0, 0, 0]
    mc.accel_8192_into((c, 0, -c), cpg, out)
    assert out == [mc.accel_8192(c, cpg), 0, mc.accel_8192(-c, cpg)]


# ---- float32 decoding -------------------------------------------------------------------

SCALES = st.one_of(st.sampled_from((1, 1 << 16, 10 ** 4, 10 ** 5, 1 << 24)),
                   st.integers(1, 10 ** 7))


def expected_fixed(bits, scale):
    x = struct.unpack("<f", struct.pack("<I", bits))[0]
    return half_away(Fraction(x) * scale)


@given(st.integers(0, 2 ** 32 - 1), SCALES)
def test_f32_fixed_matches_struct_unpack_rounded(bits, scale):
    x = struct.unpack("<f", struct.pack("<I", bits))[0]
    kind = mc.f32_kind(bits)
    if math.isnan(x):
        assert kind == mc.F32_NAN
    elif math.isinf(x):
        assert kind == mc.F32_INF
    elif x == 0:
        assert kind == mc.F32_ZERO
    else:
        assert kind == (mc.F32_DENORMAL if abs(x) < 2.0 ** -126 else mc.F32_NORMAL)
    if kind in (mc.F32_NAN, mc.F32_INF):
        with pytest.raises(ValueError, match=kind):
            mc.f32_fixed(bits, scale)
    else:
        assert mc.f32_fixed(bits, scale) == expected_fixed(bits, scale)


def test_f32_fixed_every_exponent_and_the_rounding_edges():
    rng = random.Random(7)
    n = 0
    for e in range(255):
        for s in (0, 1):
            for m in (0, 1, 0x400000, 0x7FFFFF, rng.getrandbits(23), rng.getrandbits(23)):
                bits = (s << 31) | (e << 23) | m
                for scale in (1, 10 ** 5, 1 << 16):
                    assert mc.f32_fixed(bits, scale) == expected_fixed(bits, scale)
                    n += 1
    assert n == 255 * 2 * 6 * 3
    # exact halves round away from zero
    assert mc.f32_fixed(bits_of(2.5), 1) == 3 and mc.f32_fixed(bits_of(-2.5), 1) == -3
    assert mc.f32_fixed(bits_of(0.5), 1) == 1 and mc.f32_fixed(bits_of(0.4999999), 1) == 0


def test_f32_bits_at_reads_little_endian():
    data = b"\x00" + struct.pack("<f", -1.5) + b"\xff"
    assert mc.f32_bits_at(data, 1) == bits_of(-1.5)


# ---- the packet reader ------------------------------------------------------------------------

def packet_of(seed):
    rng = random.Random(seed)
    V = [rng.uniform(-60, 60) for _ in range(3)]
    return ref.build_packet(V, rng.uniform(20, 70), np.eye(3) + rng.uniform(-0.1, 0.1))


def test_crc16_is_modbus_and_runs_to_zero_over_the_whole_packet():
    assert mc.crc16(b"123456789", 9) == 0x4B37  # CRC-16/MODBUS check value
    p = packet_of(1)
    assert mc.crc16(p, 66) == ref.crc16_modbus(p[:66]) and mc.crc16(p, 68) == 0
    assert mc.packet_ok(p) and not mc.packet_ok(p[:67]) and not mc.packet_ok(b"x" + p[1:])


def feed_all(reader, data, sizes):
    ev = []
    i = 0
    for k in sizes:
        ev += list(reader.feed(data[i:i + k]))
        i += k
    ev += list(reader.feed(data[i:]))
    return ev


@given(st.lists(st.tuples(st.binary(max_size=90), st.integers(0, 10 ** 6)), min_size=1,
                max_size=4),
       st.lists(st.integers(0, 80), max_size=12), st.booleans())
def test_reader_finds_every_packet_behind_any_garbage_in_any_pieces(parts, sizes, sigs):
    stream = b""
    packets = []
    starts = []
    garbage = 0
    for junk, seed in parts:
        if sigs:
            junk = junk + b"uT" + junk[:5]  # a false start right before the packet
        p = packet_of(seed)
        starts.append(len(stream) + len(junk))
        stream += junk + p
        packets.append(p)
        garbage += len(junk)
    # a false start whose 68 bytes pass the CRC (1 in 65536: hypothesis finds one) is a
    # packet on the wire too: no reader can tell it apart
    assume(not any(mc.packet_ok(stream[i:i + 68]) for i in range(len(stream) - 67)
                   if i not in starts and stream[i:i + 2] == b"uT"))
    r = mc.PacketReader()
    ev = feed_all(r, stream, sizes) + r.end()
    got = [v for k, v in ev if k == mc.PACKET]
    assert got == packets
    # garbage is counted once; a false start's bytes belong to its bad_crc candidate
    n_bad = sum(1 for k, _ in ev if k == mc.BAD_CRC)
    skipped = sum(v for k, v in ev if k == mc.GARBAGE)
    assert skipped == r.skipped <= garbage
    assert r.packets == len(packets) and r.bad_crc == n_bad
    if n_bad == 0:
        assert skipped == garbage


def test_reader_resynchronises_on_a_signature_inside_a_damaged_packet():
    # a packet whose floats hold 117, 84; its head lost: the false start inside it fails
    # its CRC, then the next packet is still found
    p1 = ref.build_packet((struct.unpack("<f", b"\x00uT\x41")[0], 0.0, 1.0), 50.0, np.eye(3))
    assert b"uT" in p1[2:]
    p2 = packet_of(3)
    r = mc.PacketReader()
    ev = list(r.feed(p1[5:] + p2)) + r.end()
    kinds = [k for k, _ in ev]
    assert (mc.PACKET, p2) in ev and kinds.count(mc.PACKET) == 1
    assert mc.BAD_CRC in kinds


def test_reader_reports_bad_crc_truncated_and_garbage():
    p = bytearray(packet_of(4))
    p[40] ^= 0x10
    r = mc.PacketReader()
    ev = list(r.feed(b"abc" + bytes(p)))
    assert ev[0] == (mc.GARBAGE, 3) and ev[1] == (mc.BAD_CRC, bytes(p))
    assert all(k != mc.PACKET for k, _ in ev)
    r = mc.PacketReader()
    assert r.feed(b"xyuT" + packet_of(5)[2:30]) == ()
    assert r.end() == [(mc.GARBAGE, 2), (mc.TRUNCATED, 30)]
    assert r.end() == [] and r.truncated == 1
    r = mc.PacketReader()
    r.feed(b"zzu")
    assert r.end() == [(mc.GARBAGE, 3)]
    # repeated and broken signature bytes are garbage, counted once each
    p = packet_of(6)
    r = mc.PacketReader()
    assert r.feed(b"uuuxTuzu" + p[:1]) == ()
    assert r.feed(p[1:]) == [(mc.GARBAGE, 8), (mc.PACKET, p)] and r.skipped == 8


# ---- packet -> calibration -------------------------------------------------------------------

def soft_iron(rng, cond):
    """A random symmetric positive definite invW with eigenvalue ratio `cond`, det 1."""
    q, _ = np.linalg.qr(np.array([[rng.gauss(0, 1) for _ in range(3)] for _ in range(3)]))
    lam = np.array([1.0, rng.uniform(1.0, cond), cond])
    lam /= np.prod(lam) ** (1 / 3)
    return q @ np.diag(lam) @ q.T


def f32_matrix(invw):
    d0, d1, d2, o01, o02, o12 = [ref.f32(x) for x in ref.symmetric(invw)]
    return np.array([[d0, o01, o02], [o01, d1, o12], [o02, o12, d2]])


@pytest.mark.parametrize("cpg", (12000, 3000, 1090, 230, 15000))
def test_packet_calibration_corrects_motioncal_ellipsoid_to_a_sphere_of_field_out(cpg):
    # points on MotionCal's ellipsoid, in counts, through Calibration.correct(): every
    # |out| is field_out within 1.5 counts + 0.2 % (raw rounding to counts, Q15 steps)
    rng = random.Random(cpg)
    for trial in range(8):
        B = rng.uniform(25, 65)
        V = [rng.uniform(-1, 1) * 20000 * 100 / cpg * 0.8 for _ in range(3)]
        invw = soft_iron(rng, rng.uniform(1.0, 3.0)) * rng.uniform(0.6, 1.6)  # det != 1
        fields = mc.calibration_fields(ref.build_packet(V, B, invw), cpg)
        cal = Calibration(**fields)
        W = np.linalg.inv(f32_matrix(invw))
        k = cpg / 100.0  # counts per uT
        assert cal.offset == tuple(round(ref.f32(v) * k) for v in V)
        assert abs(fields["field"] - ref.f32(B) * k) <= 0.5
        q = np.array(cal.invw).reshape(3, 3) / 32768.0
        s = np.abs(f32_matrix(invw)).sum(axis=1).max()
        assert np.allclose(q, f32_matrix(invw) * 32767 / 32768 / s, atol=1 / 32768.0)
        out = [0, 0, 0]
        for _ in range(40):
            u = np.array([rng.gauss(0, 1) for _ in range(3)])
            u *= ref.f32(B) / np.linalg.norm(u)
            raw = [int(round(x)) for x in (W @ u + np.array([ref.f32(v) for v in V])) * k]
            cal.correct(raw, out)
            tol = 1.5 + 0.002 * fields["field_out"] + np.abs(q).sum(axis=1).max()
            assert abs(math.sqrt(sum(x * x for x in out)) - fields["field_out"]) <= tol


@pytest.mark.parametrize("bad,reason", [
    (dict(V=(float("nan"), 0, 0)), mc.REASON_NOT_A_NUMBER),
    (dict(invw=(1, 1, float("inf"), 0, 0, 0)), mc.REASON_NOT_A_NUMBER),
    (dict(invw=(-1, -1, -1, 0, 0, 0)), mc.REASON_NOT_POSITIVE_DEFINITE),
    (dict(invw=(1, 1, 1, 1, 0, 0)), mc.REASON_NOT_POSITIVE_DEFINITE),  # singular
    (dict(invw=(1, 1, 0.5, 0, 0, 0.9)), mc.REASON_NOT_POSITIVE_DEFINITE),
    (dict(invw=(2.7, 0.5, 0.5, 0, 0, 0)), acceptance.REASON_SOFT_IRON_OUT_OF_RANGE),  # 5.4 : 1
    (dict(B=9.9), acceptance.REASON_FIELD_OUT_OF_RANGE),
    (dict(B=90.5), acceptance.REASON_FIELD_OUT_OF_RANGE),
    (dict(V=(0, 0, 273.1)), acceptance.REASON_OFFSET_OUT_OF_RANGE),  # 32773 counts at 12000
    (dict(V=(-273.1, 0, 0)), acceptance.REASON_OFFSET_OUT_OF_RANGE),
])
def test_calibration_fields_refusals_name_their_reason(bad, reason):
    args = dict(V=(10.0, -20.0, 30.0), B=50.0, invw=(1.1, 0.95, 0.96, 0.02, -0.03, 0.01))
    args.update(bad)
    with pytest.raises(CalibrationRejected) as e:
        mc.calibration_fields(ref.build_packet(**args), 12000)
    assert e.value.reason == reason, str(e.value)
    good = dict(V=(10.0, -20.0, 30.0), B=50.0, invw=(1.1, 0.95, 0.96, 0.02, -0.03, 0.01))
    assert Calibration(**mc.calibration_fields(ref.build_packet(**good), 12000)).model == 10


def test_calibration_fields_limits_are_the_stated_ones():
    ok = dict(V=(0.0, 0.0, 273.0), B=10.0, invw=(2.23, 0.5, 0.5, 0, 0, 0))  # 4.46 : 1
    f = mc.calibration_fields(ref.build_packet(**ok), 12000)
    assert f["offset"] == (0, 0, 32760) and f["field"] == 1200
    assert mc.calibration_fields(ref.build_packet(ok["V"], 90.0, ok["invw"]), 12000)
    p = bytearray(ref.build_packet(**ok))
    p[66] ^= 1
    with pytest.raises(CalibrationRejected, match="bad_crc"):
        mc.calibration_fields(bytes(p), 12000)
    with pytest.raises(ValueError, match="counts_per_gauss"):
        mc.calibration_fields(bytes(p), 0)


@given(st.integers(0, 2 ** 32), st.sampled_from(CPG_MAG))
@settings(max_examples=100)
def test_random_packets_are_accepted_exactly_when_a_float_check_says_so(seed, cpg):
    rng = random.Random(seed)
    V = [rng.uniform(-40000, 40000) * 100 / cpg for _ in range(3)]  # counts -> uT
    B = rng.uniform(0, 100)
    invw = soft_iron(rng, rng.uniform(1, 7)) * rng.uniform(0.5, 2)
    if rng.random() < 0.2:
        invw[0][0] = -invw[0][0]
    m = f32_matrix(invw)
    ev = np.linalg.eigvalsh(m)
    k = cpg / 100.0
    off = [ref.f32(v) * k for v in V]
    Bf = ref.f32(B)
    # stay clear of the boundaries, where float64 and the fixed point may disagree: the
    # ratio is the calibrator's (power iteration, a lower bound: up to ~2 % low when the two largest
    # eigenvalues are within 5 %), entries are Q24 then Q15, so near-singular is unclear
    cond = ev[-1] / ev[0] if ev[0] > 0 else None
    assume(abs(ev[0]) > 1e-3 * abs(ev[-1]))
    assume(ev[0] <= 0 or abs(cond - 5) > 0.15)
    assume(abs(Bf - 10) > 1e-4 and abs(Bf - 90) > 1e-4)
    assume(all(abs(abs(o) - 32767.5) > 0.01 for o in off))
    # the output field: InvW is scaled to Q15 so that its largest row sum is 32767
    # (solve.q15_steps), so the corrected field is B x 32767 / 32768 / that row sum (counts);
    # firmware/calibrate/acceptance.py check_output_field wants it within B / 8 .. 2 B and >= 16 counts
    s = 32767 / 32768 / max(sum(abs(x) for x in row) for row in m)
    fo = Bf * k * s
    assume(abs(fo - 16) > 0.6 and abs(s - 0.125) > 1e-3 and abs(s - 2) > 1e-3)
    if ev[0] <= 0:
        want = mc.REASON_NOT_POSITIVE_DEFINITE
    elif cond > 5:
        want = acceptance.REASON_SOFT_IRON_OUT_OF_RANGE
    elif not 10 <= Bf <= 90:
        want = acceptance.REASON_FIELD_OUT_OF_RANGE
    elif any(abs(o) > 32767.5 for o in off):
        want = acceptance.REASON_OFFSET_OUT_OF_RANGE
    elif fo < 16 or s < 0.125 or s > 2:
        want = acceptance.REASON_FIELD_OUT_OF_RANGE
    else:
        want = None
    try:
        f = mc.calibration_fields(ref.build_packet(V, B, invw), cpg)
        got = None
        Calibration(**f)  # the constructor's own checks pass
    except CalibrationRejected as e:
        got = e.reason
    assert got == want


# ---- the Cal1/Cal2 echo ---------------------------------------------------------------------

def test_cal_echo_exact_text():
    c1, c2 = mc.cal_echo((1234567, -5, 0), 4850000, (100000, -12, 3, -12, 99999, 0, 3, 0, 1))
    assert c1 == b"Cal1:0.00000,0.00000,0.00000,0.00000,0.00000,0.00000,12.34567,-0.00005," \
                 b"0.00000,48.50000\r\n"
    assert c2 == b"Cal2:1.00000,-0.00012,0.00003,-0.00012,0.99999,0.00000,0.00003,0.00000," \
                 b"0.00001\r\n"


FINITE = st.floats(width=32, allow_nan=False, allow_infinity=False)


@given(st.tuples(*[st.floats(-1000, 1000, width=32)] * 3), st.floats(0, 200, width=32),
       st.tuples(*[st.floats(-3, 3, width=32)] * 6))
def test_echo_confirms_any_packet_in_motioncal(V, B, invw):
    packet = ref.build_packet(V, B, invw)
    p = ref.MotionCal()
    p.read(b"Cal1:1.0,1.0,1.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0\r")  # before a send: ignored
    p.send(packet)
    assert not p.confirmed
    c1, c2 = mc.echo(packet)
    p.read(c2 + b"Raw:1,2,3,4,5,6,7,8,9\r\n" + c1)
    assert p.confirmed and p.failures == 0 and p.raw == [(1, 2, 3, 4, 5, 6, 7, 8, 9)]


def test_echo_with_three_decimals_would_not_confirm():
    # the check can fail: 0.12345 printed as 0.123 is 0.00045 off (> 0.0001 + 3e-6)
    packet = ref.build_packet((0.12345, 0.0, 0.0), 50.0, np.eye(3))
    p = ref.MotionCal()
    p.send(packet)
    c1, c2 = mc.echo(packet)
    p.read(c1.replace(b"0.12345", b"0.123") + c2)
    assert not p.confirmed
    p.read(c1)
    assert p.confirmed


def test_echo_refuses_a_nan():
    with pytest.raises(CalibrationRejected, match="not_a_number: B is nan"):
        mc.echo(ref.build_packet((0.0, 0.0, 0.0), float("nan"), np.eye(3)))


# ---- MicroPython -------------------------------------------------------------------------------

SCENARIO = "tests/scenarios/motioncal_parity.py"


def test_motioncal_same_bits_on_micropython_and_cpython():
    out = json_lines(parity([SCENARIO]))
    by = {o["case"]: o for o in out}
    # the scenario's own values cross-checked here against the host reference
    for line in by["raw"]["lines"]:
        p = ref.MotionCal()
        p.read(bytes(line))
        assert len(p.raw) == 1
    for bits, scale, value in by["f32"]["values"]:
        assert value == expected_fixed(bits, scale)
    assert by["reader"]["totals"][:3] == [2, by["reader"]["totals"][1], 0]  # 2 packets found
    assert [k for k, _ in by["reader"]["events"]].count(mc.PACKET) == 2
    fields = by["fields"]["results"]
    assert sum(1 for f in fields if isinstance(f, list)) >= 2
    assert {f for f in fields if isinstance(f, str)} >= {
        mc.REASON_NOT_POSITIVE_DEFINITE, acceptance.REASON_FIELD_OUT_OF_RANGE, mc.REASON_BAD_CRC}


def test_per_sample_path_allocates_nothing_on_micropython():
    o = json_lines(run([SCENARIO, "alloc"], micro=True))[0]
    assert o["raw_line_into"] == 0 and o["mag_01ut_into"] == 0 and o["feed_garbage"] == 0
    assert o["feed_partial"] == 0


# ---- Adafruit WebSerial 3D viewer lines ------------------------------------------------------

def viewer_read(line):
    """The viewer's reading of one line (split at LF, trim, split at ',', JS Number())."""
    text = line.decode().split("\n")[0].strip()
    for head in ("Orientation:", "Calibration:"):
        if text.startswith(head):
            return head, [float(x) for x in text[len(head):].strip().split(",")]
    return None, []


@given(st.integers(0, 35999), st.integers(-9000, 9000), st.integers(-18000, 18000))
def test_orientation_line_reads_back_in_the_viewer_and_motioncal_skips_it(h, p, r):
    line = mc.orientation_line(h, p, r)
    assert viewer_read(line) == ("Orientation:", [h / 100, p / 100, r / 100])
    m = ref.MotionCal()
    m.read(line + mc.calibration_line(0, 0, 3, 3) + mc.raw_line((1, 2, 3), (0, 0, 0), (4, 5, 6)))
    assert m.failures == 0 and m.raw == [(1, 2, 3, 0, 0, 0, 4, 5, 6)]


def test_calibration_line_levels_stay_in_the_viewers_range():
    assert mc.calibration_line(0, -1, 7, 2) == b"Calibration: 0,0,3,2\r\n"
    assert viewer_read(mc.calibration_line(0, 0, 3, mc.mag_level(10, 320))) == (
        "Calibration:", [0, 0, 3, 3])
    assert [mc.mag_level(m, f) for m, f in ((None, 0), ("minmax", 0), (4, 100), (7, 100),
                                            (10, 501), (10, 500))] == [0, 1, 1, 2, 2, 3]
