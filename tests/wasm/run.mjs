// Run a script on the MicroPython WebAssembly port (npm @micropython/micropython-webassembly-pyscript)
// the way the unix port runs it:
//
//   node tests/wasm/run.mjs [-X heapsize=N[k|m]] [-X fixedheap] [-X pystack=WORDS] script.py args...
//   node tests/wasm/run.mjs [-X ...] -m package.module args...
//   node tests/wasm/run.mjs [-X ...] -c "code" args...
//
// - The host's directories are visible at their own paths (a small node-backed Emscripten
//   filesystem, below), so `import firmware...` reads the repository's files as they are and a
//   script writes real files; the working directory is the caller's.
// - sys.path is MICROPYPATH (':'-separated, default ".frozen:/lib") after the script's directory
//   ('' for -m and -c); sys.argv is what the unix port gives.
// - stdout and stderr go to this process's stdout and stderr. An uncaught exception prints its
//   traceback on stderr and exits 1; SystemExit exits with its code.
// - The GC heap starts at heapsize (default 1 MB) and, as the port is built, GROWS: the port
//   cannot see roots held in WebAssembly locals, so it never collects while Python code runs
//   (gc.collect() included; it collects between top-level runs only) and, when an allocation
//   does not fit, mallocs a new heap area instead (MICROPY_GC_SPLIT_HEAP_AUTO). So a script's
//   heap here is the sum of everything it ever allocated, not its live peak.
//   `-X fixedheap` keeps the heap at heapsize: this runner stops the WebAssembly memory from
//   growing and takes the free malloc space before the script runs, so the first allocation that
//   does not fit raises MemoryError. With it, the smallest heapsize that runs a script bounds the
//   bytes the script allocates in total (not the heap a board needs: a board collects).
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

// the npm packages are installed by `make wasm` into build/npm/node_modules, outside the sources
const NODE_MODULES = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..", "..",
                                  "build", "npm", "node_modules");
const PKG = pathToFileURL(path.join(NODE_MODULES, "@micropython",
                                    "micropython-webassembly-pyscript", "micropython.mjs")).href;

function usage(msg) {
    process.stderr.write(`run.mjs: ${msg}\n`);
    process.exit(2);
}

function parseSize(text, what) {
    const m = /^(\d+)([kKmM]?)$/.exec(text);
    if (!m) usage(`${what} must be a byte count with an optional k or m suffix, got ${text}`);
    const scale = { "": 1, k: 1024, K: 1024, m: 1 << 20, M: 1 << 20 }[m[2]];
    return parseInt(m[1], 10) * scale;
}

// ---- command line ---------------------------------------------------------------------------
const argv = process.argv.slice(2);
let heapsize = 1 << 20;
let pystack = 2048;  // words of the Python stack (the port's default)
let fixedHeap = false;
let i = 0;
for (; i < argv.length && argv[i] === "-X"; i += 2) {
    const opt = argv[i + 1] || "";
    if (opt.startsWith("heapsize=")) heapsize = parseSize(opt.slice(9), "heapsize");
    else if (opt.startsWith("pystack=")) pystack = parseSize(opt.slice(8), "pystack");
    else if (opt === "fixedheap") fixedHeap = true;
    else usage(`unknown -X option ${opt}`);
}
let mode, target, sysArgv;
if (argv[i] === "-m" || argv[i] === "-c") {
    mode = argv[i];
    target = argv[i + 1];
    if (target === undefined) usage(`${mode} needs an argument`);
    sysArgv = argv.slice(i + 1);
} else if (argv[i] !== undefined) {
    mode = "script";
    target = argv[i];
    sysArgv = argv.slice(i);
} else {
    usage("no script, -m module or -c code given (there is no REPL here)");
}

