"""One chip model alone on a simulated bus (LIS3MDL, LIS2MDL, MMC5603), for the tests of a
driver against its model's registers; host_sim.boards.make_board builds whole boards."""
from host_sim.bus import SimI2C
from host_sim.clock import SimClock
from host_sim.world import World

MODELS = {
    "lis3mdl": ("host_sim.lis3mdl", "LIS3MDLSim", 0x1C),
    "lis2mdl": ("host_sim.lis2mdl", "LIS2MDLSim", 0x1E),
    "mmc5603": ("host_sim.mmc5603", "MMC5603Sim", 0x30),
}


class Bench:
    """.clock, .bus, .chip (the model), .address, .world, .sleep_us."""

    def __init__(self, kind, world=None, address=None, **kw):
        module, name, addr = MODELS[kind]
        cls = getattr(__import__(module, None, None, (name,)), name)
        self.clock = SimClock()
        self.bus = SimI2C(self.clock)
        self.world = World(field_ut=50.0, inclination_deg=0.0) if world is None else world
        self.address = addr if address is None else address
        self.chip = self.bus.attach(self.address, cls(self.world, **kw))
        self.sleep_us = self.bus.sleep_us

    def rd(self, reg, n=1):
        return self.bus.readfrom_mem(self.address, reg, n)

    def wr(self, reg, *vals):
        self.bus.writeto_mem(self.address, reg, bytes(vals))
