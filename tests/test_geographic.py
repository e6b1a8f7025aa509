"""Terrain the way GIS users have it (issue 30): a DEM in longitude and latitude takes --rmse,
--size and --max-error as vertical errors in its height unit, and its `x y z` export (a GIS
"export to xyz", coordinates printed to a few decimals) slices back to its own lattice in
degrees, never to a handful of nodes."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.errors import MzcError
from mzc.georef import crs_kind
from mzc.meshes import Mesh
from mzc.ops.slicing import lonlat_lattice, slice_surface

from codec_contract import header_fields
from conftest import run_mzc
from test_cli import assert_one_line_error

PUBLIC = Path(__file__).resolve().parent / "data" / "public"
BIJOU = PUBLIC / "west_bijou_escarpment_snippet.asc"   # 1 arc-second cells, WGS 84 (its .prj)


def export_points(grid):
    """The valid nodes of ``grid`` as (lon, lat, height) rows, as a GIS writes them."""
    xs, ys = np.meshgrid(grid.xs(), grid.ys())
    valid = grid.valid
    return np.column_stack([xs[valid], ys[valid], grid.z[valid]])


def export_text(grid, decimals=6):
    """``grid``'s valid nodes as `x y z` text with ``decimals`` decimals of a degree (GDAL's XYZ
    driver and most GIS exports round so)."""
    return "".join(f"{x:.{decimals}f} {y:.{decimals}f} {z:.0f}\n" for x, y, z in export_points(grid)).encode()


def valid_box(grid):
    """``grid``'s values over the box of its valid nodes (what an export of them can give back)."""
    rows, cols = np.flatnonzero(grid.valid.any(axis=1)), np.flatnonzero(grid.valid.any(axis=0))
    return grid.z[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]


# --- the codec: vertical errors ---------------------------------------------------------------


@pytest.mark.parametrize("target", [0.5, 2.0, 8.0])
def test_rmse_of_a_geographic_dem_is_its_vertical_rmse_as_diff_reports_it(tmp_path, target):
    """ASPRS and USGS state a DEM's accuracy as a vertical RMSE in metres: --rmse of a lon/lat grid
    is that, and `mzc diff` (whose grid_rmse is along z) measures it just under the target (within 5%)."""
    coded, decoded = tmp_path / "b.mzw2", tmp_path / "b.zg"
    run_mzc("encode", "--dwt2d", "--rmse", target, BIJOU, "-o", coded, check=True)
    assert header_fields(coded.read_bytes())["slope_limit"] == ["1"]   # equal steps: the lean means nothing in degrees
    run_mzc("decode", coded, "-o", decoded, check=True)
    report = dict(line.split() for line in run_mzc("diff", BIJOU, decoded, check=True).stdout.decode().splitlines())
    assert 0.95 * target <= float(report["grid_rmse"]) <= target


def test_size_of_a_geographic_dem_is_met_and_slope_scaled_steps_are_refused():
    grid = mzc.read(BIJOU)
    sizes = [len(mzc.encode(grid, size=size)) for size in (1500, 4000)]
    assert sizes[0] <= 1500 < sizes[1] <= 4000
    with pytest.raises(MzcError, match="degrees and metres") as error:
        mzc.encode(grid, rmse=1.0, slope_limit=2.0)
    assert error.value.field == "slope_limit"


def test_a_projected_dem_keeps_its_surface_rmse(tmp_path):
    """Only a geographic CRS makes the error vertical: the same heights in a projected CRS (the
    UTM of the same place) are measured across the surface, as before, and code differently."""
    from mzc.georef import WGS84_WKT

    grid = mzc.read(BIJOU)
    utm = ('PROJCS["WGS 84 / UTM zone 13N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,'
           '298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],'
           'UNIT["metre",1]]')
    metric = grid.with_z(grid.z, d1=30.86, d2=23.86, origin=(0.0, 0.0), crs=utm)
    geographic = grid.with_z(grid.z, crs=WGS84_WKT)
    assert b"slope_limit" not in mzc.encode(metric, rmse=1.0)
    assert mzc.encode(metric, rmse=1.0) != mzc.encode(geographic, rmse=1.0)


