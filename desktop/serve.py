"""`python -m host_sim serve --protocol motioncal --chip gy87 --seed 1`: the simulated board
as MotionCal sees a real one. The firmware's CompassApp runs on the simulated chips (the
demo's world: strong iron from the seed, a figure-8 by default) in MotionCal mode
(firmware/motioncal/mode.py) and speaks the protocol on stdin/stdout, the board's USB serial:
Raw: lines out, the 68-byte Send Cal packet in, the Cal1/Cal2 echo out.

    python -m host_sim serve --fast --seconds 60 > stream.txt      # a minute of Raw lines
    python -m host_sim serve --pty        # prints /dev/pts/N (MotionCal on Linux lists a pty
                                          # only as docs/motioncal.md shows: a ttyACM link and
                                          # a modem-line shim)

Binary-safe: stdin is read as bytes without blocking (select), output goes to
sys.stdout.buffer. Pace: the simulated clock follows the wall clock by default (50 Raw lines
per real second); --fast runs as fast as the reader takes the lines (a pipe's writes block
when its reader is slow). --pty opens a pseudo-terminal in raw mode (no echo, no CR/LF
translation, 0x03 is a byte) and prints its path on stdout; the stream then goes there, and
lines nobody reads are dropped, as a USB serial port without a host would.
Ends after --seconds of simulated time (default: never), at end of output, or on Ctrl-C;
a summary line goes to stderr. docs/motioncal.md has the wiring, the gauges and the figures.
"""
import os
import select
import sys
import time

from desktop import demo
from desktop.args import Parser, wrap
from desktop.memfs import MemFs

PROTOCOLS = ("motioncal",)
DEFAULT_CHIP = "gy87"
DEFAULT_RATE_HZ = 50
_READ_MAX = 4096


def parser():
    p = Parser("serve", "[--protocol motioncal] [--chip CHIP] [--seed N] [options]",
               "The simulated board in MotionCal mode on stdin/stdout (or a pseudo-terminal).")
    p.option("--protocol", "choice", default="motioncal", choices=PROTOCOLS, metavar="P",
             help="the serial protocol: motioncal (PJRC MotionCal; the only one)")
    p.option("--chip", "choice", default=DEFAULT_CHIP, choices=demo.CHIP_CHOICES,
             metavar="CHIP", help=wrap("%s (as the demo's); default gy87"
                                       % ", ".join(demo.CHIP_CHOICES)))
    p.option("--seed", "int", default=1, metavar="N",
             help="the world (iron) and the sensors' noise; default 1")
    p.option("--rate", "int", default=DEFAULT_RATE_HZ, lo=1, hi=400, metavar="HZ",
             help="Raw lines per second (at most the magnetometer's rate); default 50")
    p.option("--seconds", "int", default=None, lo=1, hi=10000000, metavar="S",
             help="stop after S simulated seconds (default: never)")
    p.option("--period", "int", default=demo.SESSION_S, lo=5, hi=100000, metavar="S",
             help="the figure-8's period in simulated seconds (default %d)"
                  % demo.SESSION_S)
    p.option("--fast", "flag", help="as fast as the reader takes (default: real time)")
    p.option("--pty", "flag", help="serve on a new pseudo-terminal; print its path")
    p.option("--store", "path", metavar="DIR",
             help="keep the calibration record in DIR (default: in memory)")
    p.option("--viewer", "flag",
             help="also print Adafruit's 3D viewer lines (Orientation:, Calibration:)")
    p.epilog = "exit status: 0 done; 2 bad usage."
    return p


