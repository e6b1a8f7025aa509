"""Multi-chart grids (spec/zgrid.md, Charts): the model, its files, densify, and slicing whole
objects into charts by default while faces, terrain and star-shaped surfaces keep one grid."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.codecs import dwt2d
from mzc.codecs.rows import dct
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.grid import Chart, ZGrid
from mzc.meshes import Mesh, read_mesh
from mzc.ops.charts import FACING, JOINING, SINGLE_COVER, single_grid_cover
from mzc.ops.densify import densify_grid
from mzc.ops.slicing import slice_surface
from mzc.ops.triangulation import CHART_JUMP_ANGLE, GridMesh, chart_meshes, grid_to_mesh
from mzc.projections import PLANAR_VIEWS, view_rotation
from mzc.samples import blob, icosphere

from codec_contract import header_fields
from conftest import REPO, edge_counts, sliced_shared_object

OBJECTS = REPO.parent / "shared" / "data" / "objects"
TRANSFORM = np.array([[0.0, -1.0, 0.0, 4.5], [1.0, 0.0, 0.0, -2.0], [0.0, 0.0, 1.0, 7.25]])


def two_charts(z=None):
    """A 6 x 9 grid of two charts, a +z one and a -x one, a column apart."""
    if z is None:
        z = np.arange(54.0).reshape(6, 9) / 7 + 10
        z[:, 4] = np.nan
        z[4:, 5:] = np.nan
    charts = (Chart("+z", 0, 0, 6, 4, -3, 2), Chart("-x", 0, 5, 4, 4, 4, -1))
    return ZGrid(z, 1.5, 1.5, transform=TRANSFORM, charts=charts)


def torus(rings=48, around=24, big=30.0, small=10.0):
    """A closed torus mesh about the z axis (genus 1: no one grid sees its inside)."""
    a, b = np.meshgrid(*(np.linspace(0, 2 * np.pi, count, endpoint=False) for count in (rings, around)))
    points = np.stack([(big + small * np.cos(b)) * np.cos(a), (big + small * np.cos(b)) * np.sin(a), small * np.sin(b)],
                      axis=-1).reshape(-1, 3)
    index = np.arange(rings * around).reshape(around, rings)
    right, up = np.roll(index, -1, axis=1), np.roll(index, -1, axis=0)
    corner = np.roll(right, -1, axis=0)
    triangles = np.concatenate([np.stack([index, right, corner], -1).reshape(-1, 3),
                                np.stack([index, corner, up], -1).reshape(-1, 3)])
    return Mesh(points, triangles)


def rough_torus(roughness=0.05):
    """The torus with every vertex moved a seeded random share ``roughness`` of its distance from
    the centre: many small facets turned every way, which cut into many small pieces."""
    mesh = torus()
    scale = 1 + roughness * np.random.default_rng(1).standard_normal((len(mesh.points), 1))
    return Mesh(mesh.points * scale, mesh.triangles)


def two_spheres():
    """Two separate unit-ish spheres: a many-part surface."""
    points, triangles = icosphere(3)
    return Mesh(np.concatenate([points * 10, points * 6 + [25.0, 0, 0]]),
                np.concatenate([triangles, triangles + len(points)]))


# --------------------------------------------------------------------------- the model


def test_a_chart_places_its_nodes_on_its_lattice_in_its_view():
    grid = two_charts()
    first, second = grid.chart_grids()
    assert first.origin == (-4.5, 3.0) and second.origin == (6.0, -1.5)
    node = second.to_input_frame(second.node_points()[1, 2])   # chart row 1, column 2
    u, v, w = (4 + 2) * 1.5, (-1 + 1) * 1.5, grid.z[1, 7]
    expected = TRANSFORM[:, :3] @ view_rotation("-x") @ np.array([u, v, w]) + TRANSFORM[:, 3]
    np.testing.assert_allclose(node, expected, rtol=1e-15)


@pytest.mark.parametrize("charts, message", [
    ((Chart("+z", 0, 0, 6, 5, 0, 0), Chart("-x", 0, 4, 4, 4, 0, 0)), "overlap"),
    ((Chart("+z", 0, 0, 7, 4, 0, 0),), "leaves the 6 x 9 grid"),
    ((Chart("+z", 0, 0, 6, 4, 0, 0),), "outside every chart"),
])
def test_charts_that_leave_overlap_or_miss_values_are_refused(charts, message):
    with pytest.raises(MzcError, match=message) as error:
        ZGrid(two_charts().z, 1.5, 1.5, charts=charts)
    assert error.value.field == "charts"


@pytest.mark.parametrize("bad", [{"origin": (1.0, 0.0)}, {"projection": "spherical", "radius": 50.0}])
def test_a_multi_chart_grid_is_planar_at_origin_zero(bad):
    with pytest.raises(MzcError, match="planar, at origin 0 0"):
        ZGrid(two_charts().z, 1.5, 1.5, charts=two_charts().charts, **bad)


@pytest.mark.parametrize("view, field", [("+w", "view"), (1.5, "row0")])
def test_a_chart_is_one_of_six_views_with_whole_places(view, field):
    with pytest.raises(MzcError):
        Chart(view, 0, 0, 1, 1, 0, 0) if field == "view" else Chart("+z", view, 0, 1, 1, 0, 0)


# --------------------------------------------------------------------------- files


def test_a_multi_chart_zgrid_is_4_0_raw_and_reads_back_exactly():
    grid = two_charts()
    data = zgrid.write(grid, raw="float64")
    assert data.startswith(b"mzc-zgrid 4.0\n") and b"\ncharts +z 0 0 6 4 -3 2 -x 0 5 4 4 4 -1\n" in data
    back = read_any(data, "t.zg")
    assert back.charts == grid.charts and back.z.tobytes() == grid.z.tobytes()
    with pytest.raises(MzcError, match="raw body"):
        zgrid.write(grid)


@pytest.mark.parametrize("line, message", [
    ("charts +z 0 0 6 4 -3", "7 values per chart"),
    ("charts +z 0 0 6 4 -3 two", "not an integer"),
    ("charts +q 0 0 6 4 -3 2 -x 0 5 4 4 4 -1", "chart view"),
    ("charts +z 0 0 6 5 -3 2 -x 0 4 4 4 4 -1", "overlap"),
])
def test_a_bad_charts_line_is_refused_naming_its_line(line, message):
    data = zgrid.write(two_charts(), raw="float64")
    header, payload = data.split(b"\ndata\n", 1)
    lines = [text if not text.startswith(b"charts ") else line.encode() for text in header.split(b"\n")]
    damaged = b"\n".join(text for text in lines if not text.startswith(b"crc32 ")) + b"\ndata\n" + payload
    from mzc.formats.header import with_checksum

    with pytest.raises(MzcError, match=message) as error:
        read_any(with_checksum(damaged), "t.zg")
    assert error.value.field == "charts" and error.value.line == lines.index(line.encode()) + 1


def test_a_charts_line_in_a_3_0_file_is_refused_as_needing_a_newer_version():
    data = zgrid.write(two_charts(), raw="float64").replace(b"mzc-zgrid 4.0", b"mzc-zgrid 3.0")
    from mzc.formats.header import with_checksum

    header, payload = data.split(b"\ndata\n", 1)
    header = b"\n".join(line for line in header.split(b"\n") if not line.startswith(b"crc32 "))
    with pytest.raises(MzcError, match="newer major version"):
        read_any(with_checksum(header + b"\ndata\n" + payload), "t.zg")


def test_dwt2d_codes_every_chart_within_one_bound():
    rng = np.random.default_rng(3)
    z = two_charts().z + rng.normal(0, 0.3, (6, 9))
    grid = two_charts(z)
    back = read_any(dwt2d.write(grid, max_error=0.05), "t.mzw2")
    assert back.charts == grid.charts and np.array_equal(back.valid, grid.valid)
    assert np.nanmax(np.abs(back.z - grid.z)) <= 0.05


def test_a_negative_chart_view_number_is_refused_not_read_from_the_end(monkeypatch):
    """A view number of -5 would pick CHART_VIEWS[-5] (-x) as Python indexes; the spec says 0..5."""

    class Shifted(tuple):
        def index(self, view, *args):   # each view written as its number minus six
            return super().index(view) - 6

    views = dwt2d.CHART_VIEWS
    monkeypatch.setattr(dwt2d, "CHART_VIEWS", Shifted(views))
    data = dwt2d.write(two_charts(), max_error=0.05)
    monkeypatch.setattr(dwt2d, "CHART_VIEWS", views)
    with pytest.raises(MzcError, match="view number is not 0..5"):
        read_any(data, "t.mzw2")


def test_the_row_codecs_refuse_charts_in_one_line():
    with pytest.raises(MzcError, match="codes one chart; the grid has 2") as error:
        dct.write(two_charts(), quality=50)
    assert error.value.field == "charts"


# --------------------------------------------------------------------------- densify and meshes


def test_densify_works_chart_by_chart():
    grid = two_charts()
    dense = densify_grid(grid, 2)
    assert dense.shape == (16, 9) and dense.d1 == 0.5
    assert dense.charts == (Chart("+z", 0, 0, 16, 4, -3, 6), Chart("-x", 0, 5, 10, 4, 4, -3))
    for chart, part in zip(dense.chart_grids(), grid.chart_grids()):
        alone = densify_grid(part, 2)
        np.testing.assert_array_equal(chart.z, alone.z)
        np.testing.assert_array_equal(chart.to_input_frame(chart.node_points()[::3]),
                                      part.to_input_frame(part.node_points()))


def test_a_multi_chart_mesh_is_its_charts_meshes_zipped():
    grid = two_charts()
    mesh = grid_to_mesh(grid)
    parts = [grid_to_mesh(chart, CHART_JUMP_ANGLE) for chart in grid.chart_grids()]
    count = sum(len(part.points) for part in parts)
    np.testing.assert_array_equal(mesh.points[:count], np.concatenate([part.points for part in parts]))
    assert len(mesh.triangles) >= sum(len(part.triangles) for part in parts) and mesh.grid is grid


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_the_charts_meshes_made_at_once_are_each_charts_own_one_after_the_other(data):
    """``chart_meshes`` (every chart's cells at once over the grid's values) gives each chart
    grid's GridMesh one after the other, point for point, triangle for triangle and colour for
    colour: charts packed side by side (no triangle across two), holes, steps steeper than the
    jump angle, any view and place on the lattice."""
    rows, widths = data.draw(st.integers(1, 6)), data.draw(st.lists(st.integers(1, 5), min_size=1, max_size=4))
    z = np.full((rows, sum(widths)), np.nan)
    charts, col0 = [], 0
    for width in widths:
        height = data.draw(st.integers(1, rows))
        row0 = data.draw(st.integers(0, rows - height))
        values = data.draw(st.lists(st.sampled_from([np.nan, 0.0, 0.5, 1.0, 3.0, 40.0, -2.5]),
                                    min_size=height * width, max_size=height * width))
        z[row0:row0 + height, col0:col0 + width] = np.reshape(values, (height, width))
        charts.append(Chart(data.draw(st.sampled_from(sorted(PLANAR_VIEWS))), row0, col0, height, width,
                            data.draw(st.integers(-5, 5)), data.draw(st.integers(-5, 5))))
        col0 += width
    colours = np.random.default_rng(len(charts)).integers(0, 256, (*z.shape, 3), dtype=np.uint8)
    grid = ZGrid(z, 1.5, 0.75, transform=TRANSFORM, charts=tuple(charts), colors=colours)
    angle = data.draw(st.sampled_from([0.0, 3.0, CHART_JUMP_ANGLE, 89.0]))
    points, triangles, chart, node = chart_meshes(grid, angle)
    parts = [GridMesh(part, angle).mesh() for part in grid.chart_grids()]
    offsets = np.cumsum([0] + [len(part.points) for part in parts])
    assert np.array_equal(points, np.concatenate([part.points for part in parts]))
    assert np.array_equal(triangles, np.concatenate([part.triangles + at for part, at in zip(parts, offsets)]))
    assert np.array_equal(chart, np.repeat(np.arange(len(parts)), np.diff(offsets)))
    assert np.array_equal(grid.colors.reshape(-1, 3)[node], np.concatenate([part.colors for part in parts]))


@pytest.mark.parametrize("mesh", [torus(), two_spheres()], ids=["torus", "two spheres"])
def test_the_rebuild_of_a_watertight_object_is_watertight_through_every_step(mesh):
    """slice, encode, decode and triangulate: no boundary edge, no edge in three triangles, and
    each edge run once each way (consistently oriented)."""
    grid = slice_surface(mesh)
    assert grid.charts is not None
    for rebuilt in (grid_to_mesh(grid), grid_to_mesh(read_any(dwt2d.write(grid, max_error=0.05), "t.mzw2"))):
        assert edge_counts(rebuilt.triangles) == (0, 0)
        directed = np.concatenate([rebuilt.triangles[:, [0, 1]], rebuilt.triangles[:, [1, 2]],
                                   rebuilt.triangles[:, [2, 0]]])
        assert len(np.unique(directed, axis=0)) == len(directed)


# --------------------------------------------------------------------------- slicing


def element_views(mesh, grid):
    """Per triangle of ``mesh`` that some chart holds (its centroid within 3 spacings of the
    chart's surface along the chart's lines), the best cosine between its normal and such a chart's
    view; NaN for triangles no chart holds."""
    corners = mesh.points[mesh.triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    centroid = corners.mean(axis=1)
    best = np.full(len(normal), np.nan)
    for chart in grid.chart_grids():
        local = chart.to_grid_frame(centroid)
        col = np.round((local[:, 0] - chart.origin[0]) / chart.d2).astype(int)
        row = np.round((local[:, 1] - chart.origin[1]) / chart.d1).astype(int)
        inside = (row >= 0) & (row < chart.shape[0]) & (col >= 0) & (col < chart.shape[1])
        held = np.zeros(len(normal), dtype=bool)
        held[inside] = np.abs(chart.z[row[inside], col[inside]] - local[inside, 2]) <= 3 * chart.d1
        cosine = normal @ chart.transform[:, 2]
        best[held] = np.fmax(best[held], cosine[held])
    return best


@pytest.mark.parametrize("mesh", [torus(), two_spheres()], ids=["torus", "two spheres"])
def test_a_closed_or_many_part_surface_is_cut_into_charts_that_see_it_within_60_degrees(mesh):
    single = slice_surface(mesh, charts=1)
    assert single.charts is None and single_grid_cover(single, mesh) < SINGLE_COVER
    grid = slice_surface(mesh)
    assert grid.charts is not None and {chart.view for chart in grid.charts} <= set(PLANAR_VIEWS)
    cosine = element_views(mesh, grid)
    assert np.mean(np.isnan(cosine)) < 0.01
    assert np.nanmin(cosine) >= JOINING and np.nanmean(cosine >= FACING) > 0.99


def test_small_pieces_join_a_neighbour_whose_view_sees_them_and_coverage_stays_whole(monkeypatch):
    """A rough torus cuts into many small pieces: those a neighbouring chart sees within 60
    degrees, in one layer with it, join it (fewer charts than with no joining), while every part
    is still held by a chart that sees it as well as before and the rebuild has no double layer
    (the zipper leaves some cracks on a surface this rough, joined or not)."""
    from mzc.ops import charts

    mesh = rough_torus()
    grid = slice_surface(mesh)
    monkeypatch.setattr(charts, "MERGE_CELLS", 0)
    unmerged = slice_surface(mesh)
    assert len(grid.charts) < len(unmerged.charts)
    merged, apart = element_views(mesh, grid), element_views(mesh, unmerged)
    assert np.mean(np.isnan(merged)) < 0.01 and np.nanmean(merged >= JOINING) > 0.99
    assert np.nanmean(merged >= FACING) >= np.nanmean(apart >= FACING)   # the rough facets' own share, no less
    assert edge_counts(grid_to_mesh(grid).triangles)[1] == 0   # no edge in three triangles: no double layer


@pytest.mark.parametrize("mesh", [rough_torus(), two_spheres()], ids=["rough torus", "two spheres"])
def test_charts_are_packed_in_a_strip_as_wide_as_the_widest_chart(mesh):
    """Blocks in shelves no wider than the widest chart (few charts share a row of the mask),
    tallest first, one invalid node apart."""
    grid = slice_surface(mesh)
    assert grid.z.shape[1] == max(chart.cols for chart in grid.charts)
    shelves = sorted({chart.row0 for chart in grid.charts})
    tallest = [max(chart.rows for chart in grid.charts if chart.row0 == row0) for row0 in shelves]
    assert tallest == sorted(tallest, reverse=True)
    assert all(later == row0 + height + 1 for row0, height, later in zip(shelves, tallest, shelves[1:]))


def fine_two_spheres():
    """``two_spheres`` at 5 subdivisions: 20,484 vertices, half its median edge under 1/200 of
    its longest side (the sampling ``data_spacing`` trusts)."""
    points, triangles = icosphere(5)
    return Mesh(np.concatenate([points * 10, points * 6 + [25.0, 0, 0]]),
                np.concatenate([triangles, triangles + len(points)]))


def test_a_multi_chart_grids_default_spacing_is_coarser_than_its_sources_and_one_grid_keeps_its_own(monkeypatch):
    """Issue 28: a closed object's charts at half its median edge hold several nodes per vertex;
    the default chart spacing (``mesh_chart_spacing``) is the area term on this evenly sampled
    mesh (0.6 of the side of its area per vertex, above half its median edge), so fewer nodes than
    at the former default (the source's spacing, what the
    fractions below give back), while a one-grid slice of the same mesh is the same grid
    whatever the chart fractions are, and --d1 still sets the charts' spacing."""
    from mzc.measure.metrics import triangle_areas
    from mzc.ops import slicing

    mesh = fine_two_spheres()
    grid, one = slice_surface(mesh), slice_surface(mesh, charts=1)
    edge = slicing.median_edge(mesh.points, mesh.triangles)
    per_vertex = np.sqrt(np.sum(triangle_areas(mesh.points, mesh.triangles)) / len(mesh.points))
    assert grid.charts is not None and grid.d1 == slicing.shortened(slicing.CHART_AREA_FRACTION * per_vertex)
    assert grid.d1 > slicing.CHART_EDGE_FRACTION * edge
    assert slice_surface(mesh, d1=0.3).d1 == 0.3
    monkeypatch.setattr(slicing, "CHART_EDGE_FRACTION", slicing.DATA_SPACING_FRACTION)
    monkeypatch.setattr(slicing, "CHART_AREA_FRACTION", 0.0)
    former = slice_surface(mesh)
    assert former.d1 == slicing.source_spacing(mesh)
    assert np.sum(grid.valid) < 0.9 * np.sum(former.valid)
    again = slice_surface(mesh, charts=1)
    assert again.charts is None and again.d1 == one.d1 and again.d2 == one.d2
    np.testing.assert_array_equal(again.z, one.z)


