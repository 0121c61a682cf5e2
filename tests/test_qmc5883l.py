"""QMC5883L driver against the independent register model (host_sim), public API only."""
import pytest
from hypothesis import example, given, settings, strategies as st

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.qmc5883l import QMC5883L
from host_sim import motion
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.world import World
from tests import intcheck

INT16 = st.integers(min_value=-32768, max_value=32767)
ADDR = 0x0D


class Spy:
    """Pass-through bus that records every transfer (addr, reg, nbytes)."""

    def __init__(self, bus):
        self.bus = bus
        self.reads = []
        self.writes = []

    def scan(self):
        return self.bus.scan()

    def readfrom_mem_into(self, addr, reg, buf):
        self.reads.append((addr, reg, len(buf)))
        return self.bus.readfrom_mem_into(addr, reg, buf)

    def writeto_mem(self, addr, reg, buf):
        self.writes.append((addr, reg, bytes(buf)))
        return self.bus.writeto_mem(addr, reg, buf)


def board_and_driver(rng=2, odr=50, osr=512, **kw):
    b = make_board("qmc5883l", **kw)
    return b, QMC5883L(b.bus, range=rng, odr=odr, osr=osr, delay_us=b.sleep_us)


@pytest.fixture(scope="module", params=[2, 8])
def qmc(request):
    return board_and_driver(rng=request.param)


# -- decode: byte order and sign extension over the whole int16 range, both ranges

@given(x=INT16, y=INT16, z=INT16)
@example(x=-32768, y=32767, z=-1)
@example(x=127, y=128, z=-129)     # carries across the byte boundary
@example(x=255, y=256, z=-256)
def test_every_int16_decodes_lsb_first_with_sign(qmc, x, y, z):
    b, d = qmc
    b.mag.inject_raw(x, y, z, latch=True)
    assert d.read() == (x, y, z)


@given(x=INT16, y=INT16, z=INT16)
@settings(max_examples=50)
def test_queued_sample_arrives_after_the_data_ready_wait(qmc, x, y, z):
    b, d = qmc
    b.mag.inject_raw(x, y, z)  # the next set the chip latches
    assert d.read() == (x, y, z)


def test_read_into_fills_lists_and_arrays(qmc):
    from array import array
    b, d = qmc
    for buf in ([0, 0, 0], array("h", [0, 0, 0]), array("i", [0, 0, 0])):
        b.mag.inject_raw(-32768, 32767, -1, latch=True)
        d.read_into(buf)
        assert list(buf) == [-32768, 32767, -1]


@pytest.mark.parametrize("rng,cpg,code", [(2, 12000, 0), (8, 3000, 1)])
def test_range_sets_counts_per_gauss_and_range_code(rng, cpg, code):
    b, d = board_and_driver(rng=rng)
    assert (d.counts_per_gauss, d.range_code, d.KIND) == (cpg, code, "qmc5883l")
    assert b.mag.counts_per_gauss() == cpg  # the chip was configured to the same range


