"""Store faults: an unreadable slot (EIO, a directory where the file should be), a slot that
refuses writes, a CRC-valid record that means nothing valid, a newest record of an unknown
payload version, a MemoryError while saving. In each, load() falls back to the newest valid
record, saves go on to a healthy slot without touching the current record, and the app
boots and keeps running (step() never raises)."""
import os
import struct
import sys
import zlib

import pytest

from firmware.calibration import Calibration
from firmware.errors import StoreError
from firmware.store import CalStore
from firmware.store_slots import decode_record, encode_record
from tests import mp
from tests.test_store import MODELS, FakeFs, PowerCut

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "scenarios"))
import app_world as W  # noqa: E402
from host_sim import motion  # noqa: E402

PA, PB, PC = "/ecompass_a.cal", "/ecompass_b.cal", "/ecompass_c.cal"
P1 = bytes(range(10, 56))
P2 = bytes(range(60, 106))


def store(fs, validate=None):
    return CalStore("/", sensor="qmc5883l", range_code=0, fs=fs, validate=validate)


def two_saved():
    fs = W.MemFs()
    store(fs).save(P1)   # slot a, seq 1
    store(fs).save(P2)   # slot b, seq 2
    return fs


# ---------------------------------------------------------------- unreadable slots

@pytest.mark.parametrize("kind", ["eio", "dir"])
def test_an_unreadable_newest_slot_falls_back_to_the_older_record(kind):
    fs = two_saved()
    fs.bad[PB] = kind
    st = store(fs)
    assert st.load() == P1 and st.seq == 1
    assert st.last_skipped == [(PB, "io_error")]


@pytest.mark.parametrize("kind", ["eio", "dir", "write_eio"])
@pytest.mark.parametrize("bad", [PA, PB])
def test_saves_go_on_to_healthy_slots_and_never_touch_the_current_record(kind, bad):
    fs = two_saved()
    fs.bad[bad] = kind
    st = store(fs)
    last = None
    failed = 0
    for n in range(6):
        payload = bytes([n]) * 46
        try:
            cur = st.load()
        except StoreError:
            cur = None
        where = st.path
        before = fs.files.get(where)
        try:
            st.save(payload)
            last = payload
        except OSError:
            failed += 1   # a slot that fails only when written is found by writing it once
        assert where is None or fs.files.get(where) == before, n  # current record untouched
        if last is not None:
            assert store(fs).load() == last
        else:
            assert store(fs).load() == cur
    assert failed <= 1 and last == bytes([5]) * 46
    if kind != "write_eio":
        assert failed == 0


def test_with_two_slots_unreadable_the_spare_alone_cannot_be_overwritten():
    fs = two_saved()
    fs.bad[PA] = fs.bad[PB] = "dir"
    st = store(fs)
    assert st.save(P1) == 3        # past both unreadable slots: they may hold 1 and 2
    st2 = store(fs)
    assert st2.load() == P1 and st2.path == PC
    with pytest.raises(OSError):     # the only healthy slot holds the current record
        st.save(P2)
    assert store(fs).load() == P1
    del fs.bad[PB]                   # slot b is readable again, with its older record
    assert store(fs).load() == P1    # numbered past it: it does not win
    assert st.save(P2) == 4 and store(fs).load() == P2


def test_the_spare_slot_keeps_power_safety_at_every_byte():
    # slot b is a directory: the save goes to the spare; a cut anywhere leaves old or new
    for model in MODELS:
        base = FakeFs(model=model)
        CalStore("/", fs=base).save(P1)   # slot a
        probe = _DirFs(base.files, model=model)
        CalStore("/", fs=probe).save(P2)
        seen_new = False
        for k in range(probe.used + 1):
            fs = _DirFs(base.files, budget=k, model=model, seed=k)
            try:
                CalStore("/", fs=fs).save(P2)
            except PowerCut:
                pass
            got = CalStore("/", fs=_DirFs(fs.files)).load()
            assert got in (P1, P2), (model, k)
            assert not (seen_new and got == P1), (model, k)
            seen_new = seen_new or got == P2
            assert PB not in fs.files
        assert seen_new


class _DirFs(FakeFs):
    """FakeFs with a directory at slot b (reads raise EISDIR, writes refuse to open)."""

    def open(self, path, mode):
        if path == PB:
            self.tick("open " + mode)
            raise OSError(21, "EISDIR")
        return super().open(path, mode)


# ---------------------------------------------------------------- meaning, not only CRC

def payload_with(**over):
    """A Calibration payload, packed by hand (firmware/calibration.py's documented layout)
    so that fields the class would refuse can be written."""
    f = dict(version=1, model=10, coverage=80, fit_error=120, samples=200,
             v=(5400, -4200, 3600), invw=(27000, 0, 0, 0, 29000, 0, 0, 0, 28000),
             field=6000, field_out=5900)
    f.update(over)
    return struct.pack("<BBBBHH3i9hii", f["version"], f["model"], f["coverage"], 0,
                       f["fit_error"], f["samples"], *(tuple(f["v"]) + tuple(f["invw"])
                                                       + (f["field"], f["field_out"])))


