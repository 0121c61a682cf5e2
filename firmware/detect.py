"""Find the compass chip (and the accelerometer) on a bus.

    from machine import I2C, Pin
    from firmware.detect import detect
    mag = detect(I2C(0, scl=Pin(22), sda=Pin(21), freq=400000))  # any chip of CHIPS below
"""
# detect(i2c, **options) scans, tries the magnetometers CHIPS puts at each address that
# answered (by ID register, never the address alone), opens an IMU's bypass when none answers,
# and returns the configured driver, else SensorNotFound naming every address tried.
# detect_accel(i2c, **options): the accelerometer's driver, or None. How: docs/design.md
# (module notes, detect); the chip table: docs/chips.md.
import sys

from firmware.compat import const, drop
from firmware.errors import BusError, SensorNotFound
from firmware.i2cdevice import bus_error

_MAG = const(0x4D)  # "M": a magnetometer
_IMU = const(0x49)  # "I": an accelerometer whose I2C bypass may hide a magnetometer

# The chips, one line each (docs/chips.md: what adding a chip touches; host_sim/chips.py is the
# simulator's side, tests/test_chips.py checks the two agree). Fields, space-separated:
#   role (M, I), its I2C addresses (hex, comma-separated), its ID register (hex) and the ID
#   bytes it reads from there on (hex), the register's datasheet name, the driver's module
#   (firmware.<module>, the class its name in capitals), the chip's name as its datasheet
#   writes it, the driver's options (comma-separated), the accelerometers it may sit behind
#   (- for none).
# Lines that share an address are tried in table order. One bytes object a line: a str would be
# an interned name held from boot on, a field its own object (docs/chips.md, heap).
CHIPS = (
    b"M 0C 00 4809 WIA1 ak09916 AK09916 range,rate ICM-20948",
    b"M 0C 00 48 WIA ak8963 AK8963 range,rate MPU-9250,MPU-9255",
    b"M 0D 0D FF ID qmc5883l QMC5883L range,odr,osr MPU6050",
    b"M 1E 0A 483433 ID hmc5883l HMC5883L gain,rate,averaging MPU6050",
    b"M 1C,1E 0F 3D WHO_AM_I lis3mdl LIS3MDL range,odr,mode -",
    b"M 1E 4F 40 WHO_AM_I lis2mdl LIS2MDL range,odr -",
    b"M 2C 00 80 ID qmc5883p QMC5883P range,odr,osr,dsr -",
    b"M 30 39 10 Product_ID mmc5603 MMC5603 range,bw -",
    b"I 68,69 75 68 WHO_AM_I mpu6050 MPU6050 accel_range,dlpf,gyro_range -",
    b"I 68,69 75 71 WHO_AM_I mpu9250 MPU-9250 accel_range,dlpf,gyro_range -",
    b"I 68,69 75 73 WHO_AM_I mpu9250 MPU-9255 accel_range,dlpf,gyro_range -",
    b"I 68,69 00 EA WHO_AM_I icm20948 ICM-20948 accel_range,dlpf,gyro_range -",
    b"I 68,69 75 70 WHO_AM_I mpu9250 MPU-6500 accel_range,dlpf,gyro_range -",
)
_COMMON = b"delay_us,timeout_us"