# --- x y z exports: recognised, never collapsed -----------------------------------------------


def test_a_lonlat_xyz_export_slices_to_its_own_lattice_in_degrees(tmp_path):
    """The 1 arc-second DEM printed to 6 decimals (0.0018 of a step off the lattice) comes back
    node for node at its step, in WGS 84; it was a 1 x 1 grid of spacing 0.5, from the metres of z."""
    grid = mzc.read(BIJOU)
    source, sliced = tmp_path / "bijou.xyz", tmp_path / "bijou.zg"
    source.write_bytes(export_text(grid))
    run_mzc("slice", source, "-o", sliced, check=True)
    back = mzc.read(sliced)
    assert back.shape == valid_box(grid).shape
    assert np.array_equal(back.z, valid_box(grid), equal_nan=True)
    assert (back.d1, back.d2) == (1 / 3600, 1 / 3600)   # the round angle printed, not 0.000277773
    assert back.origin == pytest.approx(grid.origin, abs=1e-9)   # nodes where the DEM had them, not where printed
    assert crs_kind(back.crs) == "geographic" and "WGS 84" in back.crs
    mesh = mzc.triangulate(back)   # in metres about its centre: 1 arc-second is 30.9 m of latitude
    assert np.ptp(mesh.points[:, 1]) == pytest.approx((back.shape[0] - 1) * 30.86, rel=2e-3)


def test_the_srtm_tile_exported_as_xyz_codes_to_a_vertical_rmse(tmp_path):
    """The SRTM tile in EPSG:4326 (int16 metres) as x y z: sliced, coded at --rmse 3 and decoded,
    its heights are 3 m RMS from the tile's."""
    pytest.importorskip("rasterio")
    tile = mzc.read(PUBLIC / "srtm_blurred_res.tif")
    source = tmp_path / "srtm.xyz"
    source.write_bytes(export_text(tile, decimals=4))
    grid = mzc.slice(source)
    assert grid.shape == tile.shape and np.array_equal(grid.z, tile.z)
    error = mzc.decode(mzc.encode(grid, rmse=3.0)).z - tile.z
    assert float(np.sqrt(np.mean(error ** 2))) == pytest.approx(3.0, rel=0.03)


def test_a_tile_export_starts_on_its_whole_degree():
    """A 3 arc-second tile from 7 E, 45 N printed to 6 decimals: origin 7 45 and step 1/1200
    exactly, as the tile's own header has them (the printed digits give 7.000000 and 0.000833)."""
    y, x = np.mgrid[0:50, 0:60]
    points = np.column_stack([np.round(7 + x.ravel() / 1200, 6), np.round(45 + y.ravel() / 1200, 6),
                              1500 + 100 * np.sin(x.ravel() / 5) + y.ravel()])
    grid = slice_surface(Mesh(points))
    assert grid.origin == (7.0, 45.0) and (grid.d1, grid.d2) == (3 / 3600, 3 / 3600) and grid.shape == (50, 60)
    assert np.array_equal(grid.z.ravel(), points[:, 2])


def test_a_dense_lonlat_cloud_gridded_coarser_is_binned_with_its_jumps_in_metres():
    """160,000 points of a 3 arc-second lattice at 9 arc-seconds are binned; a depth jump of 19
    spacings measured in degrees (0.05) had hidden every point but the front-most of each window,
    leaving 0.002% of the nodes valid; in metres the terrain is one layer and every node is there."""
    y, x = np.mgrid[0:400, 0:400]
    heights = 1500 + 800 * np.sin(x / 97.0) * np.cos(y / 61.0)
    points = np.column_stack([np.round(7 + x.ravel() / 1200, 6), np.round(45 + y.ravel() / 1200, 6), heights.ravel()])
    coarse = slice_surface(Mesh(points), d1=3 / 1200, d2=3 / 1200)
    assert coarse.shape == (134, 134) and np.isfinite(coarse.z).mean() > 0.99
    assert np.sqrt(np.nanmean((coarse.z - heights[::3, ::3]) ** 2)) < 0.5


