"""Central cutting surfaces: node geometry, exact ray casting, and the ``auto`` rule on real and generated surfaces."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc import elementary, projections, samples
from mzc.errors import MzcError
from mzc.measure.metrics import surface_distance, triangle_areas
from mzc.meshes import Mesh, read_mesh
from mzc.ops.rays import candidate_boxes, cast
from mzc.ops.slicing import slice_surface
from mzc.ops.triangulation import grid_to_mesh
from mzc.samples import BLOB_CENTRE, blob, tube

from conftest import FACE_NAMES, face_path

CENTRAL = ["cylindrical", "spherical"]


# --------------------------------------------------------------------------- geometry


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(CENTRAL), st.floats(0.5, 500), st.floats(-3.1, 3.1), st.floats(-1.5, 1.5),
       st.floats(0.01, 1000))
def test_nodes_and_points_are_inverse(projection, radius, azimuth, elevation, value):
    u, v = radius * azimuth, (radius * elevation if projection == "spherical" else 40 * elevation)
    point = projections.to_points(projection, radius, u, v, value)
    np.testing.assert_allclose(projections.to_nodes(projection, radius, point), [u, v, value],
                               rtol=1e-9, atol=1e-9 * max(radius, value))


@pytest.mark.parametrize("projection", CENTRAL)
def test_a_node_lies_on_its_ray_at_its_value(projection):
    u, v = np.meshgrid(np.linspace(-150, 150, 7), np.linspace(-70, 70, 5))
    value = 80 + u ** 2 / 100
    origins = projections.ray_origins(projection, v)
    directions = projections.ray_directions(projection, 100.0, u, v)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1)
    np.testing.assert_allclose(origins + value[..., None] * directions,
                               projections.to_points(projection, 100.0, u, v, value), atol=1e-12)


@pytest.mark.parametrize("projection", CENTRAL)
def test_the_metric_is_the_length_of_a_step_on_a_surface_of_constant_value(projection):
    radius, value, u, v, step = 100.0, 130.0, 20.0, 35.0, 1e-6
    at = projections.to_points(projection, radius, u, v, value)
    along_u = np.linalg.norm(projections.to_points(projection, radius, u + step, v, value) - at) / step
    along_v = np.linalg.norm(projections.to_points(projection, radius, u, v + step, value) - at) / step
    np.testing.assert_allclose(projections.metric(projection, radius, v, value), (along_u, along_v), rtol=1e-6)


# --------------------------------------------------------------------------- casting


def brute_force_rays(points, triangles, projection, radius, xs, ys):
    """Reference: every node's ray against every triangle (Moller-Trumbore), the farthest hit kept."""
    a, b, c = (points[triangles[:, i]] for i in range(3))
    out = np.full((len(ys), len(xs)), np.nan)
    for r, v in enumerate(ys):
        for k, u in enumerate(xs):
            origin = projections.ray_origins(projection, np.array(v))
            direction = projections.ray_directions(projection, radius, u, v)
            e1, e2 = b - a, c - a
            p = np.cross(direction, e2)
            det = np.einsum("ij,ij->i", e1, p)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                s = origin - a
                bu = np.einsum("ij,ij->i", s, p) / det
                q = np.cross(s, e1)
                bv = q @ direction / det
                t = np.einsum("ij,ij->i", e2, q) / det
                hit = (np.abs(det) > 1e-12) & (bu >= -1e-9) & (bv >= -1e-9) & (bu + bv <= 1 + 1e-9) & (t > 0)
            if hit.any():
                out[r, k] = t[hit].max()
    return out


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(CENTRAL))
def test_cast_matches_brute_force_on_random_triangles(seed, projection):
    """Random triangles all round the centre (across the seam, around the axis, near the poles)."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(30, 3)) * [40, 25, 40]
    points = (centres[:, None, :] + rng.normal(size=(30, 3, 3)) * 12).reshape(-1, 3)
    triangles = np.arange(90).reshape(30, 3)
    radius = 40.0
    xs = -np.pi * radius + 2 * np.pi * radius / 24 * np.arange(24)
    top = np.pi / 2 * radius if projection == "spherical" else 60.0
    ys = np.linspace(-top, top, 13)
    got = cast(points, triangles, projection, radius, xs, ys)
    expected = brute_force_rays(points, triangles, projection, radius, xs, ys)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(expected))
    np.testing.assert_allclose(got, expected, rtol=1e-9, equal_nan=True)


def sum_of_three(products):
    """Each row's sum of three in the caster's order, (p0 + p2) + p1 (_raster.c's dot)."""
    return (products[:, 0] + products[:, 2]) + products[:, 1]


def same_arithmetic_rays(points, triangles, projection, radius, xs, ys):
    """Reference: every node's ray against every triangle, no candidate boxes, in numpy's arithmetic as
    the caster's: the barycentric weights D . (b x c) - v D . (y x (c - b)) and their cyclic shifts
    (np.cross, sum_of_three) over D . n, a hit when all are >= -1e-9 and t = (n . a - v n.y) / (D . n) > 0."""
    rows, cols, owner = (index.ravel() for index in np.meshgrid(np.arange(len(ys)), np.arange(len(xs)),
                                                                np.arange(len(triangles)), indexing="ij"))
    a, b, c = (points[triangles[owner, i]] for i in range(3))
    azimuth, elevation = xs / radius, ys / radius
    ring, rise = ((elementary.cos(elevation), elementary.sin(elevation)) if projection == "spherical"
                  else (np.ones(len(ys)), np.zeros(len(ys))))
    direction = np.stack([ring[rows] * elementary.sin(azimuth)[cols], rise[rows],
                          ring[rows] * elementary.cos(azimuth)[cols]], axis=1)
    v = ys[rows] if projection == "cylindrical" else np.zeros(len(rows))
    axis = np.array([0.0, 1.0, 0.0])
    normal = np.cross(b - a, c - a)
    along = lambda vectors: sum_of_three(direction * vectors)  # noqa: E731
    weights = [along(np.cross(p, q)) - (v * along(np.cross(axis, q - p)) if projection == "cylindrical" else 0)
               for p, q in [(b, c), (c, a), (a, b)]]
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = 1.0 / along(normal)
        t = (sum_of_three(normal * a) - (v * normal[:, 1] if projection == "cylindrical" else 0)) * scale
        hit = np.isfinite(scale) & (t > 0) & np.all([weight * scale >= -1e-9 for weight in weights], axis=0)
    best = np.full(len(ys) * len(xs), -np.inf)
    np.maximum.at(best, rows[hit] * len(xs) + cols[hit], t[hit])
    return np.where(best == -np.inf, np.nan, best).reshape(len(ys), len(xs))


def at_azimuths(azimuth, distance, height):
    """Points at these azimuths (radians from +z towards +x), distances from the axis and heights."""
    return np.stack([distance * np.sin(azimuth), height, distance * np.cos(azimuth)], axis=-1)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(CENTRAL), st.floats(-np.pi, np.pi), st.integers(8, 24))
