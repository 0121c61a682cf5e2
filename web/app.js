// The browser calibrator (docs/web.md). Reads MotionCal `Raw:` lines from a board over Web
// Serial (or from the simulated board below), runs the repository's integer calibrator
// (firmware/calibrate/calibrator.py) in the MicroPython WebAssembly port through web/webcal.py, draws
// the samples, computes MotionCal's quality figures and sends the result back as MotionCal's
// 68-byte packet, confirmed by the board's Cal1/Cal2 echo. Protocol facts: the MotionCal
// notes (../shared/notes/motioncal.md in the project's reference material), sections 1, 3-5.
// Every URL is relative, so the page works from any static host serving web/ and firmware/,
// and from the disk (file://) through web/vendor/bundle.js (boot() below, docs/web.md).
//
// A classic script, not an ES module: Chromium refuses to load a module script file into a
// file:// page. The whole file is one function scope in strict mode, as a module would be.
(function () {
"use strict";

const SEND_RULE = { gaps: 15, variance: 4.5, wobble: 4, fit: 5 };  // MotionCal gui.cpp, notes 3
const BATCH = 400;          // samples fed to the calibrator per processing tick (UI stays live)
const CLOUD_MAX = 3000;     // points drawn in the raw view
const RECENT = 500;         // Raw records kept whole (accel and truth too) for headingError()
const SIM_RATE = 100;       // Hz: the rate MotionCal's fusion assumes (notes 1)
const params = new URLSearchParams(location.search);

// What the page exposes for tests and for the curious (window.webcal).
const W = window.webcal = {
    ready: false, readyMs: null, error: null,
    loadedFrom: null,       // "files" (vendor/ and ../firmware/, served) or "bundle"
    source: null, lines: 0, badLines: 0,
    samples: [],            // every magnetometer sample fed to the calibrator, 0.1 uT, in order
    log: [],                // every solve: {n: samples fed before it, cal | reason}
    current: null,          // the calibration in force (integers, see webcal.cal_dict)
    held: [], gauges: null, heading: null, recent: [],
    sentCal: null, packetHex: null, sentValues: null, confirmed: false, echo: { cal1: null, cal2: null },
    sim: null,
};

const $ = (id) => document.getElementById(id);
function setStatus(text) { $("status").textContent = text; }
function fail(text) { W.error = text; setStatus(text); }

// ---- MicroPython -----------------------------------------------------------------------
let mp = null;

async function fetchText(url) {
    const r = await fetch(url, { cache: "no-store" });
    if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
    return r.text();
}

// Where the port and the Python sources come from: {from, port: a promise of the port's
// loadMicroPython and the .wasm's URL, texts: a promise of the firmware files and webcal.py}.
// Two promises, so that the port starts while the sources still arrive.

// From a server (python -m host_sim web, any static host): the port's ES module, its .wasm
// by URL, the firmware files vendor/manifest.json lists and webcal.py, fetched.
function fromFiles() {
    const port = import("./vendor/micropython.mjs").then((m) => ({
        loadMicroPython: m.loadMicroPython,
        wasmUrl: new URL("vendor/micropython.wasm", location.href).href }));
    const texts = fetchText("vendor/manifest.json").then((t) => {
        const names = JSON.parse(t).firmware;
        return Promise.all([Promise.all(names.map((f) => fetchText("../firmware/" + f))),
            fetchText("webcal.py")]).then(([firmware, glue]) => ({
            glue, firmware: names.map((f, i) => [f, firmware[i]]) }));
    });
    return { from: "files", port, texts };
}

// From vendor/bundle.js, one classic script made by `make web` (desktop/web.py): what a
// file:// page can load. Chromium refuses fetch(), XHR and import() of files there but runs a
// <script src> of a file, and fetches a data: URL, which is how the .wasm (base64 in the
// bundle) reaches the port's loader. Its firmware is as of the last `make web`.
function fromBundle() {
    const bundle = new Promise((resolve, reject) => {
        const s = document.createElement("script");
        s.src = "vendor/bundle.js";
        s.onerror = () => reject(new Error("vendor/bundle.js did not load: run `make web` first"));
        s.onload = () => {
            const B = window.webcalBundle;
            if (B && typeof B.loadMicroPython === "function") resolve(B);
            else reject(new Error("vendor/bundle.js is incomplete: run `make web` again"));
        };
        document.head.appendChild(s);
    });
    return { from: "bundle",
        port: bundle.then((B) => ({ loadMicroPython: B.loadMicroPython,
            wasmUrl: "data:application/wasm;base64," + B.wasm })),
        texts: bundle.then((B) => ({ glue: B.glue, firmware: Object.entries(B.firmware) })) };
}

async function start(src) {
    src.texts.catch(() => {});       // reported below, once the port is up
    const { loadMicroPython, wasmUrl } = await src.port;
    const portP = loadMicroPython({
        url: wasmUrl,
        heapsize: 8 << 20,
        stdout: (line) => console.log(line),
        stderr: (line) => console.warn(line),
    });
    let texts;
    try {
        texts = await src.texts;
    } catch (e) {
        // the port sets globals when it is up: let it settle before another one starts
        await portP.catch(() => {});
        throw e;
    }
    return { from: src.from, port: await portP, texts };
}

async function boot() {
    setStatus("loading MicroPython…");
    let got;
    if (location.protocol === "file:") {
        got = await start(fromBundle());
    } else {
        try {
            got = await start(fromFiles());
        } catch (e) {
            // a static host without firmware/ beside web/, or one that refuses .mjs or .wasm
            console.warn("served files failed (" + e.message + "): trying vendor/bundle.js");
            got = await start(fromBundle()).catch(() => { throw e; });
        }
    }
    mp = got.port;
    mp.FS.mkdir("/firmware");
    for (const [f, text] of got.texts.firmware) {
        // a part's folder (firmware/calibrate/...) before its first file
        const dir = f.includes("/") ? "/firmware/" + f.slice(0, f.lastIndexOf("/")) : null;
        if (dir && !mp.FS.analyzePath(dir).exists) mp.FS.mkdir(dir);
        mp.FS.writeFile("/firmware/" + f, text);
    }
    mp.FS.writeFile("/webcal.py", got.texts.glue);
    mp.runPython("import webcal");
    W.readyMs = performance.now();   // since navigation start
    W.loadedFrom = got.from;
    W.ready = true;
    for (const id of ["sim", "clear"]) $(id).disabled = false;
    $("connect").disabled = !("serial" in navigator);
    setStatus(`ready in ${W.readyMs.toFixed(0)} ms` + (got.from === "bundle"
        ? " (from vendor/bundle.js)" : "") + ": " + ("serial" in navigator
        ? "connect a board or start the simulated board"
        : "no Web Serial in this browser (Chrome or Edge have it): try the simulated board"));
}

function py(expr) {
    mp.runPython("_webcal_r = " + expr);
    return mp.globals.get("_webcal_r");
}

// ---- MotionCal's line format (notes 1 and 5) -------------------------------------------
const RAW_RE = /^-?\d*(,-?\d*){8}$/;
const int16 = (n) => ((n + 32768) % 65536 + 65536) % 65536 - 32768;  // MotionCal wraps
let pending = [];
let textTail = "";

// truths: the simulated board's true heading of each Raw line in text (degrees), else null
function onText(text, truths = null) {
    // CR ends a record (MotionCal); LF alone is accepted here too, for terminals' sake
    const parts = (textTail + text).split(/\r\n|\r|\n/);
    textTail = parts.pop();
    let k = 0;
    for (const line of parts) if (onLine(line, truths ? truths[k] : null)) k++;
}

function onLine(line, truth) {
    let i = line.indexOf("Raw:");
    if (i >= 0) {
        const body = line.slice(i + 4);
        if (!RAW_RE.test(body)) { W.badLines++; return; }
        const v = body.split(",").map((s) => int16(s === "" || s === "-" ? 0 : parseInt(s, 10)));
        W.lines++;
        v.truth = truth;
        pending.push(v);
        return true;
    }
    for (const k of ["Cal1:", "Cal2:"]) {
        i = line.indexOf(k);
        if (i >= 0) onEcho(k, line.slice(i + 5).split(",").map(Number));
    }
    return false;
}

// ---- the packet (notes 4) and its confirmation (notes 5) -------------------------------
function crc16(bytes, n) {
    let crc = 0xFFFF;
    for (let i = 0; i < n; i++) {
        crc ^= bytes[i];
        for (let b = 0; b < 8; b++) crc = (crc & 1) ? (crc >>> 1) ^ 0xA001 : crc >>> 1;
    }
    return crc;
}

// MotionCal's model is Bc = invW (raw - V) with |Bc| = B (uT). Ours: InvW (raw - V) >> 15 has
// magnitude field_out counts on the sphere (firmware/calibration.py), so MotionCal's invW is
// InvW / 2**15 * field / field_out, V = offset / 10 and B = field / 10 (0.1 uT counts).
// The packet carries invW's diagonal and upper triangle (MotionCal mirrors it).
function packetValues(c) {
    const s = (q) => q / 32768 * c.field / c.field_out;
    const w = c.invw;
    return [0, 0, 0, 0, 0, 0, c.offset[0] / 10, c.offset[1] / 10, c.offset[2] / 10, c.field / 10,
        s(w[0]), s(w[4]), s(w[8]), s(w[1]), s(w[2]), s(w[5])];
}

function buildPacket(values) {
    const bytes = new Uint8Array(68);
    const dv = new DataView(bytes.buffer);
    bytes[0] = 117; bytes[1] = 84;
    values.forEach((v, i) => dv.setFloat32(2 + 4 * i, v, true));
    dv.setUint16(66, crc16(bytes, 66), true);
    return bytes;
}

function packetFloats(bytes) {
    const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const f = [];
    for (let i = 0; i < 16; i++) f.push(dv.getFloat32(2 + 4 * i, true));
    return f;
}

// cal_data_sent: Cal1's 10 values, then invW row-major from the packet's 6 entries
function sentValues(bytes) {
    const f = packetFloats(bytes);
    const [d0, d1, d2, o01, o02, o12] = f.slice(10, 16);
    return f.slice(0, 10).concat([d0, o01, o02, o01, d1, o12, o02, o12, d2]);
}

const floatOk = (got, want) => Math.abs(got - want) <= 0.0001 + 0.00003 * Math.abs(want);
let confirmNeeded = 0;

function onEcho(kind, nums) {
    const sent = W.sentValues;
    if (!sent || !confirmNeeded) return;
    const want = kind === "Cal1:" ? sent.slice(0, 10) : sent.slice(10);
    if (nums.length !== want.length || !nums.every((x, i) => floatOk(x, want[i]))) return;
    if (kind === "Cal1:") { W.echo.cal1 = nums; confirmNeeded &= ~1; }
    else { W.echo.cal2 = nums; confirmNeeded &= ~2; }
    if (!confirmNeeded) {
        W.confirmed = true;
        $("s-echo").textContent = "confirmed ✓";
        $("s-echo").className = "ok";
        setStatus("the board echoed the calibration: confirmed");
    }
}

async function sendCal() {
    if (!W.current || !source) return;
    W.sentCal = W.current;
    const bytes = buildPacket(packetValues(W.current));
    W.packetHex = Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
    W.sentValues = sentValues(bytes);
    W.confirmed = false;
    W.echo = { cal1: null, cal2: null };
    confirmNeeded = 3;
    $("s-echo").textContent = "sent, waiting for Cal1/Cal2";
    $("s-echo").className = "";
    await source.write(bytes);
}

// ---- sources: Web Serial, or the simulated board -----------------------------------------
let source = null;

async function connectSerial() {
    let port;
    try {
        port = await navigator.serial.requestPort();
        await port.open({ baudRate: 115200 });
    } catch (e) {
        setStatus("no port opened: " + e.message);
        return;
    }
    stopSource();
    const writer = port.writable.getWriter();
    const reader = port.readable.getReader();
    const decoder = new TextDecoder();
    source = {
        name: "serial",
        write: (bytes) => writer.write(bytes),
        stop: async () => { try { await reader.cancel(); } catch (e) { /* closed */ } },
    };
    W.source = "serial";
    setStatus("reading the board at 115200 baud");
    (async () => {
        try {
            for (;;) {
                const { value, done } = await reader.read();
                if (done) break;
                onText(decoder.decode(value, { stream: true }));
            }
        } catch (e) {
            setStatus("serial port closed: " + e.message);
        } finally {
            reader.releaseLock();
            writer.releaseLock();
            try { await port.close(); } catch (e) { /* already */ }
        }
    })();
}

function stopSource() {
    if (source) source.stop();
    source = null;
    W.source = null;
}

// A seeded simulated board: a tilted-ellipsoid field (hard iron V, symmetric soft iron M)
// seen through a figure-8-like tumble (yaw turning, pitch and roll swinging at incommensurate
// rates), with Gaussian noise, streamed as Raw lines; it answers a packet with Cal1/Cal2 as our
// board does (5 decimals, notes 5). Frame: x forward, y right, z down; a level board reads
// +1 g on z (firmware/compass.py).
function mulberry32(a) {
    return () => {
        a = (a + 0x6D2B79F5) | 0;
        let t = Math.imul(a ^ (a >>> 15), 1 | a);
        t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
        return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
    };
}

class SimBoard {
    constructor(seed, speed) {
        const rnd = this.rnd = mulberry32(seed);
        const u = (lo, hi) => lo + (hi - lo) * rnd();
        this.speed = speed;
        this.t = 0;
        this.field = u(45, 55);                       // uT
        const dip = u(50, 70) * Math.PI / 180;
        this.earth = [this.field * Math.cos(dip), 0, this.field * Math.sin(dip)];
        this.V = [u(-30, 30), u(-30, 30), u(-30, 30)];  // uT
        const a = u(-0.05, 0.05), b = u(-0.05, 0.05), c = u(-0.05, 0.05);
        this.M = [[u(0.9, 1.1), a, b], [a, u(0.9, 1.1), c], [b, c, u(0.9, 1.1)]];
        this.noise = 0.3;                             // uT, one sigma
        this.phase = [u(0, 6.28), u(0, 6.28), u(0, 6.28)];
        this.truth = null;
        this.timer = null;
        this.carry = 0;
    }
    gauss() {
        const u1 = this.rnd() || 1e-12, u2 = this.rnd();
        return Math.sqrt(-2 * Math.log(u1)) * Math.cos(2 * Math.PI * u2);
    }
    sample() {
        const t = this.t;
        this.t += 1 / SIM_RATE;
        const p = this.phase;
        const yaw = 2 * Math.PI * 0.3 * t + p[0];
        const pitch = 1.25 * Math.sin(2 * Math.PI * 0.19 * t + p[1]);
        const roll = 2.7 * Math.sin(2 * Math.PI * 0.12 * t + p[2]);
        const [cy, sy, cp, sp, cr, sr] = [Math.cos(yaw), Math.sin(yaw), Math.cos(pitch),
            Math.sin(pitch), Math.cos(roll), Math.sin(roll)];
        // body -> earth R = Rz(yaw) Ry(pitch) Rx(roll); earth -> body is R transposed
        const R = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr]];
        const toBody = (v) => [0, 1, 2].map((j) => R[0][j] * v[0] + R[1][j] * v[1] + R[2][j] * v[2]);
        const b = toBody(this.earth);
        const g = toBody([0, 0, 1]);
        const mag = [0, 1, 2].map((i) => Math.round(10 * (this.M[i][0] * b[0] + this.M[i][1] * b[1]
            + this.M[i][2] * b[2] + this.V[i] + this.noise * this.gauss())));
        const acc = g.map((x) => Math.round(8192 * (x + 0.002 * this.gauss())));
        this.truth = ((yaw * 180 / Math.PI) % 360 + 360) % 360;
        return `Raw:${acc.join(",")},0,0,0,${mag.join(",")}\r\n`;
    }
    start() {
        let last = performance.now();
        this.timer = setInterval(() => {
            const now = performance.now();
            this.carry += (now - last) / 1000 * SIM_RATE * this.speed;
            last = now;
            const n = Math.min(Math.floor(this.carry), 2000);
            this.carry -= Math.floor(this.carry);
            let text = "";
            const truths = [];
            for (let i = 0; i < n; i++) { text += this.sample(); truths.push(this.truth); }
            if (text) onText(text, truths);
        }, 20);
    }
    stop() { clearInterval(this.timer); }
    write(bytes) {
        // the board's side: signature and CRC checked, then the echo
        if (bytes.length !== 68 || bytes[0] !== 117 || bytes[1] !== 84
            || crc16(bytes, 66) !== (bytes[66] | (bytes[67] << 8))) return;
        const f = packetFloats(bytes);
        const [d0, d1, d2, o01, o02, o12] = f.slice(10, 16);
        const fmt = (xs) => xs.map((x) => x.toFixed(5)).join(",");
        setTimeout(() => onText(`Cal1:${fmt(f.slice(0, 10))}\r\n`
            + `Cal2:${fmt([d0, o01, o02, o01, d1, o12, o02, o12, d2])}\r\n`), 30);
    }
}