def test_a_scattered_lonlat_cloud_is_refused_saying_why_not_collapsed(tmp_path):
    """Off any lattice (points moved by up to a fifth of a step), the cloud is not recognised and
    its default spacing comes from the metres of z: a grid of 1 x 1 nodes is refused in one line,
    and no file is written."""
    points = export_points(mzc.read(BIJOU))
    points[:, :2] += np.random.default_rng(1).uniform(-5e-5, 5e-5, (len(points), 2))
    source, sliced = tmp_path / "moved.xyz", tmp_path / "moved.zg"
    np.savetxt(source, points, fmt="%.7f %.7f %.1f")
    assert_one_line_error(run_mzc("slice", source, "-o", sliced), "8643 points gridded to 1 x 1 nodes", "degrees")
    assert not sliced.exists()


def test_options_that_would_cut_terrain_otherwise_are_refused():
    cloud = Mesh(export_points(mzc.read(BIJOU)))
    for option in ({"view": "+x"}, {"projection": "spherical"}, {"align": "pca"}, {"charts": 4}):
        with pytest.raises(MzcError, match="longitude and latitude") as error:
            slice_surface(cloud, **option)
        assert error.value.field == next(iter(option))
    coarse = slice_surface(cloud, d1=1 / 1200, d2=1 / 1200)   # 3 arc-seconds: spacings in degrees are taken
    assert coarse.shape == (23, 43) and crs_kind(coarse.crs) == "geographic"


def test_lattices_in_one_unit_are_not_taken_for_degrees():
    """A metric DEM near the origin (relief under its width) and a steep lattice object whose
    heights span fewer than 1000 steps keep the rules of any cloud: no CRS is made up."""
    y, x = np.mgrid[0:40, 0:60].astype(float)
    dem = np.column_stack([x.ravel(), y.ravel(), (20 * np.sin(x / 9) + y / 3).ravel()])
    tower = np.column_stack([x.ravel() * 0.1, y.ravel() * 0.1, (2 * np.hypot(x - 30, y - 20)).ravel()])
    for points in (dem, tower):
        assert lonlat_lattice(Mesh(points)) is None
        assert slice_surface(Mesh(points)).crs is None


@settings(max_examples=40, deadline=None)
@given(seconds=st.sampled_from([1 / 3, 1, 3, 7.5, 15, 30]), decimals=st.integers(6, 9),
       west=st.floats(-179, 170), south=st.floats(-80, 70), rows=st.integers(5, 40), cols=st.integers(5, 40))
def test_any_printed_lonlat_lattice_is_recognised_at_its_step(seconds, decimals, west, south, rows, cols):
    """Every arc-second step of the DEMs users have, printed to 6-9 decimals anywhere on the globe,
    is recognised at its exact step, not the one its printed ends give (the relief: 5 km a degree)."""
    step = seconds / 3600
    y, x = np.mgrid[0:rows, 0:cols]
    lon, lat = np.round(west + x * step, decimals), np.round(south + y * step, decimals)
    points = np.column_stack([lon.ravel(), lat.ravel(), 5000 * step * (x + y).ravel()])
    assert lonlat_lattice(Mesh(points)) == pytest.approx((step, step), rel=1e-12)   # the round angle itself


# --- diff: one frame for two geographic grids -------------------------------------------------


