"""ICM-20948 register model (TDK InvenSense; I2C 0x68, or 0x69 with AD0 high): the
accelerometer and gyroscope, and the I2C bypass that shows its AK09916 (host_sim/ak09916.py),
from the ICM-20948 datasheet (DS-000189 rev 1.3: table 2 accelerometer, table 1 gyroscope,
sections 7-10 the registers).

    imu = ICM20948Sim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x68, imu)
    i2c.attach(0x0C, ak, gate=imu.bypass_open)

Registers in four banks, REG_BANK_SEL (0x7F, USER_BANK[5:4]) in every bank. Bank 0: 0x00
WHO_AM_I 0xEA; 0x03 USER_CTRL (bit5 I2C_MST_EN); 0x05 LP_CONFIG (power-on 0x40); 0x06
PWR_MGMT_1 (power-on 0x41: SLEEP, auto clock; bit7 DEVICE_RESET); 0x07 PWR_MGMT_2; 0x0F
INT_PIN_CFG (bit1 BYPASS_EN); 0x1A INT_STATUS_1 (bit0 RAW_DATA_0_RDY_INT, cleared by reading);
0x2D-0x32 ACCEL X/Y/Z, 0x33-0x38 GYRO X/Y/Z, int16 MSB first; 0x39-0x3A TEMP_OUT. Bank 2:
0x00 GYRO_SMPLRT_DIV; 0x01 GYRO_CONFIG_1 (power-on 0x01: GYRO_DLPFCFG[5:3], GYRO_FS_SEL[2:1]
250/500/1000/2000 deg/s = 131/65.5/32.8/16.4 counts per deg/s, GYRO_FCHOICE bit0); 0x10-0x11
ACCEL_SMPLRT_DIV (12 bits); 0x14 ACCEL_CONFIG (power-on 0x01: ACCEL_DLPFCFG[5:3],
ACCEL_FS_SEL[2:1] +-2/4/8/16 g = 16384/8192/4096/2048 counts/g, ACCEL_FCHOICE bit0). Other
registers read back what was written (0 at power-on).

Behaviour modelled (lazily, on the next transaction):
- Asleep (the power-on state): the sensor registers hold their last values (0 after power-on
  or DEVICE_RESET). Awake, a sample every (1 + ACCEL_SMPLRT_DIV) / 1125 s (the accelerometer's
  output data rate with its filter on; the gyroscope is sampled at the same instants, a model
  choice); each sample sets RAW_DATA_0_RDY_INT.
- Accelerometer: specific force in the chip's axes (+1 g on an axis pointing up) plus an
  optional bias, plus the datasheet's 230 ug/sqrt(Hz) times the square root of the filter's
  bandwidth (ACCEL_DLPFCFG 0-7: 246, 246, 111.4, 50.4, 23.9, 11.5, 5.7, 473 Hz; 1209 Hz with
  ACCEL_FCHOICE 0), saturated to int16.
- Gyroscope: the board's rotation rate through the mounting, plus the bias, temperature and
  drift terms of host_sim/mpu6050.py, plus 0.015 deg/s/sqrt(Hz) times the square root of its
  filter's bandwidth (GYRO_DLPFCFG 0-7: 196.6, 151.8, 119.5, 51.2, 23.9, 11.6, 5.7, 361.4 Hz;
  12106 Hz with GYRO_FCHOICE 0).
- Temperature: TEMP_OUT = (T - 21 C) x 333.87.
- Bypass: bypass_open() is True when USER_CTRL.I2C_MST_EN = 0 and INT_PIN_CFG.BYPASS_EN = 1
  (the AK09916 is hidden at power-on). The I2C master and the DMP are not modelled.
- Fault hooks: doze() (SLEEP set), brown_out() (power-on defaults: bank 0, asleep, bypass
  closed), glitch(bank, reg, value), free_fall.
"""
import math

try:
    from micropython import const
except ImportError:
    def const(x):
        return x

from host_sim.bus import RegisterDevice
from host_sim.prng import Prng
from host_sim.world import mount_apply

ADDRESS = 0x68
ADDRESS_AD0 = 0x69

