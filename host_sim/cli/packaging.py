"""Print the mip package.json: URLs relative to itself, so both installs work with mpremote
1.29 (mpremote/mip.py resolves a relative URL against the package.json's own location):

    mpremote mip install github:OWNER/REPO          # whoever publishes the repository
    mpremote mip install ./package.json             # from a clone, files read locally

Each lands in the board's lib folder as lib/firmware/NAME.

Install what you use: the firmware also comes in parts, one folder each (firmware/PART/;
core is the files at firmware/'s root), and one package file each at the repository's top,
package-PART.json, with the same relative URLs (micropython-lib splits a
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


FIRMWARE = os.path.join(ROOT, "firmware")
# what each part is for (the part is its folder: firmware/PART/, core the files at the root)
ABOUT = {
    "core": "a calibrated board: drivers, heading, store, status line",
    "calibrate": "collecting, solving (4, 7, 10 elements), accepting and the history of fits",
    "motioncal": "PJRC MotionCal's serial protocol and the board's MotionCal mode",
    "field": "the World Magnetic Model on the board, set_location(), quick_calibrate()",
    "calfile": "a calibration file fitted on the desktop, imported at boot",
    "gyro": "the gyro-aided heading: the MPU6050's gyroscope in an attitude filter",
    "circuitpython": "CircuitPython's busio.I2C behind the machine.I2C calls the drivers make",
}
# the parts each part needs installed beside it (tests/test_packaging.py checks every import
# of a part resolves within it and these)
REQUIRES = {"core": (), "calibrate": ("core",), "motioncal": ("core", "calibrate"),
            "field": ("core", "calibrate"), "calfile": ("core", "calibrate"), "gyro": ("core",),
            "circuitpython": ("core",)}


def firmware_files(root=FIRMWARE):
    """Every file a board installs, as paths below firmware/ ("app.py", "calibrate/solve.py",
    "field/wmm2025.bin"), sorted."""
    out = []
    for d, dirs, files in os.walk(root):
        dirs[:] = sorted(x for x in dirs if not x.startswith((".", "__")))
        rel = os.path.relpath(d, root).replace(os.sep, "/")
        for f in files:
            if f.endswith((".py", ".bin")):
                out.append(f if rel == "." else rel + "/" + f)
    return sorted(out)


def part_of(path):
    """The part a file below firmware/ belongs to: its folder, or core at the root."""
    return path.split("/")[0] if "/" in path else "core"


def module_name(path):
    """"calibrate/solve.py" -> "firmware.calibrate.solve" (None for a data file)."""
    if not path.endswith(".py"):
        return None
    m = "firmware." + path[:-3].replace("/", ".")
    return m[:-9] if m.endswith(".__init__") else m


def _parts():
    parts = {p: [] for p in ABOUT}
    for f in firmware_files():
        parts.setdefault(part_of(f), []).append(f)
    return {p: tuple(fs) for p, fs in parts.items()}


# part -> its files below firmware/, from the folders
PARTS = _parts()


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
    return _entry(firmware_files())


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
