# CPython and MicroPython must print the same integers: field-model queries at points and
# dates from an integer generator (no float, no random module: identical on both).
import json

from firmware.field.wmm import FieldModel, decimal_year_e3

model = FieldModel()
x = 12345
for k in range(300):
    x = (x * 1103515245 + 12345) % 2147483648
    lat = x % 1800000001 - 900000000
    x = (x * 1103515245 + 12345) % 2147483648
    lon = x % 3600000001 - 1800000000
    x = (x * 1103515245 + 12345) % 2147483648
    year = 2025000 + x % 5001
    d, i, f, s = model.at(lat, lon, year)
    print(json.dumps([lat, lon, year, d, i, f, s, model.declination_kang, model.inclination_kang,
                      model.north_nt, model.east_nt, model.down_nt, model.horizontal_nt]))
print(json.dumps([model.at(0, 0, None), model.at(0, 0, 2030001), decimal_year_e3(2028, 2, 29)]))
model.close()
