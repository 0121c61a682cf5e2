"""firmware/circuitpython/busio_i2c.py: the drivers over CircuitPython's busio.I2C, through a busio-shaped fake
of the simulated bus (tests/busio_fake.py). No CircuitPython interpreter runs here: busio's
semantics (lock before every transfer, RuntimeError without it, OSError on a NACK) come from
its documentation and are what the fake enforces.
"""
import importlib.util
import sys
import time
import types

import pytest

from firmware.app import CompassApp
from firmware.circuitpython.busio_i2c import BusioI2C
from firmware.detect import detect, detect_accel
from firmware.errors import BusError
from firmware.hmc5883l import HMC5883L
from firmware.mpu6050 import MPU6050
from firmware.qmc5883l import QMC5883L
from firmware.qmc5883p import QMC5883P
from host_sim.boards import make_board
from host_sim.bus import RegisterFile
from tests import mp
from tests.busio_fake import FakeBusioI2C
from tests.scenarios import app_world as W

POLL_US = 100   # the adapter's try_lock() poll interval (firmware/circuitpython/busio_i2c.py _LOCK_POLL_US)
BOARDS = [("qmc5883l", True), ("hmc5883l", True), ("qmc5883p", None), ("gy87", None),
          ("gy87-qmc", None)]


def _twins(chip, accel=None, seed=7, **kw):
    """Two identical simulated boards: one read directly, one through fake busio + adapter."""
    direct = make_board(chip, seed=seed, accel=accel)
    via = make_board(chip, seed=seed, accel=accel)
    fake = FakeBusioI2C(via.bus)
    return direct, via, fake, BusioI2C(fake, delay_us=via.sleep_us, **kw)


def _reads(mag, acc, n=30):
    out = []
    for _ in range(n):
        out.append(mag.read())
        if acc is not None:
            out.append(acc.read_accel())
    return out


@pytest.mark.parametrize("chip,accel", BOARDS)
def test_detect_and_reads_through_the_adapter_equal_the_direct_bus(chip, accel):
    direct, via, fake, adapter = _twins(chip, accel)
    m1, a1 = detect(direct.bus, delay_us=direct.sleep_us), detect_accel(direct.bus)
    m2, a2 = detect(adapter, delay_us=via.sleep_us), detect_accel(adapter)
    assert type(m1) is type(m2) and (a1 is None) == (a2 is None)
    s1, s2 = _reads(m1, a1), _reads(m2, a2)
    assert s1 == s2 and len(set(map(tuple, s1))) > 5  # noisy samples: a real comparison
    # the same transactions, so the same simulated time on the wire
    assert direct.clock.now_us == via.clock.now_us
    assert direct.bus.transactions == via.bus.transactions
    assert fake.try_locks > 0 and fake.refused == 0 and not fake.locked


@pytest.mark.parametrize("cls,chip,addr,opts", [
    (QMC5883L, "qmc5883l", 0x0D, {"range": 8, "odr": 100}),
    (HMC5883L, "hmc5883l", 0x1E, {"gain": 2, "rate": 30}),
    (QMC5883P, "qmc5883p", 0x2C, {"range": 8, "odr": 100}),
])
def test_every_magnetometer_driver_configured_by_hand_reads_the_same(cls, chip, addr, opts):
    direct, via, fake, adapter = _twins(chip)
    d1 = cls(direct.bus, address=addr, delay_us=direct.sleep_us, **opts)
    d2 = cls(adapter, address=addr, delay_us=via.sleep_us, **opts)
    assert _reads(d1, None, 20) == _reads(d2, None, 20)
    assert direct.clock.now_us == via.clock.now_us


def test_mpu6050_through_the_adapter_reads_the_same_and_opens_the_bypass():
    direct, via, fake, adapter = _twins("gy87")
    m1, m2 = MPU6050(direct.bus), MPU6050(adapter)
    assert [m1.read_accel() for _ in range(10)] == [m2.read_accel() for _ in range(10)]
    m2.enable_bypass()
    fake.try_lock()
    assert 0x1E in fake.scan()   # the HMC5883L behind the bypass answers now
    fake.unlock()


