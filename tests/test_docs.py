"""Every ```python block in README.md and docs/*.md runs on CPython against the simulator, with
exactly the setup lines it shows. A block whose first line is a comment starting `# board
only` (or `# needs`) uses a real board or names from the text around it: it must compile.
Every image they show (`![...](file)`) exists."""
import glob
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP = ("# board only", "# needs")


def _blocks():
    out = []
    for path in ["README.md"] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md"))):
        text = open(os.path.join(ROOT, path)).read()
        rel = os.path.relpath(os.path.join(ROOT, path), ROOT)
        for m in re.finditer(r"^```python\n(.*?)^```", text, re.M | re.S):
            line = text.count("\n", 0, m.start()) + 1
            out.append(pytest.param(m.group(1), id="%s:%d" % (rel, line)))
    return out


BLOCKS = _blocks()


def test_there_are_runnable_blocks():
    runnable = [b for b in BLOCKS if not b.values[0].startswith(SKIP)]
    assert len(runnable) >= 1 and len(BLOCKS) >= 5


@pytest.mark.parametrize("code", BLOCKS)
def test_doc_block(code, monkeypatch, tmp_path):
    compiled = compile(code, "<doc block>", "exec")
    if code.startswith(SKIP):
        return
    monkeypatch.chdir(ROOT)
    exec(compiled, {"__name__": "__doc_block__"})


def test_images_exist():
    """Every ![...](file) in README.md and docs/*.md names a file in the repository."""
    missing, seen = [], 0
    for path in ["README.md"] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md"))):
        full = os.path.join(ROOT, path)
        for m in re.finditer(r"!\[[^\]]*\]\(([^)\s]+)\)", open(full).read()):
            seen += 1
            if not os.path.isfile(os.path.join(os.path.dirname(full), m.group(1))):
                missing.append("%s: %s" % (os.path.relpath(full, ROOT), m.group(1)))
    assert seen >= 3 and not missing, missing


def test_readme_and_docs_send_no_one_to_a_folder_outside_the_repository():
    # what a user runs stands on the repository's own files (the 32-bit tiers: the build
    # script and its variable, docs/design.md); a development folder beside it is not theirs
    outside = re.compile(r"\.\./shared|\bshared/(tools|datasets|notes|seeds)\b")
    for path in [os.path.join(ROOT, "README.md")] + sorted(
            glob.glob(os.path.join(ROOT, "docs", "*.md"))):
        up = 0 if os.path.dirname(path) == ROOT else 1  # docs/ may link ../README.md
        for n, line in enumerate(open(path, encoding="utf-8"), 1):
            assert not outside.search(line), "%s:%d: %s" % (path, n, line.strip())
            for m in re.finditer(r"((?:\.\./)+)", line):
                assert m.group(1).count("../") <= up, "%s:%d: %s" % (path, n, line.strip())


def test_code_tests_and_messages_name_no_folder_outside_the_repository():
    # the same for what runs: the real logs are in datasets/ or build/datasets (`make
    # datasets`), never beside the repository (CI's own .ci/run passes where CI keeps the
    # prebuilt 32-bit tiers). One mention stays: comments naming the development notes a
    # model was written from, which nothing opens
    outside = re.compile(r"\.\./shared(?!/notes\b)|\bshared/(datasets|seeds|tools)\b"
                         r"|\"\.\.\", \"shared\"")   # the same, as os.path.join parts
    paths = [os.path.join(ROOT, "Makefile"), os.path.join(ROOT, "datasets", "README.md")]
    for top in ("boards", "desktop", "examples", "firmware", "host_sim", "tests", "tools", "web"):
        for dirpath, dirs, files in os.walk(os.path.join(ROOT, top)):
            dirs[:] = [d for d in dirs if d not in ("vendor", "node_modules", "__pycache__")]
            paths += [os.path.join(dirpath, f) for f in files
                      if f.endswith((".py", ".sh", ".js", ".mjs", ".json", ".md", ".html"))]
    assert len(paths) > 100
    for path in paths:
        for n, line in enumerate(open(path, encoding="utf-8", errors="replace"), 1):
            assert not outside.search(line), "%s:%d: %s" % (path, n, line.strip())


# ---- links and anchors: every relative link in README.md and docs/*.md resolves --------------
# A link resolves against the folder of the file that holds it (as GitHub renders it); an
# `#anchor` names a heading of the target by GitHub's slug: lower case, characters other than
# letters, digits, spaces, '-' and '_' dropped, spaces to '-', a repeated heading gets -1, -2.
# Links inside code (fenced blocks, `spans`) are text, not links.

