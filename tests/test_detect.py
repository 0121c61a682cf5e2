"""detect() / detect_accel() on every simulated board, and the shared bounded wait."""
import pytest
from hypothesis import given, settings, strategies as st

from firmware import detect, i2cdevice
from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.hmc5883l import HMC5883L
from firmware.mpu6050 import MPU6050
from firmware.qmc5883l import QMC5883L
from firmware.qmc5883p import QMC5883P
from host_sim import motion
from host_sim.world import World
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from tests import intcheck, mp
from tests.test_qmc5883l import Spy


def _detect(b, **kw):
    return detect.detect(b.bus, delay_us=b.sleep_us, **kw)


@pytest.mark.parametrize("chip,cls,addr", [
    ("qmc5883l", QMC5883L, 0x0D), ("gy271", QMC5883L, 0x0D), ("hmc5883l", HMC5883L, 0x1E),
    ("gy87", HMC5883L, 0x1E), ("gy87-qmc", QMC5883L, 0x0D), ("qmc5883p", QMC5883P, 0x2C)])
def test_detect_returns_the_right_configured_driver(chip, cls, addr):
    b = make_board(chip)
    mag = _detect(b)
    assert type(mag) is cls and mag.address == addr == b.mag_address
    assert mag.KIND == cls.KIND
    assert len(mag.read()) == 3


@pytest.mark.parametrize("chip", ["gy87", "gy87-qmc"])
def test_gy87_magnetometer_is_hidden_until_the_bypass_opens(chip):
    b = make_board(chip)
    before = b.bus.scan()
    assert b.mag_address not in before and 0x68 in before
    mag = _detect(b)
    assert b.mag_address in b.bus.scan() and mag.address == b.mag_address
    assert b.accel.bypass_open()


def test_detect_passes_each_driver_only_its_own_options():
    q = _detect(make_board("qmc5883l"), range=8, gain=5, odr=200)
    h = _detect(make_board("hmc5883l"), range=8, gain=5, rate=75)
    assert (q.counts_per_gauss, h.counts_per_gauss) == (3000, 390)


@pytest.mark.parametrize("chip,options,kind,period", [
    ("gy9250", {"rate": 8}, "ak8963", 125000), ("icm20948", {"rate": 50}, "ak09916", 20000),
    ("lis2mdl", {"odr": 100}, "lis2mdl", 10000)])
def test_an_option_value_only_the_chip_there_takes_is_not_refused_by_another_at_its_address(
        chip, options, kind, period):
    # 0x0C is the AK09916's and the AK8963's, 0x1E the HMC5883L's, LIS3MDL's and LIS2MDL's: a
    # driver tried first there refuses a value the chip there takes (AK8963 rate=8, LIS2MDL
    # odr=100); that is no error unless its own ID register reads its ID
    b = make_board(chip)
    mag = _detect(b, **options)
    assert mag.KIND == kind and b.mag.period_us() == period
    bad = {k: 7 for k in options}      # a value no driver at that address takes
    with pytest.raises(ValueError) as e:
        _detect(make_board(chip), **bad)
    assert mag.__class__.__name__ in str(e.value) and "=7" in str(e.value)


def test_detect_rejects_an_unknown_option():
    with pytest.raises(TypeError) as e:
        detect.detect(make_board("qmc5883l").bus, rnage=8)
    assert "rnage" in str(e.value)


def test_empty_bus_names_every_address_tried_and_that_nothing_answered():
    with pytest.raises(SensorNotFound) as e:
        detect.detect(SimI2C(SimClock()))
    msg = str(e.value)
    for a in ("0x0C", "0x0D", "0x1C", "0x1E", "0x2C", "0x30", "0x68", "0x69"):
        assert a in msg
    for name in ("AK8963", "AK09916", "MPU-9250", "ICM-20948", "QMC5883P", "LIS3MDL",
                 "LIS2MDL", "MMC5603"):
        assert name in msg
    assert "0x1E (HMC5883L, LIS3MDL, LIS2MDL)" in msg
    assert "found nothing" in msg
    assert e.value.tried == (0x0C, 0x0D, 0x1C, 0x1E, 0x2C, 0x30, 0x68, 0x69)
    assert e.value.found == ()
    assert isinstance(e.value, OSError)