def test_diff_of_a_geographic_dem_against_its_own_crop_is_zero(tmp_path):
    """Both grids are placed in metres about the first one's centre: each about its own put the crop
    hundreds of metres off (432 m RMS before), in heights and in --surface alike."""
    from mzc.formats import zgrid

    grid = mzc.read(BIJOU)
    crop = grid.with_z(grid.z[10:50, 20:100].copy(), origin=(grid.origin[0] + 20 * grid.d2,
                                                             grid.origin[1] + 10 * grid.d1))
    (tmp_path / "crop.zg").write_bytes(zgrid.write(crop))
    report = mzc.compare(BIJOU, tmp_path / "crop.zg", surface=True)
    assert report["grid_count"] == crop.valid.sum() and report["grid_rmse"] < 1e-6
    assert report["surface_b_to_a_rms"] < 1e-6   # every point of the crop lies on the whole
    cli = dict(line.split() for line in run_mzc("diff", tmp_path / "crop.zg", BIJOU, "--rmse", "--count",
                                                check=True).stdout.decode().splitlines())
    assert float(cli["grid_rmse"]) < 1e-6 and int(cli["grid_count"]) == crop.valid.sum()


# --- map grids: --tap and round default spacings ----------------------------------------------


def terrain_cloud(count=4000, seed=3, west=635_601.37, south=848_887.91):
    """Scattered ground points of a hill over 300 m x 200 m of a projected CRS (metres)."""
    rng = np.random.default_rng(seed)
    x, y = west + 300 * rng.random(count), south + 200 * rng.random(count)
    return np.column_stack([x, y, 120 + 15 * np.sin((x - west) / 40) * np.cos((y - south) / 30)])


@pytest.mark.parametrize("spacing", [None, 2.0, 0.7])
def test_tap_puts_cell_edges_on_whole_multiples_of_the_spacing(spacing):
    """As gdalwarp -tap: each node is its cell's centre, the cells' edges on multiples of the
    spacing (given, or the round default), and the cells hold every point."""
    points = terrain_cloud()
    grid = slice_surface(Mesh(points), d1=spacing, tap=True)
    d = grid.d1
    assert grid.d2 == d and (spacing == d if spacing else d in (2.0, 2.5, 5.0))
    corner = np.array(grid.origin) - d / 2
    assert np.allclose(corner / d, np.round(corner / d), rtol=0, atol=1e-6)
    far = corner + np.array([grid.shape[1], grid.shape[0]]) * d
    assert (corner <= points[:, :2].min(axis=0)).all() and (far >= points[:, :2].max(axis=0)).all()
    assert (far - d < points[:, :2].max(axis=0)).all()   # no column or row of cells beyond the points
    assert np.isfinite(grid.z).mean() > 0.9


def test_a_cloud_with_a_crs_takes_a_round_default_spacing():
    """A LAS cloud in EPSG:2994 (feet): 20 where the data's own spacing was 21.92; without a CRS and
    without --tap the data's spacing is kept, to 3 significant digits."""
    pytest.importorskip("laspy")
    from mzc.meshes import read_mesh

    cloud = read_mesh(PUBLIC / "autzen_geo_proj.las")
    assert slice_surface(cloud).d1 == 20.0
    bare = Mesh(cloud.points)
    assert slice_surface(bare).d1 == 21.9   # the data's 21.9229, to 3 significant digits
    assert slice_surface(bare, tap=True).d1 == 20.0


def test_tap_keeps_a_lattice_already_aligned_and_resamples_one_that_is_not():
    """Nodes at cell centres of multiples of the step (a GeoTIFF's export) stay node for node; nodes
    on the multiples themselves move half a step, their values interpolated between the points."""
    y, x = np.mgrid[0:30, 0:40].astype(float)
    height = (20 * np.sin(x / 7) + 3 * y).ravel()
    centres = Mesh(np.column_stack([(x.ravel() + 0.5) * 5, (y.ravel() + 0.5) * 5, height]))
    aligned = slice_surface(centres, tap=True)
    assert aligned.shape == (30, 40) and aligned.d1 == 5.0 and aligned.origin == (2.5, 2.5)
    assert np.array_equal(aligned.z.ravel(), height)
    corners = Mesh(np.column_stack([x.ravel() * 5, y.ravel() * 5, height]))
    moved = slice_surface(corners, tap=True)
    assert moved.origin == (2.5, 2.5) and moved.shape == (29, 39)
    between = (height.reshape(30, 40)[:-1, :-1] + height.reshape(30, 40)[1:, 1:]) / 2
    assert np.allclose(moved.z, between, atol=2.0)


