"""Find the compass chip (and the accelerometer) on a bus.

    from machine import I2C, Pin
    from firmware.detect import detect
    mag = detect(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000))  # any chip of CHIPS below
"""
# detect(i2c, **options) scans the bus; at each address that answered where CHIPS puts a
# magnetometer it reads that chip's ID register, and only a chip whose ID matches has its
# driver imported and made: never the address alone (0x1E is more than one chip). When no
# magnetometer answers but an accelerometer of CHIPS does (0x68/0x69), it wakes it, opens its
# I2C bypass and looks again: a GY-87 keeps its HMC5883L on the MPU6050's auxiliary bus, an
# MPU-9250 its AK8963, invisible until then. It returns the configured driver; `options` go to
# the driver that takes them (CHIPS' last but one column; every magnetometer: delay_us,
# timeout_us). A value the chip found does not support raises ValueError. An empty bus or wrong
# IDs raise SensorNotFound naming every address tried, what the scan found and what each known
# address answered.
#
# detect_accel(i2c, **options) returns the accelerometer's driver, or None when none answers
# (a DS3231 RTC also sits at 0x68: a wrong WHO_AM_I there is "no accelerometer", not an error).
import sys

from firmware.compat import const, drop
from firmware.errors import BusError, SensorNotFound
from firmware.i2cdevice import bus_error

_MAG = const(0)
_IMU = const(1)  # an accelerometer whose I2C bypass may hide a magnetometer

# The chips, one row each (docs/chips.md: what adding a chip touches; host_sim/chips.py is the
# simulator's side, tests/test_chips.py checks the two agree):
#   kind, role, name as its datasheet writes it, I2C addresses, ID register, its name, the
#   ID bytes read from there on (any of them), firmware.<module>.<class>, the driver's options,
#   the accelerometers whose bypass it sits behind (for the message when nothing is found).
# Rows sharing an address are tried in table order. Text is bytes: a str constant would be an
# interned name held from boot on (docs/design.md, memory), for every chip found or not.
CHIPS = (
    (b"qmc5883l", _MAG, b"QMC5883L", (0x0D,), 0x0D, b"ID", (b"\xff",), b"qmc5883l",
     b"QMC5883L", (b"range", b"odr", b"osr"), (b"mpu6050",)),
    (b"hmc5883l", _MAG, b"HMC5883L", (0x1E,), 0x0A, b"ID", (b"H43",), b"hmc5883l", b"HMC5883L",
     (b"gain", b"rate", b"averaging"), (b"mpu6050",)),
    (b"qmc5883p", _MAG, b"QMC5883P", (0x2C,), 0x00, b"ID", (b"\x80",), b"qmc5883p", b"QMC5883P",
     (b"range", b"odr", b"osr", b"dsr"), ()),
    (b"mpu6050", _IMU, b"MPU6050", (0x68, 0x69), 0x75, b"WHO_AM_I", (b"\x68",), b"mpu6050",
     b"MPU6050", (b"accel_range", b"dlpf", b"gyro_range"), ()),
)
_COMMON = (b"delay_us", b"timeout_us")


def driver_class(module, name):
    """The driver class firmware.<module>.<name>, imported on first use."""
    if not isinstance(module, str):
        module, name = module.decode(), name.decode()
    mod = __import__("firmware." + module, None, None, (name,))
    return getattr(mod, name)


def _hex(addrs, sep=", "):
    return sep.join("0x%02X" % a for a in addrs)


def _scan(i2c):
    try:
        return list(i2c.scan())
    except OSError as e:
        raise bus_error(e, None, None)


