# The attitude filter (firmware/gyro/attitude.py) over integer inputs (attitude_inputs): the
# heading, tilt, bias, source, how well the bias is known and the filter's gravity every 50
# samples; every tier prints the same JSON lines.
import json

from tests.scenarios import attitude_inputs as I

from array import array

from firmware.gyro import attitude

a, gyro, grav, field, c = I.filter()
own = array("h", (0, 0, 0))
rows = []
for i in range(1500):
    I.step(i, gyro, grav, field)
    c.update(field, grav)
    h = a.update(20000, I.flags(i))
    if i % 50 == 0:
        b = a.bias
        attitude.gravity(a.st, own)  # the filter's gravity, as the app's checks see it
        rows.append([i, h, a.pitch_kang, a.roll_kang, b[0], b[1], b[2], a.since_mag_us,
                     a.heading_error_kang, a.bias_estimates, a.uncertainty_cdeg, a.bias_cdps,
                     a.known, own[0], own[1], own[2]])
print(json.dumps({"name": "attitude", "rows": rows}))
# a slow loop: 0.1 s between samples (several integration chunks each)
for i in range(100):
    I.step(i * 5, gyro, grav, field)
    h = a.update(100000, 7)
print(json.dumps({"name": "slow", "v": [h, a.pitch_kang, a.roll_kang, a.heading_error_kang]}))
