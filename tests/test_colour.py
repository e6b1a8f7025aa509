"""Colour through the uncompressed pipeline: readers fill Mesh.colors, slice samples it at the
nodes, the z-grid carries it, triangulate writes it back (issue 32).

The surfaces are generated: a height field over [0, 10] x [0, 8] whose colour is a smooth
function of (x, y) (``analytic_colour``), written in each format, so every node's colour can be
checked against the colour the function gives at the node's own (x, y).
"""

import importlib.util
import io

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.colours import to_8_bits, unpack_rgb
from mzc.meshes import Mesh, mesh_from_bytes
from mzc.ops.triangulation import grid_triangles

WIDTH, HEIGHT = 10.0, 8.0


def analytic_colour(x, y):
    """(n, 3) float colours in 0..255 of the generated surface at (x, y): linear ramps in red and
    green, a smooth wave in blue."""
    return np.column_stack([255 * x / WIDTH, 255 * y / HEIGHT, 127.5 + 100 * np.sin(0.5 * x) * np.cos(0.4 * y)])


def height(x, y):
    """The generated surface's height at (x, y)."""
    return 0.5 * np.sin(0.3 * x) + 0.2 * y


def coloured_surface(nx=41, ny=33):
    """A Mesh of the height field on an nx x ny lattice, each vertex coloured by ``analytic_colour``."""
    x, y = np.meshgrid(np.linspace(0, WIDTH, nx), np.linspace(0, HEIGHT, ny))
    x, y = x.ravel(), y.ravel()
    points = np.column_stack([x, y, height(x, y)])
    triangles = grid_triangles(np.ones((ny, nx), dtype=bool))
    return Mesh(points, triangles, colors=np.round(analytic_colour(x, y)).astype(np.uint8))


def ascii_ply(mesh, colour_type="uchar"):
    """ASCII PLY bytes of ``mesh`` with its colours as ``colour_type`` properties (uchar levels,
    or float fractions)."""
    values = mesh.colors if colour_type == "uchar" else mesh.colors / 255.0
    header = ("ply\nformat ascii 1.0\n"
              f"element vertex {len(mesh.points)}\nproperty double x\nproperty double y\nproperty double z\n"
              + "".join(f"property {colour_type} {name}\n" for name in ("red", "green", "blue"))
              + f"element face {len(mesh.triangles)}\nproperty list uchar int vertex_indices\nend_header\n")
    vertices = "".join(f"{x!r} {y!r} {z!r} {r!r} {g!r} {b!r}\n" for (x, y, z), (r, g, b)
                       in zip(mesh.points.tolist(), values.tolist()))
    faces = "".join(f"3 {a} {b} {c}\n" for a, b, c in mesh.triangles.tolist())
    return (header + vertices + faces).encode()


