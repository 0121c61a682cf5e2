"""firmware/store.py + firmware/store_slots.py: versioned, CRC-protected, power-safe calibration record.

The power-cut tests run every save on a fake filesystem that counts each file operation and
each byte written, cut the power after k of them for every k, "reboot" and load: the result
must be exactly the old payload or exactly the new one, under several models of what a cut
leaves behind in the file being written.
"""
import random
import struct
import zlib

import pytest
from hypothesis import given, strategies as st

from firmware import store_slots as calstore
from firmware.store import CalStore
from firmware.store_slots import MAX_PAYLOAD, crc32, crc32_int, decode_record, encode_record
from firmware.errors import StoreError
from tests import mp

OLD = bytes(range(7, 7 + 84))                   # stand-ins for Calibration.to_bytes()
NEW = bytes((i * 37 + 11) & 255 for i in range(84))
DIR = "/flash"
PA = DIR + "/ecompass_a.cal"
PB = DIR + "/ecompass_b.cal"


# ---------------------------------------------------------------- a filesystem that loses power

class PowerCut(Exception):
    pass


MODELS = ("prefix", "zeros", "erased", "garbage", "inplace", "cow")
# prefix   open("wb") truncates at once, each byte is on flash as soon as it is written (FAT-like)
# zeros    as prefix, but a cut inside write() leaves the file at the write's full length with
#          the unwritten tail zero (size metadata committed before the data)
# erased   the same with 0xFF (erased NOR flash)
# garbage  the same with random bytes
# inplace  open("wb") does not truncate: new bytes overwrite the old file from the start and
#          its old tail stays until close() truncates
# cow      LittleFS-like: the new content becomes visible only at close()


class FakeFs:
    def __init__(self, files=None, budget=None, model="prefix", seed=0):
        self.files = dict(files or {})   # path -> bytes: what survives a reboot
        self.budget = budget
        self.used = 0
        self.model = model
        self.rng = random.Random(seed)
        self.ops = []

    def tick(self, what):
        if self.budget is not None and self.used >= self.budget:
            raise PowerCut(what)
        self.used += 1
        self.ops.append(what)

    def open(self, path, mode):
        self.tick("open " + mode)
        if "r" in mode:
            if path not in self.files:
                raise OSError(2, "ENOENT")
            return _Reader(self, self.files[path])
        return _Writer(self, path)

    def remove(self, path):
        self.tick("remove")
        if path not in self.files:
            raise OSError(2, "ENOENT")
        del self.files[path]


class _Reader:
    def __init__(self, fs, data):
        self.fs = fs
        self.data = data

    def read(self, n=-1):  # sequential, as a file's
        self.fs.tick("read")
        d, self.data = (self.data, b"") if n < 0 else (self.data[:n], self.data[n:])
        return d

    def close(self):
        self.fs.tick("close")


class _Writer:
    def __init__(self, fs, path):
        self.fs = fs
        self.path = path
        self.written = bytearray()
        self.old = fs.files.get(path, b"")
        if fs.model not in ("inplace", "cow"):
            fs.files[path] = b""

    def _show(self):
        m = self.fs.model
        if m == "inplace":
            self.fs.files[self.path] = bytes(self.written) + self.old[len(self.written):]
        elif m != "cow":
            self.fs.files[self.path] = bytes(self.written)

    def write(self, data):
        for i, b in enumerate(bytes(data)):
            try:
                self.fs.tick("byte")
            except PowerCut:
                m = self.fs.model
                tail = len(data) - i
                if m == "zeros":
                    self.fs.files[self.path] = bytes(self.written) + bytes(tail)
                elif m == "erased":
                    self.fs.files[self.path] = bytes(self.written) + b"\xff" * tail
                elif m == "garbage":
                    self.fs.files[self.path] = bytes(self.written) + bytes(
                        self.fs.rng.randrange(256) for _ in range(tail))
                raise
            self.written.append(b)
            self._show()
        return len(data)

    def close(self):
        self.fs.tick("close")
        self.fs.files[self.path] = bytes(self.written)