_BANK_SEL = const(0x7F)
# bank 0
_WHO_AM_I = const(0x00)
_USER_CTRL = const(0x03)
_LP_CONFIG = const(0x05)
_PWR_MGMT_1 = const(0x06)
_INT_PIN_CFG = const(0x0F)
_INT_STATUS_1 = const(0x1A)
_ACCEL = const(0x2D)
_TEMP_LAST = const(0x3A)
# bank 2
_GYRO_CONFIG_1 = const(0x01)
_ACCEL_DIV_1 = const(0x10)
_ACCEL_DIV_2 = const(0x11)
_ACCEL_CONFIG = const(0x14)

_ID = const(0xEA)
_SLEEP = const(0x40)
_DEVICE_RESET = const(0x80)
_I2C_MST_EN = const(0x20)
_BYPASS_EN = const(0x02)
_RDY = const(0x01)

_ACCEL_COUNTS_PER_G = (16384, 8192, 4096, 2048)
_GYRO_COUNTS_PER_DPS = (131.0, 65.5, 32.8, 16.4)
_ACCEL_BW_HZ = (246.0, 246.0, 111.4, 50.4, 23.9, 11.5, 5.7, 473.0)
_ACCEL_BW_OFF_HZ = 1209.0
_GYRO_BW_HZ = (196.6, 151.8, 119.5, 51.2, 23.9, 11.6, 5.7, 361.4)
_GYRO_BW_OFF_HZ = 12106.0
_ACCEL_PSD_G = 230e-6
_GYRO_PSD_DPS = 0.015
_TEMP_COUNTS_PER_C = 333.87
_TEMP_OFFSET_C = 21.0
_ODR_HZ = const(1125)


def _sat16(v):
    return 32767 if v > 32767 else (-32768 if v < -32768 else v)