@pytest.mark.parametrize("errno", [19, 5])
def test_a_nack_becomes_a_bus_error_naming_address_and_register_and_frees_the_lock(errno):
    direct, via, fake, adapter = _twins("qmc5883l")
    mag = detect(adapter, delay_us=via.sleep_us)
    mag.read()
    via.bus.inject_nack(after=0, count=1, errno=errno)
    with pytest.raises(BusError) as e:
        mag.read()
    assert (e.value.errno, e.value.address, e.value.register) == (errno, 0x0D, 0x06)
    assert "0x0D" in str(e.value) and "0x06" in str(e.value)
    assert not fake.locked and fake.try_lock()   # released: free for the next user
    fake.unlock()
    assert len(mag.read()) == 3                  # and the next read works


def test_a_lock_held_by_another_task_gives_etimedout_within_the_bound():
    direct, via, fake, adapter = _twins("qmc5883l", lock_timeout_us=3000)
    mag = detect(adapter, delay_us=via.sleep_us)
    fake.hold(-1)
    t0 = via.clock.now_us
    with pytest.raises(BusError) as e:
        mag.read()
    waited = via.clock.now_us - t0
    assert e.value.errno == 110 and e.value.address == 0x0D and e.value.register == 0x06
    assert "ETIMEDOUT" in str(e.value)
    assert 3000 <= waited < 3000 + POLL_US       # the bound, to one poll
    assert fake.refused == 3000 // POLL_US + 1   # the first try plus one per poll
    assert not fake.locked                       # never taken, never released by us
    fake.release()
    assert len(mag.read()) == 3


def test_a_lock_freed_within_the_bound_is_waited_for_and_the_read_succeeds():
    direct, via, fake, adapter = _twins("qmc5883l")
    mag = detect(adapter, delay_us=via.sleep_us)
    fake.hold(5)
    t0 = via.clock.now_us
    adapter.lock()
    assert via.clock.now_us - t0 == 5 * POLL_US and fake.locked
    fake.unlock()
    fake.hold(5)
    assert len(mag.read()) == 3 and fake.refused == 10 and not fake.locked


def test_the_wait_without_a_clock_counts_polls_on_cpython():
    # delay_us=None on CPython: compat has no ticks_us and sleep_us does nothing, so the bound
    # is counted in polls of _LOCK_POLL_US (as Device counts its data-ready polls)
    fake = FakeBusioI2C(make_board("qmc5883l").bus)
    adapter = BusioI2C(fake, lock_timeout_us=1000)
    fake.hold(-1)
    with pytest.raises(OSError) as e:
        adapter.scan()
    assert e.value.args[0] == 110 and fake.refused == 11


class _Exploding(FakeBusioI2C):
    def writeto_then_readfrom(self, *a, **k):
        raise self.kind("boom")

    def writeto(self, *a, **k):
        raise self.kind("boom")


@pytest.mark.parametrize("kind", [OSError, ValueError, KeyboardInterrupt])
def test_the_lock_is_released_whatever_a_transfer_raises(kind):
    fake = _Exploding(make_board("qmc5883l").bus)
    fake.kind = kind
    adapter = BusioI2C(fake)
    for call in (lambda: adapter.readfrom_mem_into(0x0D, 0, bytearray(6)),
                 lambda: adapter.writeto_mem(0x0D, 0x09, b"\x01")):
        with pytest.raises(kind):
            call()
        assert not fake.locked


def test_the_fake_refuses_what_busio_refuses():
    fake = FakeBusioI2C(make_board("qmc5883l").bus)
    buf = bytearray(1)
    for call in (lambda: fake.scan(), lambda: fake.writeto(0x0D, b"\x0b\x01"),
                 lambda: fake.readfrom_into(0x0D, buf),
                 lambda: fake.writeto_then_readfrom(0x0D, b"\x0d", buf)):
        with pytest.raises(RuntimeError, match="requires lock"):
            call()
    assert fake.try_lock() and not fake.try_lock()   # held: a second try fails, even ours
    fake.writeto_then_readfrom(0x0D, b"\x0d", buf)
    assert buf[0] == 0xFF                            # the QMC5883L's chip ID
    fake.deinit()
    with pytest.raises(ValueError, match="deinitialized"):
        fake.try_lock()


def test_long_writes_go_out_whole_in_one_transaction():
    bus = make_board("qmc5883l").bus
    chip = bus.attach(0x50, RegisterFile())
    fake = FakeBusioI2C(bus)
    adapter = BusioI2C(fake)
    for data in (b"\x07", bytes(range(1, 8)), bytes(range(10, 30))):  # buffer, fallback
        n = bus.transactions
        adapter.writeto_mem(0x50, 0x20, data)
        assert bytes(chip.regs[0x20:0x20 + len(data)]) == data
        assert bus.transactions == n + 1 and not fake.locked


