"""The code style the project keeps: ruff (pycodestyle, pyflakes, import order; pyproject.toml [tool.ruff])
is clean on the library and the first-party plugins, and mypy on the packages listed below."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_is_clean_on_src_and_optimizers():
    r = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "src", "optimizers"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


#: the packages (and top-level modules) of src/robodesign that mypy passes (pyproject.toml [tool.mypy]): all of
#: them, now that design/ and solvers/ are clean too (issue 23 §6)
MYPY_CLEAN = ["cli", "core", "design", "experiment", "formats", "generate", "model", "viewer", "web", "judge",
              "collab", "solvers", "__init__.py", "_compat.py", "plugin.py"]
#: the first-party optimizer plugins (outside src/), clean too
MYPY_CLEAN_OUTSIDE = ["optimizers"]


def test_mypy_is_clean_on_the_listed_packages():
    """Errors are reported for the listed files only: the modules they import are analysed for their types
    (``--follow-imports=silent``), not checked."""
    paths = [str(Path("src") / "robodesign" / p) for p in MYPY_CLEAN] + MYPY_CLEAN_OUTSIDE
    r = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", *paths],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0 and "Success: no issues found" in r.stdout, r.stdout + r.stderr
