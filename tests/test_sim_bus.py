"""SimI2C: machine.I2C behaviour, bus timing and fault injection (host_sim/bus.py)."""
import pytest
from hypothesis import given, strategies as st

from host_sim.bus import RegisterDevice, RegisterFile, SimI2C
from host_sim.clock import SimClock

ENODEV = 19
EIO = 5


class Recorder(RegisterDevice):
    """Logs what the bus hands the device, to check the wire-level protocol."""

    def __init__(self):
        RegisterDevice.__init__(self)
        self.writes = []
        self.begins = []

    def begin(self, now_us):
        self.begins.append(now_us)

    def write(self, data):
        self.writes.append(bytes(data))
        RegisterDevice.write(self, data)

    def read_reg(self, reg):
        return reg


def bus_with(regs=None, freq=400000):
    bus = SimI2C(SimClock(), freq)
    dev = bus.attach(0x40, RegisterFile(regs or {}))
    return bus, dev


def test_scan_lists_attached_addresses_sorted():
    bus = SimI2C(SimClock())
    for a in (0x77, 0x0D, 0x68, 0x1E):
        bus.attach(a, RegisterFile())
    assert bus.scan() == [0x0D, 0x1E, 0x68, 0x77]


def test_absent_address_raises_enodev_on_every_method():
    bus = SimI2C(SimClock())
    calls = [lambda: bus.readfrom_mem(0x10, 0, 1), lambda: bus.writeto_mem(0x10, 0, b"\x01"),
             lambda: bus.readfrom_mem_into(0x10, 0, bytearray(2)), lambda: bus.readfrom(0x10, 1),
             lambda: bus.readfrom_into(0x10, bytearray(1)), lambda: bus.writeto(0x10, b"\x00"),
             lambda: bus.writevto(0x10, [b"\x00", b"\x01"])]
    for c in calls:
        with pytest.raises(OSError) as e:
            c()
        assert e.value.errno == ENODEV


def test_write_then_read_back_through_register_pointer():
    bus, dev = bus_with()
    bus.writeto_mem(0x40, 0x10, b"\x01\x02\x03")
    assert bus.readfrom_mem(0x40, 0x10, 3) == b"\x01\x02\x03"
    assert bus.writeto(0x40, b"\x11") == 1          # pointer only: one byte ACKed
    assert bus.readfrom(0x40, 2) == b"\x02\x03"     # reads continue from the pointer
    assert isinstance(bus.readfrom_mem(0x40, 0, 1), bytes)


@given(st.integers(0, 255), st.integers(0, 40), st.integers(0, 8))
def test_readfrom_mem_into_fills_callers_buffer_in_place(reg, n, off):
    regs = {}
    for i in range(256):
        regs[i] = (i * 7 + 3) & 0xFF
    bus, dev = bus_with(regs)
    backing = bytearray(b"\xaa" * (n + off + 4))
    mv = memoryview(backing)[off:off + n]
    bus.readfrom_mem_into(0x40, reg, mv)
    assert len(backing) == n + off + 4 and len(mv) == n
    assert bytes(backing[off:off + n]) == bytes(((reg + i) * 7 + 3) & 0xFF for i in range(n))
    assert backing[:off] == b"\xaa" * off and backing[off + n:] == b"\xaa" * 4
    buf = bytearray(n)
    bus.readfrom_mem_into(0x40, reg, buf)
    assert len(buf) == n and bytes(buf) == bytes(backing[off:off + n])


@given(st.lists(st.tuples(st.integers(0, 255), st.binary(min_size=0, max_size=6)), max_size=30))
def test_register_file_behaves_like_a_dict_model(ops):
    bus, dev = bus_with()
    model = bytearray(256)
    for reg, data in ops:
        bus.writeto_mem(0x40, reg, data)
        for i, b in enumerate(data):
            model[(reg + i) & 0xFF] = b
    for reg in range(0, 256, 17):
        assert bus.readfrom_mem(0x40, reg, 1)[0] == model[reg]


def test_addrsize_16_sends_the_memory_address_msb_first():
    bus = SimI2C(SimClock())
    rec = bus.attach(0x50, Recorder())
    bus.readfrom_mem(0x50, 0x1234, 1, addrsize=16)
    bus.writeto_mem(0x50, 0xABCD, b"\x99", addrsize=16)
    assert rec.writes == [b"\x12\x34", b"\xab\xcd\x99"]


def test_bus_time_is_nine_bits_per_byte_plus_start_restart_stop():
    # readfrom_mem of 6 bytes: addr+W, register, addr+R, 6 data = 9 bytes = 81 bits,
    # plus START, repeated START and STOP = 84 bit times; 210 us at 400 kHz, 840 us at 100 kHz.
    for freq, us in ((400000, 210), (100000, 840)):
        bus, dev = bus_with(freq=freq)
        bus.readfrom_mem(0x40, 0, 6)
        assert bus.clock.now_us == us
    # writeto_mem of one byte: addr+W, register, data = 27 bits + START/STOP = 29 bits
    bus, dev = bus_with(freq=100000)
    bus.writeto_mem(0x40, 0, b"\x00")
    assert bus.clock.now_us == 290


