"""The documentation site builds (MkDocs, strict: any warning fails) from the README, every
command's --help, the public API's docstrings and the format specs."""

import subprocess
import sys
from pathlib import Path

import pytest

import mzc
from mzc.cli import COMMANDS

REPO = Path(__file__).resolve().parents[1]


def test_the_site_builds_strictly_with_every_command_name_and_spec(tmp_path):
    pytest.importorskip("mkdocs")
    site = tmp_path / "site"
    result = subprocess.run([sys.executable, str(REPO / "docs" / "build.py"), str(site)], capture_output=True)
    assert result.returncode == 0, result.stderr.decode()
    cli = (site / "cli" / "index.html").read_text()
    assert all(f"mzc {name}" in cli for name in COMMANDS) and "--dwt2d" in cli and "mzc batch encode" in cli
    api = (site / "api" / "index.html").read_text()
    assert all(f"mzc.{name}" in api for name in mzc.__all__ if not name.startswith("__"))
    assert "Mesh.to_trimesh" in api and "ZGrid.chart_grids" in api   # a class's methods under it
    for spec in (REPO / "spec").glob("*.md"):
        assert (site / "spec" / spec.stem / "index.html").exists(), spec.name
    assert "Python API" in (site / "index.html").read_text()   # the README is the guide