def _store(fs, sensor="qmc5883l", range_code=0):
    return CalStore(directory=DIR, sensor=sensor, range_code=range_code, fs=fs)


def _saved(*payloads):
    """Files after saving payloads in order, without interruption."""
    fs = FakeFs()
    for p in payloads:
        _store(fs).save(p)
    return fs.files


def _load_after_reboot(files):
    st_ = _store(FakeFs(files))
    try:
        return st_.load()
    except StoreError as e:
        return e


INITIAL = {
    "empty": (lambda: {}, None),
    "one_old": (lambda: _saved(OLD), OLD),
    "two_records": (lambda: _saved(b"older", OLD), OLD),
    "three_records": (lambda: _saved(b"first", b"second", OLD), OLD),
    "corrupt_other_slot": (lambda: dict(_saved(OLD), **{PB: b"eCAL\x01\x20" + bytes(90)}), OLD),
    "truncated_newer_slot": (lambda: dict(
        _saved(OLD), **{PB: encode_record(b"x" * 84, "qmc5883l", 0, 99)[:50]}), OLD),
    "other_sensor_newer": (lambda: dict(
        _saved(OLD), **{PB: encode_record(b"hmc", "hmc5883l", 0, 9)}), OLD),
    "seq_wraps": (lambda: {PA: encode_record(OLD, "qmc5883l", 0, 0xFFFFFFFF)}, OLD),
}


# ---------------------------------------------------------------- power cuts

@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("state", sorted(INITIAL))
def test_power_cut_at_every_byte_and_operation_loads_old_or_new_never_garbage(state, model):
    make, old = INITIAL[state]
    full = FakeFs(make(), model=model)
    _store(full).save(NEW)
    units = full.used
    assert units > len(NEW) + 32  # every byte of the record was counted
    seen_new = False
    for k in range(units + 1):
        fs = FakeFs(make(), budget=k, model=model, seed=k)
        try:
            _store(fs).save(NEW)
            done = True
        except PowerCut:
            done = False
        assert done == (k == units)
        got = _load_after_reboot(fs.files)
        if isinstance(got, StoreError):
            assert old is None, (k, got.reason)  # "nothing" only when nothing existed before
            assert not seen_new, k
        else:
            assert got in (old, NEW), (k, got)
            if got == NEW:
                seen_new = True
            else:
                assert not seen_new, k           # once the new one is there, it stays
    assert seen_new


@pytest.mark.parametrize("model", MODELS)
def test_a_chain_of_interrupted_saves_always_loads_the_last_completed_or_the_interrupted(model):
    rng = random.Random(model)
    files = {}
    last_done = None
    for n in range(12):
        payload = bytes([n]) * (20 + n)
        probe = FakeFs(files, model=model)
        _store(probe).save(payload)
        cut = rng.randrange(probe.used + 1) if n % 3 else None
        fs = FakeFs(files, budget=cut, model=model, seed=n)
        try:
            _store(fs).save(payload)
            last_done = payload
        except PowerCut:
            pass
        files = fs.files
        got = _load_after_reboot(files)
        if last_done is None:
            assert isinstance(got, StoreError) or got == payload
            if not isinstance(got, StoreError):
                last_done = payload
        else:
            assert got in (last_done, payload)
            last_done = got


def test_save_writes_the_slot_not_holding_the_current_record_and_reads_it_back():
    fs = FakeFs()
    st_ = _store(fs)
    assert st_.save(b"one") == 1
    assert st_.save(b"two") == 2
    assert st_.save(b"three") == 3
    assert decode_record(fs.files[PA], "qmc5883l", 0) == (3, b"three")
    assert decode_record(fs.files[PB], "qmc5883l", 0) == (2, b"two")
    ops = FakeFs(fs.files)
    _store(ops).save(b"four")
    # scan both slots and probe the (absent) spare, write one, read it back; nothing else
    # (no rename, no remove)
    # (a record is read as its first 8 bytes, which give its length, then the rest)
    assert [o for o in ops.ops if o != "byte"] == ["open rb", "read", "read", "close"] * 2 + [
        "open rb", "open wb", "close", "open rb", "read", "read", "close"]
    assert decode_record(ops.files[PB], "qmc5883l", 0) == (4, b"four")


