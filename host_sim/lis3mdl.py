"""LIS3MDL register model (I2C 0x1C, or 0x1E with SA1 high), from ST's LIS3MDL datasheet
(DocID024204) and application note AN4602; docs/hardware.md lists the facts and where they are.

    chip = LIS3MDLSim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x1C, chip)
    i2c.writeto_mem(0x1C, 0x22, b'\\x00')    # CTRL_REG3: continuous conversion

Registers: 0x0F WHO_AM_I 0x3D; 0x20 CTRL_REG1 (default 0x10: TEMP_EN bit7, OM[6:5] X/Y mode
lp/mp/hp/uhp, DO[4:2] 0.625/1.25/2.5/5/10/20/40/80 Hz, FAST_ODR bit1: 1000/560/300/155 Hz by OM,
ST bit0); 0x21 CTRL_REG2 (FS[6:5] +-4/8/12/16 G = 6842/3421/2281/1711 LSB/G, REBOOT bit3,
SOFT_RST bit2); 0x22 CTRL_REG3 (default 0x03: MD[1:0] 00 continuous, 01 single, 1x
power-down; LP bit5, SIM bit2); 0x23 CTRL_REG4 (OMZ[3:2], BLE bit1); 0x24 CTRL_REG5
(FAST_READ bit7, BDU bit6); 0x27 STATUS; 0x28-0x2D OUT_X_L..OUT_Z_H; 0x2E-0x2F TEMP_OUT
(8 LSB/degC, 0 at 25 degC, with TEMP_EN); 0x30 INT_CFG (default 0xE8), 0x31 INT_SRC,
0x32-0x33 INT_THS. Other addresses read 0 and ignore writes.

Model choices where the sources are silent, stated so that tests show what a driver assumes:
- Sub-address: bit 7 (SUB(7)) makes a multi-byte transfer advance the register address, as
  the datasheet's I2C section requires; without it every byte goes to (or comes from) the
  same register. Some libraries read the block without SUB(7) and report that it works, so
  real parts may advance regardless: the model keeps the datasheet's rule. Within the data
  block the address wraps from OUT_Z_H back to OUT_X_L (a reading of 0x28-0x2F in one
  transfer returns X again where the temperature would be: a bus trace reported at
  github.com/PX4/PX4-Autopilot/issues/12514).
- SOFT_RST: every register to its default (power-down, no data); the bit reads 0 after.
  REBOOT: no effect but reads 0 after.
- Single mode: one set one output period after the CTRL_REG3 write, then MD reads 11.
- BLE (big-endian data) and ST (self test) are stored, not modelled. FAST_READ not modelled.
- Output beyond the full scale stays linear up to the int16 limits and saturates there.
- Noise: the datasheet's RMS noise (ultra-high-performance mode): 3.2 mG on X and Y, 4.1 mG on
  Z, used for every operating mode (no figure for the others here).
The shared data path (STATUS bits, BDU, overrun, fault hooks) is host_sim/stmag.py's.
"""
try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.stmag import STMagModel

ADDRESS = 0x1C

_REG_WHO_AM_I = const(0x0F)
_REG_CTRL1 = const(0x20)
_REG_CTRL5 = const(0x24)
_REG_STATUS = const(0x27)
_REG_DATA = const(0x28)
_REG_DATA_LAST = const(0x2D)
_REG_TEMP_L = const(0x2E)
_REG_TEMP_H = const(0x2F)
_REG_INT_CFG = const(0x30)
_REG_INT_THS_H = const(0x33)

_WHO_AM_I = const(0x3D)
_DEFAULTS = (0x10, 0x00, 0x03, 0x00, 0x00)   # CTRL_REG1..5
_INT_CFG_DEFAULT = const(0xE8)
_SOFT_RST = const(0x04)
_REBOOT = const(0x08)
_AUTO_INC = const(0x80)

