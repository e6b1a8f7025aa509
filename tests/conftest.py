"""Shared fixtures: the real faces under ../shared/data (skipped cleanly when absent) and a CLI runner."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
FACES = REPO.parent / "shared" / "data" / "faces"
FACE_NAMES = sorted(p.name for p in FACES.glob("*.ply")) if FACES.is_dir() else []


def face_path(name):
    """Path of a shared face, skipping the test when the shared data is not there."""
    path = FACES / name
    if not path.is_file():
        pytest.skip(f"shared face data not available ({path})")
    return path


@pytest.fixture
def f18():
    """The f18 face (binary PLY, millimetres)."""
    return face_path("f18.ply")


def run_mzc(*args, input=None, check=False, cwd=None, env=None):
    """Run ``python -m mzc ARGS`` as a subprocess; ``input`` is bytes for stdin, ``env`` variables
    to add to the environment."""
    result = subprocess.run([sys.executable, "-m", "mzc", *map(str, args)], input=input,
                            capture_output=True, cwd=cwd, env={**os.environ, **(env or {}), "MZC_DEBUG": ""})
    if check and result.returncode != 0:
        raise AssertionError(f"mzc {' '.join(map(str, args))} failed: {result.stderr.decode()}")
    return result


@pytest.fixture
def mzc():
    """The run_mzc helper as a fixture."""
    return run_mzc


@pytest.fixture
def harmonic_fill(monkeypatch):
    """The dwt2d encoder as it wrote spec/dwt2d.md's worked examples: its invalid nodes filled
    harmonically (wavelet.laplace_fill), before the thin plate (smooth_fill) took over. The fill is
    the encoder's alone, so the examples decode as ever; their bytes are its output of that day."""
    from mzc.codecs.dwt2d import wavelet

    monkeypatch.setattr(wavelet, "smooth_fill", wavelet.laplace_fill)


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB tmpfs (root only; skipped otherwise), unmounted afterwards."""
    if not (hasattr(os, "geteuid") and os.geteuid() == 0):
        pytest.skip("mounting a small tmpfs needs root")
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(disk)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here")
    yield disk
    subprocess.run(["umount", str(disk)], check=True)


def shared_object(name):
    """The mesh of ../shared/data/objects/NAME; skips when the data is absent."""
    from mzc.meshes import read_mesh

    path = REPO.parent / "shared" / "data" / "objects" / name
    if not path.is_file():
        pytest.skip(f"shared object data not available ({path})")
    return read_mesh(path)


def shared_object_grid(name):
    """The default grid of ../shared/data/objects/NAME; skips when the data is absent."""
    from mzc.ops.slicing import slice_surface

    return slice_surface(shared_object(name))


def sliced_shared_object(name):
    """(the mesh of ../shared/data/objects/NAME, the rebuild of its default grid, its bounding-box
    diagonal D): the lossless floor the whole-object tests measure; skips when the data is absent."""
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    mesh = shared_object(name)
    return mesh, grid_to_mesh(slice_surface(mesh)), float(np.linalg.norm(np.ptp(mesh.points, axis=0)))


def edge_counts(triangles):
    """(edges used by one triangle, edges used by more than two): 0 and 0 for a closed manifold."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int((counts == 1).sum()), int((counts > 2).sum())