def test_tap_is_refused_where_cells_cannot_be_aligned(tmp_path):
    cloud = Mesh(terrain_cloud())
    for option in ({"rows": 20}, {"projection": "spherical"}, {"view": "+x"}, {"align": "pca"}, {"charts": 3}):
        with pytest.raises(MzcError, match="--tap aligns") as error:
            slice_surface(cloud, tap=True, **option)
        assert error.value.field == "tap"
    result = run_mzc("slice", BIJOU, "--tap", "-o", tmp_path / "x.zg")
    assert_one_line_error(result, "a raster is sliced as its own grid", "-tap")
    with pytest.raises(MzcError, match="True or False"):
        mzc.slice(cloud, tap="yes")


def test_tap_of_a_lonlat_export_aligns_on_whole_arc_seconds(tmp_path):
    """The West Bijou export (nodes at whole arc-seconds) with --tap: cells from whole arc-second to
    whole arc-second, each node a half-second, every one inside the DEM's extent."""
    source = tmp_path / "bijou.xyz"
    source.write_bytes(export_text(mzc.read(BIJOU)))
    run_mzc("slice", source, "--tap", "-o", tmp_path / "t.zg", check=True)
    grid = mzc.read(tmp_path / "t.zg")
    assert grid.d1 == grid.d2 == 1 / 3600 and crs_kind(grid.crs) == "geographic"
    seconds = np.array(grid.origin) * 3600
    assert np.allclose(seconds - 0.5, np.round(seconds - 0.5), rtol=0, atol=1e-6)
    assert grid.shape == (66, 128) and np.isfinite(grid.z).mean() > 0.95


@given(st.floats(1e-6, 1e6))
def test_round_spacing_is_one_two_two_and_a_half_or_five_times_a_power_of_ten(spacing):
    from mzc.ops.slicing import round_spacing

    rounded = round_spacing(spacing)
    mantissa, exponent = f"{rounded:e}".split("e")
    assert float(mantissa) in (1.0, 2.0, 2.5, 5.0) and rounded == float(f"{float(mantissa):g}e{int(exponent)}")
    assert max(rounded / spacing, spacing / rounded) <= 2 ** 0.5 * (1 + 1e-12)


# --- x y z text: millions of lines read at once -----------------------------------------------


@settings(max_examples=150, deadline=None)
@given(values=st.lists(st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3), min_size=1, max_size=30),
       extra=st.integers(0, 2), separator=st.sampled_from([" ", "\t", ",", ", ", "  "]),
       end=st.sampled_from(["\n", "\r\n", "\r"]), blank=st.booleans(), ragged=st.booleans(),
       comment=st.booleans(), bad=st.booleans())
def test_the_column_reader_reads_what_the_line_reader_reads(values, extra, separator, end, blank, ragged, comment,
                                                            bad):
    """Any x y z text (separators, line ends, extra columns, blank lines) reads to the same points
    either way; comments, ragged lines and bad tokens go to the line reader, which names the line."""
    from mzc.meshes import xyz

    lines = [separator.join([repr(v) for v in row] + ["7"] * extra) for row in values]
    if ragged:
        lines[0] += separator + "255"
    if comment:
        lines[-1] += " # a note"
    if bad:
        lines[-1] = lines[-1].replace(repr(values[-1][2]), "x1", 1)
    text = end.join(lines[:1] + [""] * blank + lines[1:]) + end
    fast = xyz.columns(text)
    assert (fast is None) == (ragged and len(lines) > 1 or comment or bad)
    try:
        slow = xyz.read_lines(text, "t.xyz").points
    except MzcError as error:
        assert bad and fast is None and error.line == len(lines) + (blank and len(lines) > 1)
        return
    assert fast is None or np.array_equal(fast, slow)
    assert np.array_equal(xyz.read(text.encode(), "t.xyz").points, np.array(values))