_FENCE = re.compile(r"^(```|~~~).*?^\1", re.M | re.S)
_LINK = re.compile(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def _doc_files():
    return [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "docs",
                                                                            "*.md")))


def slug(heading):
    """GitHub's anchor for a heading's text."""
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading).strip().lower()
    return "".join(c for c in h if c.isalnum() or c in " -_").replace(" ", "-")


def anchors(path):
    """Every anchor of a Markdown file: its headings' slugs, and <a name/id="..."> tags."""
    text = _FENCE.sub("", open(path, encoding="utf-8").read())
    seen, out = {}, set()
    for m in re.finditer(r"^#{1,6}\s+(.*?)\s*#*\s*$", text, re.M):
        s = slug(m.group(1))
        n = seen.get(s, 0)
        out.add(s if n == 0 else "%s-%d" % (s, n))
        seen[s] = n + 1
    out.update(re.findall(r'<a\s+(?:name|id)="([^"]+)"', text))
    return out


def links(path):
    """(target, line number) of every relative link in a Markdown file, outside code."""
    text = open(path, encoding="utf-8").read()
    # blank out code, keeping the line count, so line numbers stay right
    text = _FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    text = re.sub(r"`[^`\n]*`", "", text)
    for m in _LINK.finditer(text):
        target = m.group(1)
        if not re.match(r"[a-zA-Z][a-zA-Z0-9+.-]*:", target):   # http:, https:, mailto:
            yield target, text.count("\n", 0, m.start()) + 1


def dead_links(files):
    dead, n = [], 0
    for f in files:
        for target, line in links(f):
            n += 1
            where = "%s:%d: %s" % (os.path.relpath(f, ROOT), line, target)
            path, _, frag = target.partition("#")
            full = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
            if not os.path.exists(full):
                dead.append(where + " (no such file: %s)" % os.path.relpath(full, ROOT))
            elif frag and full.endswith(".md") and frag not in anchors(full):
                dead.append(where + " (no heading with that anchor in %s)"
                            % os.path.relpath(full, ROOT))
    return n, dead


def test_github_slugs():
    assert slug("Offline calibration of a log (`python -m host_sim calibrate`)") == \
        "offline-calibration-of-a-log-python--m-host_sim-calibrate"
    assert slug("Storage (`firmware/store.py`, `firmware/store_slots.py`)") == \
        "storage-firmwarestorepy-firmwarestore_slotspy"
    assert slug("`make run`: the story on the simulated board") == \
        "make-run-the-story-on-the-simulated-board"


def test_the_link_check_finds_a_dead_link_and_a_dead_anchor(tmp_path):
    (tmp_path / "docs").mkdir()
    a = tmp_path / "docs" / "a.md"
    (tmp_path / "docs" / "b.md").write_text("# Title\n\n## Second part (`x.py`)\n")
    a.write_text("[ok](b.md#second-part-xpy) [self](#top) [gone](docs/b.md) "
                 "[bad](b.md#nothing) `[code](nowhere.md)` [web](https://example.com)\n\n# Top\n")
    n, dead = dead_links([str(a)])
    assert n == 4 and len(dead) == 2
    assert "docs/b.md (no such file" in dead[0] and "b.md#nothing (no heading" in dead[1]


def test_every_link_and_anchor_in_readme_and_docs_resolves():
    n, dead = dead_links(_doc_files())
    assert n >= 50 and not dead, "\n".join(dead)


def test_the_tier_messages_name_the_tag_the_build_script_pins():
    # `make tiers` and the tests' skip reasons tell a user which MicroPython to clone
    from tests import mp
    script = open(os.path.join(ROOT, "tools", "build-micropython-tiers.sh")).read()
    tag = re.search(r"^PIN_TAG=(\S+)$", script, re.M).group(1)
    make = open(os.path.join(ROOT, "Makefile")).read()
    assert re.search(r"^MICROPYTHON_TAG := (\S+)$", make, re.M).group(1) == tag
    assert mp.MICROPYTHON_TAG == tag and "--branch %s " % tag in mp.BUILD_HINT
    assert "MICROPYTHON_SRC=build/micropython make tiers" in mp.BUILD_HINT
    assert "git clone --depth 1 --branch $(MICROPYTHON_TAG) " in make  # what make tiers prints


# ---- `make test` says why each skipped test skipped, and what runs it ------------------------