def test_a_low_poly_mesh_whose_rebuild_meets_the_floors_keeps_its_charts_at_1_200_of_its_longest_side():
    """The coarse torus (half its median edge above 1/200 of its longest side: ``low_poly``) is
    smooth between its few large triangles: its charts at 1/200 of the longest side rebuild within
    issue 28's floors (``meets_floors``), so they stay there, as fran's and the fuze's do."""
    from mzc.ops.slicing import MIN_NODES_ACROSS, longest_side, low_poly, meets_floors, shortened

    mesh = torus()
    grid = slice_surface(mesh)
    assert low_poly(mesh.points, mesh.triangles)
    assert grid.d1 == shortened(longest_side(mesh.points) / MIN_NODES_ACROSS)
    assert meets_floors(mesh.points, mesh.triangles, grid)


def test_a_low_poly_mesh_whose_rebuild_misses_a_floor_takes_charts_at_1_300_of_its_longest_side():
    """The rough torus's small facets turned every way miss the floors at 1/200 of its longest side
    (as the cycloidal's stitches and the dragon's fins do), so its default charts take 1/300 of it;
    a spacing given (--d1) is kept, whatever its rebuild measures."""
    from mzc.ops.slicing import (
        CHART_CAP_NODES_ACROSS,
        MIN_NODES_ACROSS,
        longest_side,
        low_poly,
        meets_floors,
        shortened,
    )

    mesh = rough_torus()
    longest = longest_side(mesh.points)
    given = slice_surface(mesh, d1=shortened(longest / MIN_NODES_ACROSS))
    assert low_poly(mesh.points, mesh.triangles) and given.d1 == shortened(longest / MIN_NODES_ACROSS)
    assert not meets_floors(mesh.points, mesh.triangles, given)
    assert slice_surface(mesh).d1 == shortened(longest / CHART_CAP_NODES_ACROSS)


