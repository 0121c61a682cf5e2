"""`python -m host_sim web`'s server (desktop/web.py, docs/web.md "What it serves, and to
whom") against raw requests: a real server on a free port, the request target written to the
socket byte for byte (no client normalises it), the answer read back whole.

What it must hold: only regular files under web/ and firmware/ are answered with a file, the
path judged after it is decoded (`..` in any spelling, encoded slashes and backslashes,
doubled slashes, dot-files, symlinks leading out, folders: 404); a request whose Host is not
this server's address answers 403; no response carries a CORS header. The two goal figures
(requests outside web/ and firmware/ answered with a file; requests with a foreign Host
answered) are counted over every case below and must be 0.
"""
import os
import socket
import threading

import pytest

from desktop import web as webcli

ROOT = webcli.ROOT
SECRET = b"SECRET-outside-web-and-firmware"

# Targets that name something outside web/ and firmware/ (or a dot-file, or a folder): each
# must answer 404 with GET and HEAD, in the repository and in the fake root below.
OUTSIDE = [
    "/web/../README.md", "/web/%2e%2e/README.md", "/firmware/../Makefile",
    "/web/vendor/../../.git/config",                      # the four
    "/web/%2E%2E/README.md", "/web/.%2e/README.md", "/web/%2e./README.md",
    "/web%2f..%2fREADME.md", "/web/..%2fREADME.md", "/web%2F..%2F.git%2Fconfig",
    "/web/..%5cREADME.md", "/web%5c..%5cREADME.md",
    "/web\\..\\README.md", "/web/..\\README.md", "/web/vendor\\..\\..\\Makefile",
    "//README.md", "//web/../README.md", "/web//../README.md", "/web//index.html",
    "/web/%252e%252e/README.md", "/web/%c0%ae%c0%ae/README.md", "/web/..%00/README.md",
    "/.git/config", "/.git/HEAD", "/%2egit/config", "/web/.hidden", "/firmware/.hidden",
    "/web/.dotdir/file.txt", "/web/out.md", "/web/abs.txt", "/web/linkdir/secret.txt",
    "/web/dotlink.txt",
    "/README.md", "/Makefile", "/tests/test_web.py", "/webx/secret.txt", "/web.md",
    "/web/vendor/", "/web/vendor", "/firmware/", "/firmware", "/web/index.html/",
    "/firmware/calibrate/calibrator.py/", "/web/missing.html",
    "http://127.0.0.1/README.md", "*",
]


def _fake_root(tmp):
    """web/ and firmware/ with the files and links the cases need, beside files that must not
    be served, and a folder outside the root a link points into."""
    root = tmp / "repo"
    (root / "web" / "vendor").mkdir(parents=True)
    (root / "web" / ".dotdir").mkdir()
    (root / "firmware").mkdir()
    (root / "webx").mkdir()
    (root / ".git").mkdir()
    (root / "web" / "index.html").write_text("<script src=\"app.js\"></script>\n")
    (root / "web" / "app.js").write_text("// app\n")
    (root / "web" / "vendor" / "manifest.json").write_text('{"firmware": ["a.py"]}\n')
    (root / "firmware" / "a.py").write_text("A = 1\n")
    for p in ("README.md", "Makefile", ".git/config", ".git/HEAD", "web/.hidden",
              "firmware/.hidden", "web/.dotdir/file.txt", "webx/secret.txt", "web.md"):
        (root / p).write_bytes(SECRET + b" " + p.encode())
    away = tmp / "elsewhere"
    away.mkdir()
    (away / "secret.txt").write_bytes(SECRET + b" elsewhere")
    os.symlink("../README.md", root / "web" / "out.md")              # out of web/, in the repo
    os.symlink(str(away / "secret.txt"), root / "web" / "abs.txt")   # out of the repository
    os.symlink(str(away), root / "web" / "linkdir")                  # a folder out of it
    os.symlink(".hidden", root / "web" / "dotlink.txt")              # to a dot-file
    os.symlink("app.js", root / "web" / "inside.js")                 # stays in web/: served
    return str(root)