def pcd_bytes(mesh, kind="F"):
    """A binary PCD of ``mesh``'s points with PCL's packed ``rgb`` (a float32, ``kind`` F, or a
    uint32, U: blue in the lowest byte)."""
    n = len(mesh.points)
    records = np.empty(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<u4")])
    records["x"], records["y"], records["z"] = mesh.points.T
    r, g, b = (mesh.colors[:, i].astype(np.uint32) for i in range(3))
    records["rgb"] = (r << 16) | (g << 8) | b
    header = (f"VERSION .7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F {kind}\nCOUNT 1 1 1 1\nWIDTH {n}\n"
              f"HEIGHT 1\nPOINTS {n}\nDATA binary\n")
    return header.encode() + records.tobytes()


def las_bytes(mesh):
    """A LAS 1.2 cloud (point format 3) of ``mesh``'s points, millimetre steps, its colours as LAS's
    16-bit levels (257 times the 8-bit ones), written by laspy."""
    import laspy

    las = laspy.create(point_format=3, file_version="1.2")
    las.header.scales = [0.001] * 3
    las.x, las.y, las.z = mesh.points.T
    las.red, las.green, las.blue = (mesh.colors[:, i].astype(np.uint16) * 257 for i in range(3))
    buffer = io.BytesIO()
    las.write(buffer)
    return buffer.getvalue()


def test_colour_values_become_8_bits_as_their_files_mean_them():
    assert to_8_bits(np.array([[0, 128, 255]]), 8).tolist() == [[0, 128, 255]]
    assert to_8_bits(np.array([[0, 32896, 65535]]), 16).tolist() == [[0, 128, 255]]
    assert to_8_bits(np.array([[0.0, 0.5, 1.0]])).tolist() == [[0, 128, 255]]      # fractions
    assert to_8_bits(np.array([[0.0, 2.0, 255.0]])).tolist() == [[0, 2, 255]]       # levels: one exceeds 1
    assert to_8_bits(np.array([[-3.0, np.nan, 1e9]]), 8).tolist() == [[0, 0, 255]]  # clipped
    packed = np.array([0x00A0B0C0, 0xFF010203], dtype="<u4")
    assert unpack_rgb(packed).tolist() == [[0xA0, 0xB0, 0xC0], [1, 2, 3]]
    assert unpack_rgb(packed.view("<f4")).tolist() == [[0xA0, 0xB0, 0xC0], [1, 2, 3]]   # a NaN's bits too


def test_mesh_colors_are_checked_like_its_other_fields():
    from mzc.errors import MzcError

    mesh = Mesh(np.zeros((2, 3)), colors=[[1, 2, 3], [4.0, 5.0, 255.0]])
    assert mesh.colors.dtype == np.uint8 and mesh.colors.tolist() == [[1, 2, 3], [4, 5, 255]]
    for bad, message in (([[1, 2, 3]], "shape"), ([[1, 2, 3], [4, 5, 256]], "256"), ([[1, 2, 3], [4, 5, 0.5]], "0.5"),
                         ([["a", "b", "c"]] * 2, "integers")):
        with pytest.raises(MzcError, match=message):
            Mesh(np.zeros((2, 3)), colors=bad)


@pytest.mark.parametrize("colour_type", ["uchar", "float", "ushort"])
def test_ply_vertex_colours_are_read(colour_type):
    mesh = coloured_surface(6, 5)
    data = ascii_ply(mesh, "uchar" if colour_type == "ushort" else colour_type)
    if colour_type == "ushort":   # 16-bit levels: 257 times the 8-bit ones
        data = data.replace(b"property uchar", b"property ushort")
        head, body = data.split(b"end_header\n")
        lines = body.decode().splitlines()
        for i in range(len(mesh.points)):
            words = lines[i].split()
            lines[i] = " ".join(words[:3] + [str(int(w) * 257) for w in words[3:]])
        data = head + b"end_header\n" + "\n".join(lines).encode() + b"\n"
    read = mesh_from_bytes(data, "c.ply")
    np.testing.assert_array_equal(read.colors, mesh.colors)
    assert read.dropped == ()


def test_binary_ply_colours_with_alpha_are_read_and_alpha_named():
    mesh = coloured_surface(5, 4)
    n = len(mesh.points)
    records = np.empty(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"),
                                 ("blue", "u1"), ("alpha", "u1")])
    records["x"], records["y"], records["z"] = mesh.points.T
    records["red"], records["green"], records["blue"] = mesh.colors.T
    records["alpha"] = 200
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
              "end_header\n")
    read = mesh_from_bytes(header.encode() + records.tobytes(), "c.ply")
    np.testing.assert_array_equal(read.colors, mesh.colors)
    assert read.dropped == ("vertex properties alpha",)


def test_obj_vertex_colours_are_read_as_fractions_or_levels():
    mesh = coloured_surface(5, 4)
    for scale in (1 / 255, 1.0):
        lines = [f"v {x!r} {y!r} {z!r} {r * scale!r} {g * scale!r} {b * scale!r}"
                 for (x, y, z), (r, g, b) in zip(mesh.points.tolist(), mesh.colors.astype(float).tolist())]
        faces = [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.triangles.tolist()]
        read = mesh_from_bytes("\n".join(lines + faces).encode(), "c.obj")
        np.testing.assert_array_equal(read.colors, mesh.colors)
        assert read.dropped == ()


@pytest.mark.parametrize("kind", ["F", "U"])
def test_pcd_packed_rgb_is_read(kind):
    mesh = coloured_surface(6, 5)
    read = mesh_from_bytes(pcd_bytes(mesh, kind), "c.pcd")
    np.testing.assert_array_equal(read.colors, mesh.colors)
    assert read.dropped == ()


@pytest.mark.skipif(not importlib.util.find_spec("laspy"), reason="laspy (the las extra) is not installed")
def test_las_rgb_is_read_from_16_bits():
    mesh = coloured_surface(6, 5)
    read = mesh_from_bytes(las_bytes(mesh), "c.las")
    np.testing.assert_array_equal(read.colors, mesh.colors)
    assert read.dropped == ()


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 255), st.integers(0, 255), st.integers(0, 255)), min_size=3, max_size=20))
def test_obj_written_with_colours_reads_back_the_same_levels(colours):
    """OBJ's ``v x y z r g b`` written as level / 255 reads back as the very levels, whatever they are
    (an all-dark mesh too: every fraction is at most 1)."""
    from mzc.meshes import mesh_to_bytes

    n = len(colours)
    mesh = Mesh(np.arange(3 * n, dtype=float).reshape(n, 3), colors=colours)
    np.testing.assert_array_equal(mesh_from_bytes(mesh_to_bytes(mesh, "obj"), "c.obj").colors, mesh.colors)


def node_errors(grid, colour_of):
    """Each valid node's colour minus ``colour_of`` its input-frame point, every chart's nodes."""
    errors = []
    for part in grid.chart_grids():
        points = part.to_input_frame(part.node_points()[part.valid])
        errors.append(part.colors[part.valid].astype(float) - colour_of(points))
    return np.concatenate(errors)