@pytest.mark.parametrize("floor, value", [("FLOOR_RMS", 0.004), ("FLOOR_HAUSDORFF", 0.03), ("FLOOR_NEAR", 0.001)])
def test_a_rebuild_misses_the_floors_when_any_one_of_them_is_beyond_it(monkeypatch, floor, value):
    """The coarse torus's charts at 1/200 rebuild within 0.0057% D RMS, 0.045% D Hausdorff and all
    its area within 0.1% D (50,000 samples each way): each floor set tighter than its figure fails
    the check on its own."""
    from mzc.ops import slicing

    mesh = torus()
    grid = slice_surface(mesh)
    assert slicing.meets_floors(mesh.points, mesh.triangles, grid)
    monkeypatch.setattr(slicing, floor, value)
    assert not slicing.meets_floors(mesh.points, mesh.triangles, grid)


def test_a_mesh_dense_in_a_few_places_takes_its_spacing_from_its_area_per_vertex():
    """A fine sphere beside a coarse one twice its size: the median edge is the fine one's,
    the area per vertex the two's; the charts' spacing is CHART_AREA_FRACTION of the side of that
    area, coarser than half the median edge (the ogre's case)."""
    from mzc.measure.metrics import triangle_areas
    from mzc.ops import slicing

    fine, coarse = icosphere(5), icosphere(3)
    mesh = Mesh(np.concatenate([fine[0] * 10, coarse[0] * 20 + [35.0, 0, 0]]),
                np.concatenate([fine[1], coarse[1] + len(fine[0])]))
    per_vertex = np.sqrt(np.sum(triangle_areas(mesh.points, mesh.triangles)) / len(mesh.points))
    spacing = slice_surface(mesh).d1
    assert spacing == slicing.shortened(slicing.CHART_AREA_FRACTION * per_vertex)
    assert spacing > slicing.CHART_EDGE_FRACTION * slicing.median_edge(mesh.points, mesh.triangles)