function startSim() {
    stopSource();
    const seed = parseInt(params.get("seed") || "1", 10);
    const speed = Math.max(0.1, Math.min(50, parseFloat(params.get("speed") || "1")));
    const sim = new SimBoard(seed, speed);
    W.sim = { seed, speed, V: sim.V, M: sim.M, field: sim.field };
    source = { name: "sim", write: async (b) => sim.write(b), stop: () => sim.stop() };
    W.source = "sim";
    sim.start();
    setStatus(`simulated board (seed ${seed}, ${speed}x real time): turn-and-tumble motion`);
}

function clearAll() {
    mp.runPython("webcal.reset()");
    pending = [];
    Object.assign(W, { samples: [], log: [], current: null, held: [], gauges: null,
        packetHex: null, sentValues: null, confirmed: false, lines: 0, badLines: 0, recent: [] });
    confirmNeeded = 0;
    $("s-echo").textContent = "–";
    $("calib").textContent = "none yet";
    dirty = true;
}

// ---- MotionCal's quality figures (notes 3: quality.c) -------------------------------------
// 100 equal-area regions: polar caps above |lat| 78.52 deg, 15 regions from 42.84 to 78.52 deg,
// 34 within +-42.84 deg (each hemisphere).
function region(x, y, z) {
    const r = Math.hypot(x, y, z);
    const lat = Math.asin(Math.max(-1, Math.min(1, z / r))) * 180 / Math.PI;
    let lon = Math.atan2(y, x) * 180 / Math.PI;
    if (lon < 0) lon += 360;
    if (lat > 78.52) return 0;
    if (lat > 42.84) return 1 + Math.min(14, Math.floor(lon / 24));
    if (lat > 0) return 16 + Math.min(33, Math.floor(lon * 34 / 360));
    if (lat > -42.84) return 50 + Math.min(33, Math.floor(lon * 34 / 360));
    if (lat > -78.52) return 84 + Math.min(14, Math.floor(lon / 24));
    return 99;
}