def _skip_calls():
    """(file:line, literal text or None) of every skip in tests/*.py: pytest.skip(...),
    pytest.importorskip(..., reason=...), @pytest.mark.skipif(..., reason=...); None when the
    text is computed (a tier's reason, missing_reason(), ...)."""
    import ast
    out = []
    for path in sorted(glob.glob(os.path.join(ROOT, "tests", "*.py"))):
        for node in ast.walk(ast.parse(open(path).read())):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            name = node.func.attr
            if name == "skip" and node.args:
                arg = node.args[0]
            elif name in ("importorskip", "skipif"):
                arg = dict((k.arg, k.value) for k in node.keywords).get("reason")
            else:
                continue
            where = "%s:%d" % (os.path.relpath(path, ROOT), node.lineno)
            if arg is None:                      # importorskip's own text names no command
                out.append((where, ""))
                continue
            texts = [n.value for n in ast.walk(arg)
                     if isinstance(n, ast.Constant) and isinstance(n.value, str)]
            computed = any(isinstance(n, (ast.Call, ast.Attribute, ast.Name))
                           for n in ast.walk(arg))
            out.append((where, None if computed else "".join(texts)))
    return out


# skips no command can lift: what the platform lacks, and what a chip lacks (a scenario of
# tests/test_faults.py that a chip cannot have, its datasheet named)
PLATFORM = ("os.openpty", "datasheet")


def test_every_literal_skip_reason_says_what_to_run_or_install():
    calls = _skip_calls()
    assert len(calls) >= 15
    vague = [(w, t) for w, t in calls if t is not None and not re.search(
        r"\bmake [a-z]|apt-get install|requirements\.txt", t) and not any(
        p in t for p in PLATFORM)]
    assert vague == []


def test_computed_skip_reasons_name_what_to_run(monkeypatch):
    # the reasons the tiers, the fetched logs and the browser tier give when they are missing
    import shutil
    from desktop.benchmarks.reference import missing_reason
    from tests import mp
    from tests import test_web
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert "make wasm" in mp._wasm_reason()
    monkeypatch.setattr(mp, "X86_32", os.path.join(ROOT, "build", "no-such-tool"))
    assert "make tiers" in mp._x86_reason() and mp.MICROPYTHON_TAG in mp._x86_reason()
    monkeypatch.setenv("ARM_TIER", "0")
    assert "make test-arm" in mp._arm_reason()
    assert "make datasets" in missing_reason(["a"]) and "make datasets" in missing_reason(
        ["a", "b", "c"])
    assert "make web" in test_web._why_skip()


def test_make_test_prints_the_skip_reasons():
    # -rs: a line per reason (pytest groups the skips that share one) after the dots
    make = open(os.path.join(ROOT, "Makefile")).read()
    recipe = re.search(r"^test:.*\n((?:\t.*\n)+)", make, re.M).group(1)
    assert re.search(r"-m pytest\b.*\s-rs\b", recipe), recipe


# ---- every firmware name README and docs quote exists ----------------------------------------
# `firmware.mod.attr` (a module, then attributes: imported and looked up) and `firmware/mod.py`
# (a file or folder; a glob must match one), resolved against the tree as it is, so a module
# moved into a sub-package must be quoted by its new name. `x` / `y` are placeholders
# (`from firmware.x import y`); `/firmware/...` after a slash is a URL path, not a name.

_FW_NAME = re.compile(r"(?<![\w/.-])firmware((?:\.[A-Za-z_]\w*)+|/[\w*./-]*)")
PLACEHOLDERS = ("x", "y")


def _defined(body):
    """{name: node} of what a module or class body defines (def, class, assignment, import,
    and the same inside its try / if blocks)."""
    import ast
    out = {}
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out[node.name] = node
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            for t in (node.targets if isinstance(node, ast.Assign) else [node.target]):
                for n in ast.walk(t):
                    if isinstance(n, ast.Name):
                        out[n.id] = node
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for a in node.names:
                out[(a.asname or a.name).split(".")[0]] = node
        elif isinstance(node, (ast.Try, ast.If, ast.With)):
            for block in ([node.body, node.orelse] + [h.body for h in getattr(
                    node, "handlers", [])] + [getattr(node, "finalbody", [])]):
                out.update(_defined(block))
    return out