def test_a_count_of_charts_caps_them_and_one_gives_one_grid():
    mesh = torus()
    assert slice_surface(mesh, charts=1).charts is None
    assert len(slice_surface(mesh, charts=3).charts) <= 3
    with pytest.raises(MzcError, match="projection shapes one grid") as error:
        slice_surface(mesh, charts=3, projection="spherical")
    assert error.value.field == "charts"
    with pytest.raises(MzcError, match="positive number of charts"):
        slice_surface(mesh, charts=0)


def test_a_star_shaped_ball_keeps_its_one_spherical_grid():
    grid = slice_surface(blob())
    assert grid.charts is None and grid.projection == "spherical"


def test_a_face_keeps_its_one_grid(f18):
    assert slice_surface(read_mesh(f18)).charts is None


@pytest.mark.parametrize("name", ["hand.ply", "armadillo.ply", "featuretype.ply"])
def test_the_shared_whole_objects_are_cut_into_charts(name):
    path = OBJECTS / name
    if not path.is_file():
        pytest.skip(f"shared objects not available ({path})")
    mesh = read_mesh(path)
    grid = slice_surface(mesh)
    assert grid.charts is not None and len(grid.charts) > 6
    assert read_any(zgrid.write(grid, raw="float64"), name).charts == grid.charts


