# Parity: one simulated session of the app, run on CPython and on MicroPython, must print the
# same lines (ints and strings only). A GY-271 (QMC5883L) + MPU6050 (or the setup argv[1]
# names, app_world.ALL_SETUPS) with strong iron, a 40 s figure-8 with faults on the way (a
# NACK burst, an overflow, a magnet, a reset of the magnetometer), then still, tilted poses.
# Prints per second the heading (KANG), status and progress; every accepted calibration's
# bytes (hex) and the record the store holds; the headings of the still poses.
import json
import sys

sys.path.append("tests/scenarios")
from app_world import inject, make_app, make_sim, mem_store, pose_headings  # noqa: E402

from binascii import hexlify  # noqa: E402

setup = sys.argv[1] if len(sys.argv) > 1 else "gy271"
b = make_sim(setup, seed=5)
b.world.add_magnet((0.0, 90.0, 40.0), 22.0, 25.0, ramp_s=0.3, frame="sensor")
store = mem_store()
app = make_app(b, store=store)
state = {"accepted": 0, "t": 0}
events = [(8000000, "nack"), (12000000, "overflow"), (30000000, "reset")]
end = 40000000
if len(sys.argv) > 2:  # a shorter session: SECONDS, the reset at 3/4 of it
    end = int(sys.argv[2]) * 1000000
    events[2] = (end * 3 // 4, "reset")


def each(a):
    now = b.clock.now_us
    while events and now >= events[0][0]:
        ev = events.pop(0)[1]
        inject(b, ev, a.mag.KIND)
        print(json.dumps(["event", ev, now]))
    if a.accepted != state["accepted"]:
        state["accepted"] = a.accepted
        c = a.calibration
        print(json.dumps(["accepted", now, c.model, c.fit_error, c.samples,
                          hexlify(c.to_bytes()).decode()]))
    if now >= state["t"]:
        state["t"] += 1000000
        p = a.progress()
        print(json.dumps(["t", now // 1000000, a.heading_kang, a.status, p["coverage"],
                          p["samples"], p["model"], p["fit_error"], p["last_reason"]]))


while b.clock.now_us < end:
    app.step()
    each(app)
for pose, hs in pose_headings(app, b):
    print(json.dumps(["pose", [int(v) for v in pose], hs]))
record = hexlify(store.load()).decode()
print(json.dumps(["store", store.seq, record]))
print(json.dumps(["end", app.accepted, app.refused, app.solves, app.slices, app.stored,
                  app.reinits, sorted(app.errors.items())]))