_COUNTS_PER_G = (6842, 3421, 2281, 1711)               # FS 00..11
_DO_PERIOD_US = (1600000, 800000, 400000, 200000, 100000, 50000, 25000, 12500)
_FAST_PERIOD_US = (1000, 1786, 3333, 6452)             # FAST_ODR: 1000/560/300/155 Hz by OM
_NOISE_G = (0.0032, 0.0032, 0.0041)                    # RMS, X Y Z
_TEMP_LSB_PER_C = 8


class LIS3MDLSim(STMagModel):
    """LIS3MDL (see the module docstring). `world` None means zero field."""

    ADDRESS = 0x1C
    DATA = _REG_DATA
    STATUS = _REG_STATUS

    def power_on(self):
        self.ctrl = list(_DEFAULTS)
        self.int_regs = [_INT_CFG_DEFAULT, 0, 0, 0]    # INT_CFG, INT_SRC, INT_THS_L, INT_THS_H
        self.reset_data()
        self.pointer = 0
        self.autoinc = False

    # --- the chip's settings ------------------------------------------------------------
    def counts_per_gauss(self):
        return _COUNTS_PER_G[(self.ctrl[1] >> 5) & 0x03]

    def period_us(self):
        c1 = self.ctrl[0]
        if c1 & 0x02:
            return _FAST_PERIOD_US[(c1 >> 5) & 0x03]
        return _DO_PERIOD_US[(c1 >> 2) & 0x07]

    def sigma_g(self):
        return _NOISE_G

    def bdu(self):
        return bool(self.ctrl[4] & 0x40)

    def bias_g(self):
        return None

    def temperature(self):
        """TEMP_OUT as an int16 (0 when TEMP_EN is off)."""
        if not self.ctrl[0] & 0x80:
            return 0
        tc = 25.0 if self.world is None else self.world.temperature_c
        return int((tc - 25.0) * _TEMP_LSB_PER_C)

    def single_done(self):
        self.ctrl[2] |= 0x03

    def glitch_range(self):
        """A glitch that flips CTRL_REG2's FS0 (+-4 <-> +-8 G, +-12 <-> +-16 G)."""
        self.glitch(_REG_CTRL1 + 1, self.ctrl[1] ^ 0x20)

    # --- sub-address and registers --------------------------------------------------------
    def select(self, reg):
        self.pointer = reg & 0x7F
        self.autoinc = bool(reg & _AUTO_INC)

    def next_pointer(self, reg):
        if not self.autoinc:
            return reg
        if reg == _REG_DATA_LAST:
            return _REG_DATA
        return (reg + 1) & 0x7F

    def read_reg(self, reg):
        if _REG_DATA <= reg <= _REG_DATA_LAST:
            return self.read_data(reg)
        if reg == _REG_STATUS:
            return self.status()
        if _REG_CTRL1 <= reg <= _REG_CTRL5:
            return self.ctrl[reg - _REG_CTRL1]
        if reg == _REG_WHO_AM_I:
            return _WHO_AM_I
        if reg == _REG_TEMP_L:
            return self.temperature() & 0xFF
        if reg == _REG_TEMP_H:
            return (self.temperature() >> 8) & 0xFF
        if _REG_INT_CFG <= reg <= _REG_INT_THS_H:
            return self.int_regs[reg - _REG_INT_CFG]
        return 0

    def write_reg(self, reg, value):
        if not _REG_CTRL1 <= reg <= _REG_CTRL5:
            if reg in (_REG_INT_CFG, _REG_INT_CFG + 2, _REG_INT_THS_H):
                self.int_regs[reg - _REG_INT_CFG] = value
            return
        i = reg - _REG_CTRL1
        if i == 1 and value & _SOFT_RST:
            self.power_on()
            self.reset_cures()
            return
        if i == 1:
            value &= ~(_SOFT_RST | _REBOOT) & 0xFF
        old = self.ctrl[i]
        self.ctrl[i] = value
        if i == 2:
            md = value & 0x03
            if md == 0:
                self.start()
            elif md == 1:
                self.start(single=True)
            else:
                self.stop()
        elif i == 0 and (old ^ value) & 0x1E and self._t0 is not None:
            self.start(self._single)   # a new output rate restarts the period