def test_a_dwt2d_file_keeps_its_chart_records_in_the_payload_and_refuses_a_wrong_count():
    assert header_fields(dwt2d.write(two_charts(), max_error=0.05))["chart_count"] == ["2"]   # 8.0
    data = dwt2d.encode_whole(two_charts(), max_error=0.05, compact=False)[0]   # 4.0: text lines
    assert b"\nchart_count 2\n" in data and b"\ncharts " not in data
    from mzc.formats.header import with_checksum

    header, payload = data.split(b"\ndata\n", 1)
    header = b"\n".join(line for line in header.split(b"\n") if not line.startswith(b"crc32 "))
    for count in (b"1", b"3"):
        damaged = with_checksum(header.replace(b"chart_count 2", b"chart_count " + count) + b"\ndata\n" + payload)
        with pytest.raises(MzcError) as error:
            read_any(damaged, "t.mzw2")
        assert error.value.field == "data"


def test_info_lists_the_charts(tmp_path, mzc):
    path = tmp_path / "t.mzw2"
    path.write_bytes(dwt2d.write(two_charts(), max_error=0.05))
    header_only = mzc("info", path, check=True).stdout.decode()
    assert "charts    2 (records in the payload" in header_only and "cut by    charts" in header_only
    decoded = mzc("info", "--decode", path, check=True).stdout.decode()
    assert "charts    2 (1 +z, 1 -x)" in decoded and "-x 4 x 4 at row 0, column 5; lattice 4 -1" in decoded