// ---- output: buffered, stdout flushed before anything goes to stderr -------------------------
class Out {
    constructor(fd) { this.fd = fd; this.buf = Buffer.alloc(1 << 16); this.n = 0; }
    put(c) { if (this.n === this.buf.length) this.flush(); this.buf[this.n++] = c; }
    flush() {
        let off = 0;
        while (off < this.n) {
            try { off += fs.writeSync(this.fd, this.buf, off, this.n - off); }
            catch (e) { if (e.code !== "EAGAIN") throw e; }
        }
        this.n = 0;
    }
}
const stdout = new Out(1), stderr = new Out(2);
const writeErr = (text) => { stdout.flush(); stderr.flush(); fs.writeSync(2, text); };

// ---- -X fixedheap: WebAssembly memory may not grow once the interpreter is up ----------------
let memoryMayGrow = true;
const instantiate = WebAssembly.instantiate;
WebAssembly.instantiate = function (source, imports, ...rest) {
    const env = imports && imports.env;
    if (env && typeof env.emscripten_resize_heap === "function") {
        const resize = env.emscripten_resize_heap;
        env.emscripten_resize_heap = (size) => (memoryMayGrow ? resize(size) : false);
    }
    return instantiate.call(this, source, imports, ...rest);
};

// ---- the host filesystem at its own paths (the port is built with MEMFS only) -----------------
// Errno numbers of Emscripten's libc, which is what the port's OSError carries (ENOENT is 44).
const EM_ERRNO = { EPERM: 63, ENOENT: 44, EIO: 29, EBADF: 8, EACCES: 2, EBUSY: 10, EEXIST: 20,
    EXDEV: 75, ENOTDIR: 54, EISDIR: 31, EINVAL: 28, EMFILE: 33, EFBIG: 22, ENOSPC: 51,
    EROFS: 69, ENOTEMPTY: 55, ENAMETOOLONG: 37, ELOOP: 32 };

function hostFs(FS) {
    const fail = (e) => {
        if (e instanceof FS.ErrnoError) throw e;
        throw new FS.ErrnoError(EM_ERRNO[e.code] || 29);
    };
    const real = (node) => {
        const parts = [];
        for (; node.parent !== node; node = node.parent) parts.push(node.name);
        return path.join(node.mount.opts.root, ...parts.reverse());
    };
    const HOSTFS = {
        mount: (mount) => HOSTFS.node(null, "/", fs.lstatSync(mount.opts.root).mode),
        node(parent, name, mode, dev) {
            const node = FS.createNode(parent, name, mode, dev);
            node.node_ops = HOSTFS.node_ops;
            node.stream_ops = HOSTFS.stream_ops;
            return node;
        },
        node_ops: {
            getattr(node) {
                try {
                    const s = fs.lstatSync(real(node));
                    return { dev: s.dev, ino: s.ino, mode: s.mode, nlink: s.nlink, uid: s.uid,
                        gid: s.gid, rdev: s.rdev, size: s.size, atime: s.atime, mtime: s.mtime,
                        ctime: s.ctime, blksize: s.blksize, blocks: s.blocks };
                } catch (e) { fail(e); }
            },
            setattr(node, attr) {
                try {
                    const p = real(node);
                    if (attr.mode !== undefined && attr.mode !== null) fs.chmodSync(p, attr.mode & 4095);
                    if (attr.size !== undefined) fs.truncateSync(p, attr.size);
                    if (attr.atime || attr.mtime) fs.utimesSync(p, new Date(attr.atime), new Date(attr.mtime));
                } catch (e) { fail(e); }
            },
            lookup(parent, name) {
                try { return HOSTFS.node(parent, name, fs.lstatSync(path.join(real(parent), name)).mode); }
                catch (e) { fail(e); }
            },
            mknod(parent, name, mode, dev) {
                const node = HOSTFS.node(parent, name, mode, dev);
                try {
                    if (FS.isDir(mode)) fs.mkdirSync(real(node), mode & 4095);
                    else fs.writeFileSync(real(node), "", { mode: mode & 4095, flag: "wx" });
                } catch (e) { FS.destroyNode(node); fail(e); }
                return node;
            },
            rename(node, newDir, newName) {
                try { fs.renameSync(real(node), path.join(real(newDir), newName)); }
                catch (e) { fail(e); }
                try { FS.destroyNode(FS.lookupNode(newDir, newName)); } catch (e) { /* not cached */ }
                FS.hashRemoveNode(node);
                node.name = newName;
                node.parent = newDir;
                FS.hashAddNode(node);
            },
            unlink(parent, name) {
                try { fs.unlinkSync(path.join(real(parent), name)); } catch (e) { fail(e); }
            },
            rmdir(parent, name) {
                try { fs.rmdirSync(path.join(real(parent), name)); } catch (e) { fail(e); }
            },
            readdir(node) {
                try { return [".", ".."].concat(fs.readdirSync(real(node))); } catch (e) { fail(e); }
            },
            symlink(parent, name, target) {
                try { fs.symlinkSync(target, path.join(real(parent), name)); } catch (e) { fail(e); }
            },
            readlink(node) {
                try { return fs.readlinkSync(real(node)); } catch (e) { fail(e); }
            },
        },
        stream_ops: {
            open(stream) {
                if (!FS.isFile(stream.node.mode)) return;
                try { stream.nfd = fs.openSync(real(stream.node), (stream.flags & 3) ? "r+" : "r"); }
                catch (e) { fail(e); }
            },
            close(stream) {
                if (stream.nfd !== undefined) {
                    try { fs.closeSync(stream.nfd); } catch (e) { fail(e); }
                    stream.nfd = undefined;
                }
            },
            dup() { throw new FS.ErrnoError(63); },
            read(stream, buffer, offset, length, position) {
                if (length === 0) return 0;
                try { return fs.readSync(stream.nfd, buffer, offset, length, position); }
                catch (e) { fail(e); }
            },
            write(stream, buffer, offset, length, position) {
                try { return fs.writeSync(stream.nfd, buffer, offset, length, position); }
                catch (e) { fail(e); }
            },
            llseek(stream, offset, whence) {
                let position = offset;
                if (whence === 1) position += stream.position;
                else if (whence === 2 && FS.isFile(stream.node.mode)) {
                    try { position += fs.fstatSync(stream.nfd).size; } catch (e) { fail(e); }
                }
                if (position < 0) throw new FS.ErrnoError(28);
                return position;
            },
        },
    };
    return HOSTFS;
}

