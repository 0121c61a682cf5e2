# The LIS3MDL, LIS2MDL and MMC5603 drivers on their simulated chips (a board turning, Prng
# noise), each error path once; run on CPython and every MicroPython tier by
# tests/test_mags_tiers.py, which requires identical output. Prints JSON ints only.
import json

from firmware.errors import BusError, DataReadyTimeout, SensorNotFound, SensorOverflow
from firmware.lis2mdl import LIS2MDL
from firmware.lis3mdl import LIS3MDL
from firmware.mmc5603 import MMC5603
from host_sim import motion
from host_sim.bus import SimI2C
from host_sim.clock import SimClock
from host_sim.lis2mdl import LIS2MDLSim
from host_sim.lis3mdl import LIS3MDLSim
from host_sim.mmc5603 import MMC5603Sim
from host_sim.world import World

N = 25


# MicroPython's json.dumps does not keep dict order: print [key, value] pairs.
def emit(*pairs):
    print(json.dumps([[k, list(v) if isinstance(v, tuple) else v] for k, v in pairs]))


FIELDS = {SensorOverflow: ("address", "raw"), BusError: ("address", "register", "errno"),
          DataReadyTimeout: ("address", "waited_us"), SensorNotFound: ("address",)}


def err(e):
    emit(("error", type(e).__name__), *[(k, getattr(e, k)) for k in FIELDS[type(e)]])


CHIPS = ((LIS3MDL, LIS3MDLSim, 0x1C, {"range": 8, "odr": 80}, (0x22, b"\x03"), (40000, 0, 0)),
         (LIS2MDL, LIS2MDLSim, 0x1E, {"odr": 100}, (0x60, b"\x83"), (20000, 0, 0)),
         (MMC5603, MMC5603Sim, 0x30, {"range": 4, "bw": 1}, None, (5 * 16384, 0, 0)))

for i, (drv, model, addr, opts, stop, big) in enumerate(CHIPS):
    clock = SimClock()
    bus = SimI2C(clock)
    world = World(hard_iron_ut=(12, -7, 30), motion=motion.figure8(period_s=4), seed=11 + i,
                  temperature_c=31.0)
    chip = bus.attach(addr, model(world, seed=11 + i))
    mag = drv(bus, delay_us=bus.sleep_us, **opts)
    emit(("kind", mag.KIND), ("address", mag.address), ("range_code", mag.range_code),
         ("counts_per_gauss", mag.counts_per_gauss), ("period_us", mag.period_us),
         ("t_us", clock.now_us))
    buf = [0, 0, 0]
    rows = []
    for _ in range(N):
        mag.read_into(buf)
        rows.append([clock.now_us, buf[0], buf[1], buf[2]])
    emit(("rows", rows))
    if mag.KIND == "mmc5603":
        emit(("offset", list(mag.offset)))
    chip.inject_raw(*big)
    try:
        mag.read()
    except SensorOverflow as e:
        err(e)
    bus.inject_eio(after=0)
    try:
        mag.read()
    except BusError as e:
        err(e)
    chip.brown_out()
    emit(("config_ok", mag.config_ok()))
    if stop is not None:
        bus.writeto_mem(addr, stop[0], stop[1])
        try:
            mag.read()
        except DataReadyTimeout as e:
            err(e)
    mag.configure()
    mag.read_into(buf)
    emit(("after", [buf[0], buf[1], buf[2]]), ("t_us", clock.now_us),
         ("transactions", bus.transactions), ("skipped", getattr(mag, "skipped", -1)))
    try:
        drv(SimI2C(SimClock()), addr)
    except SensorNotFound as e:
        err(e)