def test_the_zarr_codec_refuses_a_multi_chart_chunk_in_one_line():
    pytest.importorskip("numcodecs")
    from mzc.zarr import Dwt2d

    with pytest.raises(MzcError, match="multi-chart grid") as error:
        Dwt2d(max_error=0.05).decode(b"d" + dwt2d.write(two_charts(), max_error=0.05))
    assert error.value.field == "charts"


def test_the_hand_comes_back_closed_and_whole(tmp_path):
    """The one clean closed scan of ../shared/data/objects: its charts' rebuild is closed, its
    whole-surface RMS within 0.02% of the box diagonal D, and 99.5% of its area within 0.1% D."""
    from mzc.measure.metrics import distance_to_mesh, sample_surface, surface_distance

    mesh, rebuilt, diagonal = sliced_shared_object("hand.ply")
    assert edge_counts(rebuilt.triangles) == (0, 0)
    assert surface_distance((mesh.points, mesh.triangles), (rebuilt.points, rebuilt.triangles),
                            samples=20_000)["rms"] <= 0.0002 * diagonal
    samples = sample_surface(mesh.points, mesh.triangles, 20_000, np.random.default_rng(0))[0]
    assert np.mean(distance_to_mesh(samples, rebuilt.points, rebuilt.triangles) <= 0.001 * diagonal) >= 0.995


