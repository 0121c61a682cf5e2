"""Find the compass chip (and the accelerometer) on a bus.

    from machine import I2C, Pin
    from firmware.detect import detect
    mag = detect(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000))  # QMC5883L, HMC5883L, QMC5883P
"""
# detect(i2c, **options) scans the bus, then probes 0x0D (QMC5883L), 0x1E (HMC5883L) and 0x2C
# (QMC5883P) where something answered, checking their ID registers. When none of them answers but
# an MPU6050 does (0x68/0x69), it wakes it and opens its I2C bypass, then probes again: a
# GY-87/GY-86 board keeps its HMC5883L on the MPU6050's auxiliary bus, invisible until then.
# Only the driver module of a chip that answered is imported. It returns the configured driver;
# `options` go to the driver that accepts them (QMC5883L: range, odr, osr; HMC5883L: gain, rate,
# averaging; QMC5883P: range, odr, osr, dsr; all: delay_us, timeout_us). A value the chip found
# does not support raises ValueError. An empty bus or wrong IDs raise SensorNotFound naming every
# address tried and what the scan found.
#
# detect_accel(i2c, **options) returns an MPU6050 driver, or None when none answers (a DS3231 RTC
# also sits at 0x68: a wrong WHO_AM_I there is "no accelerometer", not an error).
from firmware.compat import const
from firmware.errors import BusError, SensorNotFound
from firmware.i2cdevice import bus_error

_QMC5883L_ADDR = const(0x0D)
_HMC5883L_ADDR = const(0x1E)
_QMC5883P_ADDR = const(0x2C)
_MPU6050_ADDR = const(0x68)
_MPU6050_ADDR_AD0 = const(0x69)

# address, module, class, the options it takes (kept here so that checking them imports nothing)
_MAGS = ((_QMC5883L_ADDR, "qmc5883l", "QMC5883L", ("range", "odr", "osr")),
         (_HMC5883L_ADDR, "hmc5883l", "HMC5883L", ("gain", "rate", "averaging")),
         (_QMC5883P_ADDR, "qmc5883p", "QMC5883P", ("range", "odr", "osr", "dsr")))
_COMMON = ("delay_us", "timeout_us")


def driver_class(module, name):
    """The driver class firmware.<module>.<name>, imported on first use."""
    mod = __import__("firmware." + module, None, None, (name,))
    return getattr(mod, name)


def _hex(addrs):
    return "[" + ", ".join("0x%02X" % a for a in addrs) + "]" if addrs else "nothing"


def _scan(i2c):
    try:
        return list(i2c.scan())
    except OSError as e:
        raise bus_error(e, None, None)


def _probe_mags(i2c, found, options, notes):
    for addr, module, name, accepts in _MAGS:
        if addr not in found:
            continue
        opts = {k: v for k, v in options.items() if k in accepts or k in _COMMON}
        try:
            return driver_class(module, name)(i2c, address=addr, **opts)
        except (SensorNotFound, BusError) as e:
            notes.append(str(e))
    return None


def _check_options(options):
    known = set(_COMMON)
    for m in _MAGS:
        known |= set(m[3])
    for k in options:
        if k not in known:
            raise TypeError("detect(): unknown option '%s' (expected one of %s)"
                            % (k, ", ".join(sorted(known))))


def detect(i2c, **options):
    """Return the driver of the magnetometer on `i2c` (see the module's opening comment)."""
    _check_options(options)
    notes = []
    found = _scan(i2c)
    seen = list(found)
    mag = _probe_mags(i2c, found, options, notes)
    if mag is not None:
        return mag
    for addr in (_MPU6050_ADDR, _MPU6050_ADDR_AD0):
        if addr not in found:
            continue
        try:
            mpu = driver_class("mpu6050", "MPU6050")(i2c, address=addr)
            mpu.enable_bypass()
        except (SensorNotFound, BusError) as e:
            notes.append(str(e))
            continue
        behind = _scan(i2c)
        for a in behind:
            if a not in seen:
                seen.append(a)
        mag = _probe_mags(i2c, [a for a in behind if a not in found], options, notes)
        if mag is not None:
            return mag
    raise SensorNotFound(
        "no magnetometer found: tried 0x0D (QMC5883L), 0x1E (HMC5883L), 0x2C (QMC5883P) and the "
        "MPU6050 bypass at 0x68/0x69 (GY-87); the bus scan found %s%s"
        % (_hex(sorted(seen)), "; " + "; ".join(notes) if notes else ""),
        address=None, tried=(_QMC5883L_ADDR, _HMC5883L_ADDR, _QMC5883P_ADDR, _MPU6050_ADDR,
                             _MPU6050_ADDR_AD0),
        found=sorted(seen))


def detect_accel(i2c, **options):
    """Return an MPU6050 driver (woken, `options` e.g. accel_range=2), or None if none answers."""
    found = _scan(i2c)
    for addr in (_MPU6050_ADDR, _MPU6050_ADDR_AD0):
        if addr in found:
            try:
                return driver_class("mpu6050", "MPU6050")(i2c, address=addr, **options)
            except SensorNotFound:
                continue  # something else lives there (a DS3231 RTC uses 0x68)
    return None
