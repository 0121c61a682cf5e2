"""The two chip tables (firmware/detect.py CHIPS, host_sim/chips.py) name the same chips with
the same facts, and what derives from them (detection, the simulated boards, the CLI lists)
covers every chip (docs/chips.md)."""
import pytest

from firmware import detect
from host_sim import chips
from host_sim.boards import make_board
from desktop import calfile, calopts, demo, serve


def fields(line):
    """A line of firmware/detect.py CHIPS as a dict (its comment says what each field is)."""
    f = line.decode().split()
    assert len(f) == 9, line
    return {"role": f[0], "addresses": tuple(int(a, 16) for a in f[1].split(",")),
            "id_reg": int(f[2], 16), "id": bytes.fromhex(f[3]), "id_name": f[4],
            "module": f[5], "cls": f[5].upper(), "name": f[6], "options": f[7].split(","),
            "behind": () if f[8] == "-" else tuple(f[8].split(","))}


ROWS = [fields(r) for r in detect.CHIPS]
MAG_ROWS = [r for r in ROWS if r["role"] == "M"]
IMU_ROWS = [r for r in ROWS if r["role"] == "I"]
assert len(MAG_ROWS) + len(IMU_ROWS) == len(ROWS)


def test_both_tables_name_the_same_chips():
    assert sorted(r["module"] for r in MAG_ROWS) == sorted(chips.MAG_KINDS)
    assert sorted(r["name"] for r in IMU_ROWS) == sorted(m["name"] for m in chips.IMUS)
    names = {r["name"] for r in IMU_ROWS}
    assert all(set(r["behind"]) <= names for r in MAG_ROWS)


@pytest.mark.parametrize("row", MAG_ROWS, ids=[r["module"] for r in MAG_ROWS])
def test_a_magnetometer_row_agrees_with_the_simulator_and_its_driver(row):
    m = chips.mag(row["module"])
    assert row["name"] == m["name"]
    assert row["addresses"] == m.get("addresses", (m["address"],))
    assert (row["id_reg"], row["id"]) == m["id"]
    cls = detect.driver_class(row["module"], row["cls"])
    assert cls.KIND == m["kind"] and cls.REGISTERS[0] == row["id_reg"] and cls.ID == row["id"]
    # every option the table lets through is one the driver takes
    assert set(row["options"] + ["delay_us", "timeout_us"]) <= set(cls.OPTIONS)
    assert [r[2] for r in m["ranges"]] == list(cls.PER_CODE[1])      # counts per gauss
    assert [r[1] for r in m["ranges"]] == list(range(len(cls.PER_CODE[1])))
    if m["range_option"] is not None:
        assert cls.OPTIONS[0] == m["range_option"]
        assert [r[3] for r in m["ranges"]] == list(cls.TABLES[0])
    assert getattr(cls, "MIRROR", False) == m["mirror"]


@pytest.mark.parametrize("row", IMU_ROWS, ids=[r["name"] for r in IMU_ROWS])
def test_an_accelerometer_row_agrees_with_the_simulator_and_its_driver(row):
    m = [i for i in chips.IMUS if i["name"] == row["name"]][0]
    assert row["addresses"] == m["addresses"] and (row["id_reg"], row["id"]) == m["id"]
    cls = detect.driver_class(row["module"], row["cls"])
    assert set(row["options"]) == set(cls.OPTIONS) and hasattr(cls, "enable_bypass")


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
        a = row["addresses"][0]
        bus = SimI2C(SimClock())
        bus.attach(a, RegisterFile())  # every register reads 0x00
        assert row["id"] != bytes(len(row["id"]))
        with pytest.raises(SensorNotFound) as e:
            detect.detect(bus)
        msg = str(e.value)
        # the first row at an address: its driver's refusal; a later one: the table's ID read
        assert ("no %s at 0x%02X: ID register 0x%02X reads " % (row["cls"], a, row["id_reg"])
                in msg or "0x%02X answers but %s (0x%02X) reads " % (
                    a, row["id_name"], row["id_reg"]) in msg), msg


def test_an_mpu9250_without_its_magnetometer_says_what_answered():
    from firmware.errors import SensorNotFound
    from host_sim.bus import RegisterFile, SimI2C
    from host_sim.clock import SimClock
    from host_sim.mpu6050 import MPU9250Sim
    bus = SimI2C(SimClock())
    imu = MPU9250Sim()
    bus.attach(0x68, imu)
    bus.attach(0x0C, RegisterFile({0x00: 0x12}), gate=imu.bypass_open)  # not an AKM chip
    with pytest.raises(SensorNotFound) as e:
        detect.detect(bus)
    msg = str(e.value)
    assert "0x0C answers but WIA (0x00) reads 0x12, not the AK8963's 0x48" in msg, msg
    assert "no AK09916 at 0x0C" in msg and e.value.found == (0x0C, 0x68)