def test_diff_measures_a_multi_chart_grids_nodes_by_their_distance_to_the_other_surface():
    from mzc.api import compare

    mesh = torus()
    grid = slice_surface(mesh)
    exact = compare(grid, mesh)
    assert exact["grid_rmse"] < 1e-9 and "surface_rms" in exact   # every node lies on the torus
    moved = grid.with_z(grid.z + 0.25)   # each node 0.25 further along its chart's line
    report = compare(moved, mesh)
    assert 0.1 < report["grid_rmse"] <= 0.25 + 1e-9


def thin_strip(width):
    """A Piece of two triangles seen along +z: a strip from x = 0.1 to 10.1 and y = 0.3 to
    0.3 + width on the plane z = 2 + 0.1 x, of a lattice of spacing 1."""
    from mzc.ops.charts import Piece

    x, y = np.array([0.1, 10.1, 10.1, 0.1]), np.array([0.3, 0.3, 0.3 + width, 0.3 + width])
    points = np.column_stack([x, y, 2 + 0.1 * x])
    return Piece(0, points, np.array([[0, 1, 2], [0, 2, 3]]))


def test_a_piece_thinner_than_a_cell_takes_its_plane_at_the_nodes_about_it():
    """No node line meets a strip 0.4 cells wide between two lattice rows: its chart would hold no
    triangle (the dragon's fins, missing from its rebuild). Its plane is carried to the nodes within
    a spacing of it, so its chart has cells, every node on the strip's plane."""
    view, i0, j0, z = thin_strip(0.4).block(1.0)
    valid = ~np.isnan(z)
    assert view == "+z" and j0 == 0 and z.shape[0] == 2 and valid.sum() >= 18
    cols = i0 + np.nonzero(valid)[1]
    np.testing.assert_allclose(z[valid], 2 + 0.1 * cols, rtol=0, atol=1e-12)


def test_a_piece_wide_enough_keeps_only_the_nodes_its_lines_meet():
    """A strip 3.4 cells wide has cells of its own: its block holds the lattice's hits, no more."""
    view, i0, j0, z = thin_strip(3.4).block(1.0)
    rows, cols = np.nonzero(~np.isnan(z))
    assert (j0 + rows).min() == 1 and (j0 + rows).max() == 3 and (i0 + cols).min() == 1 and (i0 + cols).max() == 10


@pytest.mark.parametrize("name", ["dragon.ply", "cycloidal.ply", "featuretype.ply"])
def test_the_low_poly_objects_meet_issue_28s_floor(name):
    """The objects of few large triangles, charted at 1/300 of their longest side where 1/200 misses
    a floor (the cycloidal's long stitches, the dragon's coarse bends), featuretype at 1/200, with
    their thin fins kept: whole-surface RMS within 0.02% of D, 99.5% of the area within 0.1% D, and
    nothing of the original (the dragon's fins were 1.35% D from its rebuild) beyond 0.75% D."""
    mesh, rebuilt, diagonal = sliced_shared_object(name)
    assert_within_the_floor(mesh, rebuilt, diagonal)


@pytest.mark.parametrize("name", ["fran/fran.obj", "fuze/fuze.obj"])
def test_the_smooth_low_poly_scans_keep_their_charts_at_1_200_and_meet_the_floor(name):
    """fran's and the fuze's few large triangles lie on a smooth surface: their charts at 1/200 of the
    longest side rebuild within the floor (issue 32: 2.2x fewer nodes than at 1/300)."""
    from mzc.ops.slicing import MIN_NODES_ACROSS, longest_side, shortened

    mesh = read_mesh(REPO / "tests" / "data" / "public" / name)
    grid = slice_surface(mesh)
    assert grid.d1 == shortened(longest_side(mesh.points) / MIN_NODES_ACROSS)
    assert_within_the_floor(mesh, grid_to_mesh(grid), float(np.linalg.norm(np.ptp(mesh.points, axis=0))))


def assert_within_the_floor(mesh, rebuilt, diagonal):
    """Issue 28's floor, on 20,000 samples each way: ``rebuilt`` within 0.02% of ``diagonal`` RMS of
    ``mesh``, 99.5% of the mesh's area within 0.1%, none of it beyond 0.75%."""
    from mzc.measure.metrics import distance_to_mesh, sample_surface, surface_distance

    assert surface_distance((mesh.points, mesh.triangles), (rebuilt.points, rebuilt.triangles),
                            samples=20_000)["rms"] <= 0.0002 * diagonal
    samples = sample_surface(mesh.points, mesh.triangles, 20_000, np.random.default_rng(0))[0]
    there = distance_to_mesh(samples, rebuilt.points, rebuilt.triangles)
    assert np.mean(there <= 0.001 * diagonal) >= 0.995 and there.max() <= 0.0075 * diagonal