function mountHost(FS) {
    const HOSTFS = hostFs(FS);
    // Every top-level host directory but the kernel's; /tmp and /home replace Emscripten's own.
    for (const name of fs.readdirSync("/")) {
        if (["dev", "proc", "sys"].includes(name)) continue;
        const where = "/" + name;
        let st;
        try { st = fs.statSync(where); } catch (e) { continue; }
        if (!st.isDirectory()) continue;
        try { FS.mkdir(where); } catch (e) { /* Emscripten's /tmp and /home exist already */ }
        FS.mount(HOSTFS, { root: fs.realpathSync(where) }, where);
    }
    FS.chdir(process.cwd());
}

// ---- the interpreter -------------------------------------------------------------------------
const { loadMicroPython } = await import(PKG);
const mp = await loadMicroPython({
    heapsize, pystack, linebuffer: false,
    stdout: (b) => stdout.put(b[0]),
    stderr: (b) => { stdout.flush(); stderr.put(b[0]); },
});
mountHost(mp.FS);

// What the unix port puts in sys.path and sys.argv (ports/unix/main.c).
const micropypath = (process.env.MICROPYPATH || ".frozen:/lib").split(":");
let first = "";
if (mode === "script") {
    let abs;
    try { abs = fs.realpathSync(target); }
    catch (e) { writeErr(`run.mjs: can't open file '${target}': [Errno 2] ${e.code}\n`); process.exit(2); }
    first = path.dirname(abs);
}
const q = (s) => JSON.stringify(s);  // a JSON string is a valid Python string literal
let setup = `import sys\nsys.path[:] = ${q([first].concat(micropypath))}\n`;
setup += `sys.argv[:] = ${q(sysArgv)}\n`;