def ball():
    """A ball of radius 20 about (1, 2, 3) (a subdivided icosahedron) whose colour is linear in the
    position, (x, y, z) - centre scaled from -20..20 to 0..255 (its vertices' rounded to levels),
    with that colour function: linear, so a triangle's interpolated colour is the function's at
    every point of it, to the rounding of the corners' levels."""
    from mzc.samples import icosphere

    points, faces = icosphere(4)
    centre = np.array([1.0, 2.0, 3.0])
    points = 20 * points + centre

    def colour_of(at):
        return 127.5 + 127.5 * (at - centre) / 20

    return Mesh(points, faces, colors=np.round(colour_of(points))), colour_of


@pytest.mark.parametrize("options", [{}, {"projection": "cylindrical"}, {"charts": 6}])
def test_slice_samples_a_linear_colour_within_a_level_on_every_projection_and_chart(options):
    """At every node the colour is the barycentric mix of the hit triangle's corners: for a linear
    colour that is the function's own value at the node, within half a level of the corners'
    rounding and half of the node's (spherical: the ball's default grid; cylindrical; 6 charts)."""
    from mzc.ops.slicing import slice_surface

    mesh, colour_of = ball()
    grid = slice_surface(mesh, **options)
    assert (grid.charts is not None) == ("charts" in options)
    assert grid.colors.shape == (*grid.shape, 3) and grid.colors.dtype == np.uint8
    assert not grid.colors[~grid.valid].any()
    errors = node_errors(grid, colour_of)
    assert len(errors) > 50_000 and np.abs(errors).max() <= 1.0


def test_slice_samples_a_height_fields_colour_within_its_interpolation_error():
    """A grid finer than the mesh interpolates the corners' colours linearly: the blue wave's
    second derivative bounds the error (50 levels a unit^2 over cells of 0.25: under 1.5 levels
    with the roundings)."""
    from mzc.ops.slicing import slice_surface

    grid = slice_surface(coloured_surface(), d1=0.07, align="pca")
    errors = node_errors(grid, lambda points: analytic_colour(points[:, 0], points[:, 1]))
    assert grid.valid.sum() > 15_000 and np.abs(errors).max() <= 1.5 and np.sqrt((errors ** 2).mean()) < 0.5


@pytest.mark.parametrize("fmt", ["pcd", "las"])
def test_a_cloud_gives_each_node_its_nearest_points_colour(fmt):
    """A cloud's node takes the colour of the point nearest it: on a 0.25 lattice sliced at 0.07,
    at most the colour's change over half a lattice diagonal (the red and green ramps: 25.5 and
    31.9 levels a unit, 0.18 of a unit) plus the roundings."""
    from mzc.ops.slicing import slice_surface

    if fmt == "las" and not importlib.util.find_spec("laspy"):
        pytest.skip("laspy (the las extra) is not installed")
    mesh = coloured_surface()
    cloud = mesh_from_bytes(pcd_bytes(mesh) if fmt == "pcd" else las_bytes(mesh), f"c.{fmt}")
    grid = slice_surface(cloud, d1=0.07, cloud="delaunay")
    errors = node_errors(grid, lambda points: analytic_colour(points[:, 0], points[:, 1]))
    assert np.abs(errors[:, :2]).max() <= 0.18 * 32 + 1 and np.sqrt((errors ** 2).mean()) < 3


def test_a_grid_without_colours_stays_without():
    from mzc.ops.slicing import slice_surface

    mesh = coloured_surface()
    assert slice_surface(Mesh(mesh.points, mesh.triangles)).colors is None


@st.composite
def coloured_grids(draw):
    """Small grids with holes, any colours (those of invalid nodes any too: the grid makes them
    0), raw bodies of either type."""
    from hypothesis.extra.numpy import arrays

    from mzc.grid import ZGrid

    shape = draw(st.tuples(st.integers(1, 10), st.integers(1, 10)))
    z = draw(arrays(float, shape, elements=st.floats(-1e6, 1e6, allow_nan=False, width=32)))
    z[draw(arrays(bool, shape))] = np.nan
    colours = draw(arrays(np.uint8, (*shape, 3)))
    return ZGrid(z, draw(st.floats(1e-3, 1e3)), 0.5, origin=(draw(st.floats(-1e3, 1e3)), 0.0), units="mm",
                 colors=colours), draw(st.sampled_from(["float64", "float32"]))


@settings(max_examples=150, deadline=None)
@given(coloured_grids())
def test_a_coloured_grid_round_trips_exactly_through_the_zgrid(case):
    from mzc.formats import zgrid

    grid, raw = case
    data = zgrid.write(grid, raw=raw)
    assert data.startswith(b"mzc-zgrid 5.0\n")
    back = zgrid.read(data, "t.zg")
    np.testing.assert_array_equal(back.z, grid.z)   # float32-exact heights
    assert back.colors.tobytes() == grid.colors.tobytes() and not back.colors[~back.valid].any()
    assert zgrid.write(back, raw=raw) == data


