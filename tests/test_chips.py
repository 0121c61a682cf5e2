"""The two chip tables (firmware/detect.py CHIPS, host_sim/chips.py) name the same chips with
the same facts, and what derives from them (detection, the simulated boards, the CLI lists)
covers every chip (docs/chips.md)."""
import pytest

from firmware import detect
from host_sim import chips
from host_sim.boards import make_board
from host_sim.cli import calfile, calopts, demo, serve


def _rows(role):
    return [r for r in detect.CHIPS if r[1] == role]


MAG_ROWS = _rows(0)
IMU_ROWS = _rows(1)


def test_both_tables_name_the_same_chips():
    assert sorted(r[0].decode() for r in MAG_ROWS) == sorted(chips.MAG_KINDS)
    assert sorted(r[0].decode() for r in IMU_ROWS) == sorted(m["kind"] for m in chips.IMUS)


@pytest.mark.parametrize("row", MAG_ROWS, ids=[r[0].decode() for r in MAG_ROWS])
def test_a_magnetometer_row_agrees_with_the_simulator_and_its_driver(row):
    m = chips.mag(row[0].decode())
    assert row[2].decode() == m["name"]
    assert row[3] == (m["address"],)
    assert m["id"][0] == row[4] and m["id"][1] in row[6]
    cls = detect.driver_class(row[7], row[8])
    assert cls.KIND == m["kind"]
    # every option the table lets through is one the driver takes
    assert {o.decode() for o in row[9] + detect._COMMON} <= set(cls.OPTIONS)
    assert [r[2] for r in m["ranges"]] == list(cls.PER_CODE[1])      # counts per gauss
    assert [r[1] for r in m["ranges"]] == list(range(len(cls.PER_CODE[1])))
    if m["range_option"] is not None:
        assert cls.OPTIONS[0] == m["range_option"]
        assert [r[3] for r in m["ranges"]] == list(cls.TABLES[0])
    assert cls.MIRROR == m["mirror"]


@pytest.mark.parametrize("row", IMU_ROWS, ids=[r[0].decode() for r in IMU_ROWS])
def test_an_accelerometer_row_agrees_with_the_simulator(row):
    m = chips.imu(row[0].decode())
    assert row[2].decode() == m["name"] and row[3] == m["addresses"]
    assert m["id"][0] == row[4] and m["id"][1] in row[6]
    assert detect.driver_class(row[7], row[8]).__name__ == row[8].decode()


@pytest.mark.parametrize("kind", chips.MAG_KINDS)
def test_each_magnetometer_model_answers_its_id(kind):
    from host_sim.bus import SimI2C
    from host_sim.clock import SimClock
    m = chips.mag(kind)
    bus = SimI2C(SimClock())
    bus.attach(m["address"], chips.model_class(m)())
    reg, want = m["id"]
    assert bus.readfrom_mem(m["address"], reg, len(want)) == want


@pytest.mark.parametrize("name", chips.BOARD_NAMES)
def test_detect_finds_each_simulated_boards_magnetometer(name):
    b = make_board(name)
    mag = detect.detect(b.bus, delay_us=b.sleep_us)
    kind, imu, behind, _, _ = chips.board(name)
    assert mag.KIND == kind and mag.address == b.mag_address
    if imu is not None:
        assert detect.detect_accel(b.bus) is not None


def test_the_cli_lists_derive_from_the_table():
    assert calfile.SENSOR_NAMES == chips.MAG_KINDS
    assert set(calfile.SENSORS) == set(chips.MAG_KINDS)
    assert demo.CHIP_CHOICES == chips.DEMO_CHIPS
    assert set(calopts.BREAKOUTS) == {b[0] for b in chips.BREAKOUTS}
    served = [o for o in serve.parser().options if o.name == "--chip"][0]
    assert tuple(served.choices) == chips.DEMO_CHIPS
    for c in chips.DEMO_CHIPS:
        assert chips.board(chips.demo(c)[0])[0] in chips.MAG_KINDS
    # every magnetometer can be simulated on some board, and every breakout names a chip
    assert {chips.board(b)[0] for b in chips.BOARD_NAMES} == set(chips.MAG_KINDS)
    assert {b[1][0] for b in chips.BREAKOUTS} <= set(chips.MAG_KINDS)


def test_an_unknown_chip_at_a_known_address_is_named_as_such():
    from firmware.errors import SensorNotFound
    from host_sim.bus import RegisterFile, SimI2C
    from host_sim.clock import SimClock
    for row in MAG_ROWS:
        bus = SimI2C(SimClock())
        bus.attach(row[3][0], RegisterFile())  # every register reads 0x00
        if row[6] == (b"\x00",):
            continue
        with pytest.raises(SensorNotFound) as e:
            detect.detect(bus)
        msg = str(e.value)
        # the first row at an address: its driver's refusal; a later one: the table's ID read
        assert ("no %s at 0x%02X: ID register 0x%02X reads " % (row[2].decode(), row[3][0],
                                                               row[4]) in msg
                or "0x%02X answers but %s (0x%02X) reads " % (row[3][0], row[5].decode(),
                                                              row[4]) in msg), msg
        assert row[2].decode() in msg, msg
