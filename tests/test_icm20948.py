"""The IMUs around the AK chips: the ICM-20948 driver (firmware/icm20948.py) and the MPU6050
driver on an MPU-9250 / MPU-9255, against their register models (host_sim/icm20948.py,
host_sim/mpu6050.py MPU9250Sim), and the AK09916 driver (firmware/ak09916.py) behind the
ICM-20948's bypass."""
import pytest

from firmware.ak09916 import AK09916
from firmware.errors import DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.icm20948 import ICM20948
from firmware.mpu6050 import MPU6050
from firmware.mpu9250 import MPU9250
from host_sim import motion
from host_sim.boards import make_board
from host_sim.bus import RegisterFile, SimI2C
from host_sim.clock import SimClock
from host_sim.mpu6050 import MPU9250Sim
from host_sim.world import World
from tests.test_qmc5883l import Spy


def board(pose=(0, 0, 0), name="icm20948", **kw):
    yaw, pitch, roll = pose
    w = World(field_ut=50.0, inclination_deg=0.0, motion=motion.still(yaw, pitch, roll))
    return make_board(name, world=w, noise=False, **kw)


@pytest.mark.parametrize("rng,cpg", [(2, 16384), (4, 8192), (8, 4096), (16, 2048)])
def test_icm20948_wakes_sets_its_ranges_in_bank_2_and_returns_to_bank_0(rng, cpg):
    b = board()
    assert b.accel.asleep()
    m = ICM20948(b.bus, accel_range=rng, gyro_range=1000)
    assert not b.accel.asleep() and b.accel.bank == 0
    assert m.counts_per_g == cpg == b.accel.counts_per_g() and m.counts_per_dps_x10 == 328
    assert m.config_ok() and b.accel.bank == 0


@pytest.mark.parametrize("pose,expect_milli_g", [
    ((0, 0, 0), (0, 0, 1000)), ((0, 30, 0), (500, 0, 866)), ((0, 0, 30), (0, 500, 866)),
    ((0, 0, 180), (0, 0, -1000))])
