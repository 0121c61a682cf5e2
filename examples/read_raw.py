"""Read raw samples: find the compass chip and print what it measures.

    python3 examples/read_raw.py [N]              # on the host (simulated GY-271 + GY-521)
    from examples.read_raw import read; read()    # on a board

Raw int16 counts in the chip's own axes; counts_per_gauss says the scale (1 G = 100 uT).
"""
import sys

try:
    from examples.bus import get_bus
except ImportError:  # run as a script, python examples/X.py: the folder above examples/
    sys.path.insert(0, sys.path[0] + "/..")
    from examples.bus import get_bus
from firmware.detect import detect, detect_accel


def read(n=5, seed=1):
    i2c, delay_us = get_bus(seed)
    mag = detect(i2c, delay_us=delay_us) if delay_us else detect(i2c)
    acc = detect_accel(i2c)
    print("%s at 0x%02X, %d counts/G; accelerometer: %s" % (
        mag.KIND, mag.address, mag.counts_per_gauss, "MPU6050" if acc else "none"))
    buf = [0, 0, 0]
    out = []
    for _ in range(n):
        mag.read_into(buf)
        a = acc.read_accel() if acc else (0, 0, 0)
        print("mag %6d %6d %6d   accel %6d %6d %6d" % (buf[0], buf[1], buf[2], a[0], a[1], a[2]))
        out.append((buf[0], buf[1], buf[2]))
    return out


if __name__ == "__main__":
    read(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