def test_the_caster_equals_every_ray_against_every_triangle(seed, projection, start, columns):
    """The C caster gives the same bits as every node tested against every triangle: random triangles
    all round the centre, triangles around the axis and across the seam of a window of azimuths that
    starts anywhere and may not close the turn."""
    rng = np.random.default_rng(seed)
    radius = 40.0
    random = (rng.normal(size=(20, 1, 3)) * [40, 25, 40] + rng.normal(size=(20, 3, 3)) * 12).reshape(-1, 3)
    turns = rng.uniform(0, 2 * np.pi / 3, 6)[:, None] + [0, 2 * np.pi / 3, 4 * np.pi / 3]
    around = at_azimuths(turns, rng.uniform(3, 30, (6, 3)), rng.uniform(-30, 30, (6, 1)) + rng.normal(size=(6, 3)) * 5)
    sides = rng.uniform(0.01, 0.3, (6, 3)) * [1, -1, 1] * np.sign(rng.normal(size=(6, 1)))
    across = at_azimuths(start + sides, rng.uniform(10, 60, (6, 3)), rng.uniform(-30, 30, (6, 3)))
    points = np.concatenate([random, around.reshape(-1, 3), across.reshape(-1, 3)])
    triangles = np.arange(len(points)).reshape(-1, 3)
    step = 2 * np.pi * radius / 24
    xs = radius * start + step * np.arange(columns)
    top = np.pi / 2 * radius if projection == "spherical" else 50.0
    ys = np.linspace(-top, top, 13)
    boxes, owners = candidate_boxes(points, triangles, projection, radius, xs[0])
    assert np.isinf(boxes[:, 0]).any() and len(owners) > len(triangles)   # around the axis, across the seam
    got = cast(points, triangles, projection, radius, xs, ys)
    assert np.isfinite(got).any()
    np.testing.assert_array_equal(got, same_arithmetic_rays(points, triangles, projection, radius, xs, ys))