@pytest.mark.parametrize("rng", [2, 8])
def test_physical_axes_heading_east_level(rng):
    # Level board heading east, B = 50 uT, inclination 60 deg: body field (0, -25, 43.3) uT
    # (AN4248 eq. 1-3); chip x forward, y left, z up reads (0, +25, -43.3) uT.
    b, d = board_and_driver(rng=rng, world=World(motion=motion.still(yaw=90)), noise=False)
    per_ut = d.counts_per_gauss // 100
    x, y, z = d.read()
    assert abs(x) <= 1
    assert abs(y - 25 * per_ut) <= 1
    assert abs(z + 43301 * per_ut // 1000) <= 2


# -- data-ready wait, data lock, overflow, skipped sets

@pytest.mark.parametrize("odr", [10, 50, 100, 200])
def test_consecutive_reads_are_one_output_period_apart(odr):
    b, d = board_and_driver(odr=odr)
    d.read()
    t0 = b.clock.now_us
    for _ in range(5):
        d.read()
    period = 1000000 // odr
    # each read waits for the next set; polling adds up to 1/16 period plus bus time (the
    # first read's own lag shortens the span by as much)
    lag = period // 16 + 400
    assert 5 * period - lag <= b.clock.now_us - t0 <= 5 * period + lag


def test_partial_read_freezes_the_output_and_the_driver_never_does_one():
    b = make_board("qmc5883l")
    spy = Spy(b.bus)
    d = QMC5883L(spy, delay_us=b.sleep_us)
    del spy.reads[:]  # the probe's register reads
    samples = [d.read() for _ in range(20)]
    assert len(set(samples)) > 1  # fresh, noisy samples: nothing froze
    b.mag.inject_raw(40000, 0, 0)  # overflow path too: data must still be read whole
    with pytest.raises(SensorOverflow):
        d.read()
    data_reads = [r for r in spy.reads if r[1] <= 0x05]
    assert data_reads and all(r == (ADDR, 0x00, 6) for r in data_reads)
    assert all(r in ((ADDR, 0x06, 1), (ADDR, 0x00, 6)) for r in spy.reads)

    # What the driver avoids: a read that stops before 0x05 keeps the lock; no new set latches.
    d.read()
    b.sleep_us(3 * 20000)
    frozen = b.bus.readfrom_mem(ADDR, 0x00, 4)
    b.sleep_us(5 * 20000)
    assert b.bus.readfrom_mem(ADDR, 0x06, 1)[0] & 0x01 == 0  # DRDY never comes back
    assert b.bus.readfrom_mem(ADDR, 0x00, 4) == frozen
    with pytest.raises(DataReadyTimeout):
        d.read()
    b.bus.readfrom_mem(ADDR, 0x05, 1)  # reading 0x05 releases the lock
    d.read()


@given(big=st.integers(min_value=32768, max_value=200000), axis=st.integers(0, 2),
       neg=st.booleans())
@settings(max_examples=30)
def test_overflow_raises_after_the_whole_block_is_read(qmc, big, axis, neg):
    b, d = qmc
    raw = [0, 0, 0]
    raw[axis] = -big - 1 if neg else big  # just outside int16 on either side, or far
    b.mag.inject_raw(*raw, latch=True)
    buf = [7, 7, 7]
    with pytest.raises(SensorOverflow) as e:
        d.read_into(buf)
    assert buf == [7, 7, 7]  # nothing returned as data
    assert e.value.address == ADDR
    assert e.value.raw[axis] == (-32768 if neg else 32767)  # the chip saturates
    assert "0x0D" in str(e.value) and "OVL" in str(e.value)
    b.mag.inject_raw(1, 2, 3)  # the lock was released: the next set arrives
    assert d.read() == (1, 2, 3)


def test_dor_counts_reads_that_found_skipped_sets():
    b, d = board_and_driver(odr=200)
    d.read()
    assert d.skipped == 0
    b.sleep_us(5 * 5000)  # sets complete unread: the chip skips them and sets DOR
    d.read()
    assert d.skipped == 1
    d.read()
    assert d.skipped == 1


# -- bus faults and stuck data-ready

@pytest.mark.parametrize("after,reg", [(0, 0x06), (1, 0x00)])
@pytest.mark.parametrize("errno", [19, 5])
def test_nack_or_eio_becomes_bus_error_naming_address_register_errno(after, reg, errno):
    b, d = board_and_driver()
    b.mag.inject_raw(5, 6, 7, latch=True)
    if errno == 5:
        b.bus.inject_eio(after=after)
    else:
        b.bus.inject_nack(after=after, errno=errno)
    with pytest.raises(BusError) as e:
        d.read()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, reg, errno)
    assert "0x0D" in str(e.value) and ("0x%02X" % reg) in str(e.value)
    assert "errno %d" % errno in str(e.value)
    assert d.read() == (5, 6, 7)  # a failed transfer took nothing: the set is still there


def test_dead_device_raises_bus_error():
    b, d = board_and_driver()
    b.bus.kill(ADDR)
    with pytest.raises(BusError) as e:
        d.read()
    assert e.value.errno == 19 and isinstance(e.value, OSError)


