# Runs boards/circuitpython/code.py as CircuitPython would, for argv[2] simulated seconds with
# the calibration record in directory argv[1]: CircuitPython's `board` (pin names) and `busio`
# (I2C) modules are stand-ins here, busio.I2C being tests/busio_fake.py over the simulated
# desktop board (boards/host/board.py). Prints code.py's output, then the pins and frequency
# busio.I2C was given. Stops code.py by raising StopRun from the drivers' delay.
import sys

sys.path.insert(0, "boards/host")
import board as host  # noqa: E402

del sys.modules["board"]
sys.path.pop(0)
sys.path.insert(0, "boards/circuitpython")

from tests.busio_fake import FakeBusioI2C  # noqa: E402


class Pins:
    """CircuitPython's board module of a Raspberry Pi Pico (pins as names)."""
    GP4 = "GP4"
    GP5 = "GP5"
    SCL = "SCL"
    SDA = "SDA"


class Busio:
    made = []

    @staticmethod
    def I2C(scl, sda, frequency=100000):
        Busio.made.append([scl, sda, frequency])
        return FakeBusioI2C(host.make_i2c())


class StopRun(BaseException):  # past step()'s guard, which turns an Exception into a status
    pass


sys.modules["board"] = Pins
sys.modules["busio"] = Busio
import wiring  # noqa: E402

store_dir, seconds = sys.argv[1], int(sys.argv[2])
wiring.STORE_DIR = store_dir


def delay_us(us):
    if host.ticks_us() >= seconds * 1000000:
        raise StopRun()
    host.delay_us(us)


wiring.delay_us = delay_us
wiring.ticks_us = host.ticks_us
try:
    exec(open("boards/circuitpython/code.py").read())
except StopRun:
    print("stopped at %d s" % (host.ticks_us() // 1000000))
print("busio.I2C %s" % Busio.made)
