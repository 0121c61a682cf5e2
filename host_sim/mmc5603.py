"""MMC5603NJ register model (I2C 0x30), from MEMSIC's MMC5603NJ datasheet; docs/hardware.md
lists the facts and where they are.

    chip = MMC5603Sim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x30, chip)
    i2c.writeto_mem(0x30, 0x1B, b'\\x08')    # Do_Set
    i2c.writeto_mem(0x30, 0x1B, b'\\x01')    # Take_meas_M: Status1 bit6 after the measurement

Registers: 0x00-0x05 Xout0, Xout1, Yout0, Yout1, Zout0, Zout1 (bits 19:12 and 11:4 of each
axis), 0x06-0x08 Xout2..Zout2 (bits 3:0 in the high nibble), 0x09 Tout (0.8 degC/LSB, 0 at
-75 degC); 0x18 Status1 (OTP_read_done bit4, Sat_sensor bit5, Meas_m_done bit6, Meas_t_done
bit7); 0x1A ODR; 0x1B internal control 0 (Take_meas_M bit0, Take_meas_T bit1, Do_Set bit3,
Do_Reset bit4, Auto_SR_en bit5, Auto_st_en bit6, Cmm_freq_en bit7); 0x1C internal control 1
(BW[1:0]: 6.6, 3.5, 2.0, 1.2 ms per measurement; X/Y/Z_inhibit bits 2-4, St_enp bit5,
St_enm bit6, SW_RST bit7); 0x1D internal control 2 (Prd_set[2:0], En_prd_set bit3, Cmm_en
bit4, Hpower bit7); 0x39 Product_ID 0x10. The control registers and ODR are write-only: they
read 0. The outputs are unsigned, 524288 at zero field, 16384 counts/G, 0..1048575 (+-32 G).

Behaviour modelled (lazily, on the next transaction):
- SET / RESET magnetise the sensor one way or the other: after a SET a measurement reads
  524288 + H + O, after a RESET 524288 - H + O, H the field (16384 counts/G) and O the
  bridge offset, which a SET/RESET pair cancels (O = (A + B) / 2 - 524288). Power-on leaves
  the sensor SET (a model choice); Auto_SR_en does a SET before each measurement.
- The offset O per axis: `offset_g` (default seed-derived within +-0.25 G, a model figure) plus
  `offset_drift_g_per_c` times (world temperature - 25 degC) plus `offset_drift_g_per_s` times
  the time since power-on: what SET/RESET is there to remove.
- Take_meas_M: Meas_m_done clears, the measurement completes BW's time later, the data is
  placed, Meas_m_done sets; reading any data register clears it. Take_meas_T likewise with
  Meas_t_done and Tout. Continuous mode (Cmm_en with ODR > 0 after Cmm_freq_en; Hpower: 1000
  Hz): a measurement every 1/ODR.
- SW_RST: power-on state (the datasheet's 20 ms start-up is not modelled as a busy chip).
- Noise: 2 mG RMS per axis per measurement (the datasheet's total RMS noise figure) at BW 0,
  scaled by sqrt(6.6 ms / BW's time) for the shorter measurements (a model assumption).
- Outputs saturate at 0 and 1048575.
- Fault hooks: freeze() - the data registers keep the old measurement while Meas_m_done still
  sets; constant(x, y, z) - every measurement reads 524288 + these counts; brown_out() -
  power-on state; glitch(reg, value) - a write the driver never made. SW_RST cures freeze and
  constant unless sticky. inject_raw(x, y, z): the field H (16384 counts/G) of the next two
  measurements (one SET/RESET pair; queued per call); the offset still applies.
"""
import math

try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.bus import MagnetometerModel
from host_sim.prng import Prng
from host_sim.world import sensor_counts

ADDRESS = 0x30

_REG_OUT_LAST = const(0x08)
_REG_TOUT = const(0x09)
_REG_STATUS1 = const(0x18)
_REG_ODR = const(0x1A)
_REG_CTRL0 = const(0x1B)
_REG_CTRL1 = const(0x1C)
_REG_CTRL2 = const(0x1D)
_REG_PRODUCT_ID = const(0x39)

