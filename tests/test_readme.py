"""Every Python block of the README works: a block is run on its own in a fresh interpreter (so it
must be self-contained), except a block that starts with ``# excerpt of PATH``, whose lines must
appear, in order, in that file of the repository, end-of-line comments aside (so the excerpt cannot
drift from the code)."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from tests.conftest import ROOT, child_env

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
EXCERPT = re.compile(r"# excerpt of (\S+)")
COMMENT = re.compile(r"\s+#.*$")  # an end-of-line comment (the README may annotate an excerpt)


def _code(line: str) -> str:
    return COMMENT.sub("", line).rstrip()


def _blocks() -> list[tuple[int, str]]:
    text = (ROOT / "README.md").read_text()
    return [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in BLOCK.finditer(text)]


BLOCKS = _blocks()


def test_the_readme_has_python_blocks():
    assert len(BLOCKS) >= 8


@pytest.mark.parametrize(("line", "code"), BLOCKS, ids=[f"README.md:{line}" for line, _ in BLOCKS])
def test_readme_block(line, code, tmp_path):
    first = code.splitlines()[0]
    excerpt = EXCERPT.fullmatch(first.strip())
    if excerpt:
        source = (ROOT / excerpt.group(1)).read_text().splitlines()
        pos = 0
        for wanted in (ln for ln in code.splitlines()[1:] if ln.strip() and "..." not in ln):
            hits = [i for i in range(pos, len(source)) if _code(source[i]) == _code(wanted)]
            assert hits, f"README.md:{line}: {wanted!r} not found (in order) in {excerpt.group(1)}"
            pos = hits[0] + 1
        return
    env = child_env()
    proc = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600, check=False
    )
    assert proc.returncode == 0, f"README.md:{line} failed:\n{proc.stderr[-3000:]}"
