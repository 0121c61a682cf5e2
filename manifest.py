# Freeze the eCompass firmware into a custom MicroPython build (bytecode runs from flash: less RAM).
# In a MicroPython checkout:
#   cd ports/rp2   && make BOARD=RPI_PICO   FROZEN_MANIFEST=/abs/path/to/this/manifest.py
#   cd ports/esp32 && make BOARD=ESP32_GENERIC FROZEN_MANIFEST=/abs/path/to/this/manifest.py
# Then copy only boards/<board>/board.py and boards/main.py to the board's filesystem.
include("$(PORT_DIR)/boards/manifest.py")
package("firmware")
