"""The chips the simulator models and the firmware drives, one entry each: what the
simulator's boards, the demo, serve and calibrate --sensor derive their lists from.

    from host_sim import chips
    chips.mag("qmc5883l")["ranges"]     # (("2", 0, 12000, 2), ("8", 1, 3000, 8))
    chips.MAG_KINDS                     # every magnetometer, in table order
    chips.DEMO_CHIPS                    # what `demo --chip` and `serve --chip` accept

docs/chips.md says what a new chip touches. The firmware keeps its own table
(firmware/detect.py CHIPS: this simulator never imports firmware/); tests/test_chips.py
checks that the two name the same chips, addresses, ID registers and IDs, that each range's
counts per gauss are the driver's, and that each mirror flag is the driver's.

MAGS, one dict per magnetometer:
  kind        the firmware driver's KIND (records, calibration files, --sensor)
  name        as the datasheet writes it
  address     its I2C address (the simulated board's); addresses: every one it may have,
              where more than one; id: (ID register, the bytes it reads from there on)
  model       "module.Class" of its register model in host_sim/
  ranges      per range code: (full scale in gauss as text, range code, counts per gauss, the
              value of the driver's range option for it); range_option names that option
              (None: the chip has one range and no option)
  default     the driver's default range (text); output: the raw output's (lo, hi);
  overflow    a raw value the chip writes on overflow besides the int16 rails, or None
  mirror      True where the datasheet draws the magnetometer's axes as a mirror image of
              its package's accelerometer's (a left-handed pair): MAG_AXES is then a mirror
  demo_options  driver options the demo adds (the HMC5883L's fastest rate)
  standby     (register, bytes) a write that stops the conversions (standby, idle, suspend or
              power-down): no data-ready after it; None where the driver commands each
              measurement
IMUS, one dict per accelerometer: kind, name, addresses, id, model (as above), options (what
  the model is made with: the MPU-9255 and the MPU-6500 are the MPU-9250's model with their
  WHO_AM_I).
BOARDS: make_board's names -> (magnetometer kind, accelerometer kind or None, True when the
  magnetometer sits behind the accelerometer's I2C bypass, the breakout's label, the
  magnetometer's mounting on the board: body -> sensor, host_sim.world).
DEMOS: demo --chip NAME -> (make_board name, add a GY-521 module, the breakout whose axes
  boards/breakouts.py gives, label).
BREAKOUTS: a breakout's silkscreen name (calibrate --sensor) -> (the magnetometer kind, what
  to say when that breakout may carry another chip, or None).
"""

