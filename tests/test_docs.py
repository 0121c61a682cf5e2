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