def test_the_caster_refuses_indices_and_buffers_that_do_not_fit():
    """The kernel checks every buffer's size, corner index and box's triangle before it reads or
    writes: a bad one is refused and nothing is written."""
    from mzc.ops import _raster
    from mzc.ops.raster import checked

    points, triangle = np.array([[0, 0, 5], [5, 0, 5], [0, 5, 5.0]]), np.array([[0, 1, 2]])
    boxes, nodes = np.array([[[-9, 9], [-9, 9.0]]]), np.arange(-1, 2.0)
    factors = np.array([np.sin(nodes / 10), np.cos(nodes / 10)])
    good = [points, triangle, np.array([0]), boxes, nodes, nodes, factors, factors[::-1].copy()]
    best = np.full(9, -np.inf)
    assert _raster.farthest(*good, False, 1e-9, best) == 0 and np.isfinite(best).any()
    best = np.full(9, -np.inf)
    for bad in ([[0, 3, 2]], [[0, -1, 2]]):
        with pytest.raises(MzcError, match="out of range"):
            checked(_raster.farthest(points, np.array(bad), *good[2:], False, 1e-9, best))
    for owner in (1, -1):
        with pytest.raises(MzcError, match="out of range"):
            checked(_raster.farthest(*good[:2], np.array([owner]), *good[3:], True, 1e-9, best))
    for i, argument in enumerate(good):
        assert _raster.farthest(*good[:i], argument.ravel()[:-1], *good[i + 1:], False, 1e-9, best) == 1
    assert _raster.farthest(*good, False, 1e-9, best[:8].copy()) == 1
    assert (best == -np.inf).all()


def test_a_triangle_around_the_pole_covers_the_pole_row_and_the_rows_below_it():
    radius = 10.0
    points = np.array([[-5.0, 20, -3], [5.0, 20, -3], [0.0, 20, 6]])
    ys = np.linspace(0, np.pi / 2 * radius, 21)
    xs = -np.pi * radius + 2 * np.pi * radius / 16 * np.arange(16)
    got = cast(points, np.array([[0, 1, 2]]), "spherical", radius, xs, ys)
    expected = brute_force_rays(points, np.array([[0, 1, 2]]), "spherical", radius, xs, ys)
    assert np.isfinite(got[-1]).all() and np.isfinite(got[-2]).sum() >= 8   # the pole row, most of the next
    np.testing.assert_allclose(got, expected, rtol=1e-9, equal_nan=True)


# --------------------------------------------------------------------------- slicing and auto


