"""Cutting planes: exact front-most heights, point clouds, PCA alignment, grid options and the CLI."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import Delaunay

from mzc.errors import MzcError
from mzc.formats import zgrid
from mzc.meshes import Mesh, read_mesh
from mzc.ops.delaunay import triangulate_point_cloud
from mzc.ops.raster import rasterize
from mzc.ops.slicing import pca_frame, slice_surface

from conftest import FACE_NAMES, face_path


def grid_mesh(xs, ys, height):
    """A triangle mesh over the lattice xs x ys with z = height(x, y), two triangles per cell."""
    x, y = np.meshgrid(xs, ys)
    points = np.column_stack([x.ravel(), y.ravel(), height(x, y).ravel()])
    return Mesh(points, lattice_triangles(len(ys), len(xs)))


def lattice_triangles(rows, cols, valid=None):
    """Triangles 1-2-3 and 2-3-4 of every lattice cell whose corners are valid (METHOD.md §2)."""
    index = np.arange(rows * cols).reshape(rows, cols)
    one, two, three, four = index[:-1, :-1], index[:-1, 1:], index[1:, :-1], index[1:, 1:]
    triangles = np.concatenate([np.stack([one, two, three], -1).reshape(-1, 3),
                                np.stack([two, four, three], -1).reshape(-1, 3)])
    if valid is not None:
        triangles = triangles[valid.ravel()[triangles].all(axis=1)]
    return triangles


def brute_force_heights(points, triangles, xs, ys):
    """Reference: for every node, test every triangle and keep the largest height (slow, obvious)."""
    z = np.full((len(ys), len(xs)), np.nan)
    a, b, c = (points[triangles[:, i]] for i in range(3))
    for r, y in enumerate(ys):
        for col, x in enumerate(xs):
            det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
            u = ((x - a[:, 0]) * (c[:, 1] - a[:, 1]) - (y - a[:, 1]) * (c[:, 0] - a[:, 0])) / det
            v = ((b[:, 0] - a[:, 0]) * (y - a[:, 1]) - (b[:, 1] - a[:, 1]) * (x - a[:, 0])) / det
            inside = (u >= -1e-12) & (v >= -1e-12) & (u + v <= 1 + 1e-12)
            if inside.any():
                heights = a[:, 2] + u * (b[:, 2] - a[:, 2]) + v * (c[:, 2] - a[:, 2])
                z[r, col] = heights[inside].max()
    return z


def paraboloid(x, y):
    return 4.0 - x ** 2 - y ** 2


# --------------------------------------------------------------------------- rasterize


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(-3, 3), st.floats(-3, 3), st.floats(-100, 100),
       st.integers(5, 60))
def test_planes_on_random_triangulations_slice_exactly(seed, a, b, c, count):
    rng = np.random.default_rng(seed)
    xy = np.vstack([[[0, 0], [1, 0], [0, 1], [1, 1]], rng.random((count, 2))])
    triangles = Delaunay(xy).simplices
    points = np.column_stack([xy, a * xy[:, 0] + b * xy[:, 1] + c])
    xs, ys = np.linspace(0, 1, 37), np.linspace(0, 1, 23)
    z = rasterize(points, triangles, xs, ys)
    assert not np.isnan(z).any(), "a node inside the hull fell through a crack"
    np.testing.assert_allclose(z, a * xs[None, :] + b * ys[:, None] + c, rtol=0, atol=1e-9)


def test_nodes_on_shared_vertices_and_edges_are_not_lost():
    lattice = np.linspace(-1, 1, 21)
    mesh = grid_mesh(lattice, lattice, lambda x, y: 0.5 * x - 0.25 * y)
    nodes = np.linspace(-1, 1, 81)  # every mesh vertex and edge midpoint is a node
    z = rasterize(mesh.points, mesh.triangles, nodes, nodes)
    assert not np.isnan(z).any()
    np.testing.assert_allclose(z, 0.5 * nodes[None, :] - 0.25 * nodes[:, None], atol=1e-12)


def test_paraboloid_nodes_on_mesh_vertices_return_the_vertex_heights():
    lattice = np.linspace(-1.5, 1.5, 31)
    mesh = grid_mesh(lattice, lattice, paraboloid)
    z = rasterize(mesh.points, mesh.triangles, lattice, lattice)
    np.testing.assert_allclose(z, paraboloid(lattice[None, :], lattice[:, None]), atol=1e-12)


def test_paraboloid_between_vertices_matches_brute_force():
    rng = np.random.default_rng(7)
    xy = np.vstack([[[-1, -1], [1, -1], [-1, 1], [1, 1]], rng.uniform(-1, 1, (150, 2))])
    points = np.column_stack([xy, paraboloid(xy[:, 0], xy[:, 1])])
    triangles = Delaunay(xy).simplices
    xs, ys = np.linspace(-1, 1, 29), np.linspace(-1, 1, 17)
    expected = brute_force_heights(points, triangles, xs, ys)
    got = rasterize(points, triangles, xs, ys)
    np.testing.assert_allclose(got, expected, atol=1e-9)
    assert np.abs(got - paraboloid(xs[None, :], ys[:, None])).max() > 1e-3  # truly piecewise linear


def test_nodes_over_a_hole_are_nan():
    lattice = np.linspace(-1, 1, 41)
    x, y = np.meshgrid(lattice, lattice)
    outside_hole = np.hypot(x, y) > 0.5
    mesh = grid_mesh(lattice, lattice, paraboloid)
    triangles = lattice_triangles(41, 41, outside_hole)
    nodes = np.linspace(-1, 1, 53)
    z = rasterize(mesh.points, triangles, nodes, nodes)
    np.testing.assert_allclose(z, brute_force_heights(mesh.points, triangles, nodes, nodes), atol=1e-9)
    radius = np.hypot(nodes[None, :], nodes[:, None])
    assert np.isnan(z[radius < 0.4]).all() and not np.isnan(z[radius > 0.6]).any()


@pytest.mark.parametrize("front_first", [True, False])
def test_front_most_layer_wins(front_first):
    lattice = np.linspace(0, 1, 5)
    back = grid_mesh(lattice, lattice, lambda x, y: x + y)
    front = grid_mesh(lattice[::-1], lattice, lambda x, y: 10 - x)  # other triangles, higher
    layers = [front, back] if front_first else [back, front]
    points = np.vstack([layers[0].points, layers[1].points])
    triangles = np.vstack([layers[0].triangles, layers[1].triangles + len(layers[0].points)])
    nodes = np.linspace(0, 1, 11)
    z = rasterize(points, triangles, nodes, nodes)
    np.testing.assert_allclose(z, np.broadcast_to(10 - nodes, (11, 11)), atol=1e-12)


def test_edge_on_triangles_are_skipped_and_misses_are_nan():
    points = np.array([[0, 0, 0], [1, 0, 1], [1, 0, 5.0], [5, 5, 0], [6, 5, 0], [5, 6, 0]])
    z = rasterize(points, np.array([[0, 1, 2], [3, 4, 5]]), np.arange(0, 2.0), np.arange(0, 2.0))
    assert np.isnan(z).all()


def test_the_rasterizer_refuses_indices_and_buffers_that_do_not_fit():
    """The C kernel checks every buffer's size, corner index and owner before it reads or
    writes: a bad one is refused and nothing is written."""
    from mzc.ops import _raster
    from mzc.ops.raster import heights_on_triangles

    points, triangle, nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 2]]), np.arange(3.0)
    for corner in (3, -1):
        with pytest.raises(MzcError, match="out of range"):
            rasterize(points, [[0, 1, 2], [0, corner, 1]], nodes, nodes)
    for arguments in [(points.ravel()[:7], triangle, nodes, nodes), (points, triangle.ravel()[:2], nodes, nodes)]:
        best = np.full(9, -np.inf)
        assert _raster.front_most(*arguments, 0.0, best) == 1 and (best == -np.inf).all()
    assert _raster.front_most(points, triangle, nodes, nodes, 0.0, np.full(8, -np.inf)) == 1
    for owner in (1, -1):
        with pytest.raises(MzcError, match="out of range"):
            heights_on_triangles(points[triangle], np.array([0, owner]), np.zeros(2), np.zeros(2))


# --------------------------------------------------------------------------- point clouds


def paraboloid_samples(count, seed=3):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-1, 1, (count, 2))
    return np.column_stack([xy, paraboloid(xy[:, 0], xy[:, 1])])


def test_point_cloud_slices_like_the_surface_it_samples():
    grid = slice_surface(Mesh(paraboloid_samples(20000)), d1=0.05, d2=0.05)
    x, y = np.meshgrid(grid.xs(), grid.ys())
    inner = (np.abs(x) < 0.9) & (np.abs(y) < 0.9)
    assert not np.isnan(grid.z[inner]).any()
    error = np.abs(grid.z - paraboloid(x, y))[inner]
    assert error.max() < 5e-3  # linear interpolation over ~0.015-wide triangles, curvature 2
    assert error.max() > 0     # it is an interpolation, not the formula


def test_point_cloud_plane_is_exact():
    rng = np.random.default_rng(4)
    xy = rng.uniform(0, 10, (3000, 2))
    # steeper than 60 degrees: auto would look along y; the heights are checked in the input frame
    grid = slice_surface(Mesh(np.column_stack([xy, 0.3 * xy[:, 0] - 2 * xy[:, 1] + 1])), d1=0.5, d2=0.05,
                         view="+z")
    x, y = np.meshgrid(grid.xs(), grid.ys())
    valid = grid.valid
    assert valid.mean() > 0.9
    np.testing.assert_allclose(grid.z[valid], (0.3 * x - 2 * y + 1)[valid], atol=1e-9)


def test_delaunay_long_edges_bridge_no_gaps():
    lattice = np.linspace(-1, 1, 41)
    x, y = np.meshgrid(lattice, lattice)
    keep = (np.hypot(x, y) > 0.5).ravel()
    xy = np.column_stack([x.ravel(), y.ravel()])[keep]
    jitter = np.random.default_rng(5).uniform(-0.01, 0.01, xy.shape)
    triangles = triangulate_point_cloud(xy + jitter)
    assert len(triangles) < len(Delaunay(xy + jitter).simplices)
    points = np.column_stack([xy + jitter, np.zeros(len(xy))])
    nodes = np.linspace(-0.95, 0.95, 39)
    z = rasterize(points, triangles, nodes, nodes)
    radius = np.hypot(nodes[None, :], nodes[:, None])
    assert np.isnan(z[radius < 0.4]).all() and not np.isnan(z[radius > 0.6]).any()


def test_degenerate_point_clouds_are_refused():
    with pytest.raises(MzcError, match="at least 3"):
        triangulate_point_cloud(np.zeros((2, 2)))
    with pytest.raises(MzcError, match="degenerate"):
        triangulate_point_cloud(np.column_stack([np.arange(5.0), np.arange(5.0)]))


# --------------------------------------------------------------------------- PCA alignment


def random_rotation(seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def test_pca_frame_is_a_proper_rotation_facing_the_surface():
    mesh = grid_mesh(np.linspace(-1, 1, 11), np.linspace(-2, 2, 21), lambda x, y: 0.1 * x * y)
    rotation, shift = pca_frame(mesh.points, mesh.triangles)
    np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1)
    np.testing.assert_allclose(np.abs(rotation[:, 2]), [0, 0, 1], atol=1e-9)  # least spread: z
    np.testing.assert_allclose(rotation[:, 1], [0, 1, 0], atol=1e-9)          # most spread: y
    np.testing.assert_allclose(shift, mesh.points.mean(axis=0), atol=1e-12)
    flipped, _ = pca_frame(mesh.points, mesh.triangles[:, ::-1])
    assert flipped[:, 2] @ rotation[:, 2] == pytest.approx(-1)


@pytest.mark.parametrize("seed", range(4))
def test_pca_recovers_a_rotated_plane(seed):
    mesh = grid_mesh(np.linspace(-1, 1, 21), np.linspace(-2, 2, 41), lambda x, y: 0 * x)
    rotation = random_rotation(seed)
    moved = Mesh(mesh.points @ rotation.T + [5, -3, 2], mesh.triangles)
    grid = slice_surface(moved, rows=30, align="pca")
    valid = grid.valid
    np.testing.assert_allclose(grid.z[valid], 0, atol=1e-9)
    assert grid.ys()[-1] - grid.ys()[0] == pytest.approx(4, rel=1e-6)  # y runs along the long side
    back = grid.to_input_frame(grid.node_points()[valid])
    on_plane = (back - [5, -3, 2]) @ rotation  # coordinates in the plane's own frame
    np.testing.assert_allclose(on_plane[:, 2], 0, atol=1e-9)


def test_pca_recovers_a_rotated_paraboloid():
    lattice = np.linspace(-1, 1, 61)
    mesh = grid_mesh(lattice, 1.5 * lattice, lambda x, y: 0.2 * paraboloid(x, y))
    rotation = random_rotation(11)
    moved = Mesh(mesh.points @ rotation.T + [1, 2, 3], mesh.triangles)
    grid = slice_surface(moved, d1=0.05, d2=0.05, align="pca")
    back = grid.to_input_frame(grid.node_points()[grid.valid])
    original = (back - [1, 2, 3]) @ rotation
    assert grid.valid.sum() > 1000
    np.testing.assert_allclose(original[:, 2], 0.2 * paraboloid(original[:, 0], original[:, 1]),
                               atol=2e-3)  # piecewise-linear surface vs its formula
    assert grid.transform[:, 2] @ rotation[:, 2] > 0.99  # faces the way the surface faced


def test_pca_on_point_cloud_keeps_input_z_direction():
    cloud = paraboloid_samples(4000)
    cloud[:, 2] *= 0.1
    rotation, _ = pca_frame(cloud, np.empty((0, 3)))
    assert rotation[2, 2] > 0.99


# --------------------------------------------------------------------------- grid options


@pytest.fixture
def rectangle():
    return grid_mesh(np.linspace(0, 20, 11), np.linspace(0, 71, 11), lambda x, y: x * 0 + 1)


def test_default_grid_is_the_lattice_the_vertices_lie_on(rectangle):
    grid = slice_surface(rectangle)
    assert grid.shape == (11, 11) and (grid.d1, grid.d2) == pytest.approx((7.1, 2))
    assert slice_surface(rectangle, d1=7.1001).d1 == pytest.approx(7.1)      # a hair off snaps to it


@pytest.mark.parametrize("count", [40_000, 2_000])
def test_default_spacing_elsewhere_is_half_the_median_edge(count):
    """... or 1/200 of the longest side where that is finer (a sparse cloud, a CAD part), to 3
    significant digits."""
    rng = np.random.default_rng(8)
    xy = rng.uniform(0, 10, (count, 2))
    cloud = Mesh(np.column_stack([xy, 0.1 * np.sin(xy[:, 0])]))
    corners = cloud.points[triangulate_point_cloud(xy)]
    median = np.median(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2))
    grid = slice_surface(cloud, view="+z")
    assert grid.d1 == grid.d2 == float(f"{min(median / 2, np.ptp(cloud.points, axis=0).max() / 200):.3g}")
    x, y = grid.xs(), grid.ys()
    assert xy[:, 0].max() - x[-1] < grid.d2 and xy[:, 1].max() - y[-1] < grid.d1


def test_thesis_grid_option(rectangle):
    grid = slice_surface(rectangle, thesis_grid=True)
    assert grid.shape == (72, 201)
    assert grid.d1 == pytest.approx(1) and grid.d2 == pytest.approx(0.1)
    assert grid.origin == (0, 0) and grid.units is None
    assert not np.isnan(grid.z).any()


@pytest.mark.parametrize("options,shape,spacings", [
    ({"d1": 2}, (36, 11), (2, 2)),          # d2: the vertices' own lattice step
    ({"d1": 2, "d2": 1}, (36, 21), (2, 1)),
    ({"rows": 11, "cols": 5}, (11, 5), (7.1, 5)),
    ({"rows": 36}, (36, 10), (71 / 35, 71 / 35)),
    ({"d1": 10, "cols": 3}, (8, 3), (10, 10)),
    ({"d1": 2, "thesis_grid": True}, (36, 101), (2, 0.2)),
])
def test_spacing_and_count_options(rectangle, options, shape, spacings):
    grid = slice_surface(rectangle, units="mm", **options)
    assert grid.shape == shape
    assert (grid.d1, grid.d2) == pytest.approx(spacings)
    assert grid.units == "mm"


@pytest.mark.parametrize("options,message", [
    ({"d1": 1, "rows": 5}, "not both"),
    ({"d2": 1, "cols": 5}, "not both"),
    ({"d1": -1}, "positive"),
    ({"d1": 1, "d2": 0}, "positive"),
    ({"rows": 1}, "at least 2"),
    ({"d1": 1e-6}, "too large"),
    ({"align": "best"}, "unknown alignment"),
])
def test_bad_grid_options_are_refused(rectangle, options, message):
    with pytest.raises(MzcError, match=message):
        slice_surface(rectangle, **options)


def test_surface_seen_edge_on_is_refused():
    wall = Mesh([[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 1e-20, 1]], [[0, 1, 2], [1, 3, 2]])
    with pytest.raises(MzcError, match="edge-on"):
        slice_surface(wall, d1=0.1, view="+z")
    grid = slice_surface(wall, d1=0.1)                 # auto looks at it along y
    assert grid.valid.all() and abs(grid.transform[1, 2]) == 1


# --------------------------------------------------------------------------- real faces


@pytest.mark.parametrize("name", [*FACE_NAMES, "example.obj"] if FACE_NAMES else ["f18.ply"])
def test_every_face_slices_at_the_thesis_grid(name):
    grid = slice_surface(read_mesh(face_path(name)), d1=3, d2=0.25, projection="planar")
    assert 60 <= grid.shape[0] <= 80 and 600 <= grid.shape[1] <= 750
    assert 0.5 < grid.valid.mean() < 0.95
    assert np.nanmax(grid.z) > 50  # the nose tip looks toward +z


def test_valid_nodes_cover_the_projected_area_of_the_face():
    mesh = read_mesh(face_path("example.obj"))
    grid = slice_surface(mesh, d1=0.5, d2=0.5, projection="planar")
    a, b, c = (mesh.points[mesh.triangles[:, i]] for i in range(3))
    normal_z = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    front_area = normal_z[normal_z > 0].sum() / 2  # xy area seen from +z, folds excluded
    assert grid.valid.sum() * 0.25 == pytest.approx(front_area, rel=0.03)


def test_f18_sliced_at_half_a_millimetre_matches_the_mesh(f18):
    mesh = read_mesh(f18)
    grid = slice_surface(mesh, d1=0.5, d2=0.5, projection="planar")
    rows, cols = grid.shape
    nodes = grid.node_points().reshape(-1, 3)
    rebuilt = lattice_triangles(rows, cols, grid.valid)
    fine_x = np.arange(grid.xs()[0], grid.xs()[-1], 0.1)
    fine_y = np.arange(grid.ys()[0], grid.ys()[-1], 0.1)
    original = rasterize(mesh.points, mesh.triangles, fine_x, fine_y)
    from_grid = rasterize(np.nan_to_num(nodes), rebuilt, fine_x, fine_y)
    dz = np.abs(original - from_grid)[~np.isnan(original) & ~np.isnan(from_grid)]
    assert len(dz) > 0.5 * original.size
    assert np.median(dz) < 0.01 and np.percentile(dz, 95) < 0.1


# --------------------------------------------------------------------------- command line


def write_obj(path, mesh):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.points.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.triangles]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cli_slices_a_mesh_to_a_zgrid(tmp_path, mzc):
    lattice = np.linspace(0, 4, 9)
    source = write_obj(tmp_path / "plane.obj", grid_mesh(lattice, lattice, lambda x, y: x - y))
    result = mzc("slice", source, "-o", tmp_path / "out.zg", "--d1", "0.5", "--units", "mm")
    assert result.returncode == 0, result.stderr
    grid = zgrid.read((tmp_path / "out.zg").read_bytes(), "out.zg")
    assert grid.shape == (9, 9) and grid.units == "mm"                 # d2: the vertices' own 0.5
    np.testing.assert_allclose(grid.z, grid.xs()[None, :] - grid.ys()[:, None], atol=1e-12)


def test_cli_reads_a_point_cloud_from_stdin(mzc):
    cloud = paraboloid_samples(2000)
    text = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in cloud.tolist()).encode()
    result = mzc("slice", "--rows", "11", "--cols", "11", "--plain", "--precision", "3", input=text)
    assert result.returncode == 0, result.stderr
    grid = zgrid.read(result.stdout, "-")
    x, y = np.meshgrid(grid.xs(), grid.ys())
    inner = (np.abs(x) < 0.9) & (np.abs(y) < 0.9)
    np.testing.assert_allclose(grid.z[inner], paraboloid(x, y)[inner], atol=0.02)


def test_cli_vertex_only_ply(tmp_path, mzc):
    cloud = paraboloid_samples(3000)
    header = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(cloud)}\n"
    header += "property double x\nproperty double y\nproperty double z\nend_header\n"
    path = tmp_path / "cloud.ply"
    path.write_bytes(header.encode() + cloud.astype("<f8").tobytes())
    result = mzc("slice", path, "--d1", "0.1", "--align", "pca")
    assert result.returncode == 0, result.stderr
    grid = zgrid.read(result.stdout, "-")
    assert grid.valid.mean() > 0.4


def test_cli_thesis_grid_on_f18(f18, mzc, tmp_path):
    result = mzc("slice", f18, "--projection", "planar", "--d1", "3", "--d2", "0.25", "-o", tmp_path / "f18.zg")
    assert result.returncode == 0, result.stderr
    grid = zgrid.read((tmp_path / "f18.zg").read_bytes(), "f18.zg")
    assert grid.shape == (70, 671)


@pytest.mark.parametrize("args", [("--d1", "1", "--rows", "5"), ("--d2", "1", "--cols", "5"),
                                  ("--align", "best"), ("--rows", "many")])
def test_cli_usage_errors_exit_2(tmp_path, mzc, args):
    result = mzc("slice", tmp_path / "any.obj", *args)
    assert result.returncode == 2
    assert b"Traceback" not in result.stderr


@pytest.mark.parametrize("content,options,message", [
    (None, (), b"no such file"),
    (b"\x00\x13garbage\xff" * 50, (), b"binary data"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", (), b":4: face refers to a vertex"),
    (b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", (), b"NaN"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ("--d1", "0"), b"d1: spacing must be a positive number"),
    (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ("--d1", "1e-7"), b"too large"),
])
def test_cli_bad_input_exits_1_with_one_line(tmp_path, mzc, content, options, message):
    path = tmp_path / "in.obj"
    if content is not None:
        path.write_bytes(content)
    result = mzc("slice", path, *options, "-o", tmp_path / "out.zg")
    assert result.returncode == 1
    assert len(result.stderr.splitlines()) == 1 and message in result.stderr
    assert result.stderr.startswith(b"mzc: ")
    assert not (tmp_path / "out.zg").exists()


def test_cli_refuses_to_overwrite_its_input(tmp_path, mzc):
    path = write_obj(tmp_path / "in.obj", grid_mesh(np.arange(3.0), np.arange(3.0), lambda x, y: x))
    before = path.read_bytes()
    result = mzc("slice", path, "-o", path)
    assert result.returncode == 1 and b"overwrite" in result.stderr
    assert path.read_bytes() == before
