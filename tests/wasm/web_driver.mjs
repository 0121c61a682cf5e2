// Drive the browser calibrator (web/) in a real headless Chromium for tests/test_web.py:
//
//   node tests/wasm/web_driver.mjs URL SCREENSHOT.png [CHROMIUM]
//
// Opens URL (the page, with ?seed=&speed= for the simulated board; http://... as served, or
// file:///.../web/index.html?... straight from the disk), waits until the
// MicroPython port is up, starts the simulated board, waits until MotionCal's Send Cal rule
// holds, clicks Send Cal, waits for the Cal1/Cal2 confirmation, saves a screenshot and prints
// one JSON object on stdout: readyMs, wall-clock times, console errors, page errors, and what
// the page exposes as window.webcal (samples, solve log, current calibration, packet hex...).
// playwright-core is pinned in tests/wasm/package.json (installed by `make wasm` into
// build/npm/node_modules); it downloads no browser: Debian's chromium is used.
import path from "node:path";
import { createRequire } from "node:module";
import { fileURLToPath } from "node:url";

const NODE_MODULES = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "..", "..",
                                  "build", "npm", "node_modules");
const { chromium } = createRequire(path.join(NODE_MODULES, "index.js"))("playwright-core");

const [url, shot, exe = "/usr/bin/chromium"] = process.argv.slice(2);
if (!url || !shot) {
    process.stderr.write("usage: node web_driver.mjs URL SCREENSHOT.png [CHROMIUM]\n");
    process.exit(2);
}
const STEP_MS = 25000;   // each wait below; the whole run stays well under a minute

const out = { consoleErrors: [], pageErrors: [], failedRequests: [], times: {} };
const t0 = Date.now();
const browser = await chromium.launch({
    executablePath: exe,
    headless: true,
    args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--disable-dev-shm-usage"],
});
try {
    const page = await browser.newPage({ viewport: { width: 1200, height: 900 } });
    page.on("console", (m) => { if (m.type() === "error") out.consoleErrors.push(m.text()); });
    page.on("pageerror", (e) => out.pageErrors.push(String(e)));
    page.on("requestfailed", (r) => out.failedRequests.push(r.url()));
    const nav = Date.now();
    await page.goto(url);
    await page.waitForFunction(() => window.webcal && (window.webcal.ready || window.webcal.error),
        null, { timeout: STEP_MS });
    out.times.readyWallMs = Date.now() - nav;
    out.readyMs = await page.evaluate(() => window.webcal.readyMs);
    out.bootError = await page.evaluate(() => window.webcal.error);
    // where the port and the sources came from ("files" or "bundle"), and what the page's
    // origin gets: a secure context and navigator.serial (Web Serial), as Chromium decides
    // getPorts(): the ports this origin was granted (none yet), or why it was refused
    Object.assign(out, await page.evaluate(async () => ({ loadedFrom: window.webcal.loadedFrom,
        secureContext: window.isSecureContext, webSerial: "serial" in navigator,
        serialPorts: "serial" in navigator
            ? await navigator.serial.getPorts().then((p) => p.length, (e) => String(e)) : null })));
    if (!out.bootError) {
        const s0 = Date.now();
        await page.click("#sim");
        await page.waitForFunction(() => window.webcal.lines > 0, null, { timeout: STEP_MS });
        out.times.firstLineMs = Date.now() - s0;
        await page.waitForFunction(() => window.webcal.sendEnabled, null, { timeout: STEP_MS });
        out.times.sendEnabledMs = Date.now() - s0;
        out.simSecondsAtSend = await page.evaluate(() => window.webcal.samples.length / 100);
        await page.click("#send");
        await page.waitForFunction(() => window.webcal.confirmed, null, { timeout: STEP_MS });
        out.times.confirmedMs = Date.now() - s0;
        await page.screenshot({ path: shot, fullPage: true });
    } else {
        await page.screenshot({ path: shot, fullPage: true });
    }
    if (!out.bootError) out.headingError = await page.evaluate(() => window.webcal.api.headingError());
    out.webcal = await page.evaluate(() => {
        const w = window.webcal;
        return { samples: w.samples, log: w.log, current: w.current, sentCal: w.sentCal, gauges: w.gauges && {
            gaps: w.gauges.gaps, variance: w.gauges.variance, wobble: w.gauges.wobble,
            fit: w.gauges.fit }, packetHex: w.packetHex, sentValues: w.sentValues,
            confirmed: w.confirmed, echo: w.echo, lines: w.lines, badLines: w.badLines,
            heading: w.heading, sim: w.sim, error: w.error,
            status: document.getElementById("status").textContent };
    });
    // The Web Serial path with a stand-in port (no board here): the page's reader loop and
    // line parser on a stream split at awkward places, CR-only and CR LF records, a banner,
    // a record mid-line and two records MotionCal refuses (8 fields; a space).
    const page2 = await browser.newPage();
    page2.on("console", (m) => { if (m.type() === "error") out.consoleErrors.push(m.text()); });
    page2.on("pageerror", (e) => out.pageErrors.push(String(e)));
    await page2.addInitScript(() => {
        const chunks = ["boot banner\r\n", "Raw:0,0,8192,0,0,0,200,-30,400\r", "Raw:0,0,8192,0,0,0,2",
            "01,-31,401\r\n", "heading 12.3 Raw:0,0,8192,0,0,0,202,-32,402\r",
            "Raw:1,2,3,4,5,6,7,8\r", "Raw:1, 2,3,4,5,6,7,8,9\r\n"];
        const enc = new TextEncoder();
        const port = {
            open: async () => {}, close: async () => {},
            readable: new ReadableStream({ start(c) { for (const t of chunks) c.enqueue(enc.encode(t)); } }),
            writable: new WritableStream({ write() {} }),
        };
        Object.defineProperty(navigator, "serial", { value: { requestPort: async () => port } });
    });
    await page2.goto(url);
    await page2.waitForFunction(() => window.webcal && window.webcal.ready, null, { timeout: STEP_MS });
    await page2.click("#connect");
    await page2.waitForFunction(() => window.webcal.samples.length >= 3, null, { timeout: STEP_MS });
    out.serial = await page2.evaluate(() => ({ source: window.webcal.source,
        lines: window.webcal.lines, badLines: window.webcal.badLines,
        samples: window.webcal.samples }));
} finally {
    await browser.close();
}
out.times.totalMs = Date.now() - t0;
process.stdout.write(JSON.stringify(out) + "\n");
