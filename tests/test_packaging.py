"""The install paths users rely on stay in step with firmware/."""
import json
import os
import re

import pytest

from host_sim.cli.packaging import PARTS, REQUIRES, ROOT, package_json
from tests import mp


def test_package_json_lists_every_firmware_module():
    with open(os.path.join(ROOT, "package.json")) as f:
        committed = json.load(f)
    assert committed == package_json(), "package.json is stale: run `make package-json`"


def test_every_part_has_a_current_package_file_and_every_firmware_file_one_part():
    on_disk = sorted(n for n in os.listdir(os.path.join(ROOT, "firmware"))
                     if n.endswith((".py", ".bin")))
    assert sorted(f for files in PARTS.values() for f in files) == on_disk
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
            shutil.copy(os.path.join(ROOT, "firmware", f), str(pkg / f))
    return str(tmp_path)


@pytest.mark.parametrize("part", sorted(PARTS))
def test_each_part_imports_with_only_the_parts_it_requires(tmp_path, part):
    import subprocess
    import sys
    lib = _install(tmp_path, (part,) + REQUIRES[part])
    mods = [f[:-3] for f in PARTS[part] if f.endswith(".py") and f not in (
        "__init__.py", "fast.py", "attitude_fast.py", "busio_i2c.py")]  # the viper mirrors:
    # MicroPython only; busio: CircuitPython
    code = "import sys; sys.path.insert(0, %r)\n" % lib + "".join(
        "import firmware.%s\n" % m for m in mods) + \
        "assert all(m.__file__.startswith(%r) for k, m in sys.modules.items() " \
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
    assert "firmware.calimport is not installed" in empty[4]


def test_manifest_freezes_the_parts_it_names_with_the_files_of_each_part():
    import ast
    src = open(os.path.join(ROOT, "manifest.py")).read()
    assert re.search(r'^package\("firmware", files=', src, re.M)
    tree = ast.parse(src)
    values = {t.id: ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign)
              for t in n.targets}
    assert values["_FILES"] == {p: tuple(f for f in fs if f.endswith(".py"))
                                for p, fs in PARTS.items()}
    assert "core" in values["PARTS"] and set(values["PARTS"]) <= set(PARTS)


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
    on_disk = sorted("firmware/" + n for n in os.listdir(os.path.join(ROOT, "firmware"))
                     if n.endswith((".py", ".bin")))
    assert "firmware/wmm2025.bin" in on_disk
    assert sorted(u[0] for u in urls) == on_disk
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