def unresolved_firmware_name(name, root=ROOT):
    """None when `name` ('firmware.trig.atan2', 'firmware/store.py') exists, else why not.
    Read from the sources (not imported: some modules import only on MicroPython)."""
    import ast
    if "/" in name or name == "firmware":
        path = name.rstrip(".")
        if "..." in path or any(p in PLACEHOLDERS for p in re.split(r"[/.]", path)):
            return None
        full = os.path.join(root, path)
        if "*" in path:
            return None if glob.glob(full) else "no file matches"
        if os.path.exists(full) or os.path.exists(full + ".py"):
            return None
        return "no such file or folder"
    parts = name.split(".")
    if any(p in PLACEHOLDERS for p in parts[1:2]):
        return None
    k = len(parts)        # the longest prefix that is a module: a .py or a package folder
    while k > 1 and not (os.path.isfile(os.path.join(root, *parts[:k]) + ".py") or
                         os.path.isdir(os.path.join(root, *parts[:k]))):
        k -= 1
    if k == 1:
        return "no module %s" % ".".join(parts[:2])
    mod = ".".join(parts[:k])
    src = os.path.join(root, *parts[:k]) + ".py"
    if not os.path.isfile(src):
        src = os.path.join(root, *(parts[:k] + ["__init__.py"]))
        if not os.path.isfile(src):       # a folder without __init__.py: modules only
            return None if k == len(parts) else "no module %s" % ".".join(parts[:k + 1])
    body = ast.parse(open(src, encoding="utf-8").read()).body
    for a in parts[k:]:
        node = _defined(body).get(a)
        if node is None:
            return "%s has no %s" % (mod, ".".join(parts[k:]))
        body = node.body if isinstance(node, ast.ClassDef) else []
    return None


def test_the_firmware_name_check_finds_a_wrong_module_and_a_wrong_attribute():
    assert unresolved_firmware_name("firmware.trig.atan2") is None
    assert unresolved_firmware_name("firmware.heading.atan2") == "no module firmware.heading"
    assert unresolved_firmware_name("firmware.trig.atan3") == "firmware.trig has no atan3"
    assert unresolved_firmware_name("firmware/trig.py") is None
    assert unresolved_firmware_name("firmware/heading.py") == "no such file or folder"
    assert unresolved_firmware_name("firmware/*.py") is None
    assert unresolved_firmware_name("firmware.x") is None          # a placeholder
    assert unresolved_firmware_name("firmware.fast.isqrt") is None  # imports only on MicroPython
    assert unresolved_firmware_name("firmware.calibrate.calibrator.Calibrator.solve") is None
    assert unresolved_firmware_name("firmware.calibrate.calibrator.Calibrator.nothing") is not None


def test_the_firmware_name_check_follows_modules_into_sub_packages(tmp_path):
    # a module moved into a sub-folder (with or without __init__.py) is found by its new name
    sub = tmp_path / "firmware" / "calibrate"
    sub.mkdir(parents=True)
    (sub / "solve.py").write_text("class Fit:\n    def solve(self):\n        pass\n")
    (tmp_path / "firmware" / "gyro").mkdir()
    (tmp_path / "firmware" / "gyro" / "__init__.py").write_text("from firmware.x import y\n")
    root = str(tmp_path)
    for name in ("firmware.calibrate.solve.Fit.solve", "firmware/calibrate/solve.py",
                 "firmware.calibrate", "firmware/calibrate/", "firmware.gyro.y"):
        assert unresolved_firmware_name(name, root) is None, name
    assert unresolved_firmware_name("firmware.solve.Fit", root) == "no module firmware.solve"
    assert unresolved_firmware_name("firmware.calibrate.fit", root) == \
        "no module firmware.calibrate.fit"
    assert unresolved_firmware_name("firmware/solve.py", root) == "no such file or folder"


def test_every_firmware_module_and_name_readme_and_docs_quote_exists():
    bad, n = [], 0
    for path in _doc_files():
        for k, line in enumerate(open(path, encoding="utf-8"), 1):
            for m in _FW_NAME.finditer(line):
                n += 1
                name = m.group(0).rstrip(".,;:")
                why = unresolved_firmware_name(name)
                if why:
                    bad.append("%s:%d: %s (%s)" % (os.path.relpath(path, ROOT), k, name, why))
    assert n >= 50 and not bad, "\n".join(bad)


# ---- the lists the docs keep: every command, example and package part ------------------------

def _section(path, heading):
    """The text of README's / a doc's section whose heading contains `heading` (to the next
    heading of the same or a higher level)."""
    text = open(path, encoding="utf-8").read()
    m = re.search(r"^(#+) [^\n]*%s[^\n]*\n" % re.escape(heading), text, re.M)
    assert m, (path, heading)
    end = re.compile(r"^#{1,%d} " % len(m.group(1)), re.M).search(text, m.end())
    return text[m.end():end.start() if end else len(text)]


def test_design_names_every_command_of_the_runner():
    from desktop.__main__ import _COMMANDS
    text = open(os.path.join(ROOT, "docs", "design.md"), encoding="utf-8").read()
    para = [p for p in text.split("\n\n") if "the command-line runner:" in p]
    assert len(para) == 1
    listed = re.findall(r"`(\w+)`", para[0].split("the command-line runner:")[1].split(";")[0])
    assert listed == list(_COMMANDS)