@settings(max_examples=200, deadline=None, derandomize=True)
@given(coloured_grids(), st.data())
def test_a_damaged_coloured_zgrid_is_refused_in_one_line(case, data):
    """A 5.0 file cut short, added to, without its colours line or with another layout is an
    MzcError naming the field, never other heights or colours (its crc32 fixed up, so the
    reader's own checks are what refuse it)."""
    from mzc.errors import MzcError
    from mzc.formats import zgrid

    from codec_contract import rechecksummed

    grid, raw = case
    good = zgrid.write(grid, raw=raw)
    cut = data.draw(st.integers(1, 3 * grid.z.size + 4))
    for bad in (good[:-cut], good + b"\0" * cut, good.replace(b"colours rgb8\n", b""),
                good.replace(b"colours rgb8\n", b"colours rgb16\n")):
        with pytest.raises(MzcError) as error:
            zgrid.read(rechecksummed(bad), "bad.zg")
        assert error.value.field in ("data", "colours")


def test_a_coloured_grid_has_no_plain_body():
    from mzc.errors import MzcError
    from mzc.formats import zgrid
    from mzc.grid import ZGrid

    grid = ZGrid(np.ones((2, 2)), 1, 1, colors=np.zeros((2, 2, 3)))
    with pytest.raises(MzcError, match="raw body .mzc-zgrid 5.0"):
        zgrid.write(grid)


@pytest.mark.parametrize("fmt", ["ply", "obj"])
@pytest.mark.parametrize("charts", [1, 6])
def test_triangulate_gives_each_vertex_its_nodes_colour_and_the_file_keeps_it(fmt, charts):
    """Every vertex of the grid's mesh (one grid, or six charts zipped) has its node's colour,
    within a level of the ball's linear colour at the vertex, and a PLY or OBJ written of it reads
    back the same colours; trimesh and meshio get them too."""
    from mzc.meshes import mesh_to_bytes
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    mesh, colour_of = ball()
    out = grid_to_mesh(slice_surface(mesh, charts=charts))
    assert np.abs(out.colors - colour_of(out.points)).max() <= 1.0
    back = mesh_from_bytes(mesh_to_bytes(out, fmt), f"out.{fmt}")
    np.testing.assert_array_equal(back.colors, out.colors)
    assert back.dropped == ()
    if importlib.util.find_spec("trimesh"):
        np.testing.assert_array_equal(out.to_trimesh().visual.vertex_colors[:, :3], out.colors)
    point_data = out.to_meshio().point_data
    np.testing.assert_array_equal(np.column_stack([point_data[c] for c in ("red", "green", "blue")]), out.colors)


def test_densify_mixes_the_colours_of_the_rows_it_inserts_between():
    """Inserted rows interpolate their rows' colours linearly: on the ball's linear colour the
    densified mesh stays within 1.5 levels of it (the inserted heights leave the triangles by a
    little), and the original rows keep their colours."""
    from mzc.ops.densify import densify_grid
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    mesh, colour_of = ball()
    for charts in (1, 6):
        grid = slice_surface(mesh, charts=charts)
        dense = densify_grid(grid, 2)
        assert dense.colors.shape == (*dense.shape, 3) and not dense.colors[~dense.valid].any()
        np.testing.assert_array_equal(dense.colors[::3], grid.colors)
        out = grid_to_mesh(dense)
        assert np.abs(out.colors - colour_of(out.points)).max() <= 1.5


def test_densified_colours_mix_two_rows_by_their_distance():
    from mzc.ops.colouring import densified_colours

    colours = np.array([[[0, 0, 0], [9, 9, 9]], [[30, 60, 90], [200, 200, 200]]], dtype=np.uint8)
    valid = np.ones((4, 2), dtype=bool)
    valid[1:3, 1] = [True, False]
    dense = densified_colours(colours, valid, 2)
    assert dense[:, 0].tolist() == [[0, 0, 0], [10, 20, 30], [20, 40, 60], [30, 60, 90]]
    assert dense[:, 1].tolist() == [[9, 9, 9], [73, 73, 73], [0, 0, 0], [200, 200, 200]]


def test_a_simplified_mesh_takes_the_colour_of_the_surface_where_each_vertex_lies():
    """triangulate's simplifier moves the vertices it keeps; each then takes the mesh's colour at the
    nearest point of its surface: on the generated surface's linear red and green ramps, cut from
    20,769 to 2,000 vertices, within 0.45 levels RMS and 1.25 at most of the ramps at the vertex
    (measured 0.36 and 0.99; the nearest vertex's colour, which it took before, 0.58 and 1.50)."""
    from mzc.ops.simplify import simplified

    mesh = coloured_surface(161, 129)
    fewer = simplified(mesh, 2000)
    assert 1600 <= len(fewer.points) <= 2400
    error = fewer.colors[:, :2] - analytic_colour(fewer.points[:, 0], fewer.points[:, 1])[:, :2]
    assert np.sqrt(np.mean(error ** 2)) <= 0.45 and np.abs(error).max() <= 1.25