const IDEAL = (() => {
    const out = [[0, 0, 1]];
    const band = (lat, n) => {
        const la = lat * Math.PI / 180;
        for (let i = 0; i < n; i++) {
            const lo = (i + 0.5) * 2 * Math.PI / n;
            out.push([Math.cos(la) * Math.cos(lo), Math.cos(la) * Math.sin(lo), Math.sin(la)]);
        }
    };
    band((42.84 + 78.52) / 2, 15);
    band(42.84 / 2, 34);
    band(-42.84 / 2, 34);
    band(-(42.84 + 78.52) / 2, 15);
    out.push([0, 0, -1]);
    return out;
})();

// calibrated field in uT of a raw sample (0.1 uT) with one of our calibrations
function applyCal(c, m) {
    const d = [m[0] - c.offset[0], m[1] - c.offset[1], m[2] - c.offset[2]];
    const k = c.field / c.field_out / 32768 / 10;
    const w = c.invw;
    return [0, 1, 2].map((i) => (w[3 * i] * d[0] + w[3 * i + 1] * d[1] + w[3 * i + 2] * d[2]) * k);
}

// without a calibration: the raw samples about their mid-range, in uT
function centred(points) {
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const p of points) for (let i = 0; i < 3; i++) {
        lo[i] = Math.min(lo[i], p[i]); hi[i] = Math.max(hi[i], p[i]);
    }
    const c = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
    return points.map((p) => [(p[0] - c[0]) / 10, (p[1] - c[1]) / 10, (p[2] - c[2]) / 10]);
}