# ---------------------------------------------------------------- format and refusals

def reference_record(payload, sensor, range_code, seq, version=1, hlen=32):
    """The documented layout, built independently of the module (zlib's CRC-32)."""
    head = struct.pack("<4sBBH16sBBHI", b"eCAL", version, hlen, len(payload),
                       sensor.encode().ljust(16, b"\0"), range_code, 0, 0, seq)
    body = head + bytes(hlen - 32) + payload   # a longer header: a future format's fields
    return body + struct.pack("<I", zlib.crc32(body))


@given(st.binary(max_size=300), st.sampled_from(["qmc5883l", "hmc5883l", "qmc5883p", "x"]),
       st.integers(0, 255), st.integers(0, 0xFFFFFFFF))
def test_record_layout_matches_the_documented_format_and_round_trips(payload, sensor, rng, seq):
    rec = encode_record(payload, sensor, rng, seq)
    assert rec == reference_record(payload, sensor, rng, seq)
    assert decode_record(rec, sensor, rng) == (seq, payload)


def test_crc32_is_the_ieee_crc():
    assert crc32(b"123456789") == 0xCBF43926          # the standard check value
    assert crc32_int(b"123456789") == 0xCBF43926


@given(st.binary(max_size=500), st.integers(0, 0xFFFFFFFF))
def test_integer_crc32_fallback_equals_zlib(data, start):
    assert crc32_int(data) == zlib.crc32(data)
    assert crc32_int(data, start) == zlib.crc32(data, start)
    assert crc32(data) == zlib.crc32(data)


def test_records_are_identical_with_the_fallback_crc(monkeypatch):
    rec = encode_record(OLD, "qmc5883l", 1, 42)
    monkeypatch.setattr(calstore, "_crc32_builtin", None)
    assert encode_record(OLD, "qmc5883l", 1, 42) == rec
    assert decode_record(rec, "qmc5883l", 1) == (42, OLD)


def _refusal(files, sensor="qmc5883l", range_code=0):
    st_ = _store(FakeFs(files), sensor, range_code)
    with pytest.raises(StoreError) as e:
        st_.load()
    return e.value.reason, st_.last_skipped


@pytest.mark.parametrize("content,reason", [
    (None, "missing"),
    (b"", "truncated"),
    (b"eCA", "truncated"),
    (b"PK\x03\x04 this is a zip", "bad_magic"),
    (encode_record(OLD, "qmc5883l", 0, 1)[:-1], "truncated"),
    (encode_record(OLD, "qmc5883l", 0, 1)[:20], "truncated"),
    (encode_record(OLD, "qmc5883l", 0, 1) + b"\0", "bad_length"),
    (encode_record(OLD, "qmc5883l", 0, 1) + bytes(5000), "bad_length"),
    (b"eCAL\x01\x20\xff\xff" + bytes(70000), "truncated"),  # says 64 KB, more than any record
    (encode_record(OLD, "qmc5883l", 0, 1)[:40] + b"X" + encode_record(OLD, "qmc5883l", 0, 1)[41:],
     "bad_crc"),
    (reference_record(OLD, "qmc5883l", 0, 1, version=2), "unknown_version"),
    (reference_record(OLD, "qmc5883l", 0, 1, version=2, hlen=40), "unknown_version"),
    (encode_record(OLD, "hmc5883l", 0, 1), "other_sensor"),
    (encode_record(OLD, "qmc5883l", 1, 1), "other_range"),
])
def test_every_refusal_has_its_named_reason(content, reason):
    files = {} if content is None else {PA: content}
    got, skipped = _refusal(files)
    assert got == reason
    assert skipped == [(PA, reason), (PB, "missing")]