class Served:
    def __init__(self, root):
        self.srv = webcli.make_server(0, root=root)
        self.port = self.srv.server_address[1]
        self.thread = threading.Thread(target=self.srv.serve_forever, daemon=True)
        self.thread.start()

    def close(self):
        self.srv.shutdown()
        self.srv.server_close()

    def raw(self, target, method="GET", host="default", extra=()):
        """Send one request with `target` exactly as given; (status, headers, body)."""
        lines = ["%s %s HTTP/1.1" % (method, target)]
        if host == "default":
            host = "127.0.0.1:%d" % self.port
        for h in ([host] if isinstance(host, str) else host or []):
            lines.append("Host: " + h)
        lines += list(extra) + ["Connection: close", "", ""]
        with socket.create_connection(("127.0.0.1", self.port), timeout=10) as s:
            s.sendall("\r\n".join(lines).encode("latin-1"))
            data = b""
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                data += chunk
        head, _, body = data.partition(b"\r\n\r\n")
        status_line, *header_lines = head.decode("latin-1").split("\r\n")
        if not status_line.startswith("HTTP/"):     # no answer, or not HTTP
            return 0, {}, data
        headers = {}
        for h in header_lines:
            k, _, v = h.partition(":")
            headers.setdefault(k.strip().lower(), []).append(v.strip())
        return int(status_line.split()[1]), headers, body


@pytest.fixture(scope="module")
def repo():
    s = Served(ROOT)
    yield s
    s.close()


@pytest.fixture(scope="module")
def fake(tmp_path_factory):
    s = Served(_fake_root(tmp_path_factory.mktemp("web_server")))
    yield s
    s.close()


def _no_cors(headers):
    return not [k for k in headers if k.startswith("access-control-")]


def _answered_with_file(status, body):
    return status == 200 or SECRET in body or b"[remote \"" in body


# ---- what is served -----------------------------------------------------------------------

def test_the_page_and_the_firmware_are_served_with_their_types(repo):
    checks = [("/web/", "text/html; charset=utf-8", "web/index.html"),
              ("/web/?seed=1&speed=20", "text/html; charset=utf-8", "web/index.html"),
              ("/web/index.html", "text/html; charset=utf-8", "web/index.html"),
              ("/web/app.js", "text/javascript", "web/app.js"),
              ("/web/style.css", "text/css", "web/style.css"),
              ("/web/webcal.py", "text/plain; charset=utf-8", "web/webcal.py"),
              ("/firmware/calibrate/calibrator.py", "text/plain; charset=utf-8", "firmware/calibrate/calibrator.py"),
              ("/firmware/field/wmm2025.bin", "application/octet-stream", "firmware/field/wmm2025.bin")]
    for target, ctype, rel in checks:
        status, headers, body = repo.raw(target)
        with open(os.path.join(ROOT, rel), "rb") as f:
            want = f.read()
        assert (status, headers["content-type"], body) == (200, [ctype], want), target
        assert headers["content-length"] == [str(len(want))] and _no_cors(headers)


def test_what_the_page_fetches_from_the_vendor_folder_is_served(fake):
    status, headers, body = fake.raw("/web/vendor/manifest.json")
    assert (status, headers["content-type"], body) == (200, ["application/json"],
                                                      b'{"firmware": ["a.py"]}\n')
    # the page's relative URLs as the browser resolves them: ../firmware/a.py from /web/
    assert fake.raw("/firmware/a.py")[2] == b"A = 1\n"
    # percent-encoding of ordinary letters decodes to the same file
    assert fake.raw("/web/%61pp.js")[:1] == (200,)
    # a symlink that stays inside web/ is followed
    assert fake.raw("/web/inside.js")[2] == b"// app\n"


def test_head_answers_the_headers_only(repo):
    status, headers, body = repo.raw("/web/index.html", method="HEAD")
    size = os.path.getsize(os.path.join(ROOT, "web", "index.html"))
    assert (status, headers["content-length"], body) == (200, [str(size)], b"")