function quality(points, fitPct) {
    if (points.length === 0) return null;
    const count = new Array(100).fill(0);
    const sum = IDEAL.map(() => [0, 0, 0]);
    let s = 0, s2 = 0;
    for (const p of points) {
        const m = Math.hypot(p[0], p[1], p[2]);
        s += m; s2 += m * m;
        if (m === 0) continue;
        const k = region(p[0], p[1], p[2]);
        count[k]++;
        for (let i = 0; i < 3; i++) sum[k][i] += p[i];
    }
    const n = points.length, mean = s / n;
    const variance = 100 * Math.sqrt(Math.max(0, s2 / n - mean * mean)) / mean;
    let gaps = 0;
    const off = [0, 0, 0];
    let occupied = 0;
    for (let k = 0; k < 100; k++) {
        gaps += count[k] === 0 ? 1 : count[k] === 1 ? 0.2 : count[k] === 2 ? 0.01 : 0;
        if (count[k]) {
            occupied++;
            for (let i = 0; i < 3; i++) off[i] += sum[k][i] / count[k] - IDEAL[k][i] * mean;
        }
    }
    const wobble = occupied ? 100 * Math.hypot(off[0] / occupied, off[1] / occupied,
        off[2] / occupied) / mean : 100;
    return { gaps, variance, wobble, fit: fitPct, count, radius: mean };
}

