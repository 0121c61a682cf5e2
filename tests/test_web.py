"""The browser calibrator (web/, docs/web.md) in a real headless Chromium.

Two runs of tests/wasm/web_driver.mjs (playwright-core, pinned in tests/wasm/package.json,
driving Debian's chromium), one against `python -m host_sim web`'s server and one opening
web/index.html straight from the disk (file://, through web/vendor/bundle.js), each asked
the same: the page loads the MicroPython WebAssembly port and firmware/, the simulated board
streams, MotionCal's Send Cal rule is reached, Send Cal goes out and the board's echo confirms
it. The page exposes what it fed and what came out (window.webcal); this test replays the
same samples through firmware.calibrate.calibrator on CPython and asks for the same integers, and
rebuilds the packet with tests/motioncal_ref.build_packet. Skipped, with the reason, when
node, chromium or the npm packages are missing (`make test` installs them; as root it
installs chromium).
"""
import base64
import json
import os
import pathlib
import shutil
import struct
import subprocess
import threading

import pytest

from firmware.calibrate.calibrator import SOLVE_EVERY, Calibrator
from firmware.errors import CalibrationRejected
from desktop import web as webcli
from desktop.args import UsageError
from tests import mp
from tests.motioncal_ref import build_packet, crc16_modbus, is_float_ok, sent_values

ROOT = webcli.ROOT
DRIVER = os.path.join(ROOT, "tests", "wasm", "web_driver.mjs")
PLAYWRIGHT = os.path.join(mp.NODE_MODULES, "playwright-core")
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
SHOTS = {"served": os.path.join(ROOT, "build", "web.png"),        # docs/web.png's source
         "file": os.path.join(ROOT, "build", "web-file.png")}
SEED = 1
SPEED = 20            # the simulated board at 20x real time (100 Hz -> 2000 lines/s)
READY_MS = 3000       # page ready (port + firmware imported) within 3 s of navigation start
SEND_WITHIN_S = 60    # Send Cal reached within 60 s of simulated motion
HEADING_RMS_DEG = 2   # after the calibration, against the simulator's truth (measured ~0.6)
COUNTS_PER_GAUSS = 1000   # web/webcal.py: MotionCal's 0.1 uT counts


def _why_skip():
    if shutil.which("node") is None:
        return ("browser tier skipped: node not found on PATH (install Node.js and npm, then "
                "make web)")
    if not os.path.exists(CHROMIUM):
        return ("browser tier skipped: %s missing (as root: apt-get install -y chromium; "
                "`make web` does it)" % CHROMIUM)
    if not os.path.isdir(PLAYWRIGHT):
        return "browser tier skipped: playwright-core not installed (run `make wasm`)"
    return None


def _drive(url, shot):
    os.makedirs(os.path.dirname(shot), exist_ok=True)
    if os.path.exists(shot):
        os.remove(shot)
    return subprocess.run(["node", DRIVER, url, shot, CHROMIUM], capture_output=True,
                          text=True, timeout=90, cwd=ROOT)


@pytest.fixture(scope="module", params=["served", "file"])
def run(request):
    why = _why_skip()
    if why:
        pytest.skip(why)
    mode, shot = request.param, SHOTS[request.param]
    webcli.vendor()               # what `make web` does: the port's files, manifest, bundle
    query = "?seed=%d&speed=%d" % (SEED, SPEED)
    if mode == "file":            # no server at all
        p = _drive(pathlib.Path(ROOT, "web", "index.html").as_uri() + query, shot)
    else:
        srv = webcli.make_server(0)
        t = threading.Thread(target=srv.serve_forever, daemon=True)
        t.start()
        try:
            p = _drive("http://127.0.0.1:%d/web/%s" % (srv.server_address[1], query), shot)
        finally:
            srv.shutdown()
            srv.server_close()
    assert p.returncode == 0, p.stderr[-2000:]
    out = json.loads(p.stdout)
    out["mode"], out["shot"] = mode, shot
    print("browser tier (%s): ready %.0f ms, Send Cal after %.1f s of simulated motion, "
          "heading RMS %.2f deg, run %d ms" % (mode, out["readyMs"], out["simSecondsAtSend"],
                                              out["headingError"]["rms"],
                                              out["times"]["totalMs"]))
    return out


def test_page_loads_clean_and_fast(run):
    assert run["bootError"] is None
    assert run["consoleErrors"] == [] and run["pageErrors"] == []
    assert run["failedRequests"] == []
    assert 0 < run["readyMs"] < READY_MS, run["readyMs"]


def test_page_loads_from_files_or_the_bundle(run):
    # served: the port's module, its .wasm and firmware/ fetched; file://: vendor/bundle.js
    # (Chromium fetches no file from a file:// page), with no fallback taken when served
    assert run["loadedFrom"] == {"served": "files", "file": "bundle"}[run["mode"]]
    # Chromium counts file:// as a secure context: Web Serial is offered there too, and
    # getPorts() answers (no port granted yet) rather than refusing the origin (docs/web.md)
    assert run["secureContext"] is True and run["webSerial"] is True
    assert run["serialPorts"] == 0


