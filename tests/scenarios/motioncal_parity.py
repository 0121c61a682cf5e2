# firmware.motioncal.protocol on both interpreters: Raw lines, float32 decoding, the packet reader,
# packet -> calibration fields and the Cal1/Cal2 echo, for a fixed set of inputs (an LCG, the
# same on both). Packets are built here from exact float32 bit patterns (k * 2**-shift with
# |k| < 2**24), so no float is involved. Prints one JSON object per case.
#   motioncal_parity.py          the cases (run by tests/mp.py parity())
#   motioncal_parity.py alloc    MicroPython only: bytes allocated per call (mem_total)
#   motioncal_parity.py import   MicroPython only: heap bytes the import takes (mem_alloc)
import json
import sys

mode = sys.argv[1] if len(sys.argv) > 1 else "cases"

if mode == "import":
    import gc
    gc.collect()
    a0 = gc.mem_alloc()
    import firmware.compat  # noqa: F401  (loaded by any app already)
    import firmware.errors  # noqa: F401
    import firmware.fixedpoint  # noqa: F401
    gc.collect()
    a1 = gc.mem_alloc()
    import firmware.motioncal.protocol  # noqa: F401
    gc.collect()
    a2 = gc.mem_alloc()
    import firmware.calibrate.acceptance  # noqa: F401  (calibration_fields() imports them on first packet)
    import firmware.calibrate.solve  # noqa: F401
    gc.collect()
    a3 = gc.mem_alloc()
    print(json.dumps({"deps": a1 - a0, "motioncal": a2 - a1, "acceptance_and_solve": a3 - a2}))
    sys.exit(0)

from firmware.motioncal import protocol as mc  # noqa: E402
from firmware.fixedpoint import bit_length  # noqa: E402

import sys  # noqa: E402
sys.path.append("tests/scenarios")  # smallrand, also when the script arrives on stdin (qemu)
from smallrand import SmallRand  # noqa: E402

seed = 2024
_R = SmallRand(seed)


def rnd(n):
    global seed
    return (_R.u30() >> 4) % n


def f32_bits(k, shift):
    # exact float32 bits of k * 2**-shift (|k| < 2**24)
    if k == 0:
        return 0
    s = 0
    if k < 0:
        s = 1
        k = -k
    e = bit_length(k) - 1
    return (s << 31) | ((e - shift + 127) << 23) | ((k << (23 - e)) & 0x7FFFFF)


def emit(case, pairs):
    # one JSON object, keys in the given order (MicroPython's dicts have their own order)
    print("{" + ", ".join(['"case": "%s"' % case] + ['"%s": %s' % (k, json.dumps(v))
                                                    for k, v in pairs]) + "}")


def packet(v_q8, b_q8, invw_q16, crc_ok=True):
    # V, B in 1/256 uT; the 6 invW entries (diagonal, 01 02 12) in 1/65536
    words = [0] * 6 + [f32_bits(x, 8) for x in v_q8] + [f32_bits(b_q8, 8)]
    words += [f32_bits(x, 16) for x in invw_q16]
    b = bytearray([117, 84])
    for w in words:
        b += bytes([w & 255, (w >> 8) & 255, (w >> 16) & 255, (w >> 24) & 255])
    c = mc.crc16(b, 66) ^ (0 if crc_ok else 1)
    b += bytes([c & 255, c >> 8])
    return bytes(b)


if mode == "alloc":
    import micropython
    mt = micropython.mem_total
    buf = bytearray(mc.RAW_LINE_MAX)
    acc = [100, -200, 8000]
    mag = [0, 0, 0]
    raw = [1234, -32768, 32767]
    r = mc.PacketReader()
    garbage = b"Raw:1,2,3 text not a packet " * 4
    part = packet([256, 0, 0], 50 * 256, [65536, 65536, 65536, 0, 0, 0])[:40]
    res = {}
    for _ in range(2):  # the second pass counts (warm)
        t = mt()
        mc.raw_line_into(buf, acc, mc.GYRO_NONE, raw)
        res["raw_line_into"] = mt() - t
        t = mt()
        mc.mag_01ut_into(raw, 12000, mag)
        res["mag_01ut_into"] = mt() - t
        t = mt()
        r.feed(garbage)
        res["feed_garbage"] = mt() - t
        r.end()
        t = mt()
        r.feed(part)
        res["feed_partial"] = mt() - t
        r.end()
    print(json.dumps(res))
    sys.exit(0)