let body;
if (mode === "script") {
    body = `_run_mjs_ = open(${q(target)}).read()\n` +
        `__file__ = ${q(target)}\n` +
        `exec(compile(_run_mjs_, ${q(target)}, "exec"), globals())\n`;
} else if (mode === "-m") {
    // The unix port imports the module with __name__ "__main__" (a package: its __main__.py);
    // this port's __import__ lacks that switch, so find the file on sys.path and run it, after
    // importing its package as the unix port does.
    body = `_run_mjs_ = None\n` +
        `for _run_mjs_d in sys.path:\n` +
        `    for _run_mjs_f in ("%s.py", "%s/__main__.py"):\n` +
        `        _run_mjs_f = (_run_mjs_d + "/" if _run_mjs_d else "") + _run_mjs_f % (${q(target.replace(/\./g, "/"))},)\n` +
        `        try:\n            _run_mjs_ = open(_run_mjs_f).read()\n            break\n` +
        `        except OSError:\n            pass\n` +
        `    if _run_mjs_ is not None:\n        break\n` +
        `if _run_mjs_ is None:\n` +
        `    print("%s: No module named '%s'" % (sys.argv[0], ${q(target)}), file=sys.stderr)\n` +
        `    raise SystemExit(1)\n` +
        `if _run_mjs_f.endswith("/__main__.py"):\n    __import__(${q(target)})\n` +
        `elif ${q(target.includes(".") ? target.slice(0, target.lastIndexOf(".")) : "")}:\n` +
        `    __import__(${q(target.includes(".") ? target.slice(0, target.lastIndexOf(".")) : "")})\n` +
        `__file__ = _run_mjs_f\n` +
        `exec(compile(_run_mjs_, _run_mjs_f, "exec"), globals())\n`;
} else {
    body = `exec(compile(${q(target)}, "<string>", "exec"), globals())\n`;
}
// One Python block catches what the script raises: the traceback goes to stderr like the unix
// port's, SystemExit becomes the exit status (an int, 0 for None, 1 and the value printed else).
const indent = (s) => s.split("\n").map((l) => (l ? "    " + l : l)).join("\n");
// A script may end with the heap locked (micropython.heap_lock): the handlers store only into
// names that exist already, then unlock (heap_lock() and heap_unlock() return the depth).
const unlock = "    micropython.heap_lock()\n    while micropython.heap_unlock():\n        pass\n";
const wrapper = setup +
    "import micropython\n_run_mjs_rc = 0\n_run_mjs_e = _run_mjs_v = None\n" +
    "try:\n" + indent(body) +
    "except SystemExit as _run_mjs_e:\n" + unlock +
    "    _run_mjs_v = _run_mjs_e.args[0] if _run_mjs_e.args else None\n" +
    "    if _run_mjs_v is None:\n        _run_mjs_rc = 0\n" +
    "    elif isinstance(_run_mjs_v, int):\n        _run_mjs_rc = _run_mjs_v & 255\n" +
    "    else:\n        print(_run_mjs_v, file=sys.stderr)\n        _run_mjs_rc = 1\n" +
    "except BaseException as _run_mjs_e:\n" + unlock +
    "    sys.print_exception(_run_mjs_e, sys.stderr)\n" +
    "    _run_mjs_rc = 1\n";

if (fixedHeap) {
    // No more WebAssembly memory, then take every free malloc chunk down to a reserve that JS
    // glue needs for small buffers (the wrapper's text, proxies) and that is too small for a new
    // GC area (the port asks for an area as large as the whole heap so far).
    memoryMayGrow = false;
    const M = mp._module;
    const reserve = M._malloc(16 * 1024 + 4 * wrapper.length);
    for (let chunk = 1 << 26; chunk >= 64;) {
        if (M._malloc(chunk) === 0) chunk >>= 1;
    }
    M._free(reserve);
}

let rc;
try {
    mp.runPython(wrapper);
    rc = mp.globals.get("_run_mjs_rc");
} catch (e) {
    // only an error of this runner or of the port's JS glue gets here
    writeErr(`run.mjs: ${e.name}: ${e.message}\n`);
    rc = 70;
}
stdout.flush();
stderr.flush();
process.exit(rc);
