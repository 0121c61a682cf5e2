# MicroPython only: what the field model costs on the heap (docs/field_model.md, `make bench`,
# tests/test_field.py). python -m desktop.benchmarks.fieldheap (one JSON line)
#
# import_bytes     live heap after `import firmware.field.wmm` (its bytecode and constants; the
#                  modules it imports, firmware.trig and firmware.fixedpoint, imported first)
# model_bytes      live heap held by one FieldModel (open file, 12-byte record buffer, weights)
# first_bytes      micropython.mem_total() (every byte allocated, freed or not) across the
#                  first query (includes one-time costs of the first atan2 call)
# query_bytes      the same for each later query, the largest over queries spread over the
#                  globe and the model's life: the result tuple and the call frames MicroPython
#                  takes from the heap (py/objfun.c VM_MAX_STATE_ON_STACK)
import gc
import json
import micropython

import firmware.fixedpoint  # noqa: F401
import firmware.trig  # noqa: F401

mt = micropython.mem_total
gc.collect()
a0 = gc.mem_alloc()
from firmware.field.wmm import FieldModel  # noqa: E402

gc.collect()
a1 = gc.mem_alloc()
model = FieldModel()
gc.collect()
a2 = gc.mem_alloc()

t0 = mt()
model.at(0, 0, 2025000)
first = mt() - t0
worst = 0
lat = -900000000
lon = -1800000000
year = 2025000
for k in range(64):
    t0 = mt()
    model.at(lat, lon, year)
    used = mt() - t0
    if used > worst:
        worst = used
    lat = (lat + 287000003) % 1800000001 - 900000000
    lon = (lon + 541000007) % 3600000001 - 1800000000
    year = 2025000 + (year - 2025000 + 1237) % 5001
print(json.dumps({"import_bytes": a1 - a0, "model_bytes": a2 - a1, "first_bytes": first,
                  "query_bytes": worst}))
