"""The code passes its linter (ruff) and its type checker (mypy), as configured in pyproject.toml."""

import subprocess
import sys

from conftest import REPO


def check(*command):
    """Run a checker in the repository; fail with its output when it finds something."""
    result = subprocess.run([sys.executable, "-m", *command], cwd=REPO, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]


def test_ruff_finds_nothing():
    check("ruff", "check", "--no-cache", ".")


def test_mypy_finds_nothing():
    check("mypy", "--no-incremental")