def test_simulated_board_streams(run):
    w = run["webcal"]
    assert w["lines"] > 1000 and w["badLines"] == 0
    assert len(w["samples"]) <= w["lines"]
    assert all(len(s) == 3 and all(-32768 <= v <= 32767 for v in s) for s in w["samples"])


def test_web_serial_reader_with_a_stand_in_port(run):
    # MotionCal's rules (notes section 1): CR or CR LF ends a record, text outside records is
    # skipped, a record may start mid-line, 8 fields or a space refuse the record
    s = run["serial"]
    assert s["source"] == "serial"
    assert s["samples"] == [[200, -30, 400], [201, -31, 401], [202, -32, 402]]
    assert s["lines"] == 3 and s["badLines"] == 2


def _replay(samples):
    # web/webcal.py's policy on CPython: a solve after every SOLVE_EVERY kept samples
    cal = Calibrator(model=10, counts_per_gauss=COUNTS_PER_GAUSS)
    log, kept = [], 0
    for n, (x, y, z) in enumerate(samples, 1):
        if cal.add(x, y, z):
            kept += 1
            if kept >= SOLVE_EVERY:
                kept = 0
                try:
                    c = cal.solve()
                    log.append({"n": n, "cal": {
                        "model": c.model, "offset": list(c.offset), "invw": list(c.invw),
                        "field": c.field, "field_out": c.field_out,
                        "fit_error": c.fit_error, "samples": c.samples,
                        "coverage": c.coverage}})
                except CalibrationRejected as e:
                    log.append({"n": n, "reason": e.reason, "detail": str(e.detail)})
    return log


def test_browser_fit_is_cpythons(run):
    w = run["webcal"]
    log = _replay(w["samples"])
    assert len(log) >= 3
    assert any("cal" in e for e in log)
    assert w["log"] == log       # every solve: same sample count, same integers or reason
    assert w["sentCal"] in [e["cal"] for e in log if "cal" in e]
    assert w["sentCal"]["model"] == 10


def _expected_packet(c):
    # docs/web.md: MotionCal's invW = InvW / 2**15 * field / field_out, V and B / 10 (0.1 uT);
    # the same double operations as web/app.js, then float32 in build_packet
    s = lambda q: q / 32768 * c["field"] / c["field_out"]
    w = c["invw"]
    V = [c["offset"][i] / 10 for i in range(3)]
    invw = (s(w[0]), s(w[4]), s(w[8]), s(w[1]), s(w[2]), s(w[5]))
    return build_packet(V, c["field"] / 10, invw)


def test_packet_and_echo(run):
    w = run["webcal"]
    packet = bytes.fromhex(w["packetHex"])
    assert len(packet) == 68 and packet[:2] == b"uT"
    assert crc16_modbus(packet) == 0                    # CRC over all 68 bytes is 0
    assert packet == _expected_packet(w["sentCal"])
    sent = sent_values(packet)
    assert w["sentValues"] == pytest.approx(sent, rel=0, abs=0)
    # the simulated board's echo, as MotionCal judges it (is_float_ok)
    echoed = w["echo"]["cal1"] + w["echo"]["cal2"]
    assert len(echoed) == 19 and all(is_float_ok(a, e) for a, e in zip(echoed, sent))
    assert w["confirmed"] is True


def test_send_cal_rule_and_heading(run):
    g = run["webcal"]["gauges"]
    assert g["gaps"] < 15 and g["variance"] < 4.5 and g["wobble"] < 4 and g["fit"] < 5
    assert run["simSecondsAtSend"] <= SEND_WITHIN_S
    h = run["headingError"]
    assert h["n"] >= 100 and h["rms"] < HEADING_RMS_DEG, h
    # the fit recovers the simulated hard iron within 0.5 uT (noise 0.3 uT, 0.1 uT counts)
    V = [v / 10 for v in run["webcal"]["sentCal"]["offset"]]
    assert max(abs(a - b) for a, b in zip(V, run["webcal"]["sim"]["V"])) < 0.5


def test_screenshot_saved(run):
    with open(run["shot"], "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", head[16:24])
    assert width >= 800 and height >= 600


# ---- `python -m host_sim web`: no browser needed ----------------------------------------

