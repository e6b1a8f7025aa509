"""The cases of real scans that used to come back wrong with no message (issue 17): a part
lying in the xz plane, a cloud seen from -z, a DEM at its own spacing, a PLY of triangle
strips, a point cloud on either side of diff, and a grid in lon/lat degrees."""

import json

import numpy as np
import pytest

from mzc.codecs import dwt2d
from mzc.errors import MzcError, MzcWarning
from mzc.formats import zgrid
from mzc.grid import ZGrid
from mzc.measure.metrics import surface_distance
from mzc.meshes import Mesh, read_mesh
from mzc.ops.slicing import slice_surface
from mzc.ops.triangulation import grid_to_mesh, grid_triangles


def gear_in_xz():
    """A toothed plate 70 mm across lying in the xz plane, its relief along +y (normals +y)."""
    x, z = np.meshgrid(np.linspace(-35, 35, 141), np.linspace(-35, 35, 141))
    radius, angle = np.hypot(x, z), np.arctan2(z, x)
    y = 2 + 0.3 * np.cos(radius / 3)
    points = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    triangles = grid_triangles(np.ones(x.shape, dtype=bool))[:, ::-1]   # wound to face +y
    outline = 30 + 3 * np.sign(np.sin(12 * angle)).ravel()
    inside = (radius.ravel()[triangles] <= outline[triangles]).all(axis=1)
    return Mesh(points, triangles[inside])


def test_a_part_in_the_xz_plane_is_seen_along_y():
    mesh = gear_in_xz()
    grid = slice_surface(mesh, d1=0.5, d2=0.5)
    assert grid.projection == "planar" and np.allclose(grid.transform[:, 2], [0, 1, 0])
    assert whole_rms(mesh, grid) < 0.05
    with pytest.warns(MzcWarning, match="meets only"):
        edge_on = slice_surface(mesh, d1=0.5, d2=0.5, view="+z")      # what mzc did before: its edge strip
    assert len(grid_to_mesh(edge_on).triangles) < 0.01 * len(grid_to_mesh(grid).triangles)   # seen edge-on: all jumps


def test_the_view_can_be_set_and_flips_the_side_seen():
    mesh = gear_in_xz()
    grid = slice_surface(mesh, d1=1, d2=1, view="-y")
    assert np.allclose(grid.transform[:, 2], [0, -1, 0])
    assert np.linalg.det(grid.transform[:, :3]) == pytest.approx(1)
    values = grid.z[grid.valid]
    assert np.allclose(-values, 2 + 0.3 * np.cos(np.hypot(*np.meshgrid(grid.xs(), grid.ys()))[grid.valid] / 3),
                       atol=0.01)


def test_the_command_offers_exactly_the_views_the_library_knows():
    from mzc.cli.slice import command
    from mzc.projections import PLANAR_VIEWS

    view = next(option for option in command.params if option.name == "view")
    assert list(view.type.choices) == ["auto", *PLANAR_VIEWS]