def test_the_cli_pipeline_keeps_colours_from_a_coloured_ply_to_the_rebuilt_one(tmp_path):
    """mzc slice col.ply | mzc triangulate -o out.ply: the rebuilt mesh has each vertex's colour
    within 1.5 levels of the surface's analytic colour there (the corners' linear mix of the
    blue wave); densify in between keeps them too; an STL output names them in one warning."""
    from mzc.meshes import read_mesh

    from conftest import run_mzc

    (tmp_path / "col.ply").write_bytes(ascii_ply(coloured_surface()))
    grid = run_mzc("slice", tmp_path / "col.ply", "--d1", "0.1", "--align", "pca", check=True).stdout
    assert grid.startswith(b"mzc-zgrid 5.2\n")   # 5.2: the source's vertex count
    run_mzc("triangulate", "--vertices", "all", "-o", tmp_path / "out.ply", input=grid, check=True)
    dense = run_mzc("densify", "-n", "1", input=grid, check=True).stdout
    run_mzc("triangulate", "-o", tmp_path / "dense.obj", input=dense, check=True)
    for name in ("out.ply", "dense.obj"):
        out = read_mesh(tmp_path / name)
        errors = out.colors - analytic_colour(out.points[:, 0], out.points[:, 1])
        assert len(out.points) > 5000 and np.abs(errors).max() <= 1.5, name
    stl = run_mzc("triangulate", "-o", tmp_path / "out.stl", input=grid, check=True)
    assert stl.stderr.decode().count("mzc: warning: not kept: the vertex colours (STL") == 1


def test_encoding_a_coloured_grid_keeps_its_colours_or_names_them(tmp_path):
    """A dwt2d file, coded whole or in tiles (11.0), carries the colours (no warning; they decode
    within the bound); the formats that code the shape alone (the row codecs) say so in one
    warning (the CLI and the API), and their files decode without colours."""
    import warnings

    import mzc
    from mzc.errors import MzcWarning
    from mzc.formats import zgrid
    from mzc.ops.slicing import slice_surface

    from conftest import run_mzc

    grid = slice_surface(coloured_surface(), d1=0.2, align="pca")
    (tmp_path / "c.zg").write_bytes(zgrid.write(grid, raw="float64"))
    for tiling in ([], ["--tile", "16"]):
        kept = run_mzc("encode", "--dwt2d", "--max-error", "0.05", "--colour-max-error", "2", *tiling,
                       tmp_path / "c.zg", "-o", tmp_path / "c.mzw2", check=True)
        assert "colours" not in kept.stderr.decode()
        decoded = mzc.decode((tmp_path / "c.mzw2").read_bytes())
        assert np.abs(decoded.colors.astype(int) - grid.colors)[grid.valid].max() <= 2
    result = run_mzc("encode", "--dct", "--quality", "20", tmp_path / "c.zg", "-o", tmp_path / "d", check=True)
    assert result.stderr.decode().count("mzc: warning: not kept: the nodes' colours") == 1
    assert mzc.decode((tmp_path / "d").read_bytes()).colors is None
    with warnings.catch_warnings():
        warnings.simplefilter("error", MzcWarning)
        for tile in (None, 16):
            assert mzc.decode(mzc.encode(grid, "dwt2d", max_error=0.05, tile=tile)).colors is not None
    with pytest.warns(MzcWarning, match="the nodes' colours"):
        data = mzc.encode(grid, "dct", quality=20)
    assert mzc.decode(data).colors is None


def test_a_coloured_grid_larger_than_a_tile_is_tiled_with_its_colours_unless_they_are_finer():
    """A grid of more nodes than a default tile (1024 x 1024) is tiled; with colours at its nodes,
    in 11.0 tiles that keep them; with colours finer than its nodes, up to FINE_COLOURED_WHOLE
    nodes, it is coded whole (only such a file keeps them) unless tiles are asked for."""
    import warnings

    import mzc
    from mzc.codecs.dwt2d.tiles import DEFAULT_TILE, FINE_COLOURED_WHOLE, is_tiled, tile_side
    from mzc.errors import MzcWarning
    from mzc.grid import ZGrid

    rows, cols = 1100, 1000
    y, x = np.mgrid[0:rows, 0:cols] / 100.0
    colours = np.stack([x * 25, y * 23, 128 + 100 * np.sin(x + y)], axis=-1).astype(np.uint8)
    grid = ZGrid(np.sin(x) * np.cos(y), 0.01, 0.01, colors=colours)
    with warnings.catch_warnings():
        warnings.simplefilter("error", MzcWarning)
        data = mzc.encode(grid, "dwt2d", max_error=0.01, colour_max_error=4)
    assert data.startswith(b"mzc-dwt2d 11.0\n") and np.abs(mzc.decode(data).colors.astype(int) - colours).max() <= 4
    assert is_tiled(mzc.encode(grid.with_z(grid.z, colors=None), "dwt2d", max_error=0.01))
    fine = np.repeat(np.repeat(colours, 2, axis=0), 2, axis=1)[: 2 * rows - 1, : 2 * cols - 1]
    whole = mzc.encode(grid.with_z(grid.z, colors=colours, fine_colors=fine), "dwt2d", max_error=0.01,
                       colour_max_error=4)
    back = mzc.decode(whole)
    assert not is_tiled(whole) and back.colour_scale == 2
    assert np.abs(back.fine_colors.astype(int) - fine).max() <= 4
    side = int(np.sqrt(FINE_COLOURED_WHOLE)) + 1
    assert tile_side((side, side), None, fine_coloured=True) == DEFAULT_TILE
    assert tile_side((side - 1, side - 1), None, fine_coloured=True) is None
    assert tile_side((side - 1, side - 1), None) == DEFAULT_TILE


