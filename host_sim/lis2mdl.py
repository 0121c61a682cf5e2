"""LIS2MDL register model (I2C 0x1E), from ST's LIS2MDL datasheet and AN5069 (DocID030934);
the LSM303AGR's magnetometer (DocID027765) has the same register map and ID, so this model
stands for it too. docs/hardware.md lists the facts and where they are.

    chip = LIS2MDLSim(world, mount=(1, -2, 3), seed=1)
    i2c.attach(0x1E, chip)
    i2c.writeto_mem(0x1E, 0x60, b'\\x80')    # CFG_REG_A: temperature compensation, 10 Hz, continuous

Registers: 0x45-0x4A OFFSET_X_REG_L..OFFSET_Z_REG_H (hard-iron offsets, int16 LSB first,
1.5 mG/LSB, subtracted from the output); 0x4F WHO_AM_I 0x40; 0x60 CFG_REG_A (default 0x03:
COMP_TEMP_EN bit7, REBOOT bit6, SOFT_RST bit5, LP bit4, ODR[3:2] 10/20/50/100 Hz, MD[1:0]
00 continuous, 01 single, 1x idle); 0x61 CFG_REG_B (OFF_CANC_ONE_SHOT bit4, INT_on_DataOFF
bit3, Set_FREQ bit2, OFF_CANC bit1, LPF bit0); 0x62 CFG_REG_C (INT_on_PIN bit6, I2C_DIS bit5,
BDU bit4, BLE bit3, 4WSPI bit2, Self_test bit1, DRDY_on_PIN bit0); 0x63 INT_CRTL_REG (default
0xE0), 0x64 INT_SOURCE_REG, 0x65-0x66 INT_THS; 0x67 STATUS; 0x68-0x6D OUTX_L..OUTZ_H;
0x6E-0x6F TEMP_OUT (8 LSB/degC, 0 at 25 degC). Sensitivity 1.5 mG/LSB, fixed (+-49.152 G).
Other addresses read 0 and ignore writes.

Model choices where the sources are silent:
- Sub-address: the address advances in every multi-byte transfer; bit 7 of the sub-address is
  ignored (ST's reference example and the micro:bit runtime set it for block reads, other
  libraries do not, and both read the block). The data block wraps from OUTZ_H back to OUTX_L
  (readers report X again where the temperature would be, ST community thread on the IIS2MDC,
  the same magnetometer).
- The sensor bridge's own offset: without OFF_CANC the output carries a per-axis offset
  (seed-derived, within +-50 mG, a model figure: no figure for it in the sources here) that
  the chip's set/reset offset cancellation (OFF_CANC = 1) removes.
- COMP_TEMP_EN, LP, LPF, BLE and the self test are stored, not modelled; noise 3 mG RMS per
  axis (the datasheet's high-resolution figure) in either power mode.
- SOFT_RST: every register to its default (offset registers 0, idle); reads 0 after.
- Single mode: one set one output period after the write, then MD reads 11 (idle).
- Output saturates at the int16 limits.
The shared data path (STATUS bits, BDU, overrun, fault hooks) is host_sim/stmag.py's.
"""
try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.prng import Prng
from host_sim.stmag import STMagModel

ADDRESS = 0x1E

_REG_OFFSET = const(0x45)
_REG_OFFSET_LAST = const(0x4A)
_REG_WHO_AM_I = const(0x4F)
_REG_CFG_A = const(0x60)
_REG_CFG_C = const(0x62)
_REG_INT_CTRL = const(0x63)
_REG_INT_THS_H = const(0x66)
_REG_STATUS = const(0x67)
_REG_DATA = const(0x68)
_REG_DATA_LAST = const(0x6D)
_REG_TEMP_L = const(0x6E)
_REG_TEMP_H = const(0x6F)

_WHO_AM_I = const(0x40)
_DEFAULTS = (0x03, 0x00, 0x00)          # CFG_REG_A..C
_INT_CTRL_DEFAULT = const(0xE0)
_SOFT_RST = const(0x20)
_REBOOT = const(0x40)
_OFF_CANC = const(0x02)

COUNTS_PER_G = 1000.0 / 1.5             # 1.5 mG/LSB
_ODR_PERIOD_US = (100000, 50000, 20000, 10000)
_NOISE_G = (0.003, 0.003, 0.003)
_BRIDGE_OFFSET_G = 0.05
_TEMP_LSB_PER_C = 8


def _s16(lo, hi):
    v = hi << 8 | lo
    return v - 0x10000 if v & 0x8000 else v


