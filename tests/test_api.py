"""The Python API (``import mzc``): the same work as the commands, on in-memory objects."""

import subprocess
import sys

import numpy as np
import pytest

import mzc

from golden import run


def test_import_mzc_lists_the_api_and_imports_no_numerics():
    assert {"slice", "encode", "decode", "densify", "triangulate", "compare", "read", "write",
            "ZGrid", "Mesh", "MzcError", "register_codec"} <= set(dir(mzc))
    assert set(mzc.__all__) == set(dir(mzc)) == {"__version__", *mzc.HOMES}
    script = "import sys, mzc; print(sorted({'numpy', 'scipy', 'meshio', 'pywt'} & set(sys.modules)))"
    assert subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True).stdout.strip() == "[]"
    with pytest.raises(AttributeError):
        mzc.no_such_name  # noqa: B018 - the attribute access is the test


def test_the_api_gives_the_bytes_of_the_pipeline_of_commands(tmp_path):
    """slice | encode | decode | densify | triangulate through the API = through the commands."""
    mesh_path = tmp_path / "bump.obj"
    mesh_path.write_bytes(run(["sample", "bump"]))
    grid = mzc.slice(mesh_path)
    assert mzc.read(mesh_path).points.shape == mzc.sample("bump").points.shape
    coded = mzc.encode(grid, max_error=0.05)
    assert coded == run(["encode", "--dwt2d", "--max-error", "0.05"], run(["slice", mesh_path]))
    decoded = mzc.decode(coded)
    assert np.nanmax(np.abs(decoded.z - grid.z)) <= 0.05
    dense = mzc.densify(decoded, 2)
    mzc.write(tmp_path / "dense.zg", dense, precision=6, plain=True)
    assert (tmp_path / "dense.zg").read_bytes() == run(["densify", "-n", "2", "--plain", "--precision", "6"],
                                                       run(["decode"], coded))
    mzc.write(tmp_path / "dense-raw.zg", dense)   # raw by default, as the commands write
    assert (tmp_path / "dense-raw.zg").read_bytes() == run(["densify", "-n", "2"], run(["decode"], coded))
    np.testing.assert_array_equal(mzc.read(tmp_path / "dense-raw.zg").z, dense.z)
    mesh = mzc.triangulate(dense)
    mzc.write(tmp_path / "out.obj", mesh)
    assert (tmp_path / "out.obj").read_bytes() == run(["triangulate"], run(["densify", "-n", "2"],
                                                                           run(["decode"], coded)))


def test_surfaces_come_as_trimesh_like_objects_pairs_arrays_and_grids():
    mesh = mzc.sample("blob")

    class TrimeshLike:
        vertices, faces = mesh.points, mesh.triangles

    by_pair = mzc.slice((mesh.points, mesh.triangles))
    assert np.array_equal(mzc.slice(TrimeshLike()).z, by_pair.z, equal_nan=True)
    cloud = mzc.slice(mzc.sample("bump").points)
    assert cloud.valid.sum() > 1000
    report = mzc.compare(by_pair, mesh, surface=True)
    assert report["surface_rms"] < 0.1 and report["grid_count"] > 0


def test_surfaces_come_from_trimesh_meshio_open3d_style_objects_and_oriented_arrays():
    trimesh = pytest.importorskip("trimesh")
    import meshio

    mesh = mzc.sample("blob")
    expected = mzc.slice(mesh)
    assert np.array_equal(mzc.slice(mesh.to_trimesh()).z, expected.z, equal_nan=True)
    assert np.array_equal(mzc.slice(mesh.to_meshio()).z, expected.z, equal_nan=True)
    # meshio's quads are two triangles each: a unit square of two quads is four triangles
    quads = meshio.Mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]],
                        [("quad", [[0, 1, 4, 3], [1, 2, 5, 4]])])
    assert len(mzc.api.mesh_in_memory(quads).triangles) == 4
    # an oriented cloud: an (n, 6) array, an Open3D-like object and a trimesh PointCloud
    cloud = mzc.sample("bump")
    up = np.tile([0.0, 0.0, 1.0], (len(cloud.points), 1))
    oriented = mzc.api.mesh_in_memory(np.hstack([cloud.points, up]))
    assert np.array_equal(oriented.points, cloud.points) and np.array_equal(oriented.normals, up)

    class Open3DLike:
        points, normals = cloud.points, up

    assert np.array_equal(mzc.api.mesh_in_memory(Open3DLike()).normals, up)
    by_points = mzc.slice(cloud.points)
    assert np.array_equal(mzc.slice(trimesh.PointCloud(cloud.points)).z, by_points.z, equal_nan=True)
    with pytest.raises(mzc.MzcError, match="vertices or points"):
        mzc.slice(object())