@pytest.mark.parametrize("bad", [0, -1, 1 << 30, 1.5, "5000", None])
def test_lock_timeout_must_be_a_positive_int_of_microseconds(bad):
    with pytest.raises(ValueError, match=r"lock_timeout_us=.*microseconds"):
        BusioI2C(FakeBusioI2C(None), lock_timeout_us=bad)


def test_a_held_lock_during_detect_is_a_bus_error_not_a_missing_sensor():
    fake = FakeBusioI2C(make_board("qmc5883l").bus)
    fake.hold(-1)
    with pytest.raises(BusError) as e:
        detect(BusioI2C(fake, lock_timeout_us=500))
    assert e.value.errno == 110 and "scan" in str(e.value)


def _app(b, bus):
    return CompassApp(bus, mag_axes=W.MAG_AXES, accel_axes=W.ACCEL_AXES,
                      declination_cdeg=W.DECLINATION_CDEG, delay_us=b.sleep_us,
                      ticks_us=b.clock.ticks_us)


def test_the_app_runs_500_steps_through_the_adapter_with_the_same_headings():
    d = W.make_sim("gy271", seed=5)
    v = W.make_sim("gy271", seed=5)
    fake = FakeBusioI2C(v.bus)
    a1, a2 = _app(d, d.bus), _app(v, BusioI2C(fake, delay_us=v.sleep_us))
    h1, h2 = [], []
    for _ in range(500):
        a1.step()
        a2.step()
        h1.append((a1.heading_kang, a1.status))
        h2.append((a2.heading_kang, a2.status))
    assert h1 == h2 and len(set(h for h, _ in h2)) > 50   # a turning board: many headings
    assert a2.accepted == a1.accepted >= 1 and d.clock.now_us == v.clock.now_us
    assert not fake.locked


def test_the_app_rides_out_a_held_lock_and_recovers():
    v = W.make_sim("gy271", seed=5)
    fake = FakeBusioI2C(v.bus)
    app = _app(v, BusioI2C(fake, delay_us=v.sleep_us, lock_timeout_us=2000))
    for _ in range(20):
        app.step()
    fake.hold(-1)
    for _ in range(3):
        assert app.step() is False            # step() never raises
    assert app.status == "bus_error" and app.errors.get("bus_error", 0) >= 3
    fake.release()
    for _ in range(30):
        app.step()
    assert app.status == "ok" and not fake.locked