def textured_obj(folder, image_name="skin.png", mtl_name="face.mtl", size=(64, 80)):
    """The height field as an OBJ with ``f v/vt`` corners, its material file naming a PNG texture
    (``size`` rows x cols) whose pixel (row, col) is the analytic colour at the surface point the
    uv (x / WIDTH, y / HEIGHT) maps to it; written into ``folder``. Returns the OBJ's path."""
    from PIL import Image

    mesh = coloured_surface()
    rows, cols = size
    x, y = np.meshgrid((np.arange(cols) + 0.5) / cols * WIDTH, (1 - (np.arange(rows) + 0.5) / rows) * HEIGHT)
    pixels = np.round(analytic_colour(x.ravel(), y.ravel())).reshape(rows, cols, 3).astype(np.uint8)
    Image.fromarray(pixels).save(folder / image_name)
    (folder / mtl_name).write_text(f"newmtl skin\nKd 1 1 1\nmap_Kd -s 1 1 1 {image_name}\n")
    lines = [f"mtllib {mtl_name}", "usemtl skin"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.points.tolist()]
    lines += [f"vt {x / WIDTH!r} {y / HEIGHT!r}" for x, y, _ in mesh.points.tolist()]
    lines += [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}" for a, b, c in mesh.triangles.tolist()]
    (folder / "face.obj").write_text("\n".join(lines) + "\n")
    return folder / "face.obj"


def test_an_obj_texture_is_sampled_at_its_vertices_and_sliced(tmp_path):
    """OBJ + MTL map_Kd + PNG: each vertex gets the texture's colour at its vt (bilinear between
    pixel centres: within 1.5 levels of the analytic colour, whose ramps change 3-4 levels a
    pixel, and 4 on the image's outer half pixel, which takes its edge pixels' colour), the
    texture coordinates and material are no longer named as dropped, and slicing carries the
    colours to the nodes (within 4 levels, 1.5 RMS)."""
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    mesh = read_mesh(textured_obj(tmp_path))
    errors = mesh.colors - analytic_colour(mesh.points[:, 0], mesh.points[:, 1])
    x, y = mesh.points[:, 0], mesh.points[:, 1]
    inner = (x > 0.1) & (x < WIDTH - 0.1) & (y > 0.1) & (y < HEIGHT - 0.1)
    assert np.abs(errors[inner]).max() <= 1.5 and np.abs(errors).max() <= 4 and mesh.dropped == ()
    grid = slice_surface(mesh, d1=0.1, align="pca")
    errors = node_errors(grid, lambda points: analytic_colour(points[:, 0], points[:, 1]))
    assert np.abs(errors).max() <= 4 and np.sqrt((errors ** 2).mean()) < 1.5


@pytest.mark.parametrize("case", ["missing image", "outside", "no material", "stdin"])
def test_a_texture_that_cannot_be_read_is_one_warning_not_a_crash(tmp_path, case):
    from mzc.errors import MzcWarning
    from mzc.meshes import read_mesh

    from conftest import run_mzc

    path = textured_obj(tmp_path)
    if case == "missing image":
        (tmp_path / "skin.png").unlink()
    elif case == "outside":
        (tmp_path / "face.mtl").write_text("newmtl skin\nmap_Kd ../../etc/passwd\n")
    elif case == "no material":
        (tmp_path / "face.mtl").unlink()
    if case == "stdin":
        result = run_mzc("slice", "-", "-o", tmp_path / "a.zg", input=path.read_bytes(), check=True)
        assert result.stderr.decode().count("mzc: warning: texture not read:") == 1
        return
    with pytest.warns(MzcWarning, match="texture not read") as caught:
        mesh = read_mesh(path)
    assert len([w for w in caught if "texture" in str(w.message)]) == 1
    assert mesh.colors is None and "texture coordinates" in " ".join(mesh.dropped)
    message = str(next(w.message for w in caught if "texture" in str(w.message)))
    assert "\n" not in message and ("outside" in message) == (case == "outside")