def test_cli_bad_port_is_one_line(capsys):
    from desktop.__main__ import main
    assert main(["web", "--port", "70000"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--port" in err[0] and "70000" in err[0]


def test_cli_port_in_use_is_one_line(capsys, monkeypatch):
    import socket
    monkeypatch.setattr(webcli, "vendored", lambda root=ROOT: True)
    monkeypatch.setattr(webcli, "refresh", lambda root=ROOT: None)
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)
    try:
        assert webcli.main(["--port", str(s.getsockname()[1])]) == 2
    finally:
        s.close()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot listen" in err[0]


def test_server_serves_web_and_firmware_only():
    import urllib.error
    import urllib.request
    srv = webcli.make_server(0)
    t = threading.Thread(target=srv.serve_forever, daemon=True)
    t.start()
    base = "http://127.0.0.1:%d" % srv.server_address[1]
    try:
        with urllib.request.urlopen(base + "/") as r:       # redirected to the page
            assert r.url.endswith("/web/") and b"app.js" in r.read()
        with urllib.request.urlopen(base + "/firmware/calibrate/calibrator.py") as r:
            assert b"class Calibrator" in r.read()
        with urllib.request.urlopen(base + "/web/app.js") as r:
            assert r.headers["Content-Type"].startswith("text/javascript")
        for path in ("/Makefile", "/tests/test_web.py", "/.git/config"):
            with pytest.raises(urllib.error.HTTPError) as e:
                urllib.request.urlopen(base + path)
            assert e.value.code == 404
    finally:
        srv.shutdown()
        srv.server_close()


def _fake_root(tmp_path, mjs):
    (tmp_path / "firmware").mkdir()
    (tmp_path / "firmware" / "__init__.py").write_text("")
    (tmp_path / "firmware" / "a.py").write_text("X = '\u00b5T </script>'\n")
    (tmp_path / "web" / "vendor").mkdir(parents=True)
    (tmp_path / "web" / "webcal.py").write_text("import firmware.a\n")
    (tmp_path / "web" / "vendor" / "micropython.mjs").write_text(mjs)
    (tmp_path / "web" / "vendor" / "micropython.wasm").write_bytes(b"\0asm\1\0\0\0\xff")
    return str(tmp_path)


LOADER = ("var u=import.meta.url;async function _createMicroPythonModule(m){return m}"
          "export default _createMicroPythonModule;export async function loadMicroPython(o)"
          "{return _createMicroPythonModule(o)}globalThis.x=1;")


def test_bundle_holds_the_port_and_the_sources(tmp_path):
    root = _fake_root(tmp_path, LOADER)
    with open(webcli.write_bundle(root), encoding="utf-8") as f:
        text = f.read()
    head, loader = text.split("globalThis.webcalBundle = ", 1)[1].split("\n};\n", 1)
    data = json.loads(head + "}")
    assert base64.b64decode(data["wasm"]) == b"\0asm\1\0\0\0\xff"
    assert data["glue"] == "import firmware.a\n"
    assert data["firmware"] == {"__init__.py": "", "a.py": "X = '\u00b5T </script>'\n"}
    # the loader as a classic script: no export statement, no import.meta, its export handed
    # over at the end
    assert "export " not in loader and "import.meta" not in loader
    assert "async function loadMicroPython(o)" in loader
    assert loader.endswith("\nglobalThis.webcalBundle.loadMicroPython = loadMicroPython;\n})();\n")
    if shutil.which("node"):
        p = subprocess.run(["node", "--check", os.path.join(root, "web", "vendor", "bundle.js")],
                           capture_output=True, text=True, timeout=30)
        assert p.returncode == 0, p.stderr


def test_bundle_refuses_an_unknown_loader(tmp_path):
    root = _fake_root(tmp_path, LOADER.replace("export default", "export  default"))
    with pytest.raises(UsageError) as e:
        webcli.write_bundle(root)
    assert "\n" not in str(e.value) and "micropython.mjs" in str(e.value)
    assert not os.path.exists(os.path.join(root, "web", "vendor", "bundle.js"))
    # an export left over after the two expected ones is refused too
    with pytest.raises(UsageError):
        webcli.port_script(LOADER + "export const y=2;")


def test_a_clone_without_the_port_is_told_what_make_web_needs(tmp_path, monkeypatch, capsys):
    # a fresh clone: no build/npm; `python -m host_sim web` says what gets it and what that
    # needs (node and npm), and which of them this machine lacks
    (tmp_path / "firmware").mkdir()
    with pytest.raises(UsageError) as e:
        webcli.vendor(str(tmp_path))
    msg = str(e.value)
    assert "\n" not in msg and "`make web`" in msg and "Node.js and npm on PATH" in msg
    monkeypatch.setattr(webcli.shutil, "which", lambda name: None)
    with pytest.raises(UsageError) as e:
        webcli.vendor(str(tmp_path))
    assert str(e.value).endswith("not found here: node and npm (e.g. as root: apt-get install "
                                 "-y nodejs npm)")
    # through the command: one line on stderr, exit 2
    monkeypatch.setattr(webcli, "PKG_DIR", os.path.join("build", "no-such-npm-folder"))
    assert webcli.main(["--vendor"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "`make web`" in err and "not found here: node" in err


def test_manifest_lists_every_firmware_module(tmp_path):
    (tmp_path / "firmware").mkdir()
    for name in ("__init__.py", "b.py", "a.py", "data.bin"):
        (tmp_path / "firmware" / name).write_text("")
    path = webcli.write_manifest(str(tmp_path))
    with open(path) as f:
        assert json.load(f) == {"firmware": ["__init__.py", "a.py", "b.py"]}