class LIS2MDLSim(STMagModel):
    """LIS2MDL / LSM303AGR magnetometer (see the module docstring). `bridge_offset_g`: the
    sensor's own offset (3 values in gauss) seen without OFF_CANC; None draws one from seed."""

    ADDRESS = 0x1E
    DATA = _REG_DATA
    STATUS = _REG_STATUS

    def __init__(self, world=None, mount=(1, -2, 3), seed=1, noise=True, bridge_offset_g=None):
        if bridge_offset_g is None:
            g = Prng(seed, stream=0x1234D)
            bridge_offset_g = [(2.0 * g.uniform() - 1.0) * _BRIDGE_OFFSET_G for _ in range(3)]
        self.bridge_offset_g = tuple(float(v) for v in bridge_offset_g)
        STMagModel.__init__(self, world, mount, seed, noise)

    def power_on(self):
        self.cfg = list(_DEFAULTS)
        self.offset_regs = bytearray(6)
        self.int_regs = [_INT_CTRL_DEFAULT, 0, 0, 0]   # INT_CRTL, INT_SOURCE, INT_THS_L, _H
        self.reset_data()
        self.pointer = 0

    # --- the chip's settings ------------------------------------------------------------
    # no glitch_range(): why, for a test that would glitch one
    FIXED_RANGE = ("the LIS2MDL's sensitivity is fixed, 1.5 mG/LSB (+-49.152 G in int16; "
                   "datasheet, magnetic characteristics): no range setting")

    def counts_per_gauss(self):
        return COUNTS_PER_G

    def period_us(self):
        return _ODR_PERIOD_US[(self.cfg[0] >> 2) & 0x03]

    def sigma_g(self):
        return _NOISE_G

    def bdu(self):
        return bool(self.cfg[2] & 0x10)

    def bias_g(self):
        # the bridge offset without cancellation, minus the hard-iron offset registers
        o = self.offset_regs
        bias = [0.0, 0.0, 0.0]
        for i in range(3):
            b = -_s16(o[2 * i], o[2 * i + 1]) / COUNTS_PER_G
            if not self.cfg[1] & _OFF_CANC:
                b += self.bridge_offset_g[i]
            bias[i] = b
        return bias

    def temperature(self):
        tc = 25.0 if self.world is None else self.world.temperature_c
        return int((tc - 25.0) * _TEMP_LSB_PER_C)

    def single_done(self):
        self.cfg[0] |= 0x03

    # --- sub-address and registers --------------------------------------------------------
    def select(self, reg):
        self.pointer = reg & 0x7F

    def next_pointer(self, reg):
        if reg == _REG_DATA_LAST:
            return _REG_DATA
        return (reg + 1) & 0x7F

    def read_reg(self, reg):
        if _REG_DATA <= reg <= _REG_DATA_LAST:
            return self.read_data(reg)
        if reg == _REG_STATUS:
            return self.status()
        if _REG_CFG_A <= reg <= _REG_CFG_C:
            return self.cfg[reg - _REG_CFG_A]
        if reg == _REG_WHO_AM_I:
            return _WHO_AM_I
        if _REG_OFFSET <= reg <= _REG_OFFSET_LAST:
            return self.offset_regs[reg - _REG_OFFSET]
        if reg == _REG_TEMP_L:
            return self.temperature() & 0xFF
        if reg == _REG_TEMP_H:
            return (self.temperature() >> 8) & 0xFF
        if _REG_INT_CTRL <= reg <= _REG_INT_THS_H:
            return self.int_regs[reg - _REG_INT_CTRL]
        return 0

    def write_reg(self, reg, value):
        if _REG_OFFSET <= reg <= _REG_OFFSET_LAST:
            self.offset_regs[reg - _REG_OFFSET] = value
            return
        if reg in (_REG_INT_CTRL, _REG_INT_CTRL + 2, _REG_INT_THS_H):
            self.int_regs[reg - _REG_INT_CTRL] = value
            return
        if not _REG_CFG_A <= reg <= _REG_CFG_C:
            return
        i = reg - _REG_CFG_A
        if i == 0 and value & _SOFT_RST:
            self.power_on()
            self.reset_cures()
            return
        if i == 0:
            value &= ~(_SOFT_RST | _REBOOT) & 0xFF
        old = self.cfg[i]
        self.cfg[i] = value
        if i == 0:
            md = value & 0x03
            if md == 0 and (old & 0x03 != 0 or (old ^ value) & 0x0C or self._t0 is None):
                self.start()
            elif md == 1:
                self.start(single=True)
            elif md >= 2:
                self.stop()