def test_readme_names_every_example_and_the_install_page_every_package_part():
    readme = os.path.join(ROOT, "README.md")
    examples = sorted(f for f in os.listdir(os.path.join(ROOT, "examples"))
                      if f.endswith(".py") and f not in ("__init__.py", "bus.py"))
    assert len(examples) >= 7
    section = _section(readme, "Examples")
    assert [f for f in examples if "`%s`" % f not in section] == []
    parts = sorted(os.path.basename(p) for p in glob.glob(os.path.join(ROOT, "package-*.json")))
    assert len(parts) >= 7
    text = open(os.path.join(ROOT, "docs", "install.md"), encoding="utf-8").read()
    assert [p for p in parts if "`%s`" % p not in text] == []


# ---- the interpreter the commands name --------------------------------------------------------
# Stock Debian has python3 and no `python`: README, docs and the examples' usage lines say
# python3 for what runs on the standard library alone, and .venv/bin/python (what `make run`
# and `make test` make from requirements.txt) for what needs its packages.

_BARE_PYTHON = re.compile(r"(?<![\w./-])python(?=\s)")
# host_sim / desktop commands (and modules) that import a requirements.txt package: matplotlib
# for run's plot and quality's plot, pygeomag for wmm, numpy for bench, pg8000 for a PostgreSQL
# database
VENV_ONLY = re.compile(r"-m ((host_sim|desktop) (run|wmm|bench)\b"
                       r"|(host_sim|desktop) quality\b.*(\bplot\b|postgresql:)"
                       r"|pytest\b)")


def _command_lines():
    """(where, line) of README, docs/*.md and the examples' docstrings, outside ```python
    blocks (Python code, not commands)."""
    out = []
    for path in _doc_files():
        fence = None
        for k, line in enumerate(open(path, encoding="utf-8"), 1):
            if line.lstrip().startswith("```"):
                fence = None if fence is not None else line.strip()[3:]
            elif fence != "python":
                out.append(("%s:%d" % (os.path.relpath(path, ROOT), k), line))
    for path in sorted(glob.glob(os.path.join(ROOT, "examples", "*.py"))):
        doc = open(path, encoding="utf-8").read().split('"""')
        if len(doc) > 2:
            for k, line in enumerate(doc[1].splitlines(), 1):
                out.append(("%s:%d" % (os.path.relpath(path, ROOT), k), line))
    return out


def test_no_command_starts_with_a_bare_python():
    lines = _command_lines()
    assert len(lines) > 2000
    bare = ["%s: %s" % (w, ln.strip()) for w, ln in lines if _BARE_PYTHON.search(ln)]
    assert bare == [], "\n".join(bare)


def test_what_python3_runs_needs_only_the_standard_library():
    import subprocess
    import sys
    seen, venv = set(), []
    for where, line in _command_lines():
        for m in re.finditer(r"(?<![\w./-])python3 -m ([\w.]+)(?: ([a-z]+))?", line):
            if VENV_ONLY.search(line[m.start():]):
                venv.append("%s: %s" % (where, line.strip()))
            mod, cmd = m.group(1), m.group(2)
            if mod.split(".")[0] in ("host_sim", "desktop", "examples"):
                seen.add((mod, cmd if mod in ("host_sim", "desktop") else None))
    assert venv == [], "these need .venv/bin/python:\n" + "\n".join(venv)
    assert ("host_sim", "calibrate") in seen and len(seen) >= 8
    for mod, cmd in sorted(seen, key=str):
        if mod in ("host_sim", "desktop"):       # the command's module, through the runner
            argv = [sys.executable, "-S", "-m", mod] + ([cmd] if cmd else []) + ["--help"]
        else:   # a script (a benchmark, an example): imported; their tests run them
            argv = [sys.executable, "-S", "-c", "import %s" % mod]
        p = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert p.returncode == 0 and "Traceback" not in p.stderr, (argv, p.stderr[-1000:])


def test_the_module_map_in_design_names_every_firmware_module():
    # docs/design.md's two tables (the pipeline, then every other module by part): a module
    # added or moved without a line there fails here
    from desktop.packaging import firmware_files
    text = open(os.path.join(ROOT, "docs", "design.md"), encoding="utf-8").read()
    body = text[text.index("## The pipeline, one module per step"):]
    body = body[:body.index("\n## ", 5)]
    missing = []
    for f in firmware_files():
        if not f.endswith(".py"):
            continue
        base = os.path.basename(f)
        if ("firmware/" + f) not in body and ("`%s`" % base) not in body and \
                (", %s" % base) not in body:
            missing.append(f)
    assert missing == [], missing