def test_a_sphere_is_sliced_at_its_radius_from_its_centre():
    mesh = blob(4)
    mesh = Mesh(BLOB_CENTRE + 40 * (mesh.points - BLOB_CENTRE) / np.linalg.norm(mesh.points - BLOB_CENTRE,
                                                                                axis=1, keepdims=True),
                mesh.triangles)
    grid = slice_surface(mesh, d1=2, d2=2, projection="spherical", center=BLOB_CENTRE)
    a, b, c = (mesh.points[mesh.triangles[:, i]] - BLOB_CENTRE for i in range(3))
    normal = np.cross(b - a, c - a)
    nearest_plane = np.min(np.abs(np.einsum("ij,ij->i", normal, a)) / np.linalg.norm(normal, axis=1))
    assert grid.valid.all() and np.nanmax(grid.z) <= 40 + 1e-9 and np.nanmin(grid.z) >= nearest_plane - 1e-9


def test_auto_chooses_a_spherical_grid_for_a_closed_blob_and_a_cylinder_for_a_tube():
    ball, pipe = slice_surface(blob(), d1=2, d2=2), slice_surface(tube(), d1=2, d2=2)
    assert ball.projection == "spherical" and ball.periodic and ball.pole_rows()[[0, -1]].all()
    assert pipe.projection == "cylindrical" and pipe.periodic and not pipe.pole_rows().any()
    np.testing.assert_allclose(np.abs(pipe.transform[:, 1]), [0, 1, 0], atol=1e-9)   # the tube's axis


@pytest.mark.parametrize("name", ["jacksboro", "topobathy", "bump"])
def test_auto_keeps_the_terrains_on_the_thesis_planes_node_for_node(name):
    mesh = grid_to_mesh(getattr(samples, name)())
    auto, planar = slice_surface(mesh, d1=None, rows=60), slice_surface(mesh, rows=60, projection="planar")
    assert auto.projection == "planar"
    np.testing.assert_array_equal(auto.z, planar.z)
    np.testing.assert_array_equal(auto.transform, planar.transform)


@pytest.mark.parametrize("name", [*FACE_NAMES, "example.obj"] if FACE_NAMES else ["f18.ply"])
def test_auto_chooses_a_central_projection_for_every_face(name):
    mesh = read_mesh(face_path(name))
    grid = slice_surface(mesh, d1=2, d2=2)
    assert grid.projection == "spherical" and not grid.periodic
    centre = grid.transform[:, 3]
    assert centre[2] < mesh.points[:, 2].min()   # behind the face, which looks towards +z
    np.testing.assert_allclose(grid.transform[:, 1], [0, 1, 0], atol=1e-12)   # the axis is the face's up


def test_f18_default_slice_at_half_a_millimetre_is_within_0_03_mm_over_the_whole_surface(f18):
    mesh = read_mesh(f18)
    cut = grid_to_mesh(slice_surface(mesh, d1=0.5, d2=0.5))
    kept = cut.triangles[triangle_areas(cut.points, cut.triangles) > 0]
    distance = surface_distance((mesh.points, mesh.triangles), (cut.points, kept), samples=30_000)
    assert distance["rms"] <= 0.03
    planar = grid_to_mesh(slice_surface(mesh, d1=0.5, d2=0.5, projection="planar"))
    planar_distance = surface_distance((mesh.points, mesh.triangles), (planar.points, planar.triangles), samples=30_000)
    assert planar_distance["rms"] > 20 * distance["rms"]


def test_given_centre_and_axis_are_kept_and_a_cylinder_axis_is_a_line_through_the_centre():
    mesh = tube()
    grid = slice_surface(mesh, d1=2, d2=2, projection="cylindrical", center=(0, 50, 0), axis=(0, 2, 0))
    np.testing.assert_allclose(grid.transform[:, 3], [0, 50, 0])
    np.testing.assert_allclose(grid.transform[:, 1], [0, 1, 0])
    azimuth, height = np.meshgrid(grid.xs() / grid.radius, grid.ys() + 50)
    inside = (np.abs(height) < 99) & grid.valid
    # chords of a 240-gon of 30 mm radius lie up to 30 (1 - cos(pi / 240)) = 0.0026 mm inside it
    assert np.abs(grid.z - tube_distance(grid, azimuth, height))[inside].max() < 0.05