GOOD = payload_with()


@pytest.mark.parametrize("bad", [payload_with(field=-5), payload_with(coverage=150),
                                 payload_with(version=2), payload_with(model=3),
                                 payload_with(invw=(32767, 32767, 0, 0, 1, 0, 0, 0, 1)),
                                 b"\x07" * 46, b"short"])
def test_a_crc_valid_record_that_means_nothing_valid_never_hides_the_older_one(bad):
    with pytest.raises(ValueError):
        Calibration.from_bytes(bad)
    fs = W.MemFs()
    store(fs).save(GOOD)
    store(fs).save(bad)
    st = store(fs, validate=Calibration.from_bytes)
    assert st.load() == GOOD and st.last_skipped == [(PB, "bad_payload")]
    # and the next save spares the good record, numbered past the refused one
    assert st.save(payload_with(fit_error=90)) == 3
    assert decode_record(fs.files[PA], "qmc5883l", 0) == (1, GOOD)
    # the app boots on it
    b = W.make_sim("gy271", m=motion.still(30.0, 5.0, 0.0), seed=4)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    assert app.load_reason is None and app.calibration.fit_error == 90


def test_a_newer_record_of_an_unknown_store_version_never_hides_an_intact_older_one():
    fs = W.MemFs()
    store(fs).save(GOOD)
    rec = bytearray(encode_record(GOOD, "qmc5883l", 0, 2))
    rec[4] = 2                                     # a future format, intact CRC
    body = bytes(rec[:-4])
    fs.files[PB] = body + struct.pack("<I", zlib.crc32(body))
    b = W.make_sim("gy271", m=motion.still(30.0, 5.0, 0.0), seed=4)
    st = CalStore("/", fs=fs)
    app = W.make_app(b, store=st)
    assert app.load_reason is None and app.calibration == Calibration.from_bytes(GOOD)
    assert st.last_skipped == [(PB, "unknown_version")]
    assert app.step()


def test_every_slot_unusable_boots_uncalibrated_with_the_most_telling_reason():
    fs = W.MemFs()
    store(fs).save(payload_with(field=-1))
    fs.bad[PB] = "eio"
    b = W.make_sim("gy271", m=motion.still(30.0, 5.0, 0.0), seed=4)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    assert app.load_reason == "bad_payload" and app.calibration.model is None
    assert app.step()


# ---------------------------------------------------------------- the app keeps running

def test_memory_error_during_a_save_is_reported_and_retried_never_raised():
    fs = W.MemFs()
    fs.nomem = 0                 # the first write fails for want of a buffer
    b = W.make_sim("gy271", seed=5)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    while not app.accepted:
        app.step()               # never raises
    assert app.save_errors == 1 and app.save_reason == "no_memory" and app.stored == 0
    fs.nomem = None
    W.run_until(app, b, b.clock.now_us / 1e6 + 65)   # the retry after 60 s (or a newer fit)
    assert app.stored >= 1 and app.save_reason is None
    again = W.make_app(W.make_sim("gy271", m=motion.still(), seed=6), store=CalStore("/", fs=fs))
    assert again.calibration == app.calibration


@pytest.mark.parametrize("kind", ["eio", "dir"])
def test_an_app_on_a_store_with_a_broken_slot_boots_calibrates_saves_and_reboots(kind):
    fs = two_saved()
    del fs.files[PA], fs.files[PB]
    fs.bad[PA] = kind
    b = W.make_sim("gy271", seed=8)
    app = W.make_app(b, store=CalStore("/", fs=fs))
    assert app.load_reason == "io_error" and app.calibration.model is None
    W.run_until(app, b, 40)
    assert app.calibration.model == 10 and app.stored >= 2 and app.save_errors == 0
    again = W.make_app(W.make_sim("gy271", m=motion.still(), seed=9), store=CalStore("/", fs=fs))
    assert again.load_reason is None and again.calibration == app.calibration


# ---------------------------------------------------------------- MicroPython

def test_store_faults_scenario_is_identical_on_micropython():
    lines = mp.json_lines(mp.parity(["tests/scenarios/store_faults.py"]))
    got = {line[0]: line[1:] for line in lines}
    assert got["eio_newest"] == [1, "io_error"]
    assert got["dir_saves"] == [[3, 4, 5], "/ecompass_c.cal"]
    assert got["bad_payload"] == [1, "bad_payload"]
    assert got["app_boot"] == [None, 90, True]
    assert got["app_nomem"][0] == "no_memory" and got["app_nomem"][1] >= 1
    assert got["history"][0] == "hard_iron_x"