def test_a_record_is_read_in_pieces_no_larger_than_itself_and_one_byte():
    """A board's heap at boot may hold no 4 KB in one piece: the read asks for the 8 bytes that
    give the record's length, then the rest and one byte (never more than one past the
    largest record, whatever a corrupt header says)."""
    sizes = []

    class Sized(FakeFs):
        def open(self, path, mode):
            f = FakeFs.open(self, path, mode)
            if "r" in mode:
                read = f.read
                f.read = lambda n=-1: sizes.append(n) or read(n)
            return f
    rec = encode_record(OLD, "qmc5883l", 0, 1)
    assert _store(Sized({PA: rec})).load() == OLD
    assert sizes == [8, len(rec) - 8 + 1]
    del sizes[:]
    with pytest.raises(StoreError):
        _store(Sized({PA: b"eCAL\x01\x20\xff\xff" + bytes(70000)})).load()
    assert sizes == [8, 32 + MAX_PAYLOAD + 5 - 8]


def test_the_most_telling_reason_is_raised_and_both_are_listed():
    files = {PA: b"garbage!", PB: encode_record(OLD, "hmc5883l", 0, 3)}
    reason, skipped = _refusal(files)
    assert reason == "other_sensor"
    assert skipped == [(PA, "bad_magic"), (PB, "other_sensor")]


def test_load_picks_the_newest_valid_slot_and_says_why_the_other_was_skipped():
    files = {PA: encode_record(b"new", "qmc5883l", 0, 8),
             PB: encode_record(b"old", "qmc5883l", 0, 7)}
    st_ = _store(FakeFs(files))
    assert st_.load() == b"new" and st_.seq == 8 and st_.path == PA
    assert st_.last_skipped == [(PB, "older")]
    st_.fs.files[PA] = files[PA][:-3]
    assert st_.load() == b"old" and st_.seq == 7
    assert st_.last_skipped == [(PA, "truncated")]
    # sequence numbers compare across the 2**32 wrap
    files = {PA: encode_record(b"before", "qmc5883l", 0, 0xFFFFFFFE),
             PB: encode_record(b"after", "qmc5883l", 0, 1)}
    assert _store(FakeFs(files)).load() == b"after"


