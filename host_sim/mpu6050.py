"""MPU-6050 register model (I2C 0x68, or 0x69 with AD0 high): the accelerometer for tilt,
plus the GY-87 auxiliary-bus bypass that hides or shows the HMC5883L.

    imu = MPU6050Sim(world, mount=(1, -2, -3), seed=1)
    i2c.attach(0x68, imu)
    i2c.attach(0x1E, hmc, gate=imu.bypass_open)   # GY-87: HMC5883L behind the bypass

Registers (InvenSense register map rev 4.2 / product spec PS-MPU-6000A-00 rev 3.4):
0x19 SMPLRT_DIV, 0x1A CONFIG (DLPF_CFG[2:0]), 0x1B GYRO_CONFIG, 0x1C ACCEL_CONFIG
(AFS_SEL[4:3]: +-2/4/8/16 g = 16384/8192/4096/2048 counts/g), 0x37 INT_PIN_CFG (bit1
I2C_BYPASS_EN, bit4 INT_RD_CLEAR), 0x38 INT_ENABLE, 0x3A INT_STATUS (bit0 DATA_RDY_INT),
0x3B-0x40 ACCEL X/Y/Z int16 MSB first, 0x41-0x42 TEMP_OUT, 0x43-0x48 GYRO X/Y/Z,
0x6A USER_CTRL (bit5 I2C_MST_EN), 0x6B PWR_MGMT_1 (power-on 0x40: SLEEP; bit7 DEVICE_RESET),
0x75 WHO_AM_I = 0x68 (also at address 0x69). Other registers read back what was written
(0 at power-on).

Behaviour modelled (lazily, on the next transaction):
- Asleep (PWR_MGMT_1 bit6, the power-on state): the sensor registers do not update; they
  hold their last values, which read 0 after power-on or DEVICE_RESET. Writing 0x00 or 0x01
  wakes the chip; samples then arrive at the sample rate, gyro rate / (1 + SMPLRT_DIV),
  the gyro rate being 8 kHz with DLPF_CFG 0 or 7 and 1 kHz otherwise. The registers always
  show the newest sample (no lock); each new sample sets DATA_RDY_INT (whatever INT_ENABLE
  says, a model choice), cleared by reading INT_STATUS (or by any read with INT_RD_CLEAR).
- DEVICE_RESET restores every register (asleep, bypass off); the bit reads back 0.
- Accelerometer: specific force in the chip's axes, M * (-Gp) in g (+1 g on an axis
  pointing up), plus an optional fixed bias, times counts/g, plus noise, saturated to int16.
  Noise: the datasheet's 400 ug/sqrt(Hz) power spectral density times sqrt(DLPF bandwidth)
  (260, 184, 94, 44, 21, 10, 5 Hz for DLPF_CFG 0-6; 7 taken as 260): 6.4 mg RMS (105
  counts at +-2 g) at the power-on setting.
- Temperature: TEMP_OUT = (T - 36.53) * 340 (register map: T = TEMP_OUT / 340 + 36.53).
- Gyroscope: the board's rotation rate (World.angular_rate_body) through the mounting, plus
  a zero-rate offset (gyro_bias_dps; datasheet initial ZRO tolerance +-20 deg/s), its
  temperature coefficient (gyro_temp_dps_per_c times T - 25 C; datasheet ZRO variation
  +-20 deg/s over -40..85 C) and a slow linear drift with time (gyro_drift_dps_per_s, a model
  choice), plus noise of 0.05 deg/s RMS (datasheet total RMS noise), at 131/65.5/32.8/16.4
  counts per deg/s (GYRO_CONFIG FS_SEL), saturated to int16 like the accelerometer.
- Field faults (fault hooks): doze() - SLEEP set behind the driver's back (a glitch write
  or a partial reset): the outputs freeze at their last values, a frozen tilt; free_fall =
  True - the board falls, the accelerometer reads ~0 g (noise only); brown_out() -
  power-on defaults (asleep, data 0, bypass closed: a GY-87's magnetometer disappears);
  glitch(reg, value) - a write the driver never made. Reads of 0xFF bytes are a bus fault
  (SimI2C.stuck_high); absence is SimI2C.kill/revive.
- GY-87 bypass: bypass_open() is True when USER_CTRL.I2C_MST_EN = 0 and
  INT_PIN_CFG.I2C_BYPASS_EN = 1 (both 0 at power-on: the auxiliary chip is hidden). The
  MPU's own I2C master (slave 0-4, EXT_SENS_DATA) is not modelled; the FIFO reads 0.
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

_REG_SMPLRT_DIV = const(0x19)
_REG_CONFIG = const(0x1A)
_REG_GYRO_CONFIG = const(0x1B)
_REG_ACCEL_CONFIG = const(0x1C)
_REG_INT_PIN_CFG = const(0x37)
_REG_INT_STATUS = const(0x3A)
_REG_ACCEL = const(0x3B)
_REG_TEMP = const(0x41)
_REG_GYRO = const(0x43)
_REG_GYRO_LAST = const(0x48)
_REG_USER_CTRL = const(0x6A)
_REG_PWR_MGMT_1 = const(0x6B)
_REG_FIFO_R_W = const(0x74)
_REG_WHO_AM_I = const(0x75)

_WHO_AM_I = const(0x68)
_PWR_MGMT_1_DEFAULT = const(0x40)
_PWR_SLEEP = const(0x40)
_PWR_DEVICE_RESET = const(0x80)
_BYPASS_EN = const(0x02)
_INT_RD_CLEAR = const(0x10)
_I2C_MST_EN = const(0x20)
_DATA_RDY_INT = const(0x01)

_ACCEL_COUNTS_PER_G = (16384, 8192, 4096, 2048)
_GYRO_COUNTS_PER_DPS = (131.0, 65.5, 32.8, 16.4)
_DLPF_BW_HZ = (260, 184, 94, 44, 21, 10, 5, 260)
_ACCEL_PSD_G = 400e-6        # datasheet: 400 ug/sqrt(Hz) (AFS_SEL 0, 10 Hz)
_GYRO_RMS_DPS = 0.05         # datasheet: gyro total RMS noise 0.05 deg/s
_TEMP_COUNTS_PER_C = 340.0
_TEMP_OFFSET_C = 36.53


def _sat16(v):
    return 32767 if v > 32767 else (-32768 if v < -32768 else v)


class MPU6050Sim(RegisterDevice):
    """MPU-6050 (see the module docstring). `mount` is the accelerometer's body -> sensor
    signed permutation; `bias_g` a fixed zero-g offset per sensor axis (datasheet tolerance
    +-50 mg X/Y, +-80 mg Z; default none)."""

    ADDRESS = 0x68
    WHO_AM_I = _WHO_AM_I
    GYRO_RMS_DPS = _GYRO_RMS_DPS
    TEMP_COUNTS_PER_C = _TEMP_COUNTS_PER_C
    TEMP_OFFSET_C = _TEMP_OFFSET_C

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, bias_g=(0.0, 0.0, 0.0),
                 gyro_bias_dps=(0.0, 0.0, 0.0), gyro_temp_dps_per_c=(0.0, 0.0, 0.0),
                 gyro_drift_dps_per_s=(0.0, 0.0, 0.0)):
        RegisterDevice.__init__(self)
        self.world = world
        self.mount = tuple(mount)
        self.seed = seed
        self.noise = noise
        self.bias_g = (float(bias_g[0]), float(bias_g[1]), float(bias_g[2]))
        self.gyro_bias_dps = tuple(float(v) for v in gyro_bias_dps)
        self.gyro_temp_dps_per_c = tuple(float(v) for v in gyro_temp_dps_per_c)
        self.gyro_drift_dps_per_s = tuple(float(v) for v in gyro_drift_dps_per_s)
        self.samples = 0
        self.free_fall = False
        self.power_on()

    def power_on(self):
        self.regs = bytearray(128)
        self.regs[_REG_PWR_MGMT_1] = _PWR_MGMT_1_DEFAULT
        self.accel = [0, 0, 0]
        self.gyro = [0, 0, 0]
        self.temp = 0
        self.int_status = 0
        self._t0 = None
        self._k = 0
        self.pointer = 0

    # --- helpers ----------------------------------------------------------------------
    def asleep(self):
        return bool(self.regs[_REG_PWR_MGMT_1] & _PWR_SLEEP)

    def bypass_open(self):
        """GY-87: the auxiliary bus is joined to the main bus (HMC5883L visible)."""
        return (not self.regs[_REG_USER_CTRL] & _I2C_MST_EN) and bool(
            self.regs[_REG_INT_PIN_CFG] & _BYPASS_EN)

    def counts_per_g(self):
        return _ACCEL_COUNTS_PER_G[(self.regs[_REG_ACCEL_CONFIG] >> 3) & 0x03]

    def accel_sigma_g(self):
        """The accelerometer's RMS noise in g at the filter setting in use."""
        return _ACCEL_PSD_G * math.sqrt(_DLPF_BW_HZ[self.regs[_REG_CONFIG] & 0x07])

    def _gyro_hz(self):
        """Gyro output rate: 8 kHz with the DLPF off (DLPF_CFG 0 or 7), else 1 kHz."""
        dlpf = self.regs[_REG_CONFIG] & 0x07
        return 8000 if dlpf == 0 or dlpf == 7 else 1000

    # --- fault hooks (see the module docstring) ---------------------------------------
    def doze(self):
        self.write_reg(_REG_PWR_MGMT_1, self.regs[_REG_PWR_MGMT_1] | _PWR_SLEEP)

    def brown_out(self):
        self.power_on()

    def glitch(self, reg, value):
        self.write_reg(reg, value)

    # --- lazy time --------------------------------------------------------------------
    def update(self, now_us):
        if self._t0 is None:
            return
        # sample period = (1 + SMPLRT_DIV) / gyro rate, kept as a fraction of us (exact)
        num = (1 + self.regs[_REG_SMPLRT_DIV]) * 1000000
        den = self._gyro_hz()
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
        rate = (0.0, 0.0, 0.0)
        if self.free_fall:
            f = (0.0, 0.0, 0.0)
            tc = 25.0
        elif self.world is None:
            f = (0.0, 0.0, 1.0)
            tc = 25.0
        else:
            f = self.world.specific_force(t_us, self.mount)
            tc = self.world.temperature_c
        if self.world is not None:
            rate = mount_apply(self.mount, self.world.angular_rate_body(t_us))
        g = Prng(self.seed, stream=t_us) if self.noise else None
        sigma = self.accel_sigma_g() * cpg
        gyro_rms = self.GYRO_RMS_DPS
        gcount = _GYRO_COUNTS_PER_DPS[(self.regs[_REG_GYRO_CONFIG] >> 3) & 0x03]
        t_s = t_us / 1e6
        for i in range(3):
            v = (f[i] + self.bias_g[i]) * cpg
            w = (rate[i] + self.gyro_bias_dps[i] + self.gyro_temp_dps_per_c[i] * (tc - 25.0)
                 + self.gyro_drift_dps_per_s[i] * t_s) * gcount
            if g is not None:
                v += g.gauss(sigma)
                w += g.gauss(gyro_rms * gcount)
            self.accel[i] = _sat16(int(math.floor(v + 0.5)))
            self.gyro[i] = _sat16(int(math.floor(w + 0.5)))
        self.temp = _sat16(int(math.floor((tc - self.TEMP_OFFSET_C) * self.TEMP_COUNTS_PER_C
                                          + 0.5)))
        self.int_status |= _DATA_RDY_INT
        self.samples += 1

    # --- registers --------------------------------------------------------------------
    def next_pointer(self, reg):
        if reg == _REG_FIFO_R_W:
            return reg
        return (reg + 1) & 0x7F

    def read_reg(self, reg):
        reg &= 0x7F
        if self.regs[_REG_INT_PIN_CFG] & _INT_RD_CLEAR and reg != _REG_INT_STATUS:
            v = self._read(reg)
            self.int_status = 0
            return v
        return self._read(reg)

    def _read(self, reg):
        if _REG_ACCEL <= reg <= _REG_GYRO_LAST:
            i = reg - _REG_ACCEL
            if i < 6:
                v = self.accel[i >> 1]
            elif i < 8:
                v = self.temp
            else:
                v = self.gyro[(i - 8) >> 1]
            v &= 0xFFFF
            return v & 0xFF if i & 1 else v >> 8
        if reg == _REG_INT_STATUS:
            v = self.int_status
            self.int_status = 0
            return v
        if reg == _REG_WHO_AM_I:
            return self.WHO_AM_I
        if reg == _REG_FIFO_R_W:
            return 0
        return self.regs[reg]

    def write_reg(self, reg, value):
        reg &= 0x7F
        if reg == _REG_PWR_MGMT_1:
            if value & _PWR_DEVICE_RESET:
                self.power_on()
                return
            was_asleep = self.asleep()
            self.regs[reg] = value
            if was_asleep != self.asleep():
                self._restart()
        elif reg in (_REG_WHO_AM_I, _REG_INT_STATUS) or _REG_ACCEL <= reg <= _REG_GYRO_LAST:
            return   # read-only
        else:
            self.regs[reg] = value
            if reg in (_REG_SMPLRT_DIV, _REG_CONFIG) and not self.asleep():
                self._restart()


