"""AK8963 register model (AKM; I2C 0x0C), the magnetometer inside the MPU-9250 / MPU-9255,
reached through the IMU's I2C bypass (host_sim/mpu6050.py MPU9250Sim), from the AK8963
datasheet (MS1356-E-02) and the MPU-9250 register map (RM-MPU-9250A-00, section 5).

    chip = AK8963Sim(world, mount=(-2, 1, 3), seed=1, asa=(0xB0, 0xB2, 0xA6))
    i2c.attach(0x0C, chip, gate=imu.bypass_open)
    i2c.writeto_mem(0x0C, 0x0A, b'\\x16')     # 16-bit output, continuous mode 2 (100 Hz)

Registers: 0x00 WIA 0x48; 0x01 INFO; 0x02 ST1 (bit0 DRDY, bit1 DOR); 0x03-0x08 HXL..HZH, X, Y,
Z int16 LSB first; 0x09 ST2 (bit3 HOFL, bit4 BITM: the output width of this data); 0x0A CNTL1
(MODE[3:0]: 0000 power-down, 0001 single, 0010 continuous 1 (8 Hz), 0110 continuous 2
(100 Hz), 0100 external trigger, 1000 self-test, 1111 fuse ROM access; BIT bit4: 0 14-bit,
0.6 uT/LSB, 1 16-bit, 0.15 uT/LSB); 0x0B CNTL2 (SRST bit0); 0x0C ASTC; 0x0F I2CDIS;
0x10-0x12 ASAX..ASAZ, the fuse ROM's sensitivity adjustment values. Reads auto-increment
through 0x00-0x0C back to 0x00, and through 0x10-0x12 back to 0x10 (datasheet 7.2.3).

Behaviour modelled (lazily, on the next transaction):
- Sensitivity: each axis's Hall element has its own sensitivity, the factory trim being the
  fuse ROM's ASA: the datasheet's adjustment Hadj = H x ((ASA - 128) x 0.5 / 128 + 1) gives
  the field. So the raw output here is the field in counts divided by that factor (a driver
  that does not apply ASA reads up to 50 % off, axis by axis). `asa` defaults to values drawn
  from the seed in 0xA0..0xBF (real parts read values such as 0xB0, 0xB2, 0xA6).
- The ASA registers read their values only in fuse ROM access mode; in any other mode they
  read 0x00 (the datasheet: "In other modes, read data is not correct").
- Mode changes (the datasheet's operation modes): a mode is set from power-down, at least 100 us after it was
  entered; a write of another mode that breaks the rule is ignored (the model's choice for
  what the datasheet leaves undefined), except that continuous 1 or 2 written again in that
  mode restarts the measurements. Power-on and SRST: power-down, every register 0, no data.
- Continuous modes: set k (k = 1, 2, ...) completes at t0 + k/rate after the CNTL1 write;
  single mode: one set 7.2 ms after the write (the datasheet's longest measurement time),
  then power-down.
- Data-ready and the read lock (datasheet 6.4.3.2): a completed set raises DRDY; reading any
  data register or ST2 clears DRDY and DOR and starts a read; ST2 ends it. While a read is
  open the registers keep their set and sets that complete are skipped (DOR set, DRDY not):
  a driver that never reads ST2 sees no new data again. A set completing while the last one
  is unread replaces it and sets DOR (a skipped set).
- Overflow: the sum of the absolute field on the three axes must stay below 4912 uT (the
  limit AKM's datasheets of this family state; docs/hardware.md); beyond it the set carries
  HOFL, its values clipped to the output range (+-32760 in 16-bit, +-8190 in 14-bit output).
- Noise: the datasheets give none; the model adds 0.3 uT RMS per axis (2 counts at
  0.15 uT/LSB, a model choice) and rounds to the nearest count.
- Self-test and external trigger modes are not modelled (no data).
- Fault hooks: freeze() and constant(x, y, z) (host_sim.bus.MagnetometerModel), brown_out(),
  glitch(reg, value) (the mode register takes it whatever the mode rules), glitch_range()
  (CNTL1's BIT flipped: the other output width); inject_raw(x, y, z) forces the raw counts
  of the next set (values beyond the output range are clipped and set HOFL). A write of
  power-down, SRST or power-on cures freeze and constant unless sticky (a model choice: a
  driver's re-initialisation passes through power-down, as the HMC5883L's writes MODE).
"""
import math

try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.bus import MagnetometerModel
from host_sim.prng import Prng
from host_sim.world import UT_PER_GAUSS, sensor_counts