// ---- processing ------------------------------------------------------------------------
let dirty = false;
let heldStale = true;

function process() {
    if (!W.ready || pending.length === 0) return;
    const batch = pending.splice(0, BATCH);
    const mags = batch.map((v) => v.slice(6, 9));
    try {
        mp.runPython("webcal.feed(" + JSON.stringify(mags) + ")");
        for (const m of mags) W.samples.push(m);
        const st = JSON.parse(py("webcal.state()"));
        for (const e of st.new) W.log.push(e);
        if (st.new.length) heldStale = true;
        W.current = st.current;
        $("s-held").textContent = st.held;
        $("s-solves").textContent = st.solves;
        if (heldStale || W.held.length < 50) {
            W.held = JSON.parse(py("webcal.held()"));
            heldStale = false;
        }
        const last = batch[batch.length - 1];
        W.heading = headingOf(last);
        W.recent = W.recent.concat(batch).slice(-RECENT);
    } catch (e) {
        fail("calibrator error: " + e.message);
        throw e;
    }
    const c = W.current;
    const pts = c ? W.held.map((m) => applyCal(c, m)) : centred(W.held);
    W.gauges = quality(pts, c ? c.fit_error / 100 : 100);
    dirty = true;
    updatePanels();
}

// our heading (firmware/compass.py) of a Raw record, before and after the calibration, KANG;
// truth: the simulated board's, degrees (null for a real board)
function headingOf(v) {
    const h = JSON.parse(py(`webcal.headings(${JSON.stringify(v.slice(6, 9))}, `
        + `${JSON.stringify(v.slice(0, 3))})`));
    h.truth = v.truth === undefined ? null : v.truth;
    return h;
}

