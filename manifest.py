# Freeze the eCompass firmware into a custom MicroPython build (bytecode runs from flash: less RAM).
# In a MicroPython checkout:
#   cd ports/rp2   && make BOARD=RPI_PICO   FROZEN_MANIFEST=/abs/path/to/this/manifest.py
#   cd ports/esp32 && make BOARD=ESP32_GENERIC FROZEN_MANIFEST=/abs/path/to/this/manifest.py
# Then copy only boards/<board>/board.py and boards/main.py to the board's filesystem.
# Install what you use: keep in PARTS the parts your board needs ("core" always, and the parts
# each one requires: desktop/packaging.py REQUIRES; docs/design.md gives the heap of each).
# A part is its folder, firmware/PART/ (core: the files at firmware/'s root). The field part's
# table (firmware/field/wmm2025.bin) is a data file, not frozen: copy it to the board and pass
# its path to set_location(table=...).
import os

PARTS = ("core", "calibrate", "motioncal", "field", "calfile")

include("$(PORT_DIR)/boards/manifest.py")
# the manifest runs in its own folder: the parts' files, found in their folders
_files = []
for _dir, _, _names in os.walk("firmware"):
    _rel = os.path.relpath(_dir, "firmware")
    if (_rel.split(os.sep)[0] if _rel != "." else "core") in PARTS:
        _files += [os.path.normpath(os.path.join(_rel, n)) for n in _names if n.endswith(".py")]
package("firmware", files=sorted(_files))