def _circuitpython_compat(monkeypatch):
    """firmware/compat.py loaded as CircuitPython would see it: a micropython module with
    const, and time without ticks_us/sleep_us but with monotonic_ns (CPython's time has it)."""
    fake = types.ModuleType("micropython")
    fake.const = lambda x: x
    monkeypatch.setitem(sys.modules, "micropython", fake)
    spec = importlib.util.spec_from_file_location("_cp_compat", mp.ROOT + "/firmware/compat.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_compat_gives_circuitpython_a_wrapping_microsecond_clock_and_a_real_sleep(monkeypatch):
    assert not hasattr(time, "ticks_us")
    c = _circuitpython_compat(monkeypatch)
    assert c.ticks_us is not None and c.sleep_us is not c._no_sleep
    t = c.ticks_us()
    assert 0 <= t < 1 << 30
    # MicroPython's ticks_diff: the signed difference modulo 2**30
    assert c.ticks_diff(5, (1 << 30) - 5) == 10 and c.ticks_diff((1 << 30) - 5, 5) == -10
    assert c.ticks_diff(1000, 250) == 750
    t0 = time.perf_counter()
    c.sleep_us(3000)
    assert time.perf_counter() - t0 >= 0.003
    # the CPython compat is unchanged: no clock, so the simulator must bring its own
    from firmware import compat
    assert compat.ticks_us is None


def test_busio_scenario_prints_the_same_on_micropython_and_the_32_bit_tiers():
    script = ["tests/scenarios/busio_parity.py"]
    cp = mp.run(script, micro=False)
    rows = {r[0] + (r[1] if r[0] == "drivers" else ""): r for r in mp.json_lines(cp)}
    for chip, _ in BOARDS:
        r = rows["drivers" + chip]
        assert r[5] is True and r[7] == r[8] and r[11] is False   # same samples and time
    assert rows["app"][1] == rows["app"][2] == 500 and rows["app"][5] == rows["app"][6] >= 1
    assert rows["lock_wait"][3] == 7 * POLL_US
    assert rows["lock_held"][2] == [110, 0x0D, 0x06] and 2000 <= rows["lock_held"][3] < 2100
    assert rows["nack"][1] == [19, 0x0D, 0x06] and rows["nack"][2] is False
    assert rows["no_lock"] == ["no_lock", True]
    ran = []
    for name in ("unix", "wasm", "x86-32"):
        if mp.TIERS[name].available:
            mp.parity_tier(script, name, expected=cp)
            ran.append(name)
    assert "unix" in ran


@pytest.mark.parametrize("name", ["unix", "x86-32"])
def test_a_read_through_the_adapter_allocates_nothing_on_micropython(name):
    if not mp.TIERS[name].available:
        pytest.skip("%s tier: %s" % (name, mp.TIERS[name].reason))
    rows = mp.json_lines(mp.run(["tests/scenarios/busio_alloc.py"], name))
    assert rows[0] == {"instrument_bytes": 0}
    reads = [r for r in rows if "chip" in r]
    assert len(reads) == 16   # 4 chips x lock free/busy x counted/real clock
    for r in reads:
        assert r["mem_total_bytes"] == 0 and r["heap_locked_reads"] == r["reads"], r
        assert r["locked_after"] is False
    assert all(r["refused_polls"] > 0 for r in reads if r["lock"] == "busy")


def test_circuitpython_code_py_runs_the_app_and_boots_with_its_stored_calibration(tmp_path):
    # boards/circuitpython/code.py with stand-ins for CircuitPython's board and busio
    out = mp.run(["tests/scenarios/cpy_code.py", str(tmp_path), "12"], micro=False).splitlines()
    assert out[0] == "eCompass: qmc5883l, accelerometer MPU6050, stored calibration: missing"
    status = [ln for ln in out if ln.startswith("heading ")]
    assert 22 <= len(status) <= 25  # every 0.5 s
    assert "uncalibrated" in status[0] and "model 10 fit" in status[-1]
    assert out[-2:] == ["stopped at 12 s", "busio.I2C [['GP5', 'GP4', 400000]]"]
    # reboot on MicroPython: the calibration saved through CalStore is loaded at once
    out = mp.run(["tests/scenarios/cpy_code.py", str(tmp_path), "2"], micro=True).splitlines()
    assert out[0] == "eCompass: qmc5883l, accelerometer MPU6050, stored calibration: loaded"
    assert "model 10 fit" in out[1]


def _load(path, name):
    spec = importlib.util.spec_from_file_location(name, mp.ROOT + "/" + path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_circuitpython_wiring_uses_the_pico_pins_else_the_feather_scl_sda():
    wiring = _load("boards/circuitpython/wiring.py", "_cp_wiring")
    pico = types.SimpleNamespace(GP4="gp4", GP5="gp5", SCL="scl", SDA="sda")
    feather = types.SimpleNamespace(SCL="scl", SDA="sda", D5="d5")
    assert wiring.pins(pico) == ("gp5", "gp4")
    assert wiring.pins(feather) == ("scl", "sda")


@pytest.mark.parametrize("jumper_level,readonly", [(True, True), (False, False)])
def test_circuitpython_boot_py_lets_code_write_only_with_the_jumper(monkeypatch, jumper_level,
                                                                    readonly):
    calls = []

    class Pin:
        def __init__(self, pin):
            calls.append(("pin", pin))
            self.value = jumper_level   # pulled up: True without the jumper

        def switch_to_input(self, pull=None):
            calls.append(("pull", pull))

        def deinit(self):
            calls.append(("deinit",))

    board = types.SimpleNamespace(GP15="gp15")
    digitalio = types.SimpleNamespace(DigitalInOut=Pin, Pull=types.SimpleNamespace(UP="up"))
    storage = types.SimpleNamespace(remount=lambda path, readonly: calls.append(
        ("remount", path, readonly)))
    monkeypatch.setitem(sys.modules, "board", board)
    monkeypatch.setitem(sys.modules, "digitalio", digitalio)
    monkeypatch.setitem(sys.modules, "storage", storage)
    monkeypatch.setitem(sys.modules, "wiring", _load("boards/circuitpython/wiring.py", "wiring"))
    _load("boards/circuitpython/boot.py", "_cp_boot")
    assert calls == [("pin", "gp15"), ("pull", "up"), ("remount", "/", readonly), ("deinit",)]
