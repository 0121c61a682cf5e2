"""The install paths users rely on stay in step with firmware/."""
import json
import os
import re

from host_sim.cli.packaging import ROOT, package_json


def test_package_json_lists_every_firmware_module():
    with open(os.path.join(ROOT, "package.json")) as f:
        committed = json.load(f)
    assert committed == package_json(), "package.json is stale: run `make package-json`"


def test_manifest_freezes_the_firmware_package():
    src = open(os.path.join(ROOT, "manifest.py")).read()
    assert re.search(r'^package\("firmware"\)', src, re.M)


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
