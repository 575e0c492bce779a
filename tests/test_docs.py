"""The docs run as written: every code block of README.md and docs/*.md marked runnable is extracted from the
Markdown (never copied here) and executed, in order, in a fresh working folder per document.

Markers (the first word of a fenced block's info string stays the language, so GitHub still highlights it):

* ```` ```bash run ```` — run with ``bash -euo pipefail``; ``robodesign`` and ``.venv/bin/robodesign`` are this
  checkout's, ``../shared/cobra`` is the CoBRA reference data (as beside a checkout);
* ```` ```python run ```` — run with this Python, in its own process;
* ```` ```json file=NAME ```` (any language) — written to ``NAME`` in the working folder before the blocks after it;
* ```` ```text output ```` right after a runnable block — what it prints: each non-empty line must appear in the
  block's output (stdout and stderr), ``…`` standing for anything.

A block that exits non-zero fails the test with its output. The page's test is marked slow: the README and the
tutorial solve and optimize real tasks.
"""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import COBRA, ROOT

FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```[ \t]*$", re.S | re.M)
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def blocks(path: Path):
    """(kind, argument, code) of each marked block of a Markdown file, in order: kind is "run" (argument: the
    language), "file" (argument: the file name) or "output"."""
    out = []
    for m in FENCE.finditer(path.read_text(encoding="utf-8")):
        words = m.group(1).split()
        code = m.group(2)
        if len(words) >= 2 and words[1] == "run":
            if words[0] not in ("bash", "python"):
                raise ValueError(f"{path.name}: a runnable block must be bash or python, not {words[0]!r}")
            out.append(("run", words[0], code))
        elif any(w.startswith("file=") for w in words[1:]):
            out.append(("file", next(w for w in words[1:] if w.startswith("file="))[5:], code))
        elif words[:2] == ["text", "output"]:
            out.append(("output", "", code))
    return out


def runnable_docs():
    return [p for p in DOCS if any(k == "run" for k, _, _ in blocks(p))]


def workdir(tmp_path: Path) -> Path:
    """A folder that looks like a checkout for the docs' commands: .venv, configs/ and ../shared/cobra."""
    wd = tmp_path / "checkout"
    wd.mkdir()
    (wd / ".venv").symlink_to(Path(sys.prefix))
    (wd / "configs").symlink_to(ROOT / "configs")
    (tmp_path / "shared").mkdir()
    (tmp_path / "shared" / "cobra").symlink_to(COBRA)
    return wd


def expect(output: str, expected: str, where: str) -> None:
    for line in expected.splitlines():
        parts = [p.strip() for p in line.strip().split("…") if p.strip()]
        if not parts:
            continue
        pattern = ".*?".join(re.escape(p) for p in parts)
        assert re.search(pattern, output), f"{where}: the output has no line matching {line.strip()!r}:\n{output[-3000:]}"


def test_the_marked_documents_have_runnable_blocks():
    """The marker must not silently disappear from the pages that promise runnable examples."""
    names = {p.relative_to(ROOT).as_posix() for p in runnable_docs()}
    assert {"README.md", "docs/tutorial.md", "docs/formats.md"} <= names, names
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert text.index("docs/tutorial.md") < text.index("## Set-up")  # the tutorial is linked first


def test_expect_matches_lines_with_ellipses():
    expect("cost  cyc = 3.01 (checked)\n", "cyc = … (checked)", "self-test")
    with pytest.raises(AssertionError):
        expect("cost  cyc = 3.01\n", "cyc = … (checked)", "self-test")


@pytest.mark.slow
@pytest.mark.parametrize("doc", runnable_docs(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_runnable_blocks_run_as_written(doc, tmp_path):
    wd = workdir(tmp_path)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
               PYTHONUNBUFFERED="1", MPLBACKEND="Agg")
    last = None
    for k, (kind, arg, code) in enumerate(blocks(doc)):
        where = f"{doc.name} block {k + 1} ({kind} {arg})"
        if kind == "file":
            (wd / arg).parent.mkdir(parents=True, exist_ok=True)
            (wd / arg).write_text(code, encoding="utf-8")
        elif kind == "run":
            cmd = ["bash", "-euo", "pipefail", "-c", code] if arg == "bash" else [sys.executable, "-c", code]
            r = subprocess.run(cmd, cwd=wd, env=env, capture_output=True, text=True, timeout=900)
            last = r.stdout + r.stderr
            assert r.returncode == 0, f"{where} exited {r.returncode}:\n{code}\n--- output ---\n{last[-4000:]}"
            assert "Traceback" not in last, f"{where}:\n{last[-4000:]}"
        elif kind == "output":
            assert last is not None, f"{where}: an output block must follow a runnable block"
            expect(last, code, where)
            last = None