MAGS = (
    {"kind": "qmc5883l", "name": "QMC5883L", "address": 0x0D, "id": (0x0D, b"\xff"),
     "model": "qmc5883l.QMC5883LSim",
     "ranges": (("2", 0, 12000, 2), ("8", 1, 3000, 8)), "range_option": "range",
     "default": "2", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": (0x09, b"\x00")},
    {"kind": "hmc5883l", "name": "HMC5883L", "address": 0x1E, "id": (0x0A, b"H43"),
     "model": "hmc5883l.HMC5883LSim",
     # 12-bit output -2048..2047; -4096 marks an ADC overflow (datasheet, data output registers)
     "ranges": (("0.88", 0, 1370, 0), ("1.3", 1, 1090, 1), ("1.9", 2, 820, 2),
                ("2.5", 3, 660, 3), ("4.0", 4, 440, 4), ("4.7", 5, 390, 5), ("5.6", 6, 330, 6),
                ("8.1", 7, 230, 7)), "range_option": "gain",
     "default": "1.3", "output": (-2048, 2047), "overflow": -4096, "mirror": False,
     "demo_options": {"rate": 75}, "standby": (0x02, b"\x02")},
    {"kind": "qmc5883p", "name": "QMC5883P", "address": 0x2C, "id": (0x00, b"\x80"),
     "model": "qmc5883p.QMC5883PSim",
     "ranges": (("30", 0, 1000, 30), ("12", 1, 2500, 12), ("8", 2, 3750, 8),
                ("2", 3, 15000, 2)), "range_option": "range",
     "default": "8", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": (0x0A, b"\x00")},
    # AK8963 inside the MPU-9250 / MPU-9255 (datasheet MS1356-E-02; MPU-9250 register map
    # RM-MPU-9250A-00 section 5): one range, +-4912 uT at 0.15 uT/LSB = 666.7 counts/G
    # (667 here, an integer as the firmware's counts_per_gauss), after the fuse-ROM ASA
    {"kind": "ak8963", "name": "AK8963", "address": 0x0C, "id": (0x00, b"\x48"),
     "model": "ak8963.AK8963Sim",
     "ranges": (("49", 0, 667, 49),), "range_option": "range",
     "default": "49", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": (0x0A, b"\x10")},
    # AK09916 inside the ICM-20948 (datasheet DS-000189 sections 3.3, 13): as the AK8963
    {"kind": "ak09916", "name": "AK09916", "address": 0x0C, "id": (0x00, b"\x48\x09"),
     "model": "ak09916.AK09916Sim",
     "ranges": (("49", 0, 667, 49),), "range_option": "range",
     "default": "49", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": (0x31, b"\x00")},
    # LIS3MDL (ST; docs/hardware.md): at 0x1C (SA1 low, the board here) or 0x1E
    {"kind": "lis3mdl", "name": "LIS3MDL", "address": 0x1C, "addresses": (0x1C, 0x1E),
     "id": (0x0F, b"\x3d"), "model": "lis3mdl.LIS3MDLSim",
     "ranges": (("4", 0, 6842, 4), ("8", 1, 3421, 8), ("12", 2, 2281, 12),
                ("16", 3, 1711, 16)), "range_option": "range",
     "default": "4", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": (0x22, b"\x03")},
    # LIS2MDL (ST; docs/hardware.md): one range, the driver's 2000 counts/G (three times the
    # chip's 1.5 mG LSB); its axes are a left-handed set (docs/hardware.md, handedness)
    {"kind": "lis2mdl", "name": "LIS2MDL", "address": 0x1E, "id": (0x4F, b"\x40"),
     "model": "lis2mdl.LIS2MDLSim",
     "ranges": (("16", 0, 2000, 16),), "range_option": "range",
     "default": "16", "output": (-32768, 32767), "overflow": None, "mirror": True,
     "demo_options": {}, "standby": (0x60, b"\x03")},
    # MMC5603NJ (MEMSIC; docs/hardware.md): the driver's field H / 2^s, s = 1..4; it commands
    # each measurement, so no write stops its samples (standby None)
    {"kind": "mmc5603", "name": "MMC5603", "address": 0x30, "id": (0x39, b"\x10"),
     "model": "mmc5603.MMC5603Sim",
     "ranges": (("4", 0, 8192, 4), ("8", 1, 4096, 8), ("16", 2, 2048, 16),
                ("30", 3, 1024, 30)), "range_option": "range",
     "default": "4", "output": (-32768, 32767), "overflow": None, "mirror": False,
     "demo_options": {}, "standby": None},
)

IMUS = (
    {"kind": "mpu6050", "name": "MPU6050", "addresses": (0x68, 0x69), "id": (0x75, b"\x68"),
     "model": "mpu6050.MPU6050Sim"},
    {"kind": "mpu9250", "name": "MPU-9250", "addresses": (0x68, 0x69), "id": (0x75, b"\x71"),
     "model": "mpu6050.MPU9250Sim"},
    {"kind": "mpu9255", "name": "MPU-9255", "addresses": (0x68, 0x69), "id": (0x75, b"\x73"),
     "model": "mpu6050.MPU9250Sim", "options": {"who_am_i": 0x73}},
    # the MPU-9250 without its AK8963 (register map RM-MPU-6500A-00 rev 2.1; docs/hardware.md)
    {"kind": "mpu6500", "name": "MPU-6500", "addresses": (0x68, 0x69), "id": (0x75, b"\x70"),
     "model": "mpu6050.MPU9250Sim", "options": {"who_am_i": 0x70}},
    {"kind": "icm20948", "name": "ICM-20948", "addresses": (0x68, 0x69), "id": (0x00, b"\xea"),
     "model": "icm20948.ICM20948Sim"},
)

# the usual lie of a breakout: x forward, y left, z up (host_sim.world mounting, body ->
# sensor); the magnetometers inside an IMU sit in their package as its datasheet draws them
_XFWD = (1, -2, -3)
_AK8963_IN_MPU9250 = (-2, 1, 3)   # x = the accelerometer's y, y = its x, z = -its z
_AK09916_IN_ICM20948 = (1, 2, 3)  # x = the accelerometer's x, y = -its y, z = -its z
_XFWD_MIRROR = (1, -2, 3)  # a left-handed chip (LIS2MDL): x forward, y left, its z down

BOARDS = (
    ("qmc5883l", ("qmc5883l", None, False, "QMC5883L module", _XFWD)),
    ("gy271", ("qmc5883l", None, False, "GY-271 (QMC5883L)", _XFWD)),
    ("hmc5883l", ("hmc5883l", None, False, "GY-273 (HMC5883L)", _XFWD)),
    ("qmc5883p", ("qmc5883p", None, False, "GY-271 (QMC5883P)", _XFWD)),
    ("gy87", ("hmc5883l", "mpu6050", True, "GY-87 (MPU6050 + HMC5883L behind its bypass)",
              _XFWD)),
    ("gy87-qmc", ("qmc5883l", "mpu6050", True, "GY-87 clone (MPU6050 + QMC5883L)", _XFWD)),
    ("lis3mdl", ("lis3mdl", None, False, "LIS3MDL module", _XFWD)),
    ("lis2mdl", ("lis2mdl", None, False, "LIS2MDL module", _XFWD_MIRROR)),
    ("mmc5603", ("mmc5603", None, False, "MMC5603 module", _XFWD)),
    ("gy9250", ("ak8963", "mpu9250", True, "GY-9250 (MPU-9250, its AK8963 behind the bypass)",
                _AK8963_IN_MPU9250)),
    ("icm20948", ("ak09916", "icm20948", True,
                  "ICM-20948 module (its AK09916 behind the bypass)", _AK09916_IN_ICM20948)),
)

DEMOS = (
    ("qmc5883l", ("gy271", True, "gy271", "GY-271 (QMC5883L) + GY-521 (MPU6050)")),
    ("hmc5883l", ("hmc5883l", True, "gy273", "GY-273 (HMC5883L) + GY-521 (MPU6050)")),
    ("gy87", ("gy87", None, "gy87", "GY-87 (MPU6050 + HMC5883L behind its bypass)")),
    ("qmc5883p", ("qmc5883p", True, "gy271", "GY-271 (QMC5883P) + GY-521 (MPU6050)")),
    ("lis3mdl", ("lis3mdl", True, "lis3mdl", "LIS3MDL module + GY-521 (MPU6050)")),
    ("lis2mdl", ("lis2mdl", True, "lis2mdl", "LIS2MDL module + GY-521 (MPU6050)")),
    ("mmc5603", ("mmc5603", True, "mmc5603", "MMC5603 module + GY-521 (MPU6050)")),
    ("ak8963", ("gy9250", None, "gy9250", "GY-9250 (MPU-9250 + its AK8963)")),
    ("ak09916", ("icm20948", None, "icm20948", "ICM-20948 module (+ its AK09916)")),
)

BREAKOUTS = (
    ("gy271", ("qmc5883l", "a newer GY-271 carries a QMC5883P (I2C 0x2C): --sensor qmc5883p")),
    ("gy273", ("hmc5883l", None)),
    ("gy87", ("hmc5883l", "a GY-87 with a QMC5883L: --sensor qmc5883l")),
    ("gy9250", ("ak8963", None)),
    ("gy91", ("ak8963", None)),
    ("mpu9250", ("ak8963", None)),
    ("mpu9255", ("ak8963", None)),
    ("icm20948", ("ak09916", None)),
)

MAG_KINDS = tuple(m["kind"] for m in MAGS)
BOARD_NAMES = tuple(b[0] for b in BOARDS)
DEMO_CHIPS = tuple(d[0] for d in DEMOS)


def _find(rows, key, what):
    for r in rows:
        if (r["kind"] if isinstance(r, dict) else r[0]) == key:
            return r if isinstance(r, dict) else r[1]
    raise ValueError("unknown %s %r; expected one of %s" % (
        what, key, ", ".join(r["kind"] if isinstance(r, dict) else r[0] for r in rows)))


def mag(kind):
    """The MAGS entry of `kind` (ValueError listing the kinds)."""
    return _find(MAGS, kind, "magnetometer")


def imu(kind):
    """The IMUS entry of `kind`."""
    return _find(IMUS, kind, "accelerometer")


def board(name):
    """BOARDS' (magnetometer kind, accelerometer kind or None, behind its bypass, label,
    the magnetometer's mounting)."""
    return _find(BOARDS, name, "board")


def demo(name):
    """DEMOS' (make_board name, GY-521 added, breakout, label)."""
    return _find(DEMOS, name, "demo chip")


def breakout(name):
    """BREAKOUTS' (magnetometer kind, note or None), or None for an unknown name."""
    for b in BREAKOUTS:
        if b[0] == name:
            return b[1]
    return None


def model_class(entry):
    """The register model class of a MAGS or IMUS entry (imported on first use)."""
    module, cls = entry["model"].split(".")
    mod = __import__("host_sim." + module, None, None, (cls,))
    return getattr(mod, cls)
