"""The code style the project keeps: ruff (pycodestyle, pyflakes, import order; pyproject.toml [tool.ruff])
is clean on the library and the first-party plugins."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_is_clean_on_src_and_optimizers():
    r = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "src", "optimizers"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