def test_every_single_bit_flip_is_refused():
    rec = encode_record(OLD, "qmc5883l", 0, 5)
    for i in range(len(rec) * 8):
        bad = bytearray(rec)
        bad[i // 8] ^= 1 << (i % 8)
        with pytest.raises(StoreError) as e:
            decode_record(bytes(bad), "qmc5883l", 0)
        assert e.value.reason in ("bad_crc", "bad_magic", "truncated", "bad_length")


@given(st.binary(max_size=200))
def test_arbitrary_bytes_are_refused_with_a_reason(data):
    with pytest.raises(StoreError) as e:
        decode_record(data, "qmc5883l", 0)
    assert e.value.reason in ("bad_crc", "bad_magic", "truncated", "bad_length")


def test_save_on_top_of_a_corrupt_slot_keeps_the_good_one_and_then_replaces_it():
    files = dict(_saved(OLD), **{PB: b"\xff" * 200})
    fs = FakeFs(files)
    st_ = _store(fs)
    assert st_.load() == OLD
    seq = st_.save(NEW)
    assert decode_record(fs.files[PA], "qmc5883l", 0)[1] == OLD   # the good slot untouched
    assert st_.load() == NEW and st_.seq == seq == 2


def test_a_newer_record_of_another_sensor_is_numbered_past_and_spared_when_possible():
    files = {PA: encode_record(b"hmc", "hmc5883l", 0, 9)}
    fs = FakeFs(files)
    st_ = _store(fs)
    assert st_.save(NEW) == 10
    assert fs.files[PA] == files[PA]          # written to the empty slot
    assert st_.load() == NEW


def test_a_write_that_does_not_stick_is_reported_not_trusted():
    class Lossy(FakeFs):
        def open(self, path, mode):
            f = super().open(path, mode)
            if "w" in mode:
                f.write = lambda data: len(data)   # the flash ignores the write
            return f
    fs = Lossy(_saved(OLD))
    with pytest.raises(StoreError) as e:
        _store(fs).save(NEW)
    assert e.value.reason == "verify_failed"
    assert _store(FakeFs(fs.files)).load() == OLD


def test_filesystem_errors_propagate_and_leave_the_old_record():
    class Full(FakeFs):
        def open(self, path, mode):
            if "w" in mode:
                raise OSError(28, "ENOSPC")
            return super().open(path, mode)
    fs = Full(_saved(OLD))
    with pytest.raises(OSError):
        _store(fs).save(NEW)
    assert _store(FakeFs(fs.files)).load() == OLD


def test_erase_removes_both_slots_older_first():
    fs = FakeFs(_saved(b"a", b"b"))
    st_ = _store(fs)
    st_.erase()
    assert fs.files == {}
    assert _refusal(fs.files)[0] == "missing"
    cut = FakeFs(_saved(b"a", b"b"), budget=9)   # scan (7 ops) + two removes
    with pytest.raises(PowerCut):
        _store(cut).erase()
    assert _store(FakeFs(cut.files)).load() == b"b"   # the newer survives a cut in between
    _store(FakeFs()).erase()                           # nothing to erase is fine


@pytest.mark.parametrize("bad", [
    dict(sensor=""), dict(sensor="a-very-long-sensor-name"), dict(range_code=256),
    dict(range_code=-1)])
def test_bad_store_parameters_are_refused(bad):
    with pytest.raises(ValueError):
        CalStore(fs=FakeFs(), **bad)


def test_payload_size_limits():
    fs = FakeFs()
    st_ = _store(fs)
    st_.save(b"")
    assert st_.load() == b""
    st_.save(bytes(MAX_PAYLOAD))
    assert st_.load() == bytes(MAX_PAYLOAD)
    with pytest.raises(ValueError):
        st_.save(bytes(MAX_PAYLOAD + 1))


def test_paths_in_root_current_and_nested_directories():
    assert CalStore(directory="/").paths == ("/ecompass_a.cal", "/ecompass_b.cal",
                                             "/ecompass_c.cal")
    assert CalStore(directory="").paths == ("ecompass_a.cal", "ecompass_b.cal", "ecompass_c.cal")
    assert CalStore(directory="/flash/", name="c").paths == ("/flash/c_a.cal", "/flash/c_b.cal",
                                                             "/flash/c_c.cal")


def test_real_filesystem_round_trip_on_cpython(tmp_path):
    st_ = CalStore(directory=str(tmp_path))
    with pytest.raises(StoreError) as e:
        st_.load()
    assert e.value.reason == "missing"
    st_.save(OLD)
    st_.save(NEW)
    assert CalStore(directory=str(tmp_path)).load() == NEW
    (tmp_path / "ecompass_b.cal").write_bytes(b"\0" * 50)   # corrupt the newest
    assert CalStore(directory=str(tmp_path)).load() == OLD


# ---------------------------------------------------------------- MicroPython

def test_records_and_crc_bit_identical_on_micropython():
    lines = mp.json_lines(mp.parity(["tests/scenarios/store_parity.py"]))
    # an independent check of one line: the record the scenario prints first
    assert lines[0][1] == reference_record(bytes(range(40)), "qmc5883l", 0, 1).hex()
    assert any(line[0] == "crc" for line in lines)


def test_real_filesystem_round_trip_on_micropython(tmp_path):
    outs = []
    for micro in (False, True):
        d = tmp_path / ("mp" if micro else "cp")
        d.mkdir()
        outs.append(mp.run(["tests/scenarios/store_fs.py", str(d)], micro=micro))
    assert outs[0] == outs[1]
    steps = dict((line[0], line[1:]) for line in mp.json_lines(outs[1]))
    assert steps["empty"] == ["missing"]
    assert steps["saved"] == [1, 2]
    assert steps["load"] == [2, True]
    assert steps["corrupted_newest"] == [1, True, "bad_crc"]
    assert steps["resaved"] == [2, 2, True]  # the torn record had no valid number to pass
    assert steps["erased"] == ["missing"]