def test_triangulate_texture_writes_an_image_that_reads_back_as_the_nodes_colours(tmp_path):
    """--texture: the OBJ, its material file and the PNG of the grid's colours; mzc's own OBJ
    reader samples the PNG at each vertex's vt, a pixel centre, and so gets back every vertex's
    node colour exactly. Bad requests are refused before anything is written."""
    from mzc.formats import zgrid
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    from conftest import run_mzc

    grid = slice_surface(coloured_surface(), d1=0.1, align="pca")
    (tmp_path / "c.zg").write_bytes(zgrid.write(grid, raw="float64"))
    run_mzc("triangulate", tmp_path / "c.zg", "-o", tmp_path / "out.obj", "--texture", tmp_path / "skin.png",
            check=True)
    assert (tmp_path / "out.mtl").read_text() == "newmtl grid_colours\nKa 1 1 1\nKd 1 1 1\nmap_Kd skin.png\n"
    back, expected = read_mesh(tmp_path / "out.obj"), grid_to_mesh(grid)
    np.testing.assert_array_equal(back.points, expected.points)
    np.testing.assert_array_equal(back.triangles, expected.triangles)
    np.testing.assert_array_equal(back.colors, expected.colors)
    assert back.dropped == ()
    for arguments in (["-o", tmp_path / "x.ply"], ["-o", tmp_path / "x.obj", "--vertices", "100"]):
        result = run_mzc("triangulate", tmp_path / "c.zg", *arguments, "--texture", tmp_path / "x.png")
        assert result.returncode == 2 and b"--texture" in result.stderr and b"Traceback" not in result.stderr
    assert not [path.name for path in tmp_path.iterdir() if path.name.startswith("x.")]


def test_triangulate_texture_of_a_multi_chart_grid_reads_back_as_its_vertex_coloured_mesh(tmp_path):
    """--texture on the ball's 6 charts: the same points, the same triangles (the seams' first) and,
    read back by mzc, every vertex its colour in the vertex-coloured mesh (a seam's triangle takes
    one texel, and a vertex's own comes last)."""
    from mzc.formats import zgrid
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    from conftest import run_mzc

    charted = slice_surface(ball()[0], charts=6)
    (tmp_path / "charts.zg").write_bytes(zgrid.write(charted, raw="float64"))
    run_mzc("triangulate", tmp_path / "charts.zg", "-o", tmp_path / "x.obj", "--texture", tmp_path / "x.png",
            check=True)
    back, expected = read_mesh(tmp_path / "x.obj"), grid_to_mesh(charted)
    np.testing.assert_array_equal(back.points, expected.points)
    as_set = lambda triangles: np.unique(triangles, axis=0)  # noqa: E731   (each corner order kept)
    np.testing.assert_array_equal(as_set(back.triangles), as_set(expected.triangles))
    np.testing.assert_array_equal(back.colors, expected.colors)


@pytest.mark.parametrize("layout", ["texcoord", "texture_uv"])
def test_a_ply_texture_file_is_sampled_at_its_texture_coordinates(tmp_path, layout):
    """PLY's ``comment TextureFile`` with a face's ``texcoord`` list (u v a corner) or the
    vertices' ``texture_u texture_v``: the vertices get the image's colours, as an OBJ's do."""
    from mzc.meshes import read_mesh

    obj_mesh = read_mesh(textured_obj(tmp_path))   # writes skin.png
    mesh = coloured_surface()
    uv = mesh.points[:, :2] / [WIDTH, HEIGHT]
    vertex_uv = layout == "texture_uv"
    header = ("ply\nformat ascii 1.0\ncomment TextureFile skin.png\n"
              f"element vertex {len(mesh.points)}\nproperty double x\nproperty double y\nproperty double z\n"
              + ("property float texture_u\nproperty float texture_v\n" if vertex_uv else "")
              + f"element face {len(mesh.triangles)}\nproperty list uchar int vertex_indices\n"
              + ("" if vertex_uv else "property list uchar float texcoord\n") + "end_header\n")
    vertices = [" ".join(repr(v) for v in point + (uv[i].tolist() if vertex_uv else []))
                for i, point in enumerate(mesh.points.tolist())]
    faces = [f"3 {a} {b} {c}" + ("" if vertex_uv else " 6 " + " ".join(repr(v) for v in uv[[a, b, c]].ravel().tolist()))
             for a, b, c in mesh.triangles.tolist()]
    (tmp_path / "face.ply").write_text(header + "\n".join(vertices + faces) + "\n")
    read = read_mesh(tmp_path / "face.ply")
    assert np.abs(read.colors.astype(int) - obj_mesh.colors).max() <= 1 and read.dropped == ()