def test_meshes_go_to_trimesh_and_meshio_as_they_are():
    trimesh = pytest.importorskip("trimesh")
    mesh = mzc.triangulate(mzc.slice(mzc.sample("blob")))
    as_trimesh = mesh.to_trimesh()
    assert isinstance(as_trimesh, trimesh.Trimesh)
    assert np.array_equal(as_trimesh.vertices, mesh.points) and np.array_equal(as_trimesh.faces, mesh.triangles)
    as_meshio = mesh.to_meshio()
    assert np.array_equal(as_meshio.points, mesh.points)
    assert np.array_equal(as_meshio.cells_dict["triangle"], mesh.triangles)
    cloud = mzc.Mesh(np.eye(3), normals=np.eye(3))
    assert isinstance(cloud.to_trimesh(), trimesh.PointCloud)
    assert np.array_equal(cloud.to_meshio().point_data["normals"], np.eye(3))


def test_a_2d_array_is_a_unit_spaced_grid_and_every_codec_takes_its_options():
    z = np.add.outer(np.sin(np.linspace(0, 3, 40)), np.cos(np.linspace(0, 2, 50))) * 10
    z[5:8, 10:14] = np.nan
    for codec, options in [("dwt2d", {"max_error": 0.01}), ("dct", {"quality": 100}), ("poly", {"degree": 30}),
                           ("dft", {"quality": 50}), ("dwt", {"quality": 100, "wavelet": "db2"})]:
        back = mzc.decode(mzc.encode(z, codec, **options))
        assert back.shape == z.shape and np.array_equal(np.isnan(back.z), np.isnan(z)), codec
    assert np.nanmax(np.abs(mzc.decode(mzc.encode(z, max_error=0.01)).z - z)) <= 0.01


@pytest.mark.parametrize("call", [
    lambda: mzc.encode(np.zeros(5)),
    lambda: mzc.encode(np.zeros((4, 4)), codec="nope"),
    lambda: mzc.encode(np.zeros((4, 4)), "dct", quality=0),
    lambda: mzc.encode(np.zeros((4, 4)), "dct", wavelet="db2"),
    lambda: mzc.encode(np.zeros((4, 4)), rmse=1, max_error=1),
    lambda: mzc.decode(b"not mzc"),
    lambda: mzc.slice(42),
    lambda: mzc.sample("nope"),
    lambda: mzc.read("/no/such/file.obj"),
])
def test_bad_requests_raise_mzc_error_a_value_error_never_a_usage_message(call):
    with pytest.raises(mzc.MzcError) as caught:
        call()
    assert isinstance(caught.value, ValueError)
    assert "Usage" not in str(caught.value) and "--" not in str(caught.value)


def test_the_issue_line_with_trimesh_runs_in_a_fresh_interpreter():
    pytest.importorskip("trimesh")
    line = ("import mzc, trimesh; m = trimesh.creation.icosphere(); g = mzc.slice(m); "
            "b = mzc.encode(g, max_error=0.01); print(len(b), mzc.decode(b).shape)")
    result = subprocess.run([sys.executable, "-c", line], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    size, rows, cols = map(int, result.stdout.replace("(", " ").replace(")", " ").replace(",", " ").split())
    assert 0 < size < 20_000 and rows * cols > 1000