ADDRESS = 0x0C

_DRDY = const(0x01)
_DOR = const(0x02)
_HOFL = const(0x08)
_BITM = const(0x10)
_MODE_PD = const(0x00)
_MODE_SINGLE = const(0x01)
_MODE_FUSE = const(0x0F)
_TWAT_US = const(100)            # power-down -> another mode: at least 100 us
_SINGLE_US = const(7200)         # longest measurement time (datasheet, electrical characteristics)
_SUM_LIMIT_UT = 4912.0           # |X| + |Y| + |Z| below this
_NOISE_UT = 0.3                  # model choice: the datasheets give no noise figure


class AKMagSim(MagnetometerModel):
    """What the AKM compasses modelled here share (see the module docstring); a chip gives
    its register addresses, modes and scale as class attributes."""

    ID = b"\x48"
    ST1 = 0x02
    DATA = 0x03                  # HXL; the three int16 LSB first
    ST2 = 0x09
    CNTL = 0x0A                  # the mode register
    SRST_REG = 0x0B
    MODE_MASK = 0x0F
    HAS_BITM = True              # ST2 says the output width (AK8963)
    PERIODS = {0x02: 125000, 0x06: 10000}   # continuous modes: measurement period, us
    UT_PER_COUNT = 0.15
    LIMIT = 32760

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.injected = []
        self.latched = 0
        self.skipped = 0
        self.power_on()

    # --- state ------------------------------------------------------------------------
    def power_on(self):
        self.regs = bytearray(256)
        self.out = [0, 0, 0]
        self.hofl = False
        self.bitm = False
        self.drdy = False
        self.dor = False
        self.reading = False
        self.mode = _MODE_PD
        self._t_pd = self.now_us      # power-down from now on
        self._t0 = None
        self._k = 0
        self.pointer = 0
        if not self.sticky:
            self.fault = None

    def brown_out(self):
        self.power_on()

    def glitch(self, reg, value):
        """A write the driver never made (a bus glitch); to the mode register, taken whatever
        the mode rules (a corrupted register, not a command)."""
        if reg != self.CNTL:
            self.write_reg(reg, value)
            return
        self.regs[reg] = value
        self.mode = value & self.MODE_MASK
        self._t0 = self.now_us if self.mode in self.PERIODS else None
        self._k = 0

    def inject_raw(self, x, y, z):
        self.injected.append((int(x), int(y), int(z)))

    def ut_per_count(self):
        return self.UT_PER_COUNT

    def period_us(self):
        """The continuous mode's measurement period, None in any other mode."""
        return self.PERIODS.get(self.mode)

    def counts_per_gauss(self):
        """Output counts per gauss of the output width now set (before any ASA trim)."""
        return UT_PER_GAUSS / self.ut_per_count()

    def gains(self):
        """The raw counts per count of field on each axis (1 where there is no trim)."""
        return (1.0, 1.0, 1.0)

    def limit(self):
        return self.LIMIT

    # --- lazy time --------------------------------------------------------------------
    def update(self, now_us):
        if self._t0 is None:
            return
        if self.mode == _MODE_SINGLE:
            if now_us >= self._t0 + _SINGLE_US:
                self._t0 = None
                self.mode = _MODE_PD
                self._t_pd = now_us
                self.regs[self.CNTL] &= ~self.MODE_MASK & 0xFF
                self._place(now_us)
            return
        period = self.PERIODS[self.mode]
        k = (now_us - self._t0) // period
        if k <= self._k:
            return
        if k > self._k + 1:          # sets completed and replaced before this one
            self.dor = True
            self.skipped += k - self._k - 1
        self._k = k
        self._place(self._t0 + k * period)

    def _place(self, t_us):
        if self.reading:             # the registers are held until ST2 is read
            self.dor = True
            self.skipped += 1
            return
        if self.drdy:                # the last set was never read
            self.dor = True
        lim = self.limit()
        if self.injected:
            raw = list(self.injected.pop(0))
            over = False
        elif self.fault == "freeze":
            self.drdy = True
            self.dor = True
            return
        elif self.fault == "constant":
            raw = list(self.fault_value)
            over = False
        else:
            cpg = UT_PER_GAUSS / self.ut_per_count()
            g = Prng(self.seed, stream=t_us) if self.noise else None
            v = sensor_counts(self.world, t_us, self.mount, cpg, _NOISE_UT * cpg / UT_PER_GAUSS,
                              g)
            f = (0.0, 0.0, 0.0) if self.world is None else self.world.sensor_field(t_us,
                                                                                  self.mount)
            over = abs(f[0]) + abs(f[1]) + abs(f[2]) >= _SUM_LIMIT_UT
            k = self.gains()
            raw = [int(math.floor(v[i] * k[i] + 0.5)) for i in range(3)]
        for i in range(3):
            if raw[i] > lim:
                raw[i], over = lim, True
            elif raw[i] < -lim:
                raw[i], over = -lim, True
        self.out = raw
        self.hofl = over
        self.bitm = self.HAS_BITM and self.regs[self.CNTL] & _BITM != 0
        self.drdy = True
        self.latched += 1

    # --- registers --------------------------------------------------------------------
    def read_reg(self, reg):
        d = self.DATA
        if d <= reg < d + 6:
            self._start_read()
            v = self.out[(reg - d) >> 1] & 0xFFFF
            return v >> 8 if (reg - d) & 1 else v & 0xFF
        if reg == self.ST2:
            self._start_read()
            self.reading = False
            return (_HOFL if self.hofl else 0) | (_BITM if self.bitm else 0)
        if reg == self.ST1:
            return self.st1()
        if reg < len(self.ID):
            return self.ID[reg]
        return self.read_other(reg)

    def st1(self):
        """ST1: DRDY (a set to read), DOR (a set was lost)."""
        return (_DRDY if self.drdy else 0) | (_DOR if self.dor else 0)

    def read_other(self, reg):
        return self.regs[reg]

    def _start_read(self):
        self.drdy = False
        self.dor = False
        self.reading = True

    def write_reg(self, reg, value):
        if reg == self.CNTL:
            self._set_mode(value)
        elif reg == self.SRST_REG:
            if value & 0x01:
                self.power_on()
        else:
            self.write_other(reg, value)

    def write_other(self, reg, value):
        pass

    def _set_mode(self, value):
        mode = value & self.MODE_MASK
        now = self.now_us
        if mode == _MODE_PD:
            self.regs[self.CNTL] = value
            self.mode = _MODE_PD
            self._t_pd = now
            self._t0 = None
            if not self.sticky:      # the measurement circuit stopped: a fault is cured
                self.fault = None
            return
        restart = mode == self.mode and mode in self.PERIODS
        if not restart and (self.mode != _MODE_PD or now - self._t_pd < _TWAT_US):
            return                   # not from power-down, or too soon: ignored
        self.regs[self.CNTL] = value
        self.mode = mode
        if mode in self.PERIODS or mode == _MODE_SINGLE:
            self._t0 = now
            self._k = 0
        else:
            self._t0 = None          # fuse ROM access, self-test, external trigger


