"""The install paths users rely on stay in step with firmware/."""
import json
import os
import re

import pytest

from desktop.packaging import (MPY_DIR, PARTS, REQUIRES, ROOT, build_mpy, firmware_files,
                                     module_name, package_json, shipped)
from tests import mp


def test_package_json_lists_every_firmware_module():
    with open(os.path.join(ROOT, "package.json")) as f:
        committed = json.load(f)
    assert committed == package_json(), "package.json is stale: run `make package-json`"


def test_every_part_has_a_current_package_file_and_every_firmware_file_one_part():
    on_disk = firmware_files()
    assert sorted(f for files in PARTS.values() for f in files) == on_disk
    # the folder is the part: core at the root, every other part in its own folder
    for part, files in PARTS.items():
        assert all(("/" not in f) if part == "core" else f.startswith(part + "/")
                   for f in files), part
    for part in PARTS:
        with open(os.path.join(ROOT, "package-%s.json" % part)) as f:
            assert json.load(f) == package_json(part), "run `make package-json`"
        assert set(REQUIRES[part]) <= set(PARTS) and part not in REQUIRES[part]


def _install(tmp_path, parts):
    import shutil
    pkg = tmp_path / "firmware"
    pkg.mkdir()
    for part in parts:
        for f in PARTS[part]:
            (pkg / f).parent.mkdir(exist_ok=True)
            shutil.copy(os.path.join(ROOT, "firmware", f), str(pkg / f))
    return str(tmp_path)


@pytest.mark.parametrize("part", sorted(PARTS))
def test_each_part_imports_with_only_the_parts_it_requires(tmp_path, part):
    import subprocess
    import sys
    lib = _install(tmp_path, (part,) + REQUIRES[part])
    mods = [module_name(f) for f in PARTS[part] if f.endswith(".py") and f not in (
        "__init__.py", "fast.py", "gyro/attitude_fast.py", "circuitpython/busio_i2c.py",
        "runner.py", "runner_program.py", "runner_heading.py")]
    # (the viper mirrors: MicroPython only; busio: CircuitPython; runner and its program
    # launch: a board's own `board` module, tests/test_app.py runs them through boards/main.py)
    code = "import sys; sys.path.insert(0, %r)\n" % lib + "".join(
        "import %s\n" % m for m in mods) + \
        "assert all((m.__file__ or list(m.__path__)[0]).startswith(%r) " \
        "for k, m in sys.modules.items() " \
        "if k.startswith('firmware.'))\n" % lib
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=str(tmp_path))
    assert p.returncode == 0, p.stderr


@pytest.mark.parametrize("micro", [False, True], ids=["cpython", "micropython"])
def test_a_board_with_the_core_part_only_shows_headings_and_says_what_is_missing(tmp_path, micro):
    # a stored calibration: headings as usual; an empty store: raw headings, and the status
    # line names the part that calibrating needs; a calibration file waits for its part
    lib = _install(tmp_path, ("core",))
    out = mp.json_lines(mp.run(["tests/scenarios/core_only.py", lib], micro=micro))
    stored, empty = out
    assert stored[0] == 100 and stored[2] is None  # a heading every step, nothing missing
    assert empty[0] == 100 and empty[2] == "calibrate"
    assert "cannot calibrate: install package-calibrate.json" in empty[3]
    assert "firmware.calfile.calimport is not installed" in empty[4]


def test_manifest_freezes_the_parts_it_names_with_the_files_of_each_part():
    import ast
    # run as MicroPython's makemanifest runs it: in its own folder, with package() and
    # include() given; its parts' files are those of their folders
    src = open(os.path.join(ROOT, "manifest.py")).read()
    tree = ast.parse(src)
    parts = [ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
             and n.targets[0].id == "PARTS"][0]
    assert "core" in parts and set(parts) <= set(PARTS)
    for want in (parts, ("core", "calibrate")):
        got = {}
        src_parts = re.sub(r"^PARTS = .*$", "PARTS = %r" % (tuple(want),), src, flags=re.M)
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            exec(src_parts, {"include": lambda *a, **k: None,
                             "package": lambda name, files=None: got.setdefault(name, files)})
        finally:
            os.chdir(cwd)
        assert sorted(got["firmware"]) == sorted(
            f for p in want for f in PARTS[p] if f.endswith(".py")), want