def _probe(i2c, accel, found, notes, options):
    # The drivers of one role (accel: the accelerometers) whose chips answer at addresses the
    # scan found, in table order, made with the options they take. At each address the first
    # row's driver probes its own ID register (as a driver made by hand does); a later row's
    # is imported only when the table's ID register reads its ID. What refuses leaves a note,
    # and a driver module loaded for a chip that is not there is let go again. (Named as the
    # drivers' ID probe: each name a module defines is interned for good, docs/chips.md.)
    done = []
    for row in CHIPS:
        if row[1] != accel:
            continue
        for addr in row[3]:
            if addr not in found or (addr, row[7]) in done:
                continue
            if [1 for d in done if d[0] == addr]:
                b = bytearray(len(row[6][0]))
                try:
                    i2c.readfrom_mem_into(addr, row[4], b)
                except OSError as e:
                    notes.append(str(bus_error(e, addr, row[4])))
                    continue
                if bytes(b) not in row[6]:
                    notes.append("0x%02X answers but %s (0x%02X) reads %s, not the %s's %s" % (
                        addr, row[5].decode(), row[4], _hex(b, " "), row[2].decode(),
                        ", ".join(_hex(i, " ") for i in row[6])))
                    continue
            done.append((addr, row[7]))
            name = "firmware." + row[7].decode()
            loaded = name in sys.modules
            opts = options if accel else {
                k: v for k, v in options.items() if k.encode() in row[9] + _COMMON}
            try:
                yield driver_class(row[7], row[8])(i2c, address=addr, **opts)
            except (SensorNotFound, BusError) as e:
                notes.append(str(e))
                if not loaded:
                    drop(row[7].decode())


def _check_options(options):
    known = set(_COMMON)
    for row in CHIPS:
        if row[1] == _MAG:
            known |= set(row[9])
    for k in options:
        if k.encode() not in known:
            raise TypeError("detect(): unknown option '%s' (expected one of %s)"
                            % (k, ", ".join(sorted(o.decode() for o in known))))


def detect(i2c, **options):
    """Return the driver of the magnetometer on `i2c` (see the module's opening comment)."""
    _check_options(options)
    notes = []
    found = _scan(i2c)
    seen = list(found)
    for mag in _probe(i2c, _MAG, found, notes, options):
        return mag
    for imu in _probe(i2c, _IMU, found, notes, {}):
        try:
            imu.enable_bypass()
        except BusError as e:
            notes.append(str(e))
            continue
        behind = _scan(i2c)
        for a in behind:
            if a not in seen:
                seen.append(a)
        for mag in _probe(i2c, _MAG, [a for a in behind if a not in found], notes, options):
            return mag
    # nothing: every address of the table (magnetometers first), what answered, and why
    tried = []
    mags = []
    for row in CHIPS:
        for a in row[3]:
            if row[1] == _MAG and a not in tried:
                tried.append(a)
                mags.append("0x%02X (%s)" % (a, ", ".join(
                    [r[2].decode() for r in CHIPS if r[1] == _MAG and a in r[3]])))
    n = len(tried)
    accels = []
    for row in CHIPS:
        if row[1] == _IMU:
            accels.append(row[2].decode())
            tried += [a for a in row[3] if a not in tried]
    raise SensorNotFound(
        "no magnetometer found: tried %s, and the I2C bypass of an accelerometer at %s (%s), "
        "behind which sit %s; the bus scan found %s%s" % (
            ", ".join(mags), _hex(tried[n:], "/"), ", ".join(accels),
            ", ".join(["%s (%s)" % (r[2].decode(), ", ".join(
                [i[2].decode() for i in CHIPS if i[0] in r[10]])) for r in CHIPS if r[10]]),
            "[" + _hex(sorted(seen)) + "]" if seen else "nothing",
            "; " + "; ".join(notes) if notes else ""),
        address=None, tried=tried, found=sorted(seen))


def detect_accel(i2c, **options):
    """Return the accelerometer's driver (woken, `options` e.g. accel_range=2), or None if
    none answers."""
    # (something else may answer there: a DS3231 RTC uses 0x68)
    for imu in _probe(i2c, _IMU, _scan(i2c), [], options):
        return imu
    return None