# Raw lines
lines = []
edges = [[0, 0, 0], [-32768, 32767, -1], [40000, -40000, 9], [1, -10, 100]]
vecs = edges + [[rnd(65536) - 32768 for _ in range(3)] for _ in range(20)]
for i in range(len(vecs)):
    lines.append(list(mc.raw_line(vecs[i], vecs[-1 - i], vecs[(i * 7) % len(vecs)])))
conv = [[mc.mag_01ut(c, cpg), mc.accel_8192(c, cpg)] for c in (-32768, -7, 0, 5, 12345, 32767)
        for cpg in (12000, 3000, 1370, 230, 1000, 15000, 16384)]
emit("raw", [("lines", lines), ("conv", conv)])

# float32 -> fixed point
vals = []
for e in (0, 1, 20, 100, 120, 126, 127, 128, 140, 150, 160, 254, 255):
    for _ in range(4):
        bits = (rnd(2) << 31) | (e << 23) | (rnd(1 << 23) if rnd(3) else 0)
        for scale in (1, 10000, 100000, 65536, 1 << 24, 777):
            k = mc.f32_kind(bits)
            if k in (mc.F32_NAN, mc.F32_INF):
                vals.append([bits, scale, k])
            else:
                vals.append([bits, scale, mc.f32_fixed(bits, scale)])
emit("f32", [("values", [v for v in vals if not isinstance(v[2], str)]),
             ("special", [v for v in vals if isinstance(v[2], str)])])

# packets: good ones, refusals
good = [packet([2560, -5120, 7680], 50 * 256, [72089, 62259, 62915, 1311, -1966, 655]),
        packet([-30000, 100, 0], 12000, [65536, 65536, 65536, 0, 0, 0]),
        packet([0, 0, 0], 23040, [80000, 60000, 58000, -3000, 2000, 1000])]
bad = [packet([0, 0, 0], 50 * 256, [-65536, 65536, 65536, 0, 0, 0]),
       packet([0, 0, 0], 95 * 256, [65536, 65536, 65536, 0, 0, 0]),
       packet([0, 0, 0], 50 * 256, [65536, 65536, 65536, 0, 0, 0], crc_ok=False),
       packet([0, 0, 0], 50 * 256, [6 * 65536, 65536, 65536, 0, 0, 0]),
       packet([70000, 0, 0], 50 * 256, [65536, 65536, 65536, 0, 0, 0])]
results = []
for p in good + bad:
    for cpg in (12000, 230):
        try:
            f = mc.calibration_fields(p, cpg)
            results.append([list(f["offset"]), list(f["invw"]), f["field"], f["field_out"]])
        except mc.CalibrationRejected as e:
            results.append(e.reason)
emit("fields", [("results", results)])

# the reader over a stream with garbage, false starts and a damaged packet, in pieces
stream = b"boot uT" + good[0] + b"\x75\x75\x54" + bad[2] + good[1][:30] + b"uTuT" + good[2]
r = mc.PacketReader()
events = []
i = 0
while i < len(stream):
    k = 1 + rnd(70)
    for kind, value in r.feed(stream[i:i + k]):
        events.append([kind, value if isinstance(value, int) else list(value)])
    i += k
for kind, value in r.end():
    events.append([kind, value])
emit("reader", [("events", events), ("totals", [r.packets, r.bad_crc, r.truncated, r.skipped])])

# the echo
echo = [[c.decode() for c in mc.echo(p)] for p in good + bad[:2]]
emit("echo", [("lines", echo)])

# the 3D viewer's lines
viewer = [mc.orientation_line(h, p, r).decode() for h, p, r in
          ((0, 0, 0), (35999, -9000, 18000), (15130, -5, 7), (5, 1234, -17999))]
viewer += [mc.calibration_line(s, 0, 3, mc.mag_level(m, f)).decode()
           for s, m, f in ((0, None, 0), (1, 10, 500), (3, 7, 90), (-2, 4, 0))]
emit("viewer", [("lines", viewer)])
