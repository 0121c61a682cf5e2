# Raw register bytes of the simulated boards over a figure-8 with noise, hard and soft iron
# and a magnet, plus raw PRNG output: printed as JSON integer lines and compared between
# CPython and MicroPython by tests/test_sim_world.py (tests/mp.py parity).
import json

from host_sim import motion
from host_sim.boards import make_board
from host_sim.prng import Prng
from host_sim.world import World

V = (31.5, -22.25, 12.0)
W = ((1.08, 0.06, -0.03), (0.02, 0.93, 0.05), (-0.04, 0.07, 1.01))


def world():
    w = World(field_ut=48.0, inclination_deg=64.0, declination_deg=-3.5, hard_iron_ut=V,
              soft_iron=W, motion=motion.figure8(period_s=12.0), seed=5)
    w.add_magnet((40.0, -10.0, 5.0), 1.0, 1.6, ramp_s=0.2, frame="world")
    return w


def qmc():
    b = make_board("gy271", world=world(), seed=7)
    i2c = b.bus
    i2c.writeto_mem(0x0D, 0x0B, b"\x01")
    i2c.writeto_mem(0x0D, 0x09, b"\x0d")
    buf = bytearray(9)
    for _ in range(400):
        b.sleep_us(5000)
        i2c.readfrom_mem_into(0x0D, 0x00, buf)
        print(json.dumps([0, b.clock.now_us] + list(buf)))


def gy87():
    b = make_board("gy87", world=world(), seed=9)
    i2c = b.bus
    i2c.writeto_mem(0x68, 0x6B, b"\x00")
    i2c.writeto_mem(0x68, 0x37, b"\x02")
    i2c.writeto_mem(0x1E, 0x00, b"\x18")
    i2c.writeto_mem(0x1E, 0x02, b"\x00")
    m = bytearray(6)
    a = bytearray(8)
    i2c.inject_eio(after=50, count=3)
    errors = 0
    for _ in range(300):
        b.sleep_us(13333)
        try:
            i2c.readfrom_mem_into(0x1E, 0x03, m)
            i2c.readfrom_mem_into(0x68, 0x3B, a)
        except OSError as e:
            errors += e.args[0]
        print(json.dumps([1, b.clock.now_us] + list(m) + list(a)))
    print(json.dumps([2, errors, i2c.transactions, b.mag.measurements, b.mag.lost]))


def prng():
    g = Prng(seed=123456789, stream=42)
    u = [g.next_u32() for _ in range(64)]
    n = [int(g.gauss(1000000.0)) for _ in range(64)]
    print(json.dumps([3] + u + n))


qmc()
gy87()
prng()
