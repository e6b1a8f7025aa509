"""Surfaces that go all the way round: a closed star-shaped blob and an open tube through every command."""

import numpy as np
import pytest

from mzc.codecs import dwt2d
from mzc.codecs.dwt2d.wavelet import laplace_fill
from mzc.codecs.rows import dct
from mzc.formats import read_any, zgrid
from mzc.measure.metrics import surface_distance
from mzc.meshes import read_mesh
from mzc.ops.densify import densify_grid
from mzc.ops.slicing import slice_surface
from mzc.ops.triangulation import grid_to_mesh
from mzc.samples import BLOB_CENTRE, blob, tube

from conftest import edge_counts

CODECS = {
    "dwt2d": (dwt2d, {"max_error": 0.02}),
    "dct": (dct, {"quality": 50, "precision": 6}),
}


@pytest.fixture(scope="module")
def closed():
    mesh = blob()
    return mesh, slice_surface(mesh, d1=2, d2=2)


@pytest.fixture(scope="module")
def pipe():
    mesh = tube()
    return mesh, slice_surface(mesh, d1=2, d2=2)


def rebuilt(grid, codec, method):
    """The grid through encode, decode, densify (n = 1) and triangulate."""
    module, options = CODECS[codec]
    decoded = read_any(module.write(grid, **options), codec)
    return grid_to_mesh(densify_grid(decoded, 1, method))


@pytest.mark.parametrize("codec", sorted(CODECS))
@pytest.mark.parametrize("method", ["biharmonic", "laplace", "thesis"])
def test_a_closed_blob_comes_back_closed_and_within_the_sampling_error(closed, codec, method):
    mesh, grid = closed
    assert grid.periodic and grid.pole_rows()[[0, -1]].all()
    back, exact = rebuilt(grid, codec, method), grid_to_mesh(grid)
    assert edge_counts(back.triangles) == (0, 0)   # no seam, no hole at either pole, no fold
    lossless = surface_distance((mesh.points, mesh.triangles), (exact.points, exact.triangles), samples=20_000)
    distance = surface_distance((mesh.points, mesh.triangles), (back.points, back.triangles), samples=20_000)
    assert lossless["rms"] < 0.02 and distance["rms"] < 3 * lossless["rms"] + 0.02


@pytest.mark.parametrize("codec", sorted(CODECS))
def test_an_open_tube_comes_back_with_only_its_two_ends_open(pipe, codec):
    mesh, grid = pipe
    assert grid.periodic and grid.projection == "cylindrical"
    back = rebuilt(grid, codec, "biharmonic")
    open_edges, folds = edge_counts(back.triangles)
    assert (open_edges, folds) == (2 * grid.shape[1], 0)   # the rims of the two ends
    distance = surface_distance((mesh.points, mesh.triangles), (back.points, back.triangles), samples=20_000)
    assert distance["rms"] < 0.05


def test_the_rebuilt_blob_faces_outwards_and_has_one_vertex_on_each_pole(closed):
    _mesh, grid = closed
    back = grid_to_mesh(read_any(dwt2d.write(grid, rmse=0.05), "blob"))
    points, triangles = back.points, back.triangles
    a, b, c = (points[triangles[:, i]] for i in range(3))
    outward = np.einsum("ij,ij->i", np.cross(b - a, c - a), (a + b + c) / 3 - BLOB_CENTRE)
    assert (outward > 0).all()
    axis, centre = grid.transform[:, 1], grid.transform[:, 3]
    offset = points - centre
    on_axis = np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1) < 1e-6
    assert on_axis.sum() == 2


def test_densifying_a_periodic_grid_commutes_with_turning_it(pipe):
    _mesh, grid = pipe
    turned = grid.with_z(np.roll(grid.z, 17, axis=1))
    for method in ("biharmonic", "laplace", "thesis"):
        np.testing.assert_allclose(densify_grid(turned, 2, method).z,
                                   np.roll(densify_grid(grid, 2, method).z, 17, axis=1), atol=1e-7)


def test_the_fill_of_a_full_turn_wraps_round():
    rows, cols = np.mgrid[0:20, 0:64]
    z = np.sin(2 * np.pi * cols / 64) + 0.1 * rows
    valid = ~((cols < 6) | (cols > 58)) | (rows % 5 == 0)   # a gap across the seam, bridged by some rows
    filled = laplace_fill(np.where(valid, z, np.nan), valid, periodic=True)
    turned = laplace_fill(np.roll(np.where(valid, z, np.nan), 32, axis=1), np.roll(valid, 32, axis=1), periodic=True)
    np.testing.assert_allclose(np.roll(filled, 32, axis=1), turned, atol=1e-9)
    # across the seam the fill joins the two sides smoothly instead of flattening at an edge
    assert np.abs(filled[2, 0] - filled[2, -1]) < 0.2


def test_a_full_turn_has_a_column_count_that_wraps_at_every_level(pipe):
    _mesh, grid = pipe
    cols = grid.shape[1]
    assert cols % 32 == 0 and grid.d2 * cols == pytest.approx(2 * np.pi * grid.radius, rel=1e-12)


def test_the_command_line_rebuilds_a_closed_blob(mzc, tmp_path):
    mesh = blob(4)
    obj = tmp_path / "blob.obj"
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.points.tolist()]
    obj.write_text("\n".join(lines + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.triangles]) + "\n")
    grid = mzc("slice", obj, "--d1", "2", "--d2", "2", check=True).stdout
    assert grid.startswith(b"mzc-zgrid 3.2\n") and b"\nprojection spherical\n" in grid
    packed = mzc("encode", "--dwt2d", "--max-error", "0.05", input=grid, check=True).stdout
    dense = mzc("densify", "-n", "1", input=mzc("decode", input=packed, check=True).stdout, check=True).stdout
    mzc("triangulate", "-o", tmp_path / "back.ply", input=dense, check=True)
    back = read_mesh(tmp_path / "back.ply")
    assert edge_counts(back.triangles) == (0, 0)
    assert zgrid.read(dense, "dense").projection == "spherical"
    info = mzc("info", input=packed, check=True).stdout.decode()
    assert "spherical" in info and "full turn" in info and "2 pole row(s)" in info