def stripes(columns):
    """The red at u (0..1) of a texture ``columns`` pixels wide of vertical stripes 8 pixels wide,
    200 and 30 in turn (u = 1 in the last pixel): detail far finer than two triangles."""
    return lambda u: np.where((np.minimum(np.floor(u * columns), columns - 1) // 8) % 2 == 0, 200, 30)


@pytest.mark.parametrize("layout", ["obj", "obj quad", "ply texcoord"])
def test_slice_samples_a_texture_at_every_node_not_only_at_the_vertices(tmp_path, layout):
    """A square of two triangles textured with 9 stripes: its four vertices all sit on red, so
    their colours say nothing of the stripes, but each node takes the image at its own texture
    coordinates (its triangle's corners' uv mixed by its barycentric weights): the nodes' red
    follows the stripes (within 2 levels away from their edges), in an OBJ (of two triangles, or
    a quad and a triangle, whose corners' uv fan as their vertices do) and in a PLY whose faces list their
    corners' uv."""
    from PIL import Image

    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    columns = 72
    red = stripes(columns)
    pixels = np.zeros((4, columns, 3), dtype=np.uint8)
    pixels[..., 0] = red((np.arange(columns) + 0.5) / columns)
    Image.fromarray(pixels).save(tmp_path / "stripes.png")
    corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
    if layout.startswith("obj"):
        (tmp_path / "s.mtl").write_text("newmtl s\nmap_Kd stripes.png\n")
        faces = ["f 1/1 3/3 4/4", "f 1/1 2/2 3/3"]
        if layout == "obj quad":   # a quad and a triangle: a ragged fan, the top edge's midpoint on red too
            corners = [*corners, (0.5, 1)]
            faces = ["f 2/2 3/3 5/5 1/1", "f 1/1 5/5 4/4"]
        lines = ["mtllib s.mtl", *(f"v {x} {y} 0" for x, y in corners), *(f"vt {x} {y}" for x, y in corners),
                 *faces]
        (tmp_path / "square.obj").write_text("\n".join(lines) + "\n")
        mesh = read_mesh(tmp_path / "square.obj")
    else:
        faces = [(0, 1, 2), (0, 2, 3)]
        lines = ["ply", "format ascii 1.0", "comment TextureFile stripes.png", "element vertex 4",
                 "property float x", "property float y", "property float z", "element face 2",
                 "property list uchar int vertex_indices", "property list uchar float texcoord", "end_header",
                 *(f"{x} {y} 0" for x, y in corners),
                 *(f"3 {' '.join(map(str, f))} 6 {' '.join(f'{corners[i][0]} {corners[i][1]}' for i in f)}"
                   for f in faces)]
        (tmp_path / "square.ply").write_text("\n".join(lines) + "\n")
        mesh = read_mesh(tmp_path / "square.ply")
    assert (mesh.colors[:, 0] >= 150).all()   # every vertex on red: the stripes lie between them
    grid = slice_surface(mesh, d1=0.01)
    points = grid.to_input_frame(grid.node_points()[grid.valid])
    u = points[:, 0]
    away = np.abs(u * columns / 8 - np.round(u * columns / 8)) > 0.1   # off a stripe's edge
    measured = grid.colors[grid.valid][:, 0].astype(int)
    assert away.sum() > 1000 and np.abs(measured - red(u))[away].max() <= 2


def test_a_raster_of_a_coloured_grid_names_the_colours_it_drops_and_refuses_charts(tmp_path):
    """A GeoTIFF or ESRI grid holds heights alone: writing a grid with colours (whole, or a tiled
    11.0 file tile by tile) says so in one warning; a multi-chart grid is no raster at all."""
    from test_fine_colour import two_charts

    import mzc
    from mzc.formats import zgrid
    from mzc.grid import ZGrid
    from mzc.ops.slicing import slice_surface

    from conftest import run_mzc

    grid = slice_surface(coloured_surface(), d1=0.2)
    (tmp_path / "c.zg").write_bytes(zgrid.write(grid, raw="float64"))
    (tmp_path / "t.mzw2").write_bytes(mzc.encode(grid, "dwt2d", max_error=0.05, tile=16))
    for source, output, name in (("c.zg", "c.asc", "ESRI ASCII grid"), ("c.zg", "c.tif", "GeoTIFF"),
                                 ("t.mzw2", "t.tif", "GeoTIFF")):
        result = run_mzc("decode", source, "-o", output, cwd=tmp_path, check=True)
        assert result.stderr.decode() == (f"mzc: warning: not kept: the nodes' colours (a {name} holds the heights "
                                          "alone; the z-grid and a dwt2d file keep them)\n"), source
    charted = ZGrid(np.ones((2, 4)), 1, 1, charts=two_charts())
    (tmp_path / "charts.zg").write_bytes(zgrid.write(charted, raw="float64"))
    result = run_mzc("decode", "charts.zg", "-o", "charts.tif", cwd=tmp_path)
    assert result.returncode == 1 and b"a raster holds one planar grid" in result.stderr
    assert not (tmp_path / "charts.tif").exists()