@pytest.mark.parametrize("odr", [10, 200])
def test_standby_chip_times_out_within_the_bound(odr):
    b, d = board_and_driver(odr=odr)
    d.read()
    b.bus.writeto_mem(ADDR, 0x09, b"\x00")  # MODE 00: standby, no more sets
    t0 = b.clock.now_us
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    elapsed = b.clock.now_us - t0
    assert e.value.address == ADDR and e.value.waited_us >= d.timeout_us
    assert d.timeout_us == 2 * (1000000 // odr) + 10000
    # counted delays reach the timeout; each status poll adds its bus time (< 200 us)
    polls = d.timeout_us // max((1000000 // odr) >> 4, 250) + 1
    assert d.timeout_us <= elapsed <= d.timeout_us + polls * 200


def test_timeout_is_configurable():
    b = make_board("qmc5883l")
    d = QMC5883L(b.bus, delay_us=b.sleep_us, timeout_us=3000)
    b.bus.writeto_mem(ADDR, 0x09, b"\x00")
    with pytest.raises(DataReadyTimeout) as e:
        d.read()
    assert 3000 <= e.value.waited_us < 3000 + 1250


# -- probe

def _bus_with(regs):
    bus = SimI2C(SimClock())
    bus.attach(ADDR, RegisterFile(regs))
    return bus


def test_no_chip_raises_sensor_not_found_naming_the_address():
    with pytest.raises(SensorNotFound) as e:
        QMC5883L(SimI2C(SimClock()))
    assert e.value.address == ADDR and "0x0D" in str(e.value)


def test_wrong_id_is_rejected_with_what_was_read():
    with pytest.raises(SensorNotFound) as e:
        QMC5883L(_bus_with({0x0D: 0x12}))
    assert "0x12" in str(e.value) and "0x0D" in str(e.value)


def test_id_0xff_alone_is_not_enough():
    # Everything reads 0xFF, like a bus nobody drives: CTRL1 cannot be in standby after reset.
    with pytest.raises(SensorNotFound) as e:
        QMC5883L(_bus_with({r: 0xFF for r in range(256)}))
    assert "CTRL1" in str(e.value) and "0xFF" in str(e.value)


def test_config_that_does_not_read_back_is_rejected():
    class Stuck(RegisterFile):  # answers ID 0xFF and 0 elsewhere, ignores writes
        def write_reg(self, reg, value):
            pass
    bus = SimI2C(SimClock())
    bus.attach(ADDR, Stuck({0x0D: 0xFF}))
    with pytest.raises(SensorNotFound) as e:
        QMC5883L(bus)
    assert "reads back" in str(e.value)


def test_init_writes_the_documented_registers():
    b = make_board("qmc5883l")
    spy = Spy(b.bus)
    QMC5883L(spy, range=8, odr=200, osr=64, delay_us=b.sleep_us)
    assert spy.writes == [(ADDR, 0x0A, b"\x80"),       # SOFT_RST
                          (ADDR, 0x0B, b"\x01"),       # SET/RESET period
                          (ADDR, 0x0A, b"\x00"),       # INT_ENB = 0 enables DRDY pin
                          (ADDR, 0x09, bytes([0b11011101]))]  # OSR 64, 8 G, 200 Hz, continuous
    # INT_ENB = 0 enables the DRDY pin (peers write 1 and lose it): it rises with a new set
    b.sleep_us(5000 + 1000)
    assert b.bus.readfrom_mem(ADDR, 0x06, 1)[0] & 0x01  # (the model updates on a transaction)
    assert b.mag.drdy_pin()


@pytest.mark.parametrize("kw", [{"range": 4}, {"odr": 60}, {"osr": 100}, {"timeout_us": 0}])
def test_bad_options_raise_value_error_naming_them(kw):
    b = make_board("qmc5883l")
    with pytest.raises(ValueError) as e:
        QMC5883L(b.bus, delay_us=b.sleep_us, **kw)
    assert list(kw)[0] in str(e.value)


# -- small-int bound of the decode path (32-bit MicroPython ports)

_CHECKED = {}


def _checked_driver():
    # A passive register file that satisfies the probe; the data block is rewritten per example.
    if not _CHECKED:
        mod, stats = intcheck.load("qmc5883l")
        bus = SimI2C(SimClock())
        bus.attach(ADDR, RegisterFile({0x0D: 0xFF, 0x06: 0x01}))
        _CHECKED.update(bus=bus, stats=stats, drv=mod.QMC5883L(bus, delay_us=bus.sleep_us))
    return _CHECKED["bus"], _CHECKED["drv"], _CHECKED["stats"]


@given(st.binary(min_size=6, max_size=6))
def test_decode_never_leaves_small_int_range(raw):
    bus, d, stats = _checked_driver()
    bus.writeto_mem(ADDR, 0x00, raw)
    out = [0, 0, 0]
    d.read_into(out)
    assert out == [int.from_bytes(raw[i:i + 2], "little", signed=True) for i in (0, 2, 4)]
    assert stats.max_abs < 1 << 30