def wavy_cloud(count=6000, seed=2):
    """Points of a wavy sheet 100 mm in front of a camera at the origin looking along +z."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(-40, 40, (2, count))
    return np.column_stack([x, y, 100 + 5 * np.sin(x / 10) * np.cos(y / 10)])


def test_a_cloud_whose_normals_face_minus_z_is_seen_from_minus_z(tmp_path):
    points = wavy_cloud()
    header = (f"ply\nformat ascii 1.0\nelement vertex {len(points)}\nproperty double x\nproperty double y\n"
              "property double z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n")
    rows = "".join(f"{x!r} {y!r} {z!r} 0 0 -1\n" for x, y, z in points.tolist())
    (tmp_path / "camera.ply").write_text(header + rows)
    cloud = read_mesh(tmp_path / "camera.ply")
    assert cloud.is_point_cloud and np.allclose(cloud.normals, [0, 0, -1])
    grid = slice_surface(cloud, d1=1, d2=1)
    assert np.allclose(grid.transform[:, 2], [0, 0, -1])
    assert np.allclose(slice_surface(Mesh(points), d1=1, d2=1).transform[:, 2], [0, 0, 1])   # no normals: +z


def dem_points(step=5.0, holes=True):
    """x y z of a 40 x 30 DEM lattice at ``step`` m, two no-data holes of 3 x 3 nodes."""
    x, y = np.meshgrid(1000 + step * np.arange(40), 5000 + step * np.arange(30))
    z = 20 + 3 * np.sin(x / 40) + 0.02 * y
    keep = np.ones(x.shape, dtype=bool)
    if holes:
        keep[10:13, 10:13] = keep[20:23, 30:33] = False
    return np.column_stack([x[keep], y[keep], z[keep]]), keep, z


def test_a_dem_as_text_slices_to_its_own_nodes_and_keeps_its_holes(tmp_path, mzc):
    points, keep, z = dem_points()
    np.savetxt(tmp_path / "dem.xyz", points, fmt="%.6f")
    mzc("slice", tmp_path / "dem.xyz", "-o", tmp_path / "dem.zg", check=True)
    grid = zgrid.read((tmp_path / "dem.zg").read_bytes(), "dem.zg")
    assert grid.shape == (30, 40) and (grid.d1, grid.d2) == (5.0, 5.0) and grid.origin == (1000.0, 5000.0)
    assert np.array_equal(grid.valid, keep)
    assert np.abs(grid.z[keep] - z[keep]).max() < 1e-6          # the text's six decimals
    snapped = slice_surface(Mesh(points), d1=5.004, d2=4.999)    # within 0.1% of the lattice's step
    assert (snapped.d1, snapped.d2) == (5.0, 5.0) and snapped.shape == (30, 40)


def strip_ply(tmp_path, body_format="ascii"):
    """A 4 x 5 vertex grid as one PLY triangle strip per row pair, joined into one record by -1."""
    x, y = np.meshgrid(np.arange(5.0), np.arange(4.0))
    points = np.stack([x, y, 0.1 * x * y], axis=-1).reshape(-1, 3)
    strips = []
    for row in range(3):
        for col in range(5):
            strips += [(row + 1) * 5 + col, row * 5 + col]
        strips.append(-1)
    header = ("ply\nformat ascii 1.0\nelement vertex 20\nproperty float x\nproperty float y\nproperty float z\n"
              "element tristrips 1\nproperty list int int vertex_indices\nend_header\n")
    body = "".join(f"{a} {b} {c}\n" for a, b, c in points.tolist()) + f"{len(strips)} " + " ".join(map(str, strips))
    path = tmp_path / "strips.ply"
    path.write_text(header + body + "\n")
    return path, points


def test_ply_triangle_strips_are_read_as_triangles_facing_one_way(tmp_path):
    path, points = strip_ply(tmp_path)
    mesh = read_mesh(path)
    assert len(mesh.triangles) == 2 * 3 * 4
    corners = mesh.points[mesh.triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert (normals[:, 2] > 0).all() or (normals[:, 2] < 0).all()
    assert len({tuple(sorted(t)) for t in mesh.triangles.tolist()}) == len(mesh.triangles)
    assert np.abs(normals[:, 2]).sum() / 2 == pytest.approx(12)          # they tile the 4 x 3 grid once


def test_a_ply_element_mzc_does_not_know_is_refused_by_name(tmp_path, mzc):
    path = tmp_path / "grid.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement range_grid 2\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n1 0\n1 1\n")
    with pytest.raises(MzcError, match="element 'range_grid'"):
        read_mesh(path)
    result = mzc("slice", path)
    assert result.returncode == 1 and result.stderr.decode().count("\n") == 1
    assert "range_grid" in result.stderr.decode()


def test_diff_with_a_point_cloud_on_either_side_measures_the_points(tmp_path, mzc):
    mesh = gear_in_xz()
    from mzc.meshes import write_mesh

    write_mesh(tmp_path / "gear.ply", mesh)
    cloud = mesh.points[np.unique(mesh.triangles)][::5] + [0, 0.02, 0]
    np.savetxt(tmp_path / "gear.xyz", cloud)
    for a, b in (("gear.xyz", "gear.ply"), ("gear.ply", "gear.xyz")):
        report = json.loads(mzc("diff", a, b, "--json", check=True, cwd=tmp_path).stdout)
        assert report["direction"] == "points of gear.xyz to the surface of gear.ply"
        assert report["count"] == len(cloud) and 0.015 < report["rmse"] <= 0.02 + 1e-9
    both = mzc("diff", "gear.xyz", "gear.xyz", cwd=tmp_path)
    assert both.returncode == 1 and "both sides are point clouds" in both.stderr.decode()


def lon_lat_grid():
    """A 3-arc-second DEM tile in degrees, heights in metres."""
    rows, cols = np.mgrid[0:100, 0:100]
    z = 1500 + 300 * np.sin(rows / 20) * np.cos(cols / 15)
    return ZGrid(z, 1 / 1200, 1 / 1200, origin=(-105.5, 40.0))


@pytest.mark.parametrize("option", [{"rmse": 1.34}, {"size": 400}])
def test_rmse_and_size_refuse_a_grid_whose_axes_cannot_share_a_unit(option):
    with pytest.raises(MzcError, match="cannot share one unit"):
        dwt2d.write(lon_lat_grid(), **option)


def test_max_error_still_holds_on_a_lon_lat_grid(mzc):
    grid = lon_lat_grid()
    decoded = dwt2d.read(dwt2d.write(grid, max_error=1.34))
    assert np.abs(decoded.z - grid.z).max() <= 1.34
    refused = mzc("encode", "--dwt2d", "--rmse", "1.34", input=zgrid.write(grid))
    assert refused.returncode == 1 and refused.stdout == b""
    assert refused.stderr.decode().count("\n") == 1 and "--max-error" in refused.stderr.decode()


# --------------------------------------------------------------------------- real files (tests/data/public)

PUBLIC = __import__("pathlib").Path(__file__).parent / "data" / "public"


def test_a_real_part_lying_in_the_xz_plane_is_cut_along_y():
    """numpy-stl's Moon.stl, a crescent 3 x 1.6 lying in xz, 0.35 thick in y."""
    mesh = read_mesh(PUBLIC / "moon.stl")
    with pytest.warns(MzcWarning):                        # a plate sees 29% of its area well: its top
        planar = slice_surface(mesh, projection="planar")
    assert abs(planar.transform[1, 2]) == 1
    with pytest.warns(MzcWarning):
        along_z = slice_surface(mesh, projection="planar", view="+z")
    assert whole_rms(mesh, planar) < 0.25 * whole_rms(mesh, along_z)     # measured 0.12 against 0.64
    assert whole_rms(mesh, slice_surface(mesh)) < 0.03                    # auto: a cylinder about y, 0.022


