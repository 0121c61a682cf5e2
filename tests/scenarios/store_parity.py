# Calibration records as hex, CRC-32 values (port's binascii and the integer fallback) and the
# refusal reason of corrupted records. Integers and hex strings only: both interpreters agree.
import json
from binascii import hexlify

from firmware.store_slots import crc32, crc32_int, decode_record, encode_record
from firmware.errors import StoreError


def hx(b):
    return hexlify(b).decode()


print(json.dumps(["record", hx(encode_record(bytes(range(40)), "qmc5883l", 0, 1))]))
for sensor, rng, seq, n in [("hmc5883l", 1, 7, 0), ("qmc5883l", 3, 0xFFFFFFFF, 100),
                            ("qmc5883p", 255, 123456789, 17)]:
    payload = bytes((i * 29 + seq) & 255 for i in range(n))
    print(json.dumps(["record", hx(encode_record(payload, sensor, rng, seq))]))
for data in [b"", b"123456789", bytes(range(256)), b"\xff" * 1000]:
    print(json.dumps(["crc", crc32(data), crc32_int(data), crc32_int(data, 0x12345678)]))
rec = encode_record(b"calibration payload", "qmc5883l", 0, 5)
reasons = []
for bad, sensor, rng in [(rec, "qmc5883l", 0), (rec[:-1], "qmc5883l", 0),
                         (rec + b"\x00", "qmc5883l", 0), (b"XCAL" + rec[4:], "qmc5883l", 0),
                         (rec[:33] + b"?" + rec[34:], "qmc5883l", 0), (rec, "hmc5883l", 0),
                         (rec, "qmc5883l", 1)]:
    try:
        seq, payload = decode_record(bad, sensor, rng)
        reasons.append([seq, hx(payload)])
    except StoreError as e:
        reasons.append(e.reason)
print(json.dumps(["reasons", reasons]))