def test_a_piece_left_alone_beyond_60_degrees_of_its_view_takes_the_view_that_faces_it():
    """A small piece takes a neighbour's view up to 80 degrees off to join its chart; left a chart of
    its own (the dragon's, 76 degrees off +z, 0.6% D from its rebuild) it turns to the view that sees
    it within 60 degrees, and a piece its view sees within 60 degrees keeps it."""
    from mzc.ops.charts import VIEWS, facing_cosines, refaced, view_frames

    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.24, -0.97], [1.0, 0.0, 0.0]]) * 10
    triangles = np.array([[0, 2, 1]])
    corners = points[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    cosine, frames, area = facing_cosines(normal), view_frames(points), np.array([50.0])
    assert 0.17 < cosine[0, VIEWS.index("+z")] < FACING
    view, members = refaced(VIEWS.index("+z"), np.array([0]), frames, triangles, cosine, area, 1.0)
    assert VIEWS[view] == "+y" and list(members) == [0]
    assert refaced(VIEWS.index("+y"), np.array([0]), frames, triangles, cosine, area, 1.0)[0] == VIEWS.index("+y")


def test_a_thin_pieces_widened_nodes_are_those_within_a_spacing_of_its_nearest_triangle():
    """``widened`` measures each node only against the triangles whose grown box holds it: the same
    heights as measuring every node against every triangle, the nearest triangle's plane at each
    where it rises at most WIDENED_RISE spacings beyond the triangle's heights."""
    from mzc.ops.charts import WIDENED_RISE, widened

    rng = np.random.default_rng(3)
    corners = np.concatenate([rng.uniform(0, 12, (9, 3, 2)), rng.uniform(1, 3, (9, 3, 1))], axis=2)
    xs, ys = np.arange(-2, 15) * 1.0, np.arange(-1, 14) * 1.0
    heights = widened(corners, xs, ys, 1.0)
    for row, y in enumerate(ys):
        for col, x in enumerate(xs):
            reach = [min(segment_distance((x, y), t[k, :2], t[(k + 1) % 3, :2]) for k in range(3)) for t in corners]
            t = corners[int(np.argmin(reach))]
            normal = np.cross(t[1] - t[0], t[2] - t[0])
            with np.errstate(divide="ignore", invalid="ignore"):
                expected = t[0, 2] - (normal[0] * (x - t[0, 0]) + normal[1] * (y - t[0, 1])) / normal[2]
            rises = not t[:, 2].min() - WIDENED_RISE <= expected <= t[:, 2].max() + WIDENED_RISE
            if min(reach) > 1.0 or normal[2] <= 0 or rises:
                assert np.isnan(heights[row, col])
            else:
                assert heights[row, col] == pytest.approx(expected, abs=1e-9)


def segment_distance(point, a, b):
    """The distance from a 2D point to the segment a-b, plainly."""
    point, a, b = (np.asarray(v, dtype=float) for v in (point, a, b))
    along = np.clip(np.dot(point - a, b - a) / max(np.dot(b - a, b - a), 1e-300), 0, 1)
    return float(np.linalg.norm(point - (a + along * (b - a))))


def test_a_thin_piece_carries_its_plane_to_the_nodes_beside_it_but_not_a_slivers():
    """``widened``: a triangle facing its view carries its plane a spacing off it; a sliver nearly
    edge-on, whose plane there would stand 500 above it, carries nothing."""
    from mzc.ops.charts import widened

    xs = ys = np.arange(-1.0, 2.5, 0.5)
    facing = widened(np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]]), xs, ys, 1.0)
    assert facing[np.searchsorted(ys, 1.5), np.searchsorted(xs, 0.5)] == pytest.approx(0.75)   # z = y / 2
    sliver = widened(np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.001, 1.0]]]), xs, ys, 1.0)
    assert np.nanmax(np.abs(sliver)) <= 3.0 and np.isnan(sliver[np.searchsorted(ys, 0.5), np.searchsorted(xs, 0.5)])


def test_a_cloud_sliced_coarse_keeps_its_heights_within_the_object():
    """The armadillo's cloud at 3 times its own spacing: three nodes of a thin piece once stood 10^12
    away (a sliver's plane carried to them); every height lies within the object's box now."""
    from mzc.ops.slicing import source_spacing

    from conftest import shared_object

    mesh = shared_object("armadillo.ply")
    grid = slice_surface(mesh, d1=3 * source_spacing(mesh))
    extent = float(np.linalg.norm(np.ptp(mesh.points, axis=0)))
    assert np.abs(grid.z[grid.valid]).max() <= extent
