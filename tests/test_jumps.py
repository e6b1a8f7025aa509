"""Depth discontinuities: triangulate, densify and the --rmse estimate never bridge a depth jump
(spec/zgrid.md, Connectivity), and leave real surface, steep or not, alone."""

import numpy as np
import pytest

from mzc.codecs import dwt2d
from mzc.formats import zgrid
from mzc.grid import ZGrid
from mzc.measure.metrics import surface_distance
from mzc.meshes import Mesh
from mzc.ops.densify import densify_grid
from mzc.ops.slicing import slice_surface
from mzc.ops.triangulation import JUMP_ANGLE, grid_to_mesh, grid_triangles, jump_edges

from conftest import FACE_NAMES, face_path

FRONT, BACK = 60.0, 0.0


def sheet(xs, ys, height):
    """A flat mesh at z = ``height`` over the grid of ``xs`` by ``ys``."""
    u, v = np.meshgrid(xs, ys)
    points = np.stack([u, v, np.full(u.shape, height)], axis=-1).reshape(-1, 3)
    return points, grid_triangles(np.ones(u.shape, dtype=bool))


def person_before_wall():
    """A square 'person' 60 mm in front of a wall, as one mesh of two sheets."""
    wall_points, wall_triangles = sheet(np.linspace(-50, 50, 51), np.linspace(-40, 40, 41), BACK)
    person_points, person_triangles = sheet(np.linspace(-15, 15, 16), np.linspace(-20, 20, 21), FRONT)
    return Mesh(np.vstack([wall_points, person_points]),
                np.vstack([wall_triangles, person_triangles + len(wall_points)]))


def spans_both_levels(points, triangles):
    """Per triangle, True when its corners lie on both the wall and the person."""
    z = points[triangles][:, :, 2]
    return (z.max(axis=1) - z.min(axis=1)) > 1.0


def test_a_person_in_front_of_a_wall_triangulates_with_no_sheet_between():
    mesh = person_before_wall()
    grid = slice_surface(mesh, d1=1, d2=1, projection="planar")
    cut, walled = grid_to_mesh(grid), grid_to_mesh(grid, jump_angle=0)
    assert not spans_both_levels(cut.points, cut.triangles).any()
    assert spans_both_levels(walled.points, walled.triangles).sum() > 100          # what the grid joined before
    scene = (mesh.points, mesh.triangles)
    rebuilt = surface_distance(scene, (cut.points, cut.triangles), samples=20_000)
    assert rebuilt["b_to_a_hausdorff"] < 1e-9               # every triangle lies on the scene
    assert surface_distance(scene, (walled.points, walled.triangles), samples=20_000)["b_to_a_hausdorff"] > 10


def test_a_layer_above_a_spherical_cap_is_cut_from_it():
    """Central grids: the jump is measured along the rays (a cap of radius 160 over one of 100,
    rays half a degree apart)."""
    azimuth, elevation = np.meshgrid(np.radians(np.linspace(-40, 40, 161)), np.radians(np.linspace(-30, 30, 121)))
    inner = np.abs(np.degrees(azimuth)) <= 10
    radius = np.where(inner & (np.abs(np.degrees(elevation)) <= 10), 160.0, 100.0)
    points = radius[..., None] * np.stack([np.cos(elevation) * np.sin(azimuth), np.sin(elevation),
                                           np.cos(elevation) * np.cos(azimuth)], axis=-1)
    grid = ZGrid(radius, np.radians(0.5) * 100, np.radians(0.5) * 100,
                 origin=(-np.radians(40) * 100, -np.radians(30) * 100), projection="spherical", radius=100)
    assert np.allclose(grid.node_points(), points)
    rebuilt = grid_to_mesh(grid)
    distance = np.linalg.norm(rebuilt.points[rebuilt.triangles], axis=2)
    assert (distance.max(axis=1) - distance.min(axis=1)).max() < 1e-9
    assert len(grid_to_mesh(grid, jump_angle=0).triangles) > len(rebuilt.triangles)