def test_a_three_arc_second_tile_export_slices_in_seconds(tmp_path):
    """1201 x 1201 lines of x y z (a 3 arc-second tile, 37 MB of text): read at once, not a line
    at a time (which took 9-12 s of it here), and sliced node for node."""
    import time

    y, x = np.mgrid[0:1201, 0:1201]
    heights = 1500 + 800 * np.sin(x / 97.0) * np.cos(y / 61.0)
    source = tmp_path / "tile.xyz"
    np.savetxt(source, np.column_stack([np.round(7 + x.ravel() / 1200, 6), np.round(45 + y.ravel() / 1200, 6),
                                        heights.ravel()]), fmt="%.6f %.6f %.1f")
    started = time.process_time()
    grid = mzc.slice(source)
    assert time.process_time() - started < 6
    assert grid.shape == (1201, 1201) and grid.origin == (7.0, 45.0) and np.allclose(grid.z, heights, atol=0.05)


def test_info_gives_a_geographic_grids_spacings_in_metres_from_its_header(tmp_path):
    """1 arc-second at 39.5 degrees north is 30.84 m of latitude and 23.89 m of longitude on WGS 84,
    for the raster and for its compressed file read from the header alone (whose crs line the
    header-only grid had ignored); a projected grid gets no such line."""
    coded = tmp_path / "b.mzw2"
    run_mzc("encode", "--dwt2d", "--max-error", "1", BIJOU, "-o", coded, check=True)
    for source in (BIJOU, coded):
        lines = run_mzc("info", source, check=True).stdout.decode().splitlines()
        assert lines[4].split()[:6] == ["in", "metres", "d1", "30.84", "d2", "23.89"]
    assert "in metres" not in run_mzc("info", PUBLIC / "hugo_site.asc", check=True).stdout.decode()


def test_the_default_target_of_a_geographic_grid_is_a_tenth_of_its_spacing_in_metres():
    """encode without a target: --rmse a tenth of the smaller spacing, a lon/lat grid's taken in
    metres at its centre (1 arc-second north at 39.5 N is 30.8 m, east 23.9 m: 2.39 m)."""
    from mzc.codecs.dwt2d import default_rmse
    from mzc.georef import centre_of, metres_per_unit

    grid = mzc.read(BIJOU)
    east, north = metres_per_unit(grid.crs, centre_of(grid)[1])
    assert 2.0 < default_rmse(grid) == 0.1 * min(grid.d2 * east, grid.d1 * north) < 3.2
    assert mzc.encode(grid) == mzc.encode(grid, rmse=default_rmse(grid))


def test_diff_spacings_of_geographic_grids_are_metres_as_its_help_says(tmp_path):
    """--d1/--d2 set the common grid in the metres both grids are compared in (about A's centre):
    60 m gives a 60 m error grid over the DEM's extent in metres, and --help says so."""
    from mzc.georef import metric_frame

    grid = mzc.read(BIJOU)
    metric = metric_frame(grid)
    errors = tmp_path / "errors.zg"
    report = dict(line.split() for line in run_mzc("diff", BIJOU, BIJOU, "--count", "--max", "--d1", 60, "--d2", 60,
                                                  "--error-grid", errors, check=True).stdout.decode().splitlines())
    written = mzc.read(errors)
    assert (written.d1, written.d2, written.crs) == (60.0, 60.0, None)
    rows, cols = metric.shape
    assert abs(written.shape[0] - (rows - 1) * metric.d1 / 60) <= 2
    assert abs(written.shape[1] - (cols - 1) * metric.d2 / 60) <= 2
    assert int(report["grid_count"]) > 0.8 * written.shape[0] * written.shape[1] and float(report["grid_max"]) < 1e-6
    assert mzc.compare(BIJOU, BIJOU, d1=60, d2=60)["grid_count"] == int(report["grid_count"])
    help_text = " ".join(run_mzc("diff", "--help", check=True).stdout.decode().split())
    assert "in metres for a geographic grid" in help_text