// RMS heading error (degrees) after the calibration over the recent simulated records
function headingError() {
    let s = 0, n = 0;
    for (const v of W.recent) {
        const h = headingOf(v);
        if (h.after === null || h.truth === null) continue;
        const d = ((h.after * 360 / 65536 - h.truth) % 360 + 540) % 360 - 180;
        s += d * d; n++;
    }
    return n ? { rms: Math.sqrt(s / n), n } : null;
}

const fmtPct = (x) => (x >= 100 ? "100" : x.toFixed(1)) + " %";
const deg = (kang) => (kang === null || kang === undefined ? "–"
    : (kang * 360 / 65536).toFixed(1) + "°");

function sendAllowed() {
    const g = W.gauges;
    return !!(W.current && source && g && g.gaps < SEND_RULE.gaps
        && g.variance < SEND_RULE.variance && g.wobble < SEND_RULE.wobble && g.fit < SEND_RULE.fit);
}

function updatePanels() {
    const g = W.gauges;
    if (g) {
        for (const k of ["gaps", "variance", "wobble", "fit"]) {
            const el = $("g-" + k);
            el.textContent = fmtPct(g[k]);
            el.className = g[k] < SEND_RULE[k] ? "ok" : "bad";
        }
    }
    $("send").disabled = !sendAllowed();
    W.sendEnabled = !$("send").disabled;
    $("s-lines").textContent = W.lines;
    $("s-bad").textContent = W.badLines;
    const c = W.current;
    const lastRefusal = [...W.log].reverse().find((e) => e.reason);
    let text = "";
    if (c) {
        const k = c.field / c.field_out / 32768;
        const row = (i) => [0, 1, 2].map((j) => (c.invw[3 * i + j] * k).toFixed(4).padStart(8)).join(" ");
        text = `model ${c.model}-element, fit error ${(c.fit_error / 100).toFixed(2)} %\n`
            + `V (hard iron) ${c.offset.map((v) => (v / 10).toFixed(1)).join(", ")} µT\n`
            + `B (field)     ${(c.field / 10).toFixed(1)} µT\n`
            + `invW (soft iron)\n${row(0)}\n${row(1)}\n${row(2)}\n`
            + `${c.samples} samples, ${c.coverage} % covered`;
    } else {
        text = "none yet";
    }
    if (lastRefusal && (!c || W.log[W.log.length - 1].reason)) {
        text += `\nlast solve refused: ${lastRefusal.reason}`;
    }
    $("calib").textContent = text;
    const h = W.heading || {};
    $("h-before").textContent = deg(h.before);
    $("h-after").textContent = deg(h.after);
    $("h-truth").textContent = h.truth !== null && h.truth !== undefined ? h.truth.toFixed(1) + "°" : "–";
}