# MPU-9250 / MPU-9255: the MPU-6050's accelerometer and gyroscope registers (and the same
# bypass), its own WHO_AM_I, filter register and noise (product specification PS-MPU-9250A-01
# rev 1.0, table 2, and register map RM-MPU-9250A-00 rev 1.4, 4.8 and 4.38).
_REG_ACCEL_CONFIG2 = const(0x1D)  # ACCEL_FCHOICE_B bit3, A_DLPF_CFG[2:0]
_A_DLPF_BW_HZ = (218.1, 218.1, 99.0, 44.8, 21.2, 10.2, 5.05, 420.0)
_ACCEL_PSD_G_9250 = 300e-6     # 300 ug/sqrt(Hz)


class MPU9250Sim(MPU6050Sim):
    """MPU-9250 (WHO_AM_I 0x71) or, with who_am_i=0x73, MPU-9255 (0x70: the MPU-6500, the
    MPU-9250's accelerometer and gyroscope without its magnetometer): the MPU-6050 model with
    WHO_AM_I, the accelerometer's own low-pass filter in ACCEL_CONFIG2 (0x1D: A_DLPF_CFG
    0-7 = 218, 218, 99, 45, 21, 10, 5, 420 Hz; ACCEL_FCHOICE_B = 1 bypasses it, 1046 Hz),
    300 ug/sqrt(Hz) of accelerometer noise, 0.1 deg/s RMS of gyroscope noise and the
    temperature scale T = TEMP_OUT / 333.87 + 21 C. Its AK8963 sits behind the bypass
    (host_sim/ak8963.py; host_sim/boards.py 'gy9250')."""

    WHO_AM_I = 0x71
    GYRO_RMS_DPS = 0.1
    TEMP_COUNTS_PER_C = 333.87
    TEMP_OFFSET_C = 21.0

    def __init__(self, world=None, mount=(1, -2, -3), seed=1, noise=True, who_am_i=0x71, **kw):
        self.WHO_AM_I = who_am_i
        MPU6050Sim.__init__(self, world, mount, seed, noise, **kw)

    def accel_sigma_g(self):
        a2 = self.regs[_REG_ACCEL_CONFIG2]
        bw = 1046.0 if a2 & 0x08 else _A_DLPF_BW_HZ[a2 & 0x07]
        return _ACCEL_PSD_G_9250 * math.sqrt(bw)
