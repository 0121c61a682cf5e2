"""A calibrated GY-87 (the QMC5883L clone: MPU6050 + magnetometer behind its bypass) in a
world without iron, for the gyro-aided heading's scenarios (benchmarks/gyroacc.py for make
bench, tests/test_gyro.py):
its calibration is the exact one (identity InvW, no offset), stored, so the app starts
calibrated and only the heading path runs."""
from host_sim.boards import make_board
from host_sim.world import World

from desktop.memfs import MemFs

from firmware.app import CompassApp
from firmware.calibration import Calibration
from firmware.store import CalStore

B_COUNTS = 6000  # 50 uT at the QMC5883L's 2 G range (12000 counts/G)


def board(motion=None, seed=5, gyro=None, inclination_deg=60.0):
    w = World(field_ut=50.0, inclination_deg=inclination_deg, motion=motion)
    return make_board("gy87-qmc", world=w, seed=seed, gyro=gyro)


def app(b, gyro=True, **options):
    fs = MemFs()
    CalStore("/", sensor="qmc5883l", range_code=0, fs=fs).save(Calibration(
        model=10, offset=(0, 0, 0), invw=(32767, 0, 0, 0, 32767, 0, 0, 0, 32767),
        field=B_COUNTS, field_out=B_COUNTS - 1, fit_error=50, samples=300,
        coverage=90).to_bytes())
    a = CompassApp(b.bus, mag_axes="x,-y,-z", accel_axes="-x,y,z", delay_us=b.sleep_us,
                   ticks_us=b.clock.ticks_us, store=CalStore("/", fs=fs), learn=False)
    if gyro:
        a.use_gyro(**options)
    return a


def err_deg(app, b):
    """The app's heading minus the true one, degrees in -180..180."""
    truth = b.world.magnetic_heading_deg(b.clock.now_us)
    return (app.heading_kang * 360.0 / 65536 - truth + 180.0) % 360.0 - 180.0


def run(app, b, until_s, each=None):
    end = int(until_s * 1000000)
    while b.clock.now_us < end:
        app.step()
        if each is not None:
            each(app)
