# detect() + reads on every simulated board, and each error path once; run on CPython and
# MicroPython by tests/test_detect.py, which requires identical output. Prints JSON ints only.
import json

from firmware import detect
from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from host_sim import chips, motion
from host_sim.boards import make_board
from host_sim.bus import SimI2C
from host_sim.clock import SimClock
from host_sim.world import World

N = 25


# MicroPython's json.dumps does not keep dict order: print [key, value] pairs.
def emit(*pairs):
    print(json.dumps([[k, list(v) if isinstance(v, tuple) else v] for k, v in pairs]))


FIELDS = {SensorOverflow: ("address", "raw"), BusError: ("address", "register", "errno"),
          DataReadyTimeout: ("address", "waited_us"), SensorNotFound: ("address", "tried", "found")}


def err(e):
    emit(("error", type(e).__name__), *[(k, getattr(e, k)) for k in FIELDS[type(e)]])


for i, chip in enumerate(chips.BOARD_NAMES):  # every simulated board (host_sim/chips.py)
    world = World(motion=motion.figure8(period_s=4), seed=11 + i)
    b = make_board(chip, world=world, seed=11 + i)
    mag = detect.detect(b.bus, delay_us=b.sleep_us)
    acc = detect.detect_accel(b.bus)
    emit(("kind", mag.KIND), ("address", mag.address), ("range_code", mag.range_code),
         ("counts_per_gauss", mag.counts_per_gauss), ("t_us", b.clock.now_us))
    buf = [0, 0, 0]
    a = [0, 0, 0]
    rows = []
    for _ in range(N):
        mag.read_into(buf)
        row = [b.clock.now_us, buf[0], buf[1], buf[2]]
        if acc is not None:
            acc.read_accel_into(a)
            row += [a[0], a[1], a[2]]
        rows.append(row)
    emit(("rows", rows))

    # out of range on every chip (the MMC5603's model takes the field, 16384 counts/G: 8 G)
    b.mag.inject_raw(131072 if mag.KIND == "mmc5603" else 40000, -5, 5)
    try:
        mag.read()
    except SensorOverflow as e:
        err(e)
    b.bus.inject_eio(after=0)
    try:
        mag.read()
    except BusError as e:
        err(e)
    standby = chips.mag(mag.KIND)["standby"]  # no more samples (None: the driver triggers
    if standby is not None:                   # each measurement, no write stops them)
        b.bus.writeto_mem(mag.address, standby[0], standby[1])
        try:
            mag.read()
        except DataReadyTimeout as e:
            err(e)
    emit(("t_us", b.clock.now_us), ("transactions", b.bus.transactions),
         ("skipped", getattr(mag, "skipped", -1)))

try:
    detect.detect(SimI2C(SimClock()))
except SensorNotFound as e:
    err(e)