// ---- drawing: orthographic projection, drag to rotate ------------------------------------
const view = { yaw: 0.6, pitch: 0.5 };

function project(p, s, cx, cy) {
    const [cyw, syw, cp, sp] = [Math.cos(view.yaw), Math.sin(view.yaw), Math.cos(view.pitch),
        Math.sin(view.pitch)];
    const x1 = cyw * p[0] - syw * p[1], y1 = syw * p[0] + cyw * p[1];
    const y2 = cp * y1 - sp * p[2], z2 = sp * y1 + cp * p[2];
    return [cx + s * x1, cy + s * z2, y2];
}

function drawSphere(ctx, r, s, cx, cy) {
    ctx.strokeStyle = "rgba(90,110,140,0.25)";
    ctx.lineWidth = 1;
    const ring = (f) => {
        ctx.beginPath();
        for (let i = 0; i <= 48; i++) {
            const q = project(f(i * 2 * Math.PI / 48), s, cx, cy);
            if (i) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]);
        }
        ctx.stroke();
    };
    for (const lat of [-60, -30, 0, 30, 60]) {
        const la = lat * Math.PI / 180;
        ring((t) => [r * Math.cos(la) * Math.cos(t), r * Math.cos(la) * Math.sin(t), r * Math.sin(la)]);
    }
    for (let lon = 0; lon < 180; lon += 30) {
        const lo = lon * Math.PI / 180;
        ring((t) => [r * Math.cos(t) * Math.cos(lo), r * Math.cos(t) * Math.sin(lo), r * Math.sin(t)]);
    }
}

