"""`python -m host_sim web [--port N] [--vendor]`: the browser calibrator (docs/web.md).

Serves the repository's web/ (the page) and firmware/ (the Python files the page loads into
the MicroPython WebAssembly port) on 127.0.0.1 with the standard library's http.server, and
nothing else of the repository: the path is decoded before it is judged (resolve()), dot-files,
folders without an index.html and symlinks leading out answer 404, and a request whose Host
header does not name this server (DNS rebinding) answers 403 (host_ok()). `/` redirects to
`/web/`. The page uses relative URLs only
(`vendor/...`, `../firmware/...`), so any static host that serves the repository's root (or
at least web/ and firmware/ side by side) works the same.

--vendor (what `make web` runs) copies the WebAssembly port (micropython.mjs and
micropython.wasm of npm @micropython/micropython-webassembly-pyscript, pinned in
tests/wasm/package.json and installed into build/npm/node_modules by `make wasm`) into
web/vendor/ and writes web/vendor/manifest.json, the list of firmware/*.py files the page
fetches (a static host cannot list a folder), and web/vendor/bundle.js, the same files for a
page opened from the disk (file://), where Chromium refuses fetch(), ES modules and
WebAssembly loaded from files but runs a classic <script src>: the port's loader made a classic
script (port_script()), the .wasm as base64 (the page hands it to the loader as a data: URL)
and the sources of firmware/*.py and web/webcal.py as strings. web/vendor/ is generated, not
committed (.gitignore). Serving refreshes the manifest and the bundle (so firmware edits reach
both) and vendors first when web/vendor/ is missing.

Exit status: 0 done (Ctrl-C ends serving); 2 bad usage, the port in use, or the port files
missing or not the pinned loader (one line on stderr).
"""
import base64
import http.server
import json
import os
import re
import shutil
import stat
import sys
import urllib.parse

from desktop.args import STATUS_OK, STATUS_USAGE, Parser, UsageError, warn

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PKG_DIR = os.path.join("build", "npm", "node_modules", "@micropython",
                       "micropython-webassembly-pyscript")
PORT_FILES = ("micropython.mjs", "micropython.wasm")
BUNDLE = "bundle.js"   # for file:// pages (docs/web.md)
SERVED = ("web", "firmware")   # the only top-level folders served
DEFAULT_PORT = 8014
MIME = {".mjs": "text/javascript", ".js": "text/javascript", ".wasm": "application/wasm",
        ".py": "text/plain; charset=utf-8", ".json": "application/json", ".css": "text/css",
        ".html": "text/html; charset=utf-8", ".png": "image/png", ".svg": "image/svg+xml"}


def firmware_files(root=ROOT):
    """The firmware's .py files the page loads, as paths below firmware/ (sorted)."""
    from desktop import packaging
    return [f for f in packaging.firmware_files(os.path.join(root, "firmware"))
            if f.endswith(".py")]


def write_manifest(root=ROOT):
    vendor = os.path.join(root, "web", "vendor")
    os.makedirs(vendor, exist_ok=True)
    text = json.dumps({"firmware": firmware_files(root)}, indent=1) + "\n"
    return _write_if_changed(os.path.join(vendor, "manifest.json"), text)


def _write_if_changed(path, text):
    try:
        with open(path, encoding="utf-8") as f:
            if f.read() == text:
                return path
    except OSError:
        pass
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


# micropython.mjs is Emscripten's ES-module output (MODULARIZE + EXPORT_ES6) followed by
# MicroPython's JavaScript API (loadMicroPython). A classic script cannot hold its two
# `export` statements, its `import.meta.url`s or its top-level `await` (in a Node-only
# branch). port_script() drops the two exports, puts the bundle's own URL where
# import.meta.url was (only Node branches and a default wasm location read it; the page always
# gives the wasm's URL) and wraps the whole in an async function, which keeps the module's
# scope and strict mode. Exact replacements of the pinned package's text: anything else is
# refused rather than guessed at.
_PORT_EDITS = (("export default _createMicroPythonModule;", ""),
               ("export async function loadMicroPython(", "async function loadMicroPython("))