class AK8963Sim(AKMagSim):
    """AK8963 at 0x0C (see the module docstring). `asa`: the fuse ROM's ASAX, ASAY, ASAZ
    (default: drawn from the seed); `info`: what INFO (0x01) reads."""

    ADDRESS = 0x0C

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, asa=None, info=0x00):
        if asa is None:
            g = Prng(seed, stream=0xA5A)
            asa = tuple(0xA0 + g.randrange(32) for _ in range(3))
        self.asa = tuple(int(a) & 0xFF for a in asa)
        self.info = info & 0xFF
        AKMagSim.__init__(self, world, mount, seed, noise)

    def ut_per_count(self):
        return 0.15 if self.regs[0x0A] & _BITM else 0.6

    def limit(self):
        return 32760 if self.regs[0x0A] & _BITM else 8190

    def glitch_range(self):
        """A glitch that flips CNTL1's BIT: 14-bit output (0.6 uT/LSB) <-> 16-bit (0.15)."""
        self.glitch(0x0A, self.regs[0x0A] ^ _BITM)

    def gains(self):
        # raw = field / ((ASA - 128) x 0.5 / 128 + 1) = field x 256 / (ASA + 128)
        return tuple(256.0 / (a + 128) for a in self.asa)

    def next_pointer(self, reg):
        if reg == 0x0C:
            return 0x00
        if reg == 0x12:
            return 0x10
        return (reg + 1) & 0xFF

    def read_other(self, reg):
        if reg == 0x01:
            return self.info
        if 0x10 <= reg <= 0x12:
            return self.asa[reg - 0x10] if self.mode == _MODE_FUSE else 0x00
        if reg in (0x0A, 0x0C, 0x0F):
            return self.regs[reg]
        return 0

    def write_other(self, reg, value):
        if reg in (0x0C, 0x0F):
            self.regs[reg] = value