def driver_class(module, name):
    """The driver class firmware.<module>.<name>, imported on first use."""
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
    # The drivers of one role (accel: _MAG or _IMU) whose chips answer at addresses the scan
    # found, in table order, made with the options they take. At each address the first line's
    # driver probes its own ID register (as a driver made by hand does); a later line's is
    # imported only when the table's ID register reads its ID. What refuses leaves a note, and
    # a driver module loaded for a chip that is not there is let go again. (Named as the
    # drivers' ID probe: each name a module defines is interned for good, docs/chips.md.)
    done = []
    for row in CHIPS:
        if row[0] != accel:
            continue
        for addr in found:
            i = 2  # is addr one of the line's addresses? (hex read in place: no allocation)
            while i:
                v = row[i]
                w = row[i + 1]
                if ((v - 48 if v < 58 else (v | 32) - 87) << 4
                        | (w - 48 if w < 58 else (w | 32) - 87)) == addr:
                    break
                i = i + 3 if row[i + 2] == 44 else 0  # 44: ","
            if not i:
                continue
            i = 0
            for n in range(5):  # the module: the sixth field
                i = row.find(b" ", i) + 1
            name = row[i:row.find(b" ", i)].decode()
            if (addr, name) in done:
                continue
            if [1 for d in done if d[0] == addr] and not _has_id(i2c, addr, row, notes):
                continue
            done.append((addr, name))
            loaded = "firmware." + name in sys.modules
            opts = options if accel == _IMU else {
                k: v for k, v in options.items() if _any(row, k.encode())
                or _any(_COMMON, k.encode())}
            try:
                yield driver_class(name, name.upper())(i2c, address=addr, **opts)
            except (SensorNotFound, BusError) as e:
                notes.append(str(e))
                if not loaded:
                    drop(name)
            except ValueError:
                # an option value this driver refuses (its checks come before its ID probe):
                # the caller's error only when this chip is the one there (AK8963 rate=8 is
                # not the AK09916's to refuse at their shared 0x0C)
                if _has_id(i2c, addr, row, notes):
                    raise
                if not loaded:
                    drop(name)


def _has_id(i2c, addr, row, notes):
    # True when the line's ID register at addr reads its ID; else a note says what it read
    f = row.split()
    reg = int(f[2], 16)
    want = bytearray(len(f[3]) // 2)
    for i in range(len(want)):
        want[i] = int(f[3][2 * i:2 * i + 2], 16)
    b = bytearray(len(want))
    try:
        i2c.readfrom_mem_into(addr, reg, b)
    except OSError as e:
        notes.append(str(bus_error(e, addr, reg)))
        return False
    if b != want:
        notes.append("0x%02X answers but %s (0x%02X) reads %s, not the %s's %s" % (
            addr, f[4].decode(), reg, _hex(b, " "), f[6].decode(), _hex(want, " ")))
        return False
    return True


def _any(buf, value):
    # True when the word `value` is in the line `buf` (between spaces or commas), read in place:
    # an option the line's driver takes (no other field of a line is an option's name). Its
    # names, as _probe's, are ones the firmware interns anyway (docs/chips.md, heap).
    i = buf.find(value)
    while i >= 0:
        j = i + len(value)
        if (i == 0 or buf[i - 1] in (32, 44)) and (j == len(buf) or buf[j] in (32, 44)):
            return True
        i = buf.find(value, j)
    return False


def _check_options(options):
    for k in options:
        if _any(_COMMON, k.encode()):
            continue
        for row in CHIPS:
            if row[0] == _MAG and _any(row, k.encode()):
                break
        else:
            known = [o for r in CHIPS if r[0] == _MAG for o in r.split()[7].split(b",")]
            raise TypeError("detect(): unknown option '%s' (expected one of %s)" % (
                k, ", ".join(sorted({o.decode() for o in known + _COMMON.split(b",")}))))


def detect(i2c, **options):
    """Return the driver of the magnetometer on `i2c` (see docs/design.md, module notes)."""
    if options:
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
    rows = [r.split() for r in CHIPS]
    tried = []
    mags = []
    for accel in (_MAG, _IMU):
        first = len(tried)
        for f in rows:
            for a in f[1].split(b","):
                a = int(a, 16)
                if f[0][0] == accel and a not in tried:
                    tried.append(a)
        tried[first:] = sorted(tried[first:])
    for a in tried:
        names = [g[6].decode() for g in rows if g[0][0] == _MAG and a in [
            int(h, 16) for h in g[1].split(b",")]]
        if names:
            mags.append("0x%02X (%s)" % (a, ", ".join(names)))
    raise SensorNotFound(
        "no magnetometer found: tried %s, and at %s the I2C bypass of an accelerometer (%s), "
        "behind which may sit %s; the bus scan found %s%s" % (
            ", ".join(mags), _hex(tried[len(mags):], "/"),
            ", ".join([f[6].decode() for f in rows if f[0][0] == _IMU]),
            ", ".join([(f[6] + b" (" + f[8].replace(b",", b", ") + b")").decode()
                       for f in rows if f[0][0] == _MAG and f[8] != b"-"]),
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