def test_root_and_folder_redirects(repo):
    status, headers, _ = repo.raw("/")
    assert (status, headers["location"]) == (302, ["/web/"])
    status, headers, _ = repo.raw("/web")
    assert (status, headers["location"]) == (301, ["/web/"])
    assert repo.raw("/?seed=2&speed=10")[1]["location"] == ["/web/?seed=2&speed=10"]
    assert repo.raw("/web?seed=2")[1]["location"] == ["/web/?seed=2"]
    assert repo.raw("/", host="evil.example:%d" % repo.port)[0] == 403


# ---- what is not --------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["GET", "HEAD"])
@pytest.mark.parametrize("target", OUTSIDE)
def test_outside_web_and_firmware_is_404(fake, target, method):
    status, headers, body = fake.raw(target, method=method)
    assert status == 404, (target, status, body[:200])
    assert SECRET not in body and _no_cors(headers)


def test_no_folder_is_listed(repo):
    for target in ("/web/vendor/", "/firmware/", "/firmware/?C=M;O=D"):
        status, _, body = repo.raw(target)
        assert status == 404 and b"calibrator.py" not in body and b"manifest" not in body


# ---- to whom ------------------------------------------------------------------------------

def _foreign_hosts(port):
    return ["evil.example:%d" % port, "evil.example", "127.0.0.1:%d" % (port + 1 or 1),
            "localhost:%d" % (port + 1), "127.0.0.1", "localhost", "127.0.0.1:%d.evil.example"
            % port, "127.0.0.1:%d@evil.example" % port, "0.0.0.0:%d" % port, "",
            None, ["127.0.0.1:%d" % port, "evil.example:%d" % port]]


def test_a_foreign_host_is_refused(repo):
    for host in _foreign_hosts(repo.port):
        for method in ("GET", "HEAD"):
            status, headers, body = repo.raw("/web/index.html", method=method, host=host)
            assert status == 403, (host, status)
            assert b"app.js" not in body and _no_cors(headers)


def test_the_local_names_are_answered(repo):
    for host in ("127.0.0.1:%d", "localhost:%d", "LocalHost:%d", "[::1]:%d"):
        assert repo.raw("/web/index.html", host=host % repo.port)[0] == 200, host


def test_no_cors_headers_even_when_asked(repo):
    origin = ["Origin: http://evil.example"]
    for method in ("GET", "HEAD", "OPTIONS", "POST"):
        for target in ("/web/index.html", "/README.md"):
            headers = repo.raw(target, method=method, extra=origin)[1]
            assert _no_cors(headers), (method, target, headers)
    preflight = origin + ["Access-Control-Request-Method: GET"]
    status, headers, _ = repo.raw("/web/index.html", method="OPTIONS", extra=preflight)
    assert status >= 400 and _no_cors(headers)


# ---- the goal figures ---------------------------------------------------------------------

def test_goal_figures(repo, fake):
    """Requests outside web/ and firmware/ answered with a file: 0 of len(OUTSIDE) x 2 methods
    x 2 roots; requests with a foreign Host answered (anything but 403): 0."""
    outside = answered = 0
    for srv in (repo, fake):
        for target in OUTSIDE:
            for method in ("GET", "HEAD"):
                status, _, body = srv.raw(target, method=method)
                outside += 1
                answered += _answered_with_file(status, body)
    foreign = foreign_answered = 0
    for target in ("/", "/web/", "/web/index.html", "/firmware/calibrate/calibrator.py", "/README.md"):
        for host in _foreign_hosts(repo.port):
            for method in ("GET", "HEAD"):
                foreign += 1
                foreign_answered += repo.raw(target, method=method, host=host)[0] != 403
    print("web server: %d of %d requests outside web/ and firmware/ answered with a file; "
          "%d of %d requests with a foreign or missing Host answered"
          % (answered, outside, foreign_answered, foreign))
    assert answered == 0 and foreign_answered == 0
    assert (outside, foreign) == (184, 120)     # the counts docs/web.md quotes