_EXPORT_STATEMENT = re.compile(r"(^|[;{}])\s*export\s*(default\b|async\b|function\b|const\b|"
                               r"let\b|var\b|class\b|\{|\*)")


def port_script(mjs):
    """micropython.mjs's text -> a classic script that sets webcalBundle.loadMicroPython (the
    module's export) once it has run. UsageError when the text is not what it expects."""
    for old, new in _PORT_EDITS:
        if mjs.count(old) != 1:
            raise UsageError("micropython.mjs: %r found %d times, expected once: not the loader "
                             "of the pinned package (tests/wasm/package.json); cannot make %s"
                             % (old, mjs.count(old), BUNDLE))
        mjs = mjs.replace(old, new)
    mjs = mjs.replace("import.meta.url", "webcalScriptUrl")
    left = _EXPORT_STATEMENT.search(mjs) or re.search(r"\bimport\s*\.\s*meta\b", mjs)
    if left:
        raise UsageError("micropython.mjs: module syntax left after the edits (%r); cannot "
                         "make %s" % (left.group(0).strip(), BUNDLE))
    return ("(async function () {\n\"use strict\";\n"
            "const webcalScriptUrl = document.currentScript ? document.currentScript.src "
            ": location.href;\n"
            + mjs + "\nglobalThis.webcalBundle.loadMicroPython = loadMicroPython;\n})();\n")


def bundle_text(root=ROOT):
    """web/vendor/bundle.js's text from the vendored port, firmware/*.py and web/webcal.py."""
    vdir = os.path.join(root, "web", "vendor")
    with open(os.path.join(vdir, "micropython.mjs"), encoding="utf-8") as f:
        loader = port_script(f.read())
    with open(os.path.join(vdir, "micropython.wasm"), "rb") as f:
        wasm = base64.b64encode(f.read()).decode("ascii")
    firmware = {}
    for name in firmware_files(root):
        with open(os.path.join(root, "firmware", name), encoding="utf-8") as f:
            firmware[name] = f.read()
    with open(os.path.join(root, "web", "webcal.py"), encoding="utf-8") as f:
        glue = f.read()
    js = json.dumps      # ASCII JSON: a valid JavaScript string and object literal
    return ("// web/vendor/bundle.js: GENERATED by `python -m host_sim web --vendor` (make web) "
            "from\n// web/vendor/micropython.mjs and .wasm, firmware/*.py and web/webcal.py; "
            "do not edit.\n// What web/app.js loads when the page is opened from a file "
            "(docs/web.md).\n"
            "globalThis.webcalBundle = {\n\"wasm\": " + js(wasm) + ",\n\"glue\": " + js(glue)
            + ",\n\"firmware\": " + js(firmware, indent=0) + "\n};\n" + loader)


def write_bundle(root=ROOT):
    vdir = os.path.join(root, "web", "vendor")
    os.makedirs(vdir, exist_ok=True)
    return _write_if_changed(os.path.join(vdir, BUNDLE), bundle_text(root))


def vendor(root=ROOT):
    """Copy the port's files into web/vendor/, write the manifest and the bundle; UsageError
    when the npm package is not installed. Returns the vendor folder."""
    src = os.path.join(root, PKG_DIR)
    dst = os.path.join(root, "web", "vendor")
    missing = [f for f in PORT_FILES if not os.path.isfile(os.path.join(src, f))]
    if missing:
        raise UsageError(missing_port_message(missing, src))
    os.makedirs(dst, exist_ok=True)
    for f in PORT_FILES:
        shutil.copyfile(os.path.join(src, f), os.path.join(dst, f))
    write_manifest(root)
    write_bundle(root)
    return dst


