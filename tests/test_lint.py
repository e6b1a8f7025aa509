"""The code passes its linter (ruff) and its type checker (mypy), as configured in pyproject.toml."""

import os
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


def test_a_users_code_is_checked_against_the_public_api(tmp_path):
    """A mypy user sees mzc's hints (py.typed): a misspelt or mistyped encode option is an error,
    and the options every built-in codec takes are the ones ``mzc.api.EncodeOptions`` names."""
    from mzc.api import EncodeOptions
    from mzc.codecs import codec_names, get_codec

    assert set(EncodeOptions.__annotations__) == {o.name for n in codec_names() for o in get_codec(n).options}
    good, bad = tmp_path / "good.py", tmp_path / "bad.py"
    good.write_text("import mzc\n\ngrid = mzc.slice(mzc.sample('bump'))\ndata: bytes = mzc.encode(grid, rmse=0.05)\n"
                    "mesh = mzc.triangulate(mzc.decode(data), vertices=1000)\nmesh.to_trimesh()\n")
    bad.write_text("import mzc\n\ngrid = mzc.slice(mzc.sample('bump'))\nmzc.encode(grid, max_eror=0.05)\n"
                   "mzc.encode(grid, rmse='0.05')\n")
    command = [sys.executable, "-m", "mypy", "--no-incremental", "--strict", "--follow-imports=silent"]
    # mypy does not follow an editable install's import hook: it is told where the package is
    found = {**os.environ, "MYPYPATH": str(REPO)}
    result = subprocess.run([*command, str(good)], cwd=tmp_path, capture_output=True, text=True, env=found)
    assert result.returncode == 0, result.stdout
    result = subprocess.run([*command, str(bad)], cwd=tmp_path, capture_output=True, text=True, env=found)
    assert 'Unexpected keyword argument "max_eror"' in result.stdout and "bad.py:5" in result.stdout, result.stdout
