"""MicroPython only: boards/main.py itself, run as a board runs it, over a recorded session.

    micropython -X heapsize=N boardrun.py SESSION.bin STOREDIR DANCE_S END_S [START_US]

The current directory holds the install (firmware/ as .py or .mpy files, main.py copied from
boards/main.py). A `board` module is made here: a QMC5883L (0x0D) and an MPU6050 (0x68) whose
data registers serve SESSION.bin (mag bytes, then accelerometer bytes: 6 per sample each),
read from the open file into the drivers' own buffers (nothing of the recording is on the
heap), 5 ms of board time per magnetometer sample. For DANCE_S seconds the samples are the
recording's figure-8, lap after lap; then the board is put down (it jitters among its first
50 samples, directions it has seen); at END_S the clock raises SystemExit, which is how this
script stops main.py's endless loop (no firmware code catches it: step() keeps only
Exception). main.py prints what a board prints (its status line every 0.5 s); this script
then prints one last line, "boardrun: model M stored S collecting C", from the app
main.py made. board.restart() (main.py's restart into the heading after the calibration
program) ends the process as a reset ends a board's: "boardrun: restart at T" is the last
line, and the caller starts the next process at board time T (START_US) with the same store. Any other exception leaves main.py as a traceback on stderr: the heap sweep
(desktop/bench.py board_sweep, tests/test_heap_sweep.py) counts those.
"""
import sys

_SESSION, _STORE = sys.argv[1], sys.argv[2]
_DANCE_US = int(sys.argv[3]) * 1000000
_END_US = int(sys.argv[4]) * 1000000
_START_US = int(sys.argv[5]) if len(sys.argv) > 5 else 0
_PERIOD_US = 5000
_REST = 50


class _Bus:
    """machine.I2C stand-in: register images, the data registers served from the file."""

    def __init__(self, f):
        self.f = f
        self.n = f.seek(0, 2) // 12
        self.qmc = bytearray(256)
        self.qmc[0x0D] = 0xFF  # chip ID
        self.qmc[0x06] = 0x01  # DRDY, never OVL/DOR
        self.mpu = bytearray(256)
        self.mpu[0x75] = 0x68  # WHO_AM_I
        self.now = _START_US
        self.i = (_START_US // _PERIOD_US - 1) % self.n if _START_US else -1

    def scan(self):
        return [0x0D, 0x68]

    def readfrom_mem_into(self, addr, reg, buf):
        if addr == 0x0D and reg == 0:  # a new magnetometer sample: board time moves on
            self.now += _PERIOD_US
            if self.now >= _END_US:
                raise SystemExit
            i = self.i + 1
            if self.now >= _DANCE_US:
                i %= _REST
            elif i >= self.n:
                i = 0
            self.i = i
            self.f.seek(6 * i)
            self.f.readinto(buf)
        elif addr == 0x68 and reg == 0x3B:
            self.f.seek(6 * self.n + 6 * (self.i if self.i > 0 else 0))
            self.f.readinto(buf)
        else:
            img = self.qmc if addr == 0x0D else self.mpu
            for k in range(len(buf)):
                buf[k] = img[reg + k]

    def writeto_mem(self, addr, reg, buf):
        img = self.qmc if addr == 0x0D else self.mpu
        for k in range(len(buf)):
            img[reg + k] = buf[k]
        if addr == 0x0D and reg == 0x0A and buf[0] & 0x80:
            # QMC5883L SOFT_RST (control register 2, bit 7): every register back to its
            # default (0: standby), as a boot that retries after running out of memory sees
            img[0x09] = img[0x0A] = img[0x0B] = 0

    def readfrom_mem(self, addr, reg, n):
        b = bytearray(n)
        self.readfrom_mem_into(addr, reg, b)
        return bytes(b)


class _Board:
    MAG_AXES = "x,-y,-z"
    ACCEL_AXES = "-x,y,z"
    DECLINATION_CDEG = 0
    STORE_DIR = _STORE
    MODE = "compass"
    GYRO = False

    def __init__(self, bus):
        self.bus = bus

    def make_i2c(self):
        return self.bus

    def delay_us(self, us):  # the drivers' waits, main.py's pauses between retries
        self.bus.now += us
        if self.bus.now >= _END_US:
            raise SystemExit

    def ticks_us(self):
        return self.bus.now

    def restart(self):  # a reset: this process ends, the next one boots at this board time
        raise _Restart


class _Restart(BaseException):
    pass


_bus = _Bus(open(_SESSION, "rb"))
sys.modules["board"] = _Board(_bus)
_g = {"__name__": "__main__"}
with open("main.py") as _f:  # compiled as a board compiles its main.py, the source let go
    _code = compile(_f.read(), "main.py", "exec")
_restarted = False
try:
    exec(_code, _g)
except SystemExit:
    pass
except _Restart:
    print("boardrun: restart at %d" % _bus.now)
    _restarted = True
_app = _g.get("app") or getattr(sys.modules.get("firmware.runner"), "app", None)
if _restarted:
    pass
elif _app is None:
    print("boardrun: no app")
else:
    _c = getattr(_app, "calibration", None)  # None: the app itself never fitted
    print("boardrun: model %s stored %d collecting %d" % (
        _c.model if _c is not None else None, getattr(_app, "stored", 0),
        getattr(_app, "collector", None) is not None))