def test_bus_time_carries_fractions_without_drift():
    bus, dev = bus_with(freq=400000)
    for _ in range(1000):
        bus.readfrom_mem(0x40, 0, 1)   # 4 bytes = 36 bits + 3 = 39 bits = 97.5 us each
    assert bus.clock.now_us == 97500


def test_device_sees_transaction_start_time():
    bus = SimI2C(SimClock())
    rec = bus.attach(0x50, Recorder())
    bus.sleep_us(1000)
    bus.readfrom_mem(0x50, 0, 1)
    t1 = bus.clock.now_us
    bus.readfrom_mem(0x50, 0, 1)
    assert rec.begins == [1000, t1]


def test_sleep_us_advances_the_shared_clock():
    clock = SimClock()
    bus = SimI2C(clock)
    bus.sleep_us(1234)
    bus.sleep_ms(2)
    assert clock.now_us == 3234


def test_inject_nack_fails_exactly_the_nth_transaction():
    bus, dev = bus_with()
    bus.inject_nack(after=2)
    bus.readfrom_mem(0x40, 0, 1)
    bus.writeto_mem(0x40, 0, b"\x05")
    with pytest.raises(OSError) as e:
        bus.readfrom_mem(0x40, 0, 1)
    assert e.value.errno == ENODEV
    assert bus.readfrom_mem(0x40, 0, 1) == b"\x05"
    assert bus.transactions == 4


def test_inject_nack_count_and_custom_errno():
    bus, dev = bus_with()
    bus.inject_nack(after=0, count=3, errno=EIO)
    errs = []
    for _ in range(5):
        try:
            bus.readfrom_mem(0x40, 0, 1)
            errs.append(0)
        except OSError as e:
            errs.append(e.errno)
    assert errs == [EIO, EIO, EIO, 0, 0]


@given(st.integers(0, 6), st.integers(1, 6))
def test_inject_eio_burst_raises_errno_5_k_times(after, k):
    bus, dev = bus_with()
    bus.inject_eio(after=after, count=k)
    outcome = []
    for _ in range(after + k + 3):
        try:
            bus.readfrom(0x40, 1)
            outcome.append(0)
        except OSError as e:
            outcome.append(e.errno)
    assert outcome == [0] * after + [EIO] * k + [0] * 3


def test_faulted_write_does_not_reach_the_device():
    bus, dev = bus_with()
    bus.inject_nack(after=0)
    with pytest.raises(OSError):
        bus.writeto_mem(0x40, 0x03, b"\x77")
    assert bus.readfrom_mem(0x40, 0x03, 1) == b"\x00"


def test_kill_silences_a_device_until_revived():
    bus, dev = bus_with({0: 0x42})
    bus.kill(0x40)
    assert bus.scan() == []
    with pytest.raises(OSError) as e:
        bus.readfrom_mem(0x40, 0, 1)
    assert e.value.errno == ENODEV
    bus.revive(0x40)
    assert bus.scan() == [0x40] and bus.readfrom_mem(0x40, 0, 1) == b"\x42"


def test_scan_is_neither_counted_nor_faulted():
    bus, dev = bus_with()
    bus.inject_nack(after=0)
    assert bus.scan() == [0x40]
    assert bus.transactions == 0
    with pytest.raises(OSError):
        bus.readfrom_mem(0x40, 0, 1)


def test_gate_hides_a_device_while_closed():
    bus = SimI2C(SimClock())
    state = {"open": False}
    bus.attach(0x1E, RegisterFile({0: 1}), gate=lambda: state["open"])
    assert bus.scan() == []
    with pytest.raises(OSError):
        bus.readfrom_mem(0x1E, 0, 1)
    state["open"] = True
    assert bus.scan() == [0x1E] and bus.readfrom_mem(0x1E, 0, 1) == b"\x01"


def test_trace_records_transactions_when_enabled():
    bus, dev = bus_with()
    bus.trace = []
    bus.writeto_mem(0x40, 2, b"\x09")
    bus.readfrom_mem(0x40, 2, 1)
    assert bus.trace == [("wm", 0x40, 2, b"\x09"), ("rm", 0x40, 2, b"\x09")]


def test_attach_rejects_duplicate_and_non_7bit_addresses():
    bus, dev = bus_with()
    with pytest.raises(ValueError):
        bus.attach(0x40, RegisterFile())
    with pytest.raises(ValueError):
        bus.attach(0x80, RegisterFile())


def test_settle_lets_devices_catch_up_without_a_transaction():
    bus = SimI2C(SimClock())
    rec = bus.attach(0x50, Recorder())
    bus.sleep_us(500)
    bus.settle()
    assert rec.begins == [500] and bus.transactions == 0


def test_per_sample_bus_calls_allocate_nothing_on_micropython():
    from tests import mp
    rows = mp.json_lines(mp.parity(["tests/scenarios/sim_heaplock.py"]))[0]
    assert [r[0] for r in rows] == [0, 0, 0, 0]          # no MemoryError under heap_lock
    assert all(any(r[1:]) for r in rows)                  # and real data came back
