"""Which modules this interpreter compiled from their .py source (firmware.calibrate.calibrator's
compat.compiled_here), and whether calibration mode's release_solver() then keeps the solver: the
solver from the folder given (the repository's sources, or .mpy files), and a module frozen
into the port (asyncio on the unix ports), whose __file__ names a source not on the disk."""
import json
import sys

sys.path.insert(0, sys.argv[1])
from firmware import compat  # noqa: E402
from firmware.calibrate import calibrator

try:
    import asyncio
except ImportError:
    asyncio = None
calibrator._load_solver()
solve = calibrator.solve
calibrator.release_solver()
print(json.dumps({"solve": compat.compiled_here(solve),
                  "frozen": compat.compiled_here(asyncio) if asyncio else None,
                  "kept": "firmware.calibrate.solve" in sys.modules}))