def test_make_deploy_prints_mpy_cross_and_mpremote_commands():
    import subprocess
    out = subprocess.run(["make", "-n", "deploy", "BOARD=rp2040", "PORT=/dev/ttyACM0"],
                         cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "mpy-cross -march=armv6m" in out.stdout
    assert "mpremote connect /dev/ttyACM0 fs cp" in out.stdout
    esp = subprocess.run(["make", "-n", "deploy", "BOARD=esp32", "PORT=/dev/ttyUSB0"],
                         cwd=ROOT, capture_output=True, text=True)
    assert "mpy-cross -march=xtensawin" in esp.stdout


def test_package_json_lists_every_firmware_file_and_each_entry_exists():
    with open(os.path.join(ROOT, "package.json")) as f:
        urls = json.load(f)["urls"]
    on_disk = firmware_files()
    assert "field/wmm2025.bin" in on_disk
    assert sorted(u[0] for u in urls) == sorted(shipped(f)[0] for f in on_disk)
    # bytecode for every module but the viper mirrors, which come as sources
    assert {u[0] for u in urls if u[0].endswith(".py")} == {"firmware/fast.py",
                                                           "firmware/gyro/attitude_fast.py"}
    for target, url in urls:
        assert not url.startswith(("github:", "http", "/")), url  # relative to package.json
        assert os.path.isfile(os.path.join(ROOT, url)), url


class _FakeBoard:
    """mpremote's transport as mip uses it: a board filesystem in a dict."""

    def __init__(self):
        self.files = {}

    def fs_exists(self, path):
        return any(p == path or p.startswith(path + "/") for p in self.files)

    def fs_mkdir(self, path):
        pass

    def fs_writefile(self, path, data, progress_callback=None):
        self.files[path] = data


def _expected_files():
    with open(os.path.join(ROOT, "package.json")) as f:
        urls = json.load(f)["urls"]
    return {"/lib/" + t: open(os.path.join(ROOT, u), "rb").read() for t, u in urls}


def test_mip_installs_from_the_local_package_json(monkeypatch):
    # the pinned mpremote's own installer: `mpremote mip install ./package.json` from a clone
    from mpremote import mip
    board = _FakeBoard()
    monkeypatch.chdir(ROOT)
    mip._install_package(board, "./package.json", mip._PACKAGE_INDEX, "/lib", None, False)
    assert board.files == _expected_files()


def test_mip_installs_from_github_urls_relative_to_the_package(monkeypatch):
    # `mpremote mip install github:OWNER/REPO`: every file is fetched from the same repository
    import io
    from mpremote import mip
    prefix = "https://raw.githubusercontent.com/someone/ecompass/HEAD/"
    fetched = []

    def urlopen(url):
        assert url.startswith(prefix), url
        fetched.append(url)
        return io.BytesIO(open(os.path.join(ROOT, url[len(prefix):]), "rb").read())

    monkeypatch.setattr(mip.urllib.request, "urlopen", urlopen)
    board = _FakeBoard()
    mip._install_package(board, "github:someone/ecompass", mip._PACKAGE_INDEX, "/lib", None,
                         False)
    assert fetched[0] == prefix + "package.json"
    assert board.files == _expected_files()


def test_make_help_lists_every_target_with_one_line():
    import subprocess
    out = subprocess.run(["make", "-s", "help"], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    listed = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
    src = open(os.path.join(ROOT, "Makefile")).read()
    phony = re.search(r"^\.PHONY:(.*)$", src, re.M).group(1).split()
    targets = re.findall(r"^([a-z][a-z0-9-]*):(?!=)", src, re.M)
    assert sorted(listed) == sorted(set(targets)) == sorted(phony)
    for line in out.stdout.splitlines():
        assert len(line.split(None, 1)) == 2, "no description: %r" % line


def test_every_firmware_import_resolves_within_its_part_or_the_parts_it_requires():
    # module level, inside functions and by a string held in a name (tests/test_layout.py
    # _imports): a part installed with only what it requires never meets ModuleNotFoundError
    # A part may reach into one it does not require only where the import is guarded (an
    # ImportError handler around it, or compat.need(), whose ImportError names the part: the
    # board says which part to install), as core's calibrate(), set_location(), use_gyro()
    # and the boot's calibration file do.
    import ast
    from tests.test_layout import _imports, _needed
    owner = {module_name(f): p for p, fs in PARTS.items() for f in fs if f.endswith(".py")}

    def guarded(path):
        out = set()
        for t in ast.walk(ast.parse(open(path).read())):
            if _needed(t, "firmware"):
                out.add(_needed(t, "firmware"))
            if isinstance(t, ast.Try) and any(
                    "ImportError" in ast.dump(h.type) for h in t.handlers if h.type):
                for n in t.body:
                    for m in ast.walk(n):
                        if isinstance(m, ast.ImportFrom) and m.module:
                            out.add(m.module)
                            out.update(m.module + "." + a.name for a in m.names)
                        elif isinstance(m, ast.Import):
                            out.update(a.name for a in m.names)
        return out
    packages = {m.rsplit(".", 1)[0] for m in owner if m.count(".") > 1}
    bad = []
    for part, files in PARTS.items():
        allowed = {part} | set(REQUIRES[part])
        for f in files:
            if not f.endswith(".py"):
                continue
            path = os.path.join(ROOT, "firmware", f)
            ok = guarded(path)
            for dep in _imports(path, "firmware"):
                if dep in owner:
                    if owner[dep] not in allowed and dep not in ok:
                        bad.append("%s (%s) imports %s (%s)" % (f, part, dep, owner[dep]))
                elif dep.startswith("firmware.") and dep != "firmware.*" and \
                        dep not in packages and dep.rsplit(".", 1)[0] not in owner:
                    bad.append("%s imports %s, which is no firmware module" % (f, dep))
    assert not bad, bad


# what each part's entry point gives with only its requirements installed (part_alone.py);
# circuitpython's adapter runs on CircuitPython only (tests/test_busio.py)
ENTRY = {"core": None, "calibrate": [True, None, None], "calfile": ["imported", 10],
         "motioncal": None, "field": ["ok"], "gyro": [100, True]}


@pytest.mark.parametrize("micro", [False, True], ids=["cpython", "micropython"])
@pytest.mark.parametrize("part", sorted(ENTRY))
def test_each_part_alone_with_what_it_requires_runs_its_entry_point(tmp_path, part, micro):
    lib = _install(tmp_path, (part,) + REQUIRES[part])
    [(name, got, outside)] = mp.json_lines(mp.run(["tests/scenarios/part_alone.py", lib, part],
                                                  micro=micro))
    assert name == part and outside == []
    want = ENTRY[part]
    if part == "core":  # a heading every step (the hand-made record is not this world's
        assert got[0] == 50, got  # iron: its status may say interference)
    elif part == "calibrate":
        assert got[0] and got[1] > 0 and got[2] is None, got
    elif part == "motioncal":
        assert got[0] > 0 and got[1] == got[0], got
    else:
        assert got == want, got


def test_a_calibration_file_waits_for_the_calibrate_part_and_is_not_lost(tmp_path):
    # core + calfile without calibrate (its acceptance gate): the file stays for a later boot
    lib = _install(tmp_path, ("core", "calfile"))
    p = mp.run(["tests/scenarios/part_alone.py", lib, "calfile"], micro=False)
    [(name, got, outside)] = mp.json_lines(p)
    assert got[0] == "not" and os.path.exists(os.path.join(lib, "calibration.json"))


def test_the_bytecode_the_package_files_install_is_current(tmp_path):
    # mpy/ is what `make package-json` builds with the pinned mpy-cross: the same bytes
    made = build_mpy(str(tmp_path))
    assert made
    for path in made:
        rel = os.path.relpath(path, str(tmp_path))
        with open(path, "rb") as a, open(os.path.join(MPY_DIR, rel), "rb") as b:
            assert a.read() == b.read(), "mpy/%s is stale: run `make package-json`" % rel
    committed = sorted(os.path.relpath(os.path.join(d, f), MPY_DIR)
                       for d, _, fs in os.walk(MPY_DIR) for f in fs)
    assert committed == sorted(os.path.relpath(p, str(tmp_path)) for p in made)


@pytest.mark.parametrize("tier", ["unix", "x86-32"])
def test_what_mip_installs_loads_and_calibrates_on_micropython(tmp_path, tier):
    # the files package.json installs, laid as mip lays them in lib/, run the calibration
    # program's entry point and a calibrated board's (part_alone.py) on the unix port and
    # the 32-bit build
    import shutil
    t = mp.TIERS[tier]
    if not t.available:
        pytest.skip("%s tier: %s" % (tier, t.reason))
    with open(os.path.join(ROOT, "package.json")) as f:
        urls = json.load(f)["urls"]
    lib = tmp_path / "lib"
    for target, url in urls:
        dst = lib / target
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(os.path.join(ROOT, url), str(dst))
    assert not list(lib.glob("firmware/**/app.py"))  # bytecode, not sources
    for part in ("core", "calibrate", "calfile"):
        [(name, got, outside)] = mp.json_lines(mp.run(
            ["tests/scenarios/part_alone.py", str(lib), part], tier))
        assert outside == [] and (got[0] if part != "calibrate" else got[0] is True), got
