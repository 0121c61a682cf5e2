"""MPU6050 accelerometer driver against the independent register model (host_sim)."""
import pytest
from hypothesis import example, given, strategies as st

from firmware.errors import BusError, SensorNotFound
from firmware.mpu6050 import MPU6050
from host_sim import motion
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.mpu6050 import MPU6050Sim
from host_sim.world import World
from tests import intcheck

ADDR = 0x68


def accel_board(pose=(0, 0, 0), **kw):
    yaw, pitch, roll = pose
    return make_board("gy87", world=World(motion=motion.still(yaw=yaw, pitch=pitch, roll=roll)),
                      noise=False, **kw)


@pytest.mark.parametrize("rng,cpg", [(2, 16384), (4, 8192), (8, 4096), (16, 2048)])
def test_constructor_wakes_the_chip_and_sets_the_range(rng, cpg):
    b = accel_board()
    assert b.accel.asleep()
    m = MPU6050(b.bus, accel_range=rng)
    assert not b.accel.asleep()
    assert m.counts_per_g == cpg == b.accel.counts_per_g()


# Chip x forward, y left, z up; the accelerometer reads specific force (+1 g on an axis that
# points up). AN4248 eqs. 1-3: Gp = Rx(phi) Ry(theta) (0, 0, 1); the chip reads -Gp mapped
# through (x, -y, -z): (sin theta, cos theta sin phi, cos theta cos phi) in g.
@pytest.mark.parametrize("pose,expect_milli_g", [
    ((0, 0, 0), (0, 0, 1000)),
    ((0, 30, 0), (500, 0, 866)),       # nose up
    ((0, -30, 0), (-500, 0, 866)),     # nose down: a negative x count
    ((0, 0, 30), (0, 500, 866)),       # right side down: chip y (left) points up
    ((0, 0, 180), (0, 0, -1000)),      # upside down
    ((45, 0, -30), (0, -500, 866)),    # yaw does not change gravity
])
@pytest.mark.parametrize("rng", [2, 16])
def test_physical_gravity_signs_and_scale(pose, expect_milli_g, rng):
    b = accel_board(pose)
    m = MPU6050(b.bus, accel_range=rng)
    b.sleep_us(2000)  # awake: samples flow
    got = m.read_accel()
    for g, e in zip(got, expect_milli_g):
        assert abs(g - e * m.counts_per_g // 1000) <= m.counts_per_g // 500 + 1


def test_read_accel_into_fills_lists_and_arrays():
    from array import array
    b = accel_board()
    m = MPU6050(b.bus)
    b.sleep_us(2000)
    for buf in ([0, 0, 0], array("h", [0, 0, 0]), array("i", [0, 0, 0])):
        m.read_accel_into(buf)
        assert list(buf) == list(m.read_accel())


def test_enable_bypass_changes_only_its_two_bits():
    b = make_board("gy87")
    m = MPU6050(b.bus)
    b.bus.writeto_mem(ADDR, 0x6A, bytes([0x24]))  # I2C_MST_EN + another bit
    b.bus.writeto_mem(ADDR, 0x37, bytes([0x10]))  # INT_RD_CLEAR
    assert 0x1E not in b.bus.scan()
    m.enable_bypass()
    assert b.bus.readfrom_mem(ADDR, 0x6A, 1)[0] == 0x04
    assert b.bus.readfrom_mem(ADDR, 0x37, 1)[0] == 0x12
    assert b.accel.bypass_open() and 0x1E in b.bus.scan()


def test_address_0x69_works():
    bus = SimI2C(SimClock())
    bus.attach(0x69, MPU6050Sim(noise=False))
    m = MPU6050(bus, address=0x69)
    assert m.address == 0x69 and m.counts_per_g == 16384


def test_wrong_who_am_i_is_rejected_naming_what_was_read():
    bus = SimI2C(SimClock())
    bus.attach(ADDR, RegisterFile({0x75: 0x70}))  # an MPU6500 answers 0x70
    with pytest.raises(SensorNotFound) as e:
        MPU6050(bus)
    assert "0x70" in str(e.value) and "0x68" in str(e.value) and e.value.address == ADDR


def test_absent_chip_is_sensor_not_found():
    with pytest.raises(SensorNotFound) as e:
        MPU6050(SimI2C(SimClock()))
    assert "0x68" in str(e.value)


@pytest.mark.parametrize("errno", [19, 5])
def test_bus_fault_during_a_read_is_bus_error(errno):
    b = accel_board()
    m = MPU6050(b.bus)
    if errno == 5:
        b.bus.inject_eio()
    else:
        b.bus.inject_nack()
    with pytest.raises(BusError) as e:
        m.read_accel()
    assert (e.value.address, e.value.register, e.value.errno) == (ADDR, 0x3B, errno)


def test_bad_range_is_value_error():
    with pytest.raises(ValueError):
        MPU6050(make_board("gy87").bus, accel_range=3)


# -- decode over every byte pattern (MSB first, hardware.md), small-int bound

_CHECKED = {}


@given(st.binary(min_size=6, max_size=6))
@example(b"\x80\x00\x7f\xff\xff\xff")
def test_decode_msb_first_never_leaves_small_int_range(raw):
    if not _CHECKED:
        mod, stats = intcheck.load("mpu6050")
        bus = SimI2C(SimClock())
        bus.attach(ADDR, RegisterFile({0x75: 0x68}))
        _CHECKED.update(bus=bus, stats=stats, drv=mod.MPU6050(bus))
    bus, d, stats = _CHECKED["bus"], _CHECKED["drv"], _CHECKED["stats"]
    bus.writeto_mem(ADDR, 0x3B, raw)
    out = [0, 0, 0]
    d.read_accel_into(out)
    assert out == [int.from_bytes(raw[i:i + 2], "big", signed=True) for i in (0, 2, 4)]
    assert stats.max_abs < 1 << 30


def _spread(board, drv, n=400):
    import math
    zs = []
    for _ in range(n):
        board.clock.advance(1000)
        zs.append(drv.read_accel()[2])
    m = sum(zs) / n
    return math.sqrt(sum((z - m) ** 2 for z in zs) / (n - 1))


def test_dlpf_option_sets_config_and_its_bandwidth_cuts_the_noise():
    # 400 ug/sqrt(Hz): sqrt(260 / 21) = 3.5 times less noise at the default 21 Hz
    noisy = make_board("gy87", world=World(motion=motion.still()), noise=True)
    quiet = make_board("gy87", world=World(motion=motion.still()), noise=True)
    a = MPU6050(noisy.bus, dlpf=260)
    b = MPU6050(quiet.bus)
    assert b.dlpf == 21 and quiet.bus.readfrom_mem(ADDR, 0x1A, 1) == b"\x04"
    assert noisy.bus.readfrom_mem(ADDR, 0x1A, 1) == b"\x00"
    ratio = _spread(noisy, a) / _spread(quiet, b)
    assert 2.8 < ratio < 4.3, ratio
    with pytest.raises(ValueError, match="dlpf=30"):
        MPU6050(quiet.bus, dlpf=30)


# -- the gyroscope (use_gyro, docs/gyro.md)

@pytest.mark.parametrize("rng,cpd10", [(250, 1310), (500, 655), (1000, 328), (2000, 164)])
def test_gyro_range_sets_gyro_config_and_the_scale(rng, cpd10):
    b = make_board("gy87", world=World(motion=motion.flat_spin(period_s=8)), noise=False)
    m = MPU6050(b.bus, gyro_range=rng)
    assert m.counts_per_dps_x10 == cpd10 and m.gyro_range == rng
    assert b.bus.readfrom_mem(ADDR, 0x1B, 1)[0] == [250, 500, 1000, 2000].index(rng) << 3
    b.sleep_us(2000)
    x, y, z = m.read_gyro()               # +45 deg/s about body z (down); chip z points up
    assert x == 0 and y == 0 and abs(z * 10 + 45 * cpd10) <= 10


def test_bad_gyro_range_names_the_option_and_its_choices():
    with pytest.raises(ValueError, match="gyro_range=300: expected one of 250, 500, 1000, 2000"):
        MPU6050(make_board("gy87").bus, gyro_range=300)


def test_one_burst_reads_accelerometer_temperature_and_gyroscope():
    from array import array
    w = World(motion=motion.flat_spin(period_s=8), temperature_c=30.0)
    b = make_board("gy87", world=w, noise=False)
    m = MPU6050(b.bus)
    b.sleep_us(2000)
    acc, gyr = array("h", [0, 0, 0]), array("h", [0, 0, 0])
    m.read_all_into(acc, gyr)
    assert list(acc) == [0, 0, 16384] and abs(gyr[2] + 45 * 65.5) <= 1
    assert abs(m.temp_cdeg() - 3000) <= 1   # register map 4.18: raw / 340 + 36.53
    # the app's path: sample_into() with .gyro_into set reads the same burst
    m.gyro_into = array("h", [0, 0, 0])
    buf = [0, 0, 0]
    m.read_accel_into(buf)
    assert buf == list(acc) and list(m.gyro_into) == list(gyr)


def test_data_ready_is_set_by_each_sample_and_cleared_by_the_read():
    b = accel_board()
    m = MPU6050(b.bus)
    b.sleep_us(2000)
    assert m.data_ready() is True and m.data_ready() is False
    b.sleep_us(2000)
    assert m.data_ready() is True


def test_a_glitched_gyro_range_fails_config_ok_until_configure():
    b = accel_board()
    m = MPU6050(b.bus)
    assert m.config_ok()
    b.accel.glitch(0x1B, 3 << 3)          # +-2000 deg/s behind the driver's back
    assert not m.config_ok()
    m.configure()
    assert m.config_ok()


# -- the MPU-6500: an MPU-9250 without its magnetometer (WHO_AM_I 0x70, docs/hardware.md), sold
# on many "GY-9250" / "MPU-9250" modules; beside a separate magnetometer it is the board's
# accelerometer

def test_an_mpu6500_is_found_as_the_accelerometer_and_named():
    from firmware import detect
    from firmware.mpu9250 import MPU9250
    b = make_board("qmc5883l", accel="mpu6500")
    assert b.bus.readfrom_mem(ADDR, 0x75, 1) == b"\x70"
    with pytest.raises(SensorNotFound):
        MPU6050(b.bus)                                 # the MPU6050's WHO_AM_I is 0x68
    a = detect.detect_accel(b.bus, accel_range=4)
    assert type(a) is MPU9250 and a.NAME == "MPU-6500" and a.counts_per_g == 8192
    assert not b.accel.asleep() and b.accel.regs[0x1C] == 1 << 3   # ACCEL_CONFIG: +-4 g
    assert detect.detect(b.bus, delay_us=b.sleep_us).KIND == "qmc5883l"


def test_a_board_with_an_mpu6500_and_a_qmc5883l_calibrates_and_gives_tilted_headings():
    from tests.scenarios import app_world as W
    b = make_board("qmc5883l", world=W.make_world(), seed=3, accel="mpu6500")
    app = W.make_app(b)                                # the accelerometer detected
    assert app.accel.NAME == "MPU-6500"
    W.run_until(app, b, 30)
    assert app.calibration.model == 10
    worst = 0
    for pose in W.TILTED_POSES:
        W.hold(b, *pose)
        for _ in range(12):
            app.step()
            worst = max(worst, abs(W.heading_error_cdeg(app, b)))
    assert app.status == "ok" and worst < 300           # every heading within 3 deg


def test_a_board_with_an_mpu6500_boots_naming_it_and_shows_headings(tmp_path):
    # boards/main.py on the simulated desktop board with an MPU-6500 module in place of its
    # GY-521: the calibration program, the restart, the heading from the store
    from tests import mp
    out = mp.run(["tests/scenarios/app_main.py", "boards/main.py", str(tmp_path), "40",
                  "mpu6500"], micro=False).splitlines()
    assert out[0].startswith("eCompass: calibrating (qmc5883l, accelerometer MPU-6500)")
    i = [k for k, ln in enumerate(out) if ln.startswith("restarted at ")][0]
    assert out[i + 1] == "eCompass: qmc5883l, accelerometer MPU-6500, stored calibration: loaded"
    status = [ln for ln in out[i + 2:] if ln.startswith("heading ")]
    assert status and all("model 10 fit" in ln and "---.-" not in ln for ln in status)