class ICM20948Sim(RegisterDevice):
    """ICM-20948 (see the module docstring). `mount`: the accelerometer's body -> sensor
    signed permutation; bias_g and the gyro_* terms as host_sim/mpu6050.py's MPU6050Sim."""

    ADDRESS = 0x68

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, bias_g=(0.0, 0.0, 0.0),
                 gyro_bias_dps=(0.0, 0.0, 0.0), gyro_temp_dps_per_c=(0.0, 0.0, 0.0),
                 gyro_drift_dps_per_s=(0.0, 0.0, 0.0)):
        RegisterDevice.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.bias_g = tuple(float(v) for v in bias_g)
        self.gyro_bias_dps = tuple(float(v) for v in gyro_bias_dps)
        self.gyro_temp_dps_per_c = tuple(float(v) for v in gyro_temp_dps_per_c)
        self.gyro_drift_dps_per_s = tuple(float(v) for v in gyro_drift_dps_per_s)
        self.samples = 0
        self.free_fall = False
        self.power_on()

    def power_on(self):
        self.banks = [bytearray(128) for _ in range(4)]
        self.banks[0][_PWR_MGMT_1] = 0x41
        self.banks[0][_LP_CONFIG] = 0x40
        self.banks[2][_GYRO_CONFIG_1] = 0x01
        self.banks[2][_ACCEL_CONFIG] = 0x01
        self.bank = 0
        self.data = bytearray(14)   # accel, gyro, temperature as the registers hold them
        self.int_status = 0
        self._t0 = None
        self._k = 0
        self.pointer = 0

    # --- helpers ----------------------------------------------------------------------
    def asleep(self):
        return bool(self.banks[0][_PWR_MGMT_1] & _SLEEP)

    def bypass_open(self):
        """The auxiliary bus joined to the main bus: the AK09916 visible at 0x0C."""
        b0 = self.banks[0]
        return (not b0[_USER_CTRL] & _I2C_MST_EN) and bool(b0[_INT_PIN_CFG] & _BYPASS_EN)

    def counts_per_g(self):
        return _ACCEL_COUNTS_PER_G[(self.banks[2][_ACCEL_CONFIG] >> 1) & 0x03]

    def _period(self):
        # (1 + ACCEL_SMPLRT_DIV) / 1125 s as (numerator us, denominator), exact
        b2 = self.banks[2]
        div = (b2[_ACCEL_DIV_1] & 0x0F) << 8 | b2[_ACCEL_DIV_2]
        return (1 + div) * 1000000, _ODR_HZ

    # --- fault hooks ------------------------------------------------------------------
    def doze(self):
        self.banks[0][_PWR_MGMT_1] |= _SLEEP
        self._restart()

    def brown_out(self):
        self.power_on()

    def glitch(self, bank, reg, value):
        keep = self.bank
        self.bank = bank
        self.write_reg(reg, value)
        self.bank = keep

    # --- lazy time --------------------------------------------------------------------
    def update(self, now_us):
        if self._t0 is None:
            return
        num, den = self._period()
        k = (now_us - self._t0) * den // num
        if k <= self._k:
            return
        self._k = k
        self._sample(self._t0 + k * num // den)

    def _restart(self):
        self._t0 = None if self.asleep() else self.now_us
        self._k = 0

    def _sample(self, t_us):
        cpg = self.counts_per_g()
        b2 = self.banks[2]
        if self.free_fall:
            f, tc = (0.0, 0.0, 0.0), 25.0
        elif self.world is None:
            f, tc = (0.0, 0.0, 1.0), 25.0
        else:
            f = self.world.specific_force(t_us, self.mount)
            tc = self.world.temperature_c
        rate = (0.0, 0.0, 0.0)
        if self.world is not None:
            rate = mount_apply(self.mount, self.world.angular_rate_body(t_us))
        ac, gc = b2[_ACCEL_CONFIG], b2[_GYRO_CONFIG_1]
        abw = _ACCEL_BW_HZ[(ac >> 3) & 7] if ac & 1 else _ACCEL_BW_OFF_HZ
        gbw = _GYRO_BW_HZ[(gc >> 3) & 7] if gc & 1 else _GYRO_BW_OFF_HZ
        gcount = _GYRO_COUNTS_PER_DPS[(gc >> 1) & 0x03]
        g = Prng(self.seed, stream=t_us) if self.noise else None
        t_s = t_us / 1e6
        out = [0] * 7
        for i in range(3):
            v = (f[i] + self.bias_g[i]) * cpg
            w = (rate[i] + self.gyro_bias_dps[i] + self.gyro_temp_dps_per_c[i] * (tc - 25.0)
                 + self.gyro_drift_dps_per_s[i] * t_s) * gcount
            if g is not None:
                v += g.gauss(_ACCEL_PSD_G * math.sqrt(abw) * cpg)
                w += g.gauss(_GYRO_PSD_DPS * math.sqrt(gbw) * gcount)
            out[i] = _sat16(int(math.floor(v + 0.5)))
            out[3 + i] = _sat16(int(math.floor(w + 0.5)))
        out[6] = _sat16(int(math.floor((tc - _TEMP_OFFSET_C) * _TEMP_COUNTS_PER_C + 0.5)))
        for i in range(7):
            self.data[2 * i] = (out[i] >> 8) & 0xFF
            self.data[2 * i + 1] = out[i] & 0xFF
        self.int_status |= _RDY
        self.samples += 1

    # --- registers --------------------------------------------------------------------
    def next_pointer(self, reg):
        return (reg + 1) & 0x7F

    def read_reg(self, reg):
        reg &= 0x7F
        if reg == _BANK_SEL:
            return self.bank << 4
        if self.bank == 0:
            if _ACCEL <= reg <= _TEMP_LAST:
                return self.data[reg - _ACCEL]
            if reg == _WHO_AM_I:
                return _ID
            if reg == _INT_STATUS_1:
                v = self.int_status
                self.int_status = 0
                return v
        return self.banks[self.bank][reg]

    def write_reg(self, reg, value):
        reg &= 0x7F
        if reg == _BANK_SEL:
            self.bank = (value >> 4) & 0x03
            return
        if self.bank == 0:
            if reg == _PWR_MGMT_1:
                if value & _DEVICE_RESET:
                    self.power_on()
                    return
                was = self.asleep()
                self.banks[0][reg] = value
                if was != self.asleep():
                    self._restart()
                return
            if reg in (_WHO_AM_I, _INT_STATUS_1) or _ACCEL <= reg <= _TEMP_LAST:
                return   # read-only
        self.banks[self.bank][reg] = value
        if self.bank == 2 and reg in (_ACCEL_DIV_1, _ACCEL_DIV_2) and not self.asleep():
            self._restart()