def test_steep_real_surface_keeps_every_triangle():
    """A plane leaning 80 degrees from the node lines, a cylinder seen side-on: all of it is surface."""
    u, v = np.meshgrid(np.arange(40.0), np.arange(30.0))
    steep = ZGrid(np.tan(np.radians(80)) * u, 1, 1)
    assert len(grid_to_mesh(steep).triangles) == len(grid_to_mesh(steep, jump_angle=0).triangles) == 2 * 39 * 29
    x = np.linspace(-0.99, 0.99, 199) * 50
    side = ZGrid(np.tile(np.sqrt(50 ** 2 - x ** 2), (20, 1)), 1, x[1] - x[0])
    assert len(grid_to_mesh(side).triangles) == len(grid_to_mesh(side, jump_angle=0).triangles)


@pytest.mark.parametrize("name", FACE_NAMES or ["f18.ply"])
def test_the_faces_default_grids_lose_no_triangle(name):
    from mzc.meshes import read_mesh

    grid = slice_surface(read_mesh(face_path(name)), d1=0.5, d2=0.5)
    jumps = jump_edges(grid)
    assert not (jumps.across.any() or jumps.along.any() or jumps.diagonal.any())


@pytest.mark.parametrize("method", ["biharmonic", "laplace", "thesis"])
def test_densify_inserts_nothing_across_a_jump(method):
    grid = slice_surface(person_before_wall(), d1=1, d2=1, projection="planar")
    dense = densify_grid(grid, 3, method, iterations=20_000, tol=1e-12)
    values = dense.z[dense.valid]
    on_a_level = np.minimum(np.abs(values - BACK), np.abs(values - FRONT))
    assert on_a_level.max() < 1e-6
    rebuilt = grid_to_mesh(dense)
    assert not spans_both_levels(rebuilt.points, rebuilt.triangles).any()
    assert np.isnan(dense.z).sum() > np.isnan(densify_grid(grid, 3, method, iterations=20_000, tol=1e-12,
                                                             jump_angle=0).z).sum()


def test_densify_keeps_jumps_across_the_seam_of_a_full_turn():
    """A tube of radius 50 with a ridge of radius 100 on the seam: the ridge stays cut from the tube."""
    cols = 512
    radius = np.full((12, cols), 50.0)
    radius[:, [0, 1, 2, cols - 2, cols - 1]] = 100.0
    grid = ZGrid(radius, 2.0, 2 * np.pi * 50 / cols, origin=(-np.pi * 50, 0), projection="cylindrical", radius=50)
    assert grid.periodic
    dense = densify_grid(grid, 2)
    values = dense.z[dense.valid]
    assert np.minimum(np.abs(values - 50), np.abs(values - 100)).max() < 1e-6
    smoothed = densify_grid(grid, 2, jump_angle=0).z                # smoothed across the ridge's flanks
    assert np.minimum(np.abs(smoothed - 50), np.abs(smoothed - 100)).max() > 0.1


def jumpy_grids():
    """A planar scene with jumps and holes, and a periodic tube with ridges along its seam, along
    a middle column and across some rows, and a hole."""
    planar = slice_surface(person_before_wall(), d1=1, d2=1, projection="planar")
    cols = 64
    radius = np.full((30, cols), 50.0) + np.sin(np.arange(30))[:, None]
    radius[:, [0, 1, cols - 1]] = radius[:, 30:33] = radius[15:17, 40:60] = 100.0
    radius[10:13, 5:9] = np.nan
    tube = ZGrid(radius, 2.0, 2 * np.pi * 50 / cols, origin=(-np.pi * 50, 0.3), projection="cylindrical", radius=50)
    return planar, tube


def jumps_by_the_definition(grid, angle):
    """(across, along, diagonal) of spec/zgrid.md's test on the nodes' points: |e . d(m)| > cos(A) |e|."""
    points = grid.node_points()
    if grid.periodic:
        points = np.concatenate([points, points[:, :1]], axis=1)

    def jump(start, end):
        edge, middle = end - start, (start + end) / 2
        if grid.projection == "planar":
            line = np.broadcast_to([0.0, 0.0, 1.0], middle.shape)
        else:
            middle[..., 1] *= grid.projection == "spherical"
            line = middle / np.linalg.norm(middle, axis=-1, keepdims=True)
        with np.errstate(invalid="ignore"):
            return np.abs(np.sum(edge * line, axis=-1)) > np.cos(np.radians(angle)) * np.linalg.norm(edge, axis=-1)

    along = jump(points[:, :-1], points[:, 1:])
    along[grid.pole_rows()] = False
    return jump(points[:-1], points[1:]), along, jump(points[:-1, 1:], points[1:, :-1])