def missing_port_message(missing, src):
    """What a clone without the WebAssembly port needs: `make web` once, which downloads it
    with npm (so node and npm on PATH), and which of the two is missing here."""
    lacking = [t for t in ("node", "npm") if shutil.which(t) is None]
    return ("%s not in %s: the page runs on the MicroPython WebAssembly port from npm; `make "
            "web` installs it once (npm ci of tests/wasm/package-lock.json into build/npm, 17 "
            "MB), which needs Node.js and npm on PATH%s"
            % (", ".join(missing), src, "; not found here: %s (e.g. as root: apt-get install "
                                        "-y nodejs npm)" % " and ".join(lacking)
               if lacking else ""))


def refresh(root=ROOT):
    """Before serving: the manifest and the bundle follow firmware/ and web/webcal.py. A
    bundle that cannot be made is a warning here (the served page does not need it)."""
    write_manifest(root)
    try:
        write_bundle(root)
    except UsageError as e:
        warn("web", "%s (pages opened from file:// will not load)" % e)


def vendored(root=ROOT):
    d = os.path.join(root, "web", "vendor")
    return all(os.path.isfile(os.path.join(d, f)) for f in PORT_FILES)


class Handler(http.server.SimpleHTTPRequestHandler):
    """Regular files under web/ and firmware/ only, to the local browser only; quiet unless
    verbose. docs/web.md, "What it serves, and to whom", states the rules resolve() and
    host_ok() apply."""
    verbose = False

    def __init__(self, request, client_address, server):
        super().__init__(request, client_address, server, directory=server.root)

    def guess_type(self, path):
        ext = os.path.splitext(path)[1].lower()
        return MIME.get(ext) or super().guess_type(path)

    def end_headers(self):
        self.send_header("Cache-Control", "no-store")  # firmware edits show on reload
        super().end_headers()

    def parse_request(self):
        # http.server turns a leading "//" into "/" before we see the path: keep the target
        # exactly as the client sent it, so that resolve() judges that.
        ok = super().parse_request()
        words = self.requestline.split()
        self.raw_target = words[1] if ok and len(words) >= 2 else ""
        return ok

    def send_head(self):
        """Used by do_GET and do_HEAD (SimpleHTTPRequestHandler): answers 403, 302, 404 or
        the file's headers; returns the open file for a 200, else None. Never a listing."""
        if not host_ok(self.headers.get_all("Host") or [], self.server.allowed_hosts):
            self.send_error(403, "only the address this server listens on is answered")
            return None
        target, _, query = self.raw_target.split("#", 1)[0].partition("?")
        query = "?" + query if query else ""    # kept by the redirects (?seed=2, docs/web.md)
        if target == "/":
            self.send_response(302)
            self.send_header("Location", "/web/" + query)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return None
        found = resolve(self.server.root, target)
        if found is None:
            self.send_error(404, "only files under /web/ and /firmware/ are served")
            return None
        kind, path = found
        if kind == "redirect":          # a folder with an index.html, asked without its "/"
            self.send_response(301)
            self.send_header("Location", path + query)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return None
        try:
            f = open(path, "rb")
            st = os.fstat(f.fileno())
        except OSError:
            self.send_error(404, "only files under /web/ and /firmware/ are served")
            return None
        if not stat.S_ISREG(st.st_mode):
            f.close()
            self.send_error(404, "only files under /web/ and /firmware/ are served")
            return None
        self.send_response(200)
        self.send_header("Content-Type", self.guess_type(path))
        self.send_header("Content-Length", str(st.st_size))
        self.send_header("Last-Modified", self.date_time_string(st.st_mtime))
        self.end_headers()
        return f

    def list_directory(self, path):     # never reached (send_head above); no listings
        self.send_error(404)
        return None

    def log_message(self, fmt, *args):
        if self.verbose:
            super().log_message(fmt, *args)


def host_ok(hosts, allowed):
    """True when the request carries exactly one Host header and it names this server
    (`allowed`: lower-case host:port forms). A page elsewhere that reaches 127.0.0.1 by DNS
    rebinding sends its own name here, so it is refused."""
    return len(hosts) == 1 and hosts[0].strip().lower() in allowed