def tube_distance(grid, azimuth, height):
    """The tube's own radius at the grid's azimuths (the grid's azimuth 0 may be turned about y)."""
    from mzc.samples import tube_radius

    front = grid.transform[:, 2]
    turn = np.arctan2(front[0], front[2])
    return tube_radius(azimuth + turn, height)


@pytest.mark.parametrize("options, message", [
    (dict(projection="planar", center=(0, 0, 0)), "central projection"),
    (dict(projection="spherical", axis=(0, 0, 0)), "non-zero"),
    (dict(projection="spherical", center=(0, np.inf, 0)), "finite"),
])
def test_bad_projection_options_are_refused(options, message):
    with pytest.raises(MzcError, match=message):
        slice_surface(tube(), d1=5, **options)


def test_a_point_cloud_can_be_cut_by_a_named_central_projection():
    mesh = tube(around=120, along=60)
    grid = slice_surface(Mesh(mesh.points), d1=4, d2=4, projection="cylindrical", center=(0, 0, 0))
    assert grid.projection == "cylindrical" and grid.valid.mean() > 0.9
    assert slice_surface(Mesh(mesh.points), d1=4).projection == "planar"   # auto needs triangles to score


# --------------------------------------------------------------------------- command line


def write_obj(path, mesh):
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.points.tolist()]
    path.write_text("\n".join(lines + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.triangles]) + "\n")
    return path


def test_cli_slice_takes_the_projection_centre_and_axis(mzc, tmp_path):
    obj = write_obj(tmp_path / "tube.obj", tube(around=96, along=40))
    text = mzc("slice", obj, "--projection", "cylindrical", "--center", "0", "0", "0", "--axis", "0", "1", "0",
               "--d1", "5", "--d2", "4", check=True).stdout
    grid = read_any_grid(text)
    assert grid.projection == "cylindrical" and grid.periodic
    np.testing.assert_allclose(grid.transform[:, 1], [0, 1, 0])
    planar = read_any_grid(mzc("slice", obj, "--projection", "planar", "--d1", "5", check=True).stdout)
    assert planar.projection == "planar"


def read_any_grid(data):
    from mzc.formats import read_any

    return read_any(data, "test")


@pytest.mark.parametrize("args, message", [
    (("--projection", "planar", "--center", "0", "0", "0"), "central projection"),
    (("--projection", "spherical", "--axis", "0", "0", "0"), "axis: must be a non-zero 3-vector"),
    (("--projection", "conical"), "--projection: 'conical' is not one of"),
    (("--center", "0", "nan-ish", "0"), "--center: 'nan-ish' is not a valid float"),
])
def test_cli_bad_projection_options_are_one_line_errors(mzc, tmp_path, args, message):
    obj = write_obj(tmp_path / "tube.obj", tube(around=48, along=20))
    out = tmp_path / "out.zg"
    result = mzc("slice", obj, *args, "--d1", "5", "-o", out)
    errors = result.stderr.decode().strip().splitlines()
    assert message in errors[-1] and b"Traceback" not in result.stderr and not out.exists()
    # bad values exit 1, options click cannot parse are usage errors (exit 2): one line either way
    assert result.returncode in (1, 2) and len(errors) == 1


def test_diff_of_central_grids_measures_in_space(mzc, tmp_path):
    obj = write_obj(tmp_path / "tube.obj", tube(around=96, along=40))
    grid = tmp_path / "tube.zg"
    mzc("slice", obj, "--d1", "5", "--d2", "4", "-o", grid, check=True)
    packed = tmp_path / "tube.mzw2"
    mzc("encode", "--dwt2d", "--max-error", "0.1", grid, "-o", packed, check=True)
    import json

    report = json.loads(mzc("diff", grid, packed, "--json", "--samples", "2000", check=True).stdout)
    assert report["grid_max"] <= 0.1 + 1e-9                  # along the rays, the bound of --max-error
    assert 0 < report["surface_rms"] <= 0.1            # in space, without asking for --surface
    text = mzc("info", grid, check=True).stdout.decode()
    assert "cut by    cylindrical" in text and "full turn" in text