def test_wrong_ids_are_reported_with_what_each_address_answered():
    bus = SimI2C(SimClock())
    bus.attach(0x0D, RegisterFile({0x0D: 0x42}))
    bus.attach(0x1E, RegisterFile({0x0A: 0x41, 0x0B: 0x42, 0x0C: 0x43}))
    bus.attach(0x68, RegisterFile({0x75: 0x00}))  # a DS3231 RTC shares 0x68
    with pytest.raises(SensorNotFound) as e:
        detect.detect(bus)
    msg = str(e.value)
    assert "[0x0D, 0x1E, 0x68]" in msg
    assert "reads 0x42" in msg and "0x41 0x42 0x43" in msg and "WHO_AM_I (0x75) reads 0x00" in msg
    assert e.value.found == (0x0D, 0x1E, 0x68)
    assert detect.detect_accel(bus) is None


def test_a_chip_that_answers_the_scan_but_fails_the_probe_is_reported():
    b = make_board("qmc5883l")
    b.bus.inject_nack(after=0, count=50)
    with pytest.raises(SensorNotFound) as e:
        _detect(b)
    assert "0x0D" in str(e.value) and "errno 19" in str(e.value)


@pytest.mark.parametrize("chip,accel", [("gy87", True), ("gy87-qmc", True), ("qmc5883l", False)])
def test_detect_accel(chip, accel):
    b = make_board(chip)
    a = detect.detect_accel(b.bus)
    assert (a is not None) == accel
    if accel:
        assert type(a) is MPU6050 and a.counts_per_g == 16384
        assert not b.accel.asleep()


def test_detect_accel_on_a_board_with_a_separate_gy521():
    b = make_board("hmc5883l", accel=True)
    a = detect.detect_accel(b.bus, accel_range=4)
    assert a.counts_per_g == 8192
    assert type(_detect(b)) is HMC5883L


def test_bus_error_message_names_address_register_errno():
    e = i2cdevice.bus_error(OSError(5), 0x1E, 0x09)
    assert isinstance(e, BusError) and isinstance(e, OSError)
    assert (e.address, e.register, e.errno) == (0x1E, 0x09, 5)
    assert "0x1E" in str(e) and "0x09" in str(e) and "errno 5" in str(e) and "EIO" in str(e)


# -- QMC5883P (the optional driver; its tests live here with detect)

INT16 = st.integers(min_value=-32768, max_value=32767)
_P = {}


def _qmc5883p():
    if not _P:
        b = make_board("qmc5883p")
        _P.update(b=b, d=QMC5883P(b.bus, delay_us=b.sleep_us))
    return _P["b"], _P["d"]


@given(x=INT16, y=INT16, z=INT16)
def test_qmc5883p_every_int16_decodes_lsb_first(x, y, z):
    b, d = _qmc5883p()
    b.mag.inject_raw(x, y, z)
    assert d.read() == (x, y, z)


