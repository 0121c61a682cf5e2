# Calibrator results on CPython and MicroPython must be bit-identical. Two cases:
#   1. synthetic: a QMC5883L on the simulated bus (host_sim), figure-8 motion, hard iron 2.4x
#      the field and a rotated (non-diagonal) soft-iron matrix; every model is solved;
#   2. a real log: every 4th row of datasets/qmc5883l_tomisuarez_filtered.csv (QMC5883L raw
#      counts, 60 s still then turning; datasets/README.md), model 10 and min/max;
#   3. the halves check's integer sums (acceptance.check_consistency's arguments) on that log
#      and on two hard-iron states (the simulated stream, then 10 uT more on x).
# Prints integers only, one JSON list per line (the payload bytes as ints, the fit error...).
import json
import struct
from array import array

from firmware.calibrate.calibrator import Calibrator
from firmware.errors import CalibrationRejected

CPG = 12000                      # QMC5883L counts/G at +-2 G
V_UT = (120.0, -80.0, 40.0)      # hard iron, uT (2.4x a 50 uT field)
W = ((1.1, 0.05, -0.03), (0.05, 0.92, 0.04), (-0.03, 0.04, 1.0))


def sim_raw(n, hard_iron_ut=V_UT, soft_iron=W, seed=3, period_s=30.0, field_ut=50.0,
            dt_us=5000, noise=True):
    """n raw samples (array 'h', 3n) read through the simulated QMC5883L's registers at
    200 Hz (CTRL1 0x0D: continuous, 200 Hz, +-2 G, OSR 512; data LSB first at 0x00)."""
    from host_sim import motion
    from host_sim.boards import make_board
    from host_sim.world import World
    w = World(field_ut=field_ut, inclination_deg=60.0, hard_iron_ut=hard_iron_ut,
              soft_iron=soft_iron, motion=motion.figure8(period_s=period_s))
    b = make_board("qmc5883l", world=w, seed=seed, noise=noise)
    b.bus.writeto_mem(0x0D, 0x0B, b"\x01")
    b.bus.writeto_mem(0x0D, 0x09, b"\x0d")
    raw = array("h", bytearray(6 * n))
    for i in range(n):
        b.clock.advance(dt_us)
        x, y, z = struct.unpack("<hhh", b.bus.readfrom_mem(0x0D, 0x00, 6))
        raw[3 * i] = x
        raw[3 * i + 1] = y
        raw[3 * i + 2] = z
    return raw


def feed(cal, raw):
    kept = 0
    for i in range(len(raw) // 3):
        if cal.add(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]):
            kept += 1
    return kept


def result(cal, model):
    try:
        c = cal.solve(model=model, accept=False)
    except CalibrationRejected as e:
        return [str(model), e.reason]
    return [str(model), list(c.to_bytes()), cal.count, sum(cal.moments.s)]


if __name__ == "__main__":
    raw = sim_raw(6000)
    cal = Calibrator(model=10, counts_per_gauss=CPG)
    kept = feed(cal, raw)
    print(json.dumps([kept, cal.count, cal.separation]))
    for m in ("minmax", 4, 7, 10):
        print(json.dumps(result(cal, m)))
    auto = Calibrator(model=10)           # separation from the data's range (rebuilds)
    feed(auto, raw)
    print(json.dumps([auto.separation, auto.count, result(auto, 10)]))
    log = Calibrator(model=10, capacity=300)
    with open("datasets/qmc5883l_tomisuarez_filtered.csv") as f:
        f.readline()
        for i, line in enumerate(f):
            if i % 4 == 0:  # a 12.5 Hz log of the whole session
                x, y, z = line.strip().split(",")
                log.add(int(x), int(y), int(z))
    print(json.dumps([log.count, result(log, 10), result(log, "minmax")]))
    from firmware.calibrate import acceptance
    seen = []
    check = acceptance.check_consistency

    def spy(*args):
        seen.append(list(args))
        return check(*args)
    acceptance.check_consistency = spy
    two = Calibrator(model=10, counts_per_gauss=CPG)
    feed(two, sim_raw(3000))
    feed(two, sim_raw(3000, hard_iron_ut=(V_UT[0] + 10.0, V_UT[1], V_UT[2]), seed=4))
    log.solve(model=10, accept=False)     # accepted: its halves agree
    print(json.dumps([result(two, 10), seen]))