function drawPoints(ctx, pts, s, cx, cy, colour) {
    ctx.fillStyle = colour;
    for (const p of pts) {
        const q = project(p, s, cx, cy);
        ctx.fillRect(q[0] - 1, q[1] - 1, 2, 2);
    }
}

function draw() {
    requestAnimationFrame(draw);
    if (!dirty) return;
    dirty = false;
    // before: every recent raw sample about the mid-range, uT
    const raw = $("raw"), rc = raw.getContext("2d");
    rc.clearRect(0, 0, raw.width, raw.height);
    const recent = W.samples.slice(-CLOUD_MAX);
    if (recent.length) {
        const pts = centred(recent);
        let rmax = 1;
        for (const p of pts) rmax = Math.max(rmax, Math.hypot(p[0], p[1], p[2]));
        const s = 0.45 * raw.width / rmax;
        drawSphere(rc, rmax * 0.8, s, raw.width / 2, raw.height / 2);
        drawPoints(rc, pts, s, raw.width / 2, raw.height / 2, "rgba(200,80,40,0.55)");
    }
    // after: the held samples through the calibration, on the sphere of radius B
    const cal = $("cal"), cc = cal.getContext("2d");
    cc.clearRect(0, 0, cal.width, cal.height);
    const c = W.current;
    const g = W.gauges;
    if (c && g) {
        const r = c.field / 10;
        const s = 0.4 * cal.width / r;
        drawSphere(cc, r, s, cal.width / 2, cal.height / 2);
        IDEAL.forEach((u, k) => {
            const q = project([u[0] * r, u[1] * r, u[2] * r], s, cal.width / 2, cal.height / 2);
            cc.fillStyle = g.count[k] ? "rgba(40,160,70,0.9)" : "rgba(150,150,150,0.8)";
            cc.beginPath();
            cc.arc(q[0], q[1], 3.5, 0, 2 * Math.PI);
            cc.fill();
        });
        drawPoints(cc, W.held.map((m) => applyCal(c, m)), s, cal.width / 2, cal.height / 2,
            "rgba(30,80,200,0.8)");
    } else {
        cc.fillStyle = "#889";
        cc.fillText("no calibration yet: move the board in a figure 8 and turn it over", 20, 180);
    }
}

function rotateWithMouse(canvas) {
    let drag = null;
    canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointermove", (e) => {
        if (!drag) return;
        view.yaw += (e.clientX - drag[0]) * 0.01;
        view.pitch = Math.max(-1.5, Math.min(1.5, view.pitch + (e.clientY - drag[1]) * 0.01));
        drag = [e.clientX, e.clientY];
        dirty = true;
    });
}

// ---- wiring -------------------------------------------------------------------------------
$("connect").addEventListener("click", connectSerial);
$("sim").addEventListener("click", startSim);
$("clear").addEventListener("click", clearAll);
$("send").addEventListener("click", sendCal);
rotateWithMouse($("raw"));
rotateWithMouse($("cal"));
W.api = { buildPacket, packetValues, crc16, region, headingError };
boot().then(() => {
    setInterval(process, 50);
    requestAnimationFrame(draw);
    if (params.get("autostart") === "sim") startSim();
}).catch((e) => fail("could not start: " + e.message));
})();