_PRODUCT_ID = const(0x10)
_OTP_READ_DONE = const(0x10)
_MEAS_M_DONE = const(0x40)
_MEAS_T_DONE = const(0x80)
_TAKE_MEAS_M = const(0x01)
_TAKE_MEAS_T = const(0x02)
_DO_SET = const(0x08)
_DO_RESET = const(0x10)
_AUTO_SR = const(0x20)
_CMM_FREQ_EN = const(0x80)
_SW_RST = const(0x80)
_CMM_EN = const(0x10)
_HPOWER = const(0x80)

NULL_FIELD = 524288
COUNTS_PER_G = 16384
_TOP = const(1048575)
_MEAS_US = (6600, 3500, 2000, 1200)
_NOISE_G = 0.002
_OFFSET_G = 0.25


class MMC5603Sim(MagnetometerModel):
    """MMC5603NJ at 0x30 (see the module docstring). `world` None means zero field."""

    ADDRESS = 0x30

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, offset_g=None,
                 offset_drift_g_per_c=0.0, offset_drift_g_per_s=0.0):
        MagnetometerModel.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        if offset_g is None:
            g = Prng(seed, stream=0x5603)
            offset_g = [(2.0 * g.uniform() - 1.0) * _OFFSET_G for _ in range(3)]
        self.offset_g = tuple(float(v) for v in offset_g)
        self.offset_drift_g_per_c = float(offset_drift_g_per_c)
        self.offset_drift_g_per_s = float(offset_drift_g_per_s)
        self.injected = []
        self.measurements = 0
        self.sets = 0
        self.resets = 0
        self._powered_us = 0
        self.power_on()

    def power_on(self):
        self.out = [NULL_FIELD, NULL_FIELD, NULL_FIELD]
        self.tout = 0
        self.m_done = False
        self.t_done = False
        self.polarity = 1            # +1 after SET, -1 after RESET
        self.ctrl0 = 0               # kept for Auto_SR_en
        self.ctrl1 = 0
        self.ctrl2 = 0
        self.odr = 0
        self._due_m = None           # time the commanded measurement completes
        self._due_t = None
        self._cmm_t0 = None
        self._cmm_k = 0
        self._freq_ok = False        # Cmm_freq_en was written
        self._pending_field = None   # an injected H for the second measurement of a pair
        self._powered_us = self.now_us
        self.pointer = 0

    # --- helpers ------------------------------------------------------------------------
    def meas_us(self):
        return _MEAS_US[self.ctrl1 & 0x03]

    # no glitch_range(): why, for a test that would glitch one
    FIXED_RANGE = ("the MMC5603NJ has one range, +-30 G at 16384 counts/G (datasheet, "
                   "electrical characteristics), and write-only controls: no range setting")

    def counts_per_gauss(self):
        """Counts per gauss of the 20-bit output (the field H a SET/RESET pair gives)."""
        return COUNTS_PER_G

    def status1(self):
        return (_OTP_READ_DONE | (_MEAS_M_DONE if self.m_done else 0)
                | (_MEAS_T_DONE if self.t_done else 0))

    def offset_at(self, t_us):
        """The bridge offset O (gauss, 3 values) at t_us."""
        tc = 25.0 if self.world is None else self.world.temperature_c
        age_s = (t_us - self._powered_us) / 1e6
        return [self.offset_g[i] + self.offset_drift_g_per_c * (tc - 25.0)
                + self.offset_drift_g_per_s * age_s for i in range(3)]

    def inject_raw(self, x, y, z):
        """The field H (16384 counts/G) of the next SET/RESET pair (two measurements)."""
        self.injected.append((int(x), int(y), int(z)))

    # --- fault hooks --------------------------------------------------------------------
    def _reset_cures(self):
        if not self.sticky:
            self.fault = None

    def brown_out(self):
        self.power_on()
        self._reset_cures()

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    # --- lazy time ----------------------------------------------------------------------
    def update(self, now_us):
        if self._due_m is not None and now_us >= self._due_m:
            t = self._due_m
            self._due_m = None
            self._convert(t)
        if self._due_t is not None and now_us >= self._due_t:
            self._due_t = None
            tc = 25.0 if self.world is None else self.world.temperature_c
            self.tout = max(0, min(255, int(math.floor((tc + 75.0) / 0.8 + 0.5))))
            self.t_done = True
        if self._cmm_t0 is not None:
            period = self._cmm_period_us()
            k = (now_us - self._cmm_t0) // period
            if k > self._cmm_k:
                self._cmm_k = k
                self._convert(self._cmm_t0 + k * period)

    def _cmm_period_us(self):
        if self.ctrl2 & _HPOWER:
            return 1000
        return 1000000 // self.odr

    def _convert(self, t_us):
        if self.ctrl0 & _AUTO_SR:
            self.polarity = 1
        self.m_done = True
        self.measurements += 1
        if self.fault == "freeze":
            return
        if self.fault == "constant":
            for i in range(3):
                self.out[i] = self._clip(NULL_FIELD + self.fault_value[i])
            return
        h = None
        if self._pending_field is not None:
            h = self._pending_field
            self._pending_field = None
        elif self.injected:
            h = self.injected.pop(0)
            self._pending_field = h
        o = self.offset_at(t_us)
        g = Prng(self.seed, stream=t_us) if self.noise else None
        sigma = _NOISE_G * COUNTS_PER_G * math.sqrt(_MEAS_US[0] / self.meas_us())
        if h is None:
            f = sensor_counts(self.world, t_us, self.mount, COUNTS_PER_G, 0.0, None)
        else:
            f = [float(h[0]), float(h[1]), float(h[2])]
        for i in range(3):
            v = self.polarity * f[i] + o[i] * COUNTS_PER_G
            if g is not None:
                v += g.gauss(sigma)
            self.out[i] = self._clip(NULL_FIELD + int(math.floor(v + 0.5)))

    @staticmethod
    def _clip(v):
        return 0 if v < 0 else _TOP if v > _TOP else v

    # --- registers ----------------------------------------------------------------------
    def read_reg(self, reg):
        if reg <= _REG_OUT_LAST:
            self.m_done = False
            if reg < 6:
                v = self.out[reg >> 1]
                return (v >> 12) & 0xFF if reg & 1 == 0 else (v >> 4) & 0xFF
            return (self.out[reg - 6] & 0x0F) << 4
        if reg == _REG_TOUT:
            self.t_done = False
            return self.tout
        if reg == _REG_STATUS1:
            return self.status1()
        if reg == _REG_PRODUCT_ID:
            return _PRODUCT_ID
        return 0

    def write_reg(self, reg, value):
        if reg == _REG_CTRL0:
            self.ctrl0 = value & _AUTO_SR         # the other bits are commands, self-clearing
            if value & _DO_SET:
                self.polarity = 1
                self.sets += 1
            if value & _DO_RESET:
                self.polarity = -1
                self.resets += 1
            if value & _TAKE_MEAS_M:
                self.m_done = False
                self._due_m = self.now_us + self.meas_us()
            if value & _TAKE_MEAS_T:
                self.t_done = False
                self._due_t = self.now_us + self.meas_us()
            if value & _CMM_FREQ_EN:
                self._freq_ok = self.odr > 0 or bool(self.ctrl2 & _HPOWER)
        elif reg == _REG_CTRL1:
            if value & _SW_RST:
                self.power_on()
                self._reset_cures()
                return
            self.ctrl1 = value
        elif reg == _REG_CTRL2:
            self.ctrl2 = value
            if value & _CMM_EN and self._freq_ok:
                self._cmm_t0 = self.now_us
                self._cmm_k = 0
            else:
                self._cmm_t0 = None
        elif reg == _REG_ODR:
            self.odr = value
