"""The simulated board of the desktop: a GY-271 (QMC5883L) and a GY-521 (MPU6050) on host_sim's
I2C bus, in a world with strong hard and soft iron, the user doing a figure-8.
It is what `make run` and the demo use in place of boards/esp32 or boards/rp2040.

    import board                      # boards/host on the path, or: from boards.host import board
    i2c = board.make_i2c()            # host_sim SimI2C; board.sim is the host_sim Board
    app = CompassApp(i2c, delay_us=board.delay_us, ticks_us=board.ticks_us, ...)

delay_us advances the simulated clock (the drivers' waits), ticks_us reads it: simulated time
moves only through the bus and these sleeps, so a run repeats bit for bit.
"""
from host_sim import motion
from host_sim.boards import make_board
from host_sim.world import World

CHIP = "gy271"              # host_sim.boards chip; ACCEL adds a GY-521 module
ACCEL = True
SEED = 1
MAG_AXES = "x,-y,-z"        # the GY-271 flat, X arrow forward (boards/breakouts.py)
ACCEL_AXES = "-x,y,z"       # GY-521 lying like the breakout (x forward, y left, z up)
DECLINATION_CDEG = 0
MODE = "compass"            # "compass": headings, self-calibrating; "motioncal": stream to
#                             PJRC MotionCal and take its Send Cal (docs/motioncal.md)
GYRO = False                # True: the MPU6050's gyroscope holds the heading through magnets
#                             and fast turns (docs/gyro.md; package-gyro.json installed)
CALIBRATE = "auto"          # "auto": a board without a good stored calibration runs the
#                             calibration program at boot; "never": it never calibrates itself
STORE_DIR = "build"         # the calibration record (build/ecompass_a.cal, _b.cal)
# Strong iron: |V| = 1.4 Earth fields, soft iron with eigenvalues ~0.85..1.2 and shear.
HARD_IRON_UT = (40.0, -30.0, 25.0)
SOFT_IRON = ((1.15, 0.08, -0.05), (0.08, 0.9, 0.06), (-0.05, 0.06, 1.05))

sim = None                  # the host_sim Board made by make_i2c()


def make_world(seed=SEED):
    return World(field_ut=50.0, inclination_deg=60.0, hard_iron_ut=HARD_IRON_UT,
                 soft_iron=SOFT_IRON, motion=motion.figure8(), seed=seed)


def make_i2c(seed=SEED, chip=CHIP, world=None):
    """A fresh simulated board; returns its bus (a machine.I2C look-alike)."""
    global sim
    sim = make_board(chip, world=world if world is not None else make_world(seed),
                     seed=seed, accel=ACCEL if chip not in ("gy87", "gy87-qmc") else None)
    return sim.bus


def delay_us(us):
    sim.bus.sleep_us(us)


def ticks_us():
    return sim.clock.now_us