@pytest.mark.parametrize("strip", [1, 5, 64, 200, 10**9])
def test_jumps_found_in_strips_of_rows_are_those_of_the_definition(monkeypatch, strip):
    """jump_edges tests the edges from the nodes' values a strip of rows at a time: the edges
    that the spec's test on the points finds, with the rows where strips meet, a periodic seam,
    one- and two-row grids and a spherical pole, at the default angle and steeper ones."""
    from mzc.ops import triangulation

    step = np.radians(2) * 100                  # rows from the equator to the pole, 2 degrees apart
    values = 100 + 400.0 * (np.add.outer(np.arange(46), np.arange(40)) % 7 == 0)
    cap = ZGrid(values, step, step, origin=(-np.radians(40) * 100, 0.0), projection="spherical", radius=100)
    assert cap.pole_rows()[-1] and jumps_by_the_definition(cap, JUMP_ANGLE)[0].any()
    grids = [*jumpy_grids(), cap, cap.with_z(cap.z[:1]), cap.with_z(cap.z[:2])]
    monkeypatch.setattr(triangulation, "STRIP_NODES", strip)
    for grid in grids:
        for angle in (JUMP_ANGLE, 30.0, 80.0):
            found = jump_edges(grid, angle)
            for edges, expected in zip(("across", "along", "diagonal"), jumps_by_the_definition(grid, angle)):
                np.testing.assert_array_equal(getattr(found, edges), expected)


@pytest.mark.parametrize("method", ["biharmonic", "laplace", "thesis"])
def test_densify_in_strips_finds_the_jumps_of_the_whole_grid(method):
    """Strips of one and of three gaps (jumps found strip by strip) give the whole grid's result:
    exactly for the gap-by-gap methods, within the solve's tolerance for biharmonic."""
    for grid in jumpy_grids():
        assert np.isnan(densify_grid(grid, 2, method).z).sum() > np.isnan(densify_grid(grid, 2, method,
                                                                                        jump_angle=0).z).sum()
        whole = densify_grid(grid, 2, method).z
        for gaps in (1, 3):
            stripped = densify_grid(grid, 2, method, strip=gaps * 2 * grid.shape[1]).z
            np.testing.assert_array_equal(np.isnan(stripped), np.isnan(whole))
            if method == "biharmonic":
                np.testing.assert_allclose(stripped, whole, rtol=0, atol=1e-10 * np.nanmax(np.abs(grid.z)))
            else:
                np.testing.assert_array_equal(stripped, whole)


def test_rmse_estimate_holds_on_a_scene_with_a_jump():
    """The estimate gives a node beside a jump the lean of its own side, so the measured error
    between the rebuilt scenes (no sheets in either) stays under the target."""
    mesh = person_before_wall()
    bumps = mesh.points.copy()
    bumps[:, 2] += 2 * np.sin(bumps[:, 0] / 7) * np.cos(bumps[:, 1] / 5)
    grid = slice_surface(Mesh(bumps, mesh.triangles), d1=0.5, d2=0.5, projection="planar")
    for target in (0.05, 0.2):
        decoded = dwt2d.read(dwt2d.write(grid, rmse=target))
        before, after = grid_to_mesh(grid), grid_to_mesh(decoded)
        measured = surface_distance((before.points, before.triangles), (after.points, after.triangles),
                                    samples=50_000)["rms"]
        assert measured <= 1.1 * target


def test_the_command_line_drops_jumps_unless_told(mzc, tmp_path):
    grid = slice_surface(person_before_wall(), d1=1, d2=1, projection="planar")
    data = zgrid.write(grid)
    cut = mzc("triangulate", input=data, check=True).stdout.decode()
    joined = mzc("triangulate", "--jump-angle", "0", input=data, check=True).stdout.decode()
    assert cut.count("\nf ") < joined.count("\nf ")
    assert f"default: {JUMP_ANGLE:g}]" in mzc("triangulate", "--help").stdout.decode()
    dense = mzc("densify", "-n", "2", input=data, check=True).stdout
    assert np.isnan(zgrid.read(dense).z).sum() > np.isnan(
        zgrid.read(mzc("densify", "-n", "2", "--jump-angle", "0", input=data, check=True).stdout).z).sum()

