# Parity on every board: app_parity.py's session (a first calibration through a figure-8 with
# a NACK burst, an overflow, a magnet and a reset of the magnetometer on the way, then still
# tilted poses) on each board of app_world.ALL_SETUPS and PARITY_SETUPS, one after the other in
# this process.
# tests/test_boards_tiers.py runs it on every interpreter and compares the output bit for bit.
# Per board: each status and refusal reason as it changes (with the step), per second a digest
# of every step's heading since the last line, the heading and the status line, every accepted
# calibration's bytes, the headings of the still poses, the store's record and the counters.
# Then the same session with the gyro-aided heading (use_gyro(), docs/gyro.md) on a board of
# each gyroscope driver (GYRO: MPU6050, ICM-20948; the MPU-9250's reads are the MPU6050's),
# with the filter's bias and uncertainty per second.
# argv: [plain] [seed=N] [SECONDS] [SETUP ...]: "plain" gives CompassApp fast=False (the plain
# kernels where the port has the native ones); N the board's seed (5); SECONDS (40) the
# session, its reset at 3/4 of it; SETUP/gyro a session with the gyro.
import json
import sys

sys.path.append("tests/scenarios")
from app_world import (ALL_SETUPS, PARITY_SETUPS, inject, make_app, make_sim,  # noqa: E402
                       mem_store, pose_headings)

from binascii import hexlify  # noqa: E402

from firmware.app import status_line  # noqa: E402

args = sys.argv[1:]
plain = bool(args) and args[0] == "plain"
if plain:
    args = args[1:]
seed = 5
if args and args[0].startswith("seed="):  # another simulated world (noise, sensor seeds)
    seed = int(args.pop(0)[5:])
seconds = int(args[0]) if args else 40
GYRO = ("gy271/gyro", "icm20948/gyro")
boards = args[1:] or sorted(ALL_SETUPS) + sorted(PARITY_SETUPS) + list(GYRO)


def mix(h, v):
    # a digest in 24 bits: h * 31 + v stays a small int on a 32-bit port (below 2**30)
    return (h * 31 + (v & 0xFFFF)) & 0xFFFFFF


def session(setup):
    b = make_sim(setup.split("/")[0], seed=seed)
    b.world.add_magnet((0.0, 90.0, 40.0), 22.0, 25.0, ramp_s=0.3, frame="sensor")
    store = mem_store()
    app = make_app(b, store=store, fast=False if plain else None)
    att = app.use_gyro() if setup.endswith("/gyro") else None
    end = seconds * 1000000
    print(json.dumps(["board", setup, app.mag.KIND, app.accel.NAME]))
    print(json.dumps(["kernels", setup, app.fast]))  # the one line that differs by tier
    events = [(8000000, "nack"), (12000000, "overflow"), (end * 3 // 4, "reset")]
    accepted, next_t, step, digest = 0, 0, 0, 0
    status, reason = None, None
    while b.clock.now_us < end:
        app.step()
        step += 1
        now = b.clock.now_us
        digest = mix(digest, app.heading_kang)
        while events and now >= events[0][0]:
            ev = events.pop(0)[1]
            inject(b, ev, app.mag.KIND)
            print(json.dumps(["event", ev, step, now]))
        if app.status != status or app.last_reason != reason:
            status, reason = app.status, app.last_reason
            print(json.dumps(["status", step, status, reason]))
        if app.accepted != accepted:
            accepted = app.accepted
            c = app.calibration
            print(json.dumps(["accepted", step, now, c.model, c.fit_error, c.samples,
                              c.coverage, hexlify(c.to_bytes()).decode()]))
        if now >= next_t:
            next_t += 1000000
            print(json.dumps(["t", now // 1000000, step, digest, app.heading_kang,
                              status_line(app)] + ([] if att is None else [
                                  list(att.bias), att.uncertainty_cdeg, att.known])))
            digest = 0
    for pose, hs in pose_headings(app, b):
        print(json.dumps(["pose", [int(v) for v in pose], hs, app.status]))
    c = app.pending or app.calibration
    print(json.dumps(["fit", c.model, c.fit_error, c.samples, c.coverage,
                      hexlify(c.to_bytes()).decode()]))
    record = hexlify(store.load()).decode()  # (load() sets .seq)
    print(json.dumps(["store", store.seq, record]))
    print(json.dumps(["end", app.accepted, app.refused, app.solves, app.slices, app.stored,
                      app.reinits, sorted(app.errors.items())]))


for setup in boards:
    session(setup)