class Session:
    """The simulated board in MotionCal mode: .setup (demo.Setup: board, world, drivers,
    the figure-8 stage), .app (firmware.app.CompassApp, learn=False), .mode
    (firmware.motioncal.mode.MotionCalMode), .store. write(bytes) and poll() -> bytes are
    the serial line's two ends (module docstring)."""

    def __init__(self, write, poll, chip=DEFAULT_CHIP, seed=1, rate_hz=DEFAULT_RATE_HZ,
                 period_s=demo.SESSION_S, store_dir=None, viewer=False):
        from firmware.app import CompassApp
        from firmware.motioncal.mode import MotionCalMode
        from firmware.store import CalStore

        self.setup = s = demo.Setup(chip, seed, period_s)
        b = s.board
        self.store = CalStore(store_dir) if store_dir else CalStore("/", fs=MemFs())
        self.app = CompassApp(b.bus, mag=s.mag, accel=s.accel, mag_axes=s.mag_axes,
                              accel_axes=s.accel_axes, model=demo.MODEL,
                              declination_cdeg=demo.DECLINATION_CDEG, store=self.store,
                              delay_us=b.sleep_us, ticks_us=b.clock.ticks_us, learn=False)
        self.mode = MotionCalMode(self.app, write=write, poll=poll, rate_hz=rate_hz,
                                  mag_axes=s.mag_axes, ticks_us=b.clock.ticks_us,
                                  viewer=viewer)

    @property
    def now_us(self):
        return self.setup.board.clock.now_us

    def step(self):
        return self.mode.step()


class _Port:
    """One end of the serial line on file descriptors: non-blocking reads with select;
    writes block (a pipe: the reader sets the pace) or drop (a pty nobody reads)."""

    def __init__(self, rfd, wfd, drop):
        self.rfd = rfd
        self.wfd = wfd
        self.drop = drop
        self.eof = False
        self.dropped = 0
        self.pending = bytearray()

    def poll(self):
        if self.eof or not select.select([self.rfd], [], [], 0)[0]:
            return b""
        try:
            b = os.read(self.rfd, _READ_MAX)
        except OSError:  # a pty whose other side is closed (EIO): nothing arrived
            return b""
        if not b and not self.drop:
            self.eof = True  # stdin closed: keep streaming, stop listening
        return b

    def write(self, data):
        self.pending += data

    def flush(self):
        if not self.pending:
            return
        data = bytes(self.pending)
        self.pending = bytearray()
        if not self.drop:
            while data:
                n = os.write(self.wfd, data)
                data = data[n:]
            return
        try:
            n = os.write(self.wfd, data)
        except BlockingIOError:
            n = 0
        self.dropped += len(data) - n


def _open_pty():
    import tty
    master, slave = os.openpty()
    tty.setraw(slave)          # bytes as they are: no echo, no CR/LF mapping, no signals
    os.set_blocking(master, False)
    return master, slave, os.ttyname(slave)


def body(opts):
    if opts["pty"]:
        master, slave, path = _open_pty()
        port = _Port(master, master, drop=True)
        print(path, flush=True)
    else:
        port = _Port(sys.stdin.fileno(), sys.stdout.fileno(), drop=False)
    s = Session(port.write, port.poll, chip=opts["chip"], seed=opts["seed"],
                rate_hz=opts["rate"], period_s=opts["period"], store_dir=opts["store"],
                viewer=opts["viewer"])
    end_us = opts["seconds"] * 1000000 if opts["seconds"] else None
    t0 = time.monotonic()
    sim0 = s.now_us
    try:
        while end_us is None or s.now_us < end_us:
            s.step()
            port.flush()
            if not opts["fast"]:
                ahead = (s.now_us - sim0) / 1e6 - (time.monotonic() - t0)
                if ahead > 0:
                    time.sleep(ahead)
    except (BrokenPipeError, KeyboardInterrupt):
        pass
    m = s.mode
    print("host_sim serve: %.1f s simulated, %d Raw lines, packets applied %d, rejected %d, "
          "bad CRC %d, truncated %d, bytes skipped %d; status %s"
          % (s.now_us / 1e6, m.lines, m.applied, m.rejected, m.bad_crc, m.truncated,
             m.garbage, m.status), file=sys.stderr)
    return 0


def main(argv):
    return parser().main(argv, body)