@pytest.mark.parametrize("rng,cpg", [(2, 15000), (8, 3750), (12, 2500), (30, 1000)])
def test_qmc5883p_physical_axes_heading_east_level(rng, cpg):
    b = make_board("qmc5883p", world=World(motion=motion.still(yaw=90)), noise=False)
    d = QMC5883P(b.bus, range=rng, delay_us=b.sleep_us)
    assert (d.counts_per_gauss, b.mag.counts_per_gauss()) == (cpg, cpg)
    x, y, z = d.read()
    assert abs(x) <= 1 and abs(y - cpg // 4) <= 1 and abs(z + 43301 * cpg // 100000) <= 1


def test_qmc5883p_overflow_standby_and_faults():
    b = make_board("qmc5883p")
    d = QMC5883P(b.bus, range=2, odr=200, delay_us=b.sleep_us)
    b.mag.inject_raw(-40000, 0, 0)
    with pytest.raises(SensorOverflow) as e:
        d.read()
    assert e.value.raw == (-32768, 0, 0) and "0x2C" in str(e.value)
    b.mag.inject_raw(1, 2, 3)
    assert d.read() == (1, 2, 3)
    b.bus.inject_eio(after=0)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (0x2C, 0x09, 5)
    b.bus.writeto_mem(0x2C, 0x0A, b"\x00")  # suspend
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert e.value.waited_us >= d.timeout_us == 20000


def test_qmc5883p_probe_and_init():
    bus = SimI2C(SimClock())
    bus.attach(0x2C, RegisterFile({0x00: 0xFF}))
    with pytest.raises(SensorNotFound) as e:
        QMC5883P(bus)
    assert "0xFF" in str(e.value) and "0x80" in str(e.value)
    b = make_board("qmc5883p")
    spy = Spy(b.bus)
    QMC5883P(spy, range=2, odr=100, osr=4, dsr=2, delay_us=b.sleep_us)
    assert spy.writes == [(0x2C, 0x0B, b"\x80"), (0x2C, 0x0B, bytes([0b1100])),
                          (0x2C, 0x0A, bytes([0b01011001]))]  # DSR 2, OSR 4, 100 Hz, normal


@given(st.binary(min_size=6, max_size=6))
def test_qmc5883p_decode_never_leaves_small_int_range(raw):
    if "chk" not in _P:
        mod, stats = intcheck.load("qmc5883p")
        bus = SimI2C(SimClock())
        bus.attach(0x2C, RegisterFile({0x00: 0x80, 0x09: 0x01}))
        _P["chk"] = (bus, mod.QMC5883P(bus, delay_us=bus.sleep_us), stats)
    bus, d, stats = _P["chk"]
    bus.writeto_mem(0x2C, 0x01, raw)
    out = [0, 0, 0]
    d.read_into(out)
    assert out == [int.from_bytes(raw[i:i + 2], "little", signed=True) for i in (0, 2, 4)]
    assert stats.max_abs < 1 << 30


# -- the bounded wait: counted delays never overshoot by more than one poll

@given(period=st.integers(min_value=1, max_value=1 << 28), polls=st.integers(1, 300))
@settings(max_examples=100)
def test_counted_wait_times_out_after_its_bound_and_stays_small_int(period, polls):
    mod, stats = intcheck.load("i2cdevice")
    bus = SimI2C(SimClock())
    bus.attach(0x0D, RegisterFile())  # status never ready
    poll = max(period >> 4, 250)
    timeout = min(polls * poll, 1 << 29)
    slept = []
    dev = mod.Device(bus, 0x0D, period, delay_us=slept.append, timeout_us=timeout)
    with pytest.raises(DataReadyTimeout) as e:
        dev.wait_ready(0x06, 0x01)
    assert timeout <= e.value.waited_us == sum(slept) < timeout + poll
    assert stats.max_abs < 1 << 30


def test_timeout_out_of_range_is_value_error():
    with pytest.raises(ValueError):
        i2cdevice.Device(SimI2C(SimClock()), 0x0D, 1000, timeout_us=(1 << 29) + 1)


# -- the same scenario on CPython and MicroPython; allocation-free per-sample path

def test_drivers_bit_identical_on_micropython():
    out = [dict(pairs) for pairs in mp.json_lines(mp.parity(["tests/scenarios/drivers_parity.py"]))]
    from host_sim import chips
    kinds = [o["kind"] for o in out if "kind" in o]
    assert kinds == [chips.board(b)[0] for b in chips.BOARD_NAMES]
    n = len(kinds)
    errors = [o["error"] for o in out if "error" in o]
    triggered = len([k for k in kinds if chips.mag(k)["standby"] is None])  # no standby
    assert errors.count("SensorOverflow") == n
    assert errors.count("DataReadyTimeout") == n - triggered
    assert errors.count("BusError") == n and errors.count("SensorNotFound") == 1
    rows = [o["rows"] for o in out if "rows" in o]
    assert len(rows) == n and all(len(r) == 25 and len(set(map(tuple, r))) == 25 for r in rows)


def test_read_into_allocates_nothing_on_micropython():
    out = mp.json_lines(mp.run(["tests/scenarios/drivers_alloc.py"], micro=True))
    rows = [o for o in out if "chip" in o]
    assert len(rows) == 22
    for o in rows:
        assert o["heap_locked_reads"] == o["reads"] == 200, o
        assert o["net_bytes"] == 0, o
        assert o["instrument_bytes"] == 0, o
        # not even a transient frame: the try/except around the bus call is native code
        # (firmware/detect.py), whose frame lives on the C stack
        assert o["frame_bytes"] == 0, o
    timeouts = [o for o in out if "board_timeout_us" in o]
    assert timeouts and timeouts[0]["waited_us"] >= timeouts[0]["board_timeout_us"]
    assert timeouts[0]["elapsed_us"] < timeouts[0]["board_timeout_us"] + 20000


def test_non_bus_errors_carry_no_errno_on_either_interpreter():
    from firmware.errors import DataReadyTimeout, SensorNotFound
    from tests import mp
    code = ("from firmware.errors import DataReadyTimeout, SensorNotFound\n"
            "print(SensorNotFound('x', address=13).errno, DataReadyTimeout('y', 13, 5).errno)")
    assert mp.parity(["-c", code]).strip() == "None None"
    assert SensorNotFound("x").errno is None


@given(st.binary(min_size=6, max_size=6))
def test_int16x3_decode_is_exact_in_both_byte_orders_and_stays_small_int(raw):
    import struct
    mod, stats = intcheck.load("i2cdevice")
    out = [0, 0, 0]
    mod.int16x3_into(raw, out, 0)
    assert tuple(out) == struct.unpack("<hhh", raw)
    mod.int16x3_into(raw, out, 1)
    assert tuple(out) == struct.unpack(">hhh", raw)
    assert stats.max_abs < 1 << 30