def test_icm20948_gravity_signs_and_scale(pose, expect_milli_g):
    b = board(pose)
    m = ICM20948(b.bus)
    b.sleep_us(2000)
    for g, e in zip(m.read_accel(), expect_milli_g):
        assert abs(g - e * m.counts_per_g // 1000) <= m.counts_per_g // 500 + 1


def test_icm20948_burst_reads_gyroscope_and_temperature_in_its_order():
    from array import array
    w = World(motion=motion.flat_spin(period_s=4))   # 90 deg/s about the vertical
    b = make_board("icm20948", world=w, noise=False)
    m = ICM20948(b.bus)
    b.sleep_us(5000)
    acc, gyro = array("h", [0, 0, 0]), array("h", [0, 0, 0])
    m.read_all_into(acc, gyro)
    assert abs(acc[2] - 16384) < 400
    assert abs(abs(gyro[2]) - 90 * 655 // 10) <= 70 and abs(gyro[0]) < 70
    assert abs(m.temp_cdeg() - round(b.world.temperature_c * 100)) <= 1
    m.gyro_into = array("h", [0, 0, 0])
    m.read_accel_into(acc)       # use_gyro(): the accelerometer's read brings the gyroscope
    assert abs(m.gyro_into[2]) > 5000


def test_icm20948_start_up_and_bypass():
    b = board()
    spy = Spy(b.bus)
    m = ICM20948(spy, dlpf=12)
    assert spy.writes == [(0x68, 0x7F, b"\x00"), (0x68, 0x06, b"\x01"), (0x68, 0x07, b"\x00"),
                          (0x68, 0x7F, b"\x20"), (0x68, 0x14, bytes([5 << 3 | 1])),
                          (0x68, 0x01, bytes([5 << 3 | 1 << 1 | 1])), (0x68, 0x7F, b"\x00")]
    assert 0x0C not in b.bus.scan()
    m.enable_bypass()
    assert 0x0C in b.bus.scan() and b.accel.bypass_open()


def test_icm20948_reset_glitch_and_wrong_chip():
    b = board()
    m = ICM20948(b.bus)
    b.accel.brown_out()
    assert not m.config_ok()
    m.configure()
    assert m.config_ok()
    b.accel.glitch(2, 0x14, 0x07)   # a range flipped behind the driver's back
    assert not m.config_ok() and b.accel.bank == 0
    bus = SimI2C(SimClock())
    bus.attach(0x68, RegisterFile({0x00: 0x68}))
    with pytest.raises(SensorNotFound) as e:
        ICM20948(bus)
    assert "0xEA" in str(e.value)
    with pytest.raises(ValueError) as e:
        ICM20948(b.bus, dlpf=21)
    assert "dlpf=21" in str(e.value)


@pytest.mark.parametrize("who,name", [(0x71, "MPU-9250"), (0x73, "MPU-9255"), (0x70, "MPU-6500")])
def test_an_mpu9250_runs_as_an_mpu6050_with_its_accelerometer_filter(who, name):
    bus = SimI2C(SimClock())
    w = World(motion=motion.still(0, 30, 0))
    imu = MPU9250Sim(w, noise=False, who_am_i=who)
    bus.attach(0x68, imu)
    with pytest.raises(SensorNotFound):
        MPU6050(bus)                                  # its WHO_AM_I is not the MPU6050's
    m = MPU9250(bus, dlpf=10)
    assert m.who_am_i == who and m.NAME == name and m.config_ok()
    assert imu.regs[0x1D] == 5 and imu.regs[0x1A] == 5   # ACCEL_CONFIG2 and CONFIG: code 5
    bus.sleep_us(2000)
    x, y, z = m.read_accel()
    assert abs(x - 8192) < 40 and abs(z - 14189) < 40
    m.gyro_into = [0, 0, 0]
    m.read_accel_into([0, 0, 0])
    assert abs(m.temp_cdeg() - 2500) <= 1            # 25 C, raw / 333.87 + 21
    bus2 = SimI2C(SimClock())
    bus2.attach(0x68, RegisterFile({0x75: 0x72}))     # not one of the family
    with pytest.raises(SensorNotFound) as e:
        MPU9250(bus2)
    assert "0x72" in str(e.value) and "0x71 (MPU-9250)" in str(e.value)
    assert "0x70 (MPU-6500)" in str(e.value)
    imu.brown_out()
    assert not m.config_ok()
    m.configure()
    assert m.config_ok() and imu.regs[0x1D] == 5


# -- the AK09916 behind the ICM-20948's bypass

def ak(yaw=0.0, world=None):
    b = board((yaw, 0, 0)) if world is None else make_board("icm20948", world=world,
                                                               noise=False)
    ICM20948(b.bus).enable_bypass()
    return b, AK09916(b.bus, delay_us=b.sleep_us)


def test_ak09916_reads_the_field_in_its_axes():
    # north along the board's x: the AK09916's x (its y and z are the ICM-20948's -y, -z)
    b, d = ak(0)
    assert (d.KIND, d.counts_per_gauss, d.period_us) == ("ak09916", 667, 10000)
    x, y, z = d.read()
    assert abs(x - 333) <= 1 and abs(y) <= 1 and abs(z) <= 1
    b, d = ak(90)   # facing east: north is on the board's left, the chip's -y
    x, y, z = d.read()
    assert abs(x) <= 1 and abs(y + 333) <= 1


def test_ak09916_start_up_soft_resets_then_starts_continuous_mode_4():
    b = board()
    ICM20948(b.bus).enable_bypass()
    spy = Spy(b.bus)
    AK09916(spy, rate=50, delay_us=b.sleep_us)
    assert spy.writes == [(0x0C, 0x32, b"\x01"), (0x0C, 0x31, b"\x06")]


def test_ak09916_overflow_skips_and_power_down():
    w = World(field_ut=50.0, motion=motion.still())
    w.add_magnet((3000.0, 0.0, 2000.0), 1.0, 100.0, ramp_s=0.0)
    b, d = ak(world=w)
    d.read()
    b.sleep_us(35000)
    d.read()
    assert d.skipped == 1
    b.sleep_us(1000000)
    with pytest.raises(SensorOverflow) as e:
        d.read()
    assert "HOFL" in str(e.value)
    b.bus.writeto_mem(0x0C, 0x31, b"\x00")
    with pytest.raises(DataReadyTimeout):
        d.read()
    assert not d.config_ok()
    d.configure()
    assert d.config_ok()


def test_ak09916_refuses_an_ak8963():
    b = make_board("gy9250")
    MPU9250(b.bus).enable_bypass()
    with pytest.raises(SensorNotFound) as e:
        AK09916(b.bus, delay_us=b.sleep_us)
    assert "0x48 0x09" in str(e.value)