def test_a_real_cad_part_encodes_on_its_full_turn_grid():
    """trimesh's angle_block.STL as one grid: auto picks a spherical full turn with pole rows,
    whose jumps and seam the --rmse estimate must handle."""
    mesh = read_mesh(PUBLIC / "angle_block.stl")
    grid = slice_surface(mesh, charts=1)
    assert grid.periodic and grid.pole_rows().any()
    decoded = dwt2d.read(dwt2d.write(grid, rmse=0.003))
    assert whole_rms(mesh, decoded) < whole_rms(mesh, grid) + 0.003


def whole_rms(mesh, grid):
    """The symmetric point-to-surface RMS between ``mesh`` and the triangulated ``grid``."""
    rebuilt = grid_to_mesh(grid)
    return surface_distance((mesh.points, mesh.triangles), (rebuilt.points, rebuilt.triangles), samples=20_000)["rms"]


@pytest.mark.parametrize("name", ["jacksboro", "topobathy"])
def test_a_dem_mesh_slices_by_default_to_its_own_grid_exactly(name):
    """matplotlib's DEMs as meshes: the default grid is the DEM's, every node its height (no
    resampling: 72 x 669 resampled nodes before the default followed the data)."""
    from mzc import samples

    truth = getattr(samples, name)()
    grid = slice_surface(samples.sample_mesh(name))
    assert grid.shape == truth.shape and (grid.d1, grid.d2) == (truth.d1, truth.d2)
    assert np.array_equal(grid.valid, truth.valid) and np.array_equal(grid.z[grid.valid], truth.z[truth.valid])


def test_the_command_line_warns_once_when_the_grid_sees_little(mzc, tmp_path):
    seen_edge_on = mzc("slice", PUBLIC / "moon.stl", "--projection", "planar", "--view", "+z", "-o", tmp_path / "a.zg")
    assert seen_edge_on.returncode == 0
    lines = seen_edge_on.stderr.decode().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mzc: warning: the planar grid meets only")
    assert mzc("slice", PUBLIC / "moon.stl", "-o", tmp_path / "b.zg").stderr == b""
