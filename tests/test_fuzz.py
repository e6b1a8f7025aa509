"""Hostile input: mutated codec files and mesh files must fail with an MzcError, never anything else."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mzc.codecs.rows import dct, dft, dwt, poly
from mzc.errors import MzcError
from mzc.formats import read_any
from mzc.grid import ZGrid
from mzc.meshes import read_mesh


def sample_grid():
    y, x = np.mgrid[0:6, 0:9].astype(float)
    z = np.sin(x / 3) + y / 4
    z[2, 4] = np.nan
    z[0, :2] = np.nan
    return ZGrid(z, 3.0, 0.25)


ENCODED = {
    "dct": dct.write(sample_grid(), quality=60),
    "dft": dft.write(sample_grid(), quality=60),
    "dwt": dwt.write(sample_grid(), quality=60),
    "poly": poly.write(sample_grid(), degree=3),
}


def mutate(data, draw):
    """Truncate, overwrite a span with junk, or duplicate a line of ``data``."""
    lines = data.split(b"\n")
    choice = draw(st.sampled_from(["truncate", "junk", "duplicate", "token"]))
    if choice == "truncate":
        return data[:draw(st.integers(0, len(data) - 1))]
    if choice == "junk":
        at = draw(st.integers(0, len(data) - 1))
        return data[:at] + draw(st.binary(min_size=1, max_size=12)) + data[at + 1:]
    index = draw(st.integers(0, len(lines) - 1))
    if choice == "duplicate":
        return b"\n".join(lines[:index + 1] + lines[index:])
    tokens = lines[index].split(b" ")
    position = draw(st.integers(0, len(tokens) - 1))
    tokens[position] = draw(st.sampled_from([b"nan", b"inf", b"-1", b"0", b"99999999999", b"1e308", b"x", b""]))
    lines[index] = b" ".join(tokens)
    return b"\n".join(lines)


@pytest.mark.parametrize("kind", sorted(ENCODED))
@given(data=st.data())
@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
def test_mutated_codec_files_fail_cleanly_or_decode_to_the_grid_shape(kind, data):
    mutated = mutate(ENCODED[kind], data.draw)
    try:
        grid = read_any(mutated, "fuzz")
    except MzcError:
        return
    assert grid.z.ndim == 2 and not np.isinf(grid.z).any()


MESH_PREFIXES = {
    ".obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    ".ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    ".xyz": b"0 0 0\n1 0 0\n0 1 0\n",
    ".off": b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
}


@pytest.mark.parametrize("extension", sorted(MESH_PREFIXES))
@given(data=st.data())
@settings(max_examples=100, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
def test_mutated_mesh_files_fail_cleanly(extension, data, tmp_path):
    path = tmp_path / f"m{extension}"
    path.write_bytes(mutate(MESH_PREFIXES[extension], data.draw))
    try:
        mesh = read_mesh(str(path))
    except MzcError:
        return
    assert np.isfinite(mesh.points).all()
    assert mesh.triangles.size == 0 or mesh.triangles.max() < len(mesh.points)
