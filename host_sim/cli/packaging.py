"""Print the mip package.json: URLs relative to itself, so both installs work with mpremote
1.29 (mpremote/mip.py resolves a relative URL against the package.json's own location):

    mpremote mip install github:OWNER/REPO          # whoever publishes the repository
    mpremote mip install ./package.json             # from a clone, files read locally

Each lands in the board's lib folder as lib/firmware/NAME.

Install what you use: the firmware also comes in parts (PARTS), one package file each at the
repository's top, package-PART.json, with the same relative URLs (micropython-lib splits a
large package into feature packages the same way):

    mpremote mip install github:OWNER/REPO/package-core.json       # a calibrated board
    mpremote mip install github:OWNER/REPO/package-calibrate.json  # + calibrating on the board

"core" is what a board needs to show a heading from a stored calibration (its drivers, boot,
store, status line); every other part adds one capability and needs the parts in its
REQUIRES entry. README.md's install section gives the measured heap beside each.

`make package-json` writes them all; tests/test_packaging.py checks the committed files are
current, that every firmware file is in exactly one part, and that each part imports with
only the parts it requires installed.
"""
import json
import os
import sys

from host_sim.cli.args import Parser

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


# part -> firmware files (docs/design.md, memory: what each job loads)
PARTS = {
    "core": ("__init__.py", "compat.py", "errors.py", "fixedpoint.py", "i2cdevice.py",
             "devinit.py", "detect.py", "qmc5883l.py", "qmc5883p.py", "hmc5883l.py",
             "mpu6050.py", "axes.py", "calibration.py", "kang_tables.py", "trig.py",
             "compass.py", "health.py", "fieldwatch.py", "store.py", "slots.py", "persist.py", "appsetup.py",
             "app.py", "status.py", "accuracy.py", "boot.py", "fast.py", "mountnote.py"),
    # collecting, solving (4, 7, 10 elements), accepting and the history of fits
    "calibrate": ("session.py", "calibrator.py", "samples.py", "accum.py", "solve.py",
                  "acceptance.py", "history.py", "calmode.py", "mounting.py", "mountcheck.py"),
    # PJRC MotionCal's serial protocol and the board's MotionCal mode
    "motioncal": ("motioncal.py", "motioncal_mode.py"),
    # the World Magnetic Model on the board, set_location(), quick_calibrate()
    "field": ("field.py", "wmm2025.bin", "location.py", "quickcal.py"),
    # a calibration file fitted on the desktop, imported at boot
    "import": ("calimport.py",),
    # the gyro-aided heading: the MPU6050's gyroscope in an attitude filter (use_gyro())
    "gyro": ("attitude.py", "attitude_plain.py", "attitude_fast.py", "gyrosetup.py"),
    # CircuitPython's busio.I2C behind the machine.I2C calls the drivers make
    "circuitpython": ("busio_i2c.py",),
}
# the parts each part needs installed beside it
REQUIRES = {"core": (), "calibrate": ("core",), "motioncal": ("core", "calibrate"),
            "field": ("core", "calibrate"), "import": ("core",), "gyro": ("core",),
            "circuitpython": ("core",)}


def _entry(files):
    sys.path.insert(0, ROOT)
    from firmware import __version__
    return {
        "urls": [["firmware/" + m, "firmware/" + m] for m in sorted(files)],
        "deps": [],
        "version": __version__,
    }


def package_json(part=None):
    """The package file of `part` (None: the whole firmware, package.json)."""
    if part is not None:
        return _entry(PARTS[part])
    return _entry(f for f in os.listdir(os.path.join(ROOT, "firmware"))
                  if f.endswith(".py") or f.endswith(".bin"))  # .bin: field.py's table


def write_all():
    """package.json and package-PART.json for every part, at the repository's top."""
    for part in (None,) + tuple(PARTS):
        name = "package.json" if part is None else "package-%s.json" % part
        with open(os.path.join(ROOT, name), "w") as f:
            f.write(json.dumps(package_json(part), indent=2) + "\n")


def main(argv=()):
    p = Parser("cli.packaging", "[--write]",
               "Print the mip package.json; --write writes it and package-PART.json for every "
               "part (make package-json).")
    p.option("--write", "flag", help="write package.json and the parts' package files")
    return p.main(list(argv), _body)


def _body(opts):
    if opts["write"]:
        write_all()
    else:
        print(json.dumps(package_json(), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