def allowed_hosts(host, port):
    """The Host values a browser sends for this server: 127.0.0.1, localhost and [::1] (and
    the address it listens on) with the port; without it too on port 80."""
    names = {"127.0.0.1", "localhost", "[::1]",
             ("[%s]" % host if ":" in host else host).lower()}
    out = {"%s:%d" % (n, port) for n in names}
    if port == 80:
        out |= names
    return frozenset(out)


def resolve(root, target):
    """The file a request target names, or None (404). The target is percent-decoded once
    (strict UTF-8) and then judged as a whole: it must be "/" and segments that are not empty
    (no "//"), start with no "." (no "..", no dot-files or dot-folders such as .git) and hold
    no backslash, NUL or other control character; the first segment must be web or firmware.
    The real path (symlinks followed) must stay inside that folder's real path, its parts
    starting with no "." either. Returns ("file", real path) or, for a folder, only through
    its index.html: asked with a trailing "/", ("file", the index's path); without it,
    ("redirect", the URL with the "/"); no index, None. A file returned may still fail to
    open or not be a regular file (send_head answers 404 then)."""
    if not target.startswith("/"):
        return None
    try:
        path = urllib.parse.unquote_to_bytes(target).decode("utf-8")
    except UnicodeDecodeError:
        return None
    parts = path[1:].split("/")
    trailing = len(parts) > 1 and parts[-1] == ""
    if trailing:
        parts.pop()
    if not parts or parts[0] not in SERVED:
        return None
    for p in parts:
        if (not p or p.startswith(".") or "\\" in p
                or any(ord(c) < 32 or ord(c) == 127 for c in p)):
            return None
    base = os.path.realpath(os.path.join(root, parts[0]))
    real = os.path.realpath(os.path.join(root, *parts))
    if real != base and os.path.commonpath([base, real]) != base:
        return None
    if any(p.startswith(".") for p in os.path.relpath(real, base).split(os.sep) if p != "."):
        return None
    if os.path.isdir(real):
        index = os.path.join(real, "index.html")
        if not os.path.isfile(index):
            return None
        if trailing:
            return "file", index
        return "redirect", urllib.parse.quote("/" + "/".join(parts) + "/")
    if trailing or not os.path.isfile(real):
        return None
    return "file", real


class Server(http.server.ThreadingHTTPServer):
    daemon_threads = True


def make_server(port=DEFAULT_PORT, root=ROOT, host="127.0.0.1"):
    """A Server on host:port (0: any free port; .server_address[1] tells) serving root's
    web/ and firmware/. OSError when the port is taken."""
    srv = Server((host, port), type("WebHandler", (Handler,), {}))
    srv.root = root
    srv.allowed_hosts = allowed_hosts(host, srv.server_address[1])
    return srv


def _body(opts):
    if opts["vendor"]:
        d = vendor()
        print("vendored %s, manifest.json and %s (for file:// pages) into %s"
              % (", ".join(PORT_FILES), BUNDLE, os.path.relpath(d, os.getcwd())))
        return STATUS_OK
    if not vendored():
        vendor()
    else:
        refresh()
    try:
        srv = make_server(opts["port"])
    except OSError as e:
        raise UsageError("--port %d: cannot listen on 127.0.0.1 (%s)"
                         % (opts["port"], e.strerror or e))
    srv.RequestHandlerClass.verbose = opts["verbose"]
    print("serving the browser calibrator at http://127.0.0.1:%d/web/  (Ctrl-C stops)"
          % srv.server_address[1])
    sys.stdout.flush()
    try:
        srv.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        srv.server_close()
    return STATUS_OK


def main(argv):
    p = Parser("web", "[--port N] [--vendor] [--verbose]",
               "Serve the browser calibrator (web/ and firmware/) on 127.0.0.1 (docs/web.md).")
    p.option("--port", "int", default=DEFAULT_PORT, lo=0, hi=65535, metavar="N",
             help="TCP port (default %d; 0 picks a free one)" % DEFAULT_PORT)
    p.option("--vendor", "flag", help="only copy the WebAssembly port into web/vendor/ "
             "(make web) and exit")
    p.option("--verbose", "flag", help="log every request on stderr")
    return p.main(argv, _body)
