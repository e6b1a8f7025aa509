"""Rasters written the way GIS users have them (issue 30): an integer DEM coded with a max error
comes back as integers of its own type with its no-data value (mzc-dwt2d 6.0, spec/dwt2d.md,
Rounding), and GeoTIFFs take GDAL's creation options and come as Cloud Optimized GeoTIFFs on
request, each checked with rasterio (GDAL) on public and generated DEMs.
"""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc as api
from mzc.codecs import dwt2d
from mzc.errors import MzcError
from mzc.formats.header import split_magic
from mzc.grid import Raster, ZGrid

from codec_contract import header_fields, rechecksummed

rasterio = pytest.importorskip("rasterio")
from rasterio.crs import CRS  # noqa: E402
from rasterio.transform import Affine  # noqa: E402

PUBLIC = Path(__file__).resolve().parent / "data" / "public"
SRTM = PUBLIC / "srtm_blurred_res.tif"   # 138 x 138 int16 metres, EPSG:4326, as SRTM tiles are


def read_tif(path):
    """(values, valid mask, dtype, nodata) of a GeoTIFF as GDAL reads it."""
    with rasterio.open(path) as dataset:
        return dataset.read(1), dataset.read_masks(1) > 0, dataset.dtypes[0], dataset.nodata


def int16_dem_with_nodata(path):
    """A 70 x 90 int16 DEM in UTM with a block of no-data cells (-32768), written by GDAL."""
    rng = np.random.default_rng(3)
    r, c = np.mgrid[0:70, 0:90]
    z = np.round(900 + 60 * np.sin(r / 9) * np.cos(c / 13) + rng.normal(0, 3, r.shape))
    z[10:16, 20:31] = -32768
    return written_int16_dem(path, z)


def written_int16_dem(path, z):
    """``z`` written by GDAL as an int16 GeoTIFF in UTM 11N, 30 m cells, no-data -32768: ``path``."""
    rows, cols = z.shape
    profile = {"driver": "GTiff", "width": cols, "height": rows, "count": 1, "dtype": "int16", "nodata": -32768,
               "transform": Affine(30, 0, 440720, 0, -30, 3751320), "crs": CRS.from_epsg(32611)}
    with rasterio.open(path, "w", **profile) as dataset:
        dataset.write(z.astype("int16"), 1)
    return path


# --- integer samples come back as integers -----------------------------------------------


@pytest.mark.parametrize("max_error, kept", [(0.25, 0), (0.5, 0), (0.99, 0), (1, 1), (1.7, 1), (3, 3)])
def test_an_int16_dem_at_a_max_error_comes_back_int16_within_it(mzc, tmp_path, max_error, kept):
    """SRTM-style int16 in, int16 out: every value an integer within floor(E) <= E of the input's."""
    coded, back = tmp_path / "dem.mzw2", tmp_path / "back.tif"
    mzc("encode", "--dwt2d", "--max-error", max_error, SRTM, "-o", coded, check=True)
    assert header_fields(coded.read_bytes())["rounding"] == ["integer"]   # as 6.0 does, in 7.0
    mzc("decode", coded, "-o", back, check=True)
    values, valid, dtype, _ = read_tif(back)
    source = read_tif(SRTM)[0]
    assert dtype == "int16" and valid.all()
    assert np.abs(values.astype(int) - source).max() == kept   # the bound is met, and used
    assert api.decode(coded.read_bytes()).z.tobytes() == api.read(back).z.tobytes()


def test_the_no_data_value_and_cells_come_back(mzc, tmp_path):
    source = int16_dem_with_nodata(tmp_path / "dem.tif")
    coded, back = tmp_path / "dem.mzw2", tmp_path / "back.tif"
    mzc("encode", "--dwt2d", "--max-error", "2", source, "-o", coded, check=True)
    mzc("decode", coded, "--format", "tif", "-o", back, check=True)
    values, valid, dtype, nodata = read_tif(back)
    original, original_valid, _, _ = read_tif(source)
    assert (dtype, nodata) == ("int16", -32768)
    assert np.array_equal(valid, original_valid) and (values[~valid] == -32768).all()
    assert np.abs(values[valid].astype(int) - original[valid]).max() <= 2


def test_the_integer_file_is_smaller_than_the_float_one_at_the_same_bound(tmp_path):
    """Coding an integer source at floor(E) + 1/2 costs fewer bytes than at E (E = 1, 0.25)."""
    grid = api.read(SRTM)
    as_floats = grid.with_z(grid.z, raster=Raster(grid.raster.cells, grid.raster.rows, "float64"))
    for max_error in (1.0, 0.25):
        rounded = api.encode(grid, "dwt2d", max_error=max_error)
        unrounded = api.encode(as_floats, "dwt2d", max_error=max_error)
        assert len(rounded) < len(unrounded)


def integer_grids():
    """Grids of a raster's integer samples: any integer type, a random mask, values in its range."""
    @st.composite
    def build(draw):
        sample = draw(st.sampled_from(["uint8", "int8", "uint16", "int16", "int32", "uint32"]))
        info = np.iinfo(sample)
        rows, cols = draw(st.integers(1, 12)), draw(st.integers(1, 12))
        seed = draw(st.integers(0, 2**32 - 1))
        rng = np.random.default_rng(seed)
        low = draw(st.integers(int(info.min), int(info.max)))
        high = draw(st.integers(low, min(int(info.max), low + draw(st.sampled_from([1, 10, 1000, 2**31])))))
        z = rng.integers(low, high, (rows, cols), endpoint=True).astype(float)
        z[rng.random((rows, cols)) < draw(st.sampled_from([0.0, 0.2]))] = np.nan
        return ZGrid(z, d1=30.0, d2=30.0, raster=Raster("area", "down", sample))
    return build()


@settings(max_examples=60, deadline=None)
@given(integer_grids(), st.floats(0.01, 6.0))
def test_integer_samples_decode_to_integers_within_floor_of_the_bound(grid, max_error):
    data, decoded = dwt2d.encode_grid_with_decoded(grid, max_error=max_error)
    back = api.decode(data)
    assert np.array_equal(back.z, decoded, equal_nan=True)   # the encoder knows what the decoder gets
    valid = grid.valid
    assert np.array_equal(back.valid, valid)
    assert np.array_equal(back.z[valid], np.round(back.z[valid]))
    if valid.any():
        assert np.abs(back.z[valid] - grid.z[valid]).max() <= np.floor(max_error)


def test_a_raster_grid_of_fractions_keeps_its_float_bound_and_version():
    """Integer type, but not integer values (a densified int16 grid): coded as before, 3.2."""
    grid = api.read(SRTM)
    fractions = grid.with_z(grid.z + 0.3)
    data = api.encode(fractions, "dwt2d", max_error=1.0)
    assert "rounding" not in header_fields(data) and "raster" in header_fields(data)   # as 3.2 did, in 7.0
    assert np.abs(api.decode(data).z - fractions.z).max() <= 1.0


def test_rmse_and_size_targets_do_not_round(tmp_path):
    grid = ZGrid(np.round(api.slice(api.sample("jacksboro")).z), d1=30.0, d2=30.0, raster=Raster(sample="int16"))
    for options in ({"rmse": 1.0}, {"size": 3000}):
        assert "rounding" not in header_fields(api.encode(grid, "dwt2d", **options))


def test_a_rounding_line_means_nothing_before_6_0_and_is_one_word_in_it():
    grid = api.read(SRTM)
    fractions = grid.with_z(grid.z + 0.3)
    old = dwt2d.encode_whole(fractions, max_error=1.0, compact=False)[0]   # 3.2: text lines
    marked = rechecksummed(old.replace(b"\ndata\n", b"\nrounding integer\ndata\n", 1))
    assert api.decode(marked).z.tobytes() == api.decode(old).z.tobytes()
    new = dwt2d.encode_whole(grid, max_error=1.0, compact=False)[0]   # 6.0
    with pytest.raises(MzcError, match="rounding") as error:
        api.decode(rechecksummed(new.replace(b"rounding integer\n", b"rounding nearest\n", 1)))
    assert error.value.field == "rounding"


def example_of(version):
    """(file bytes, expected values) of spec/dwt2d.md's worked example of ``version`` (b"6.0")."""
    from codec_contract import spec_examples

    return [e[:2] for e in spec_examples("dwt2d") if e[0].startswith(b"mzc-dwt2d " + version + b"\n")][0]


def integer_dem_of_the_spec():
    """The int16 DEM the 6.0 worked example states (30 m cells, one no-data cell), as a ZGrid."""
    from codec_contract import SPEC

    page = (SPEC / "dwt2d.md").read_text()
    stated = page.split("## Worked example of version 6.0 (rounding)")[1].split("```\n")[1]
    z = np.array([[float(v) for v in line.split()] for line in stated.strip().splitlines()])
    return ZGrid(z, d1=30.0, d2=30.0, origin=(440735.0, 3750015.0), units="m", nodata="-32768",
                 raster=Raster("area", "down", "int16"))


def test_the_spec_example_of_6_0_is_its_input_rounded_back_within_its_bound(harmonic_fill):
    """spec/dwt2d.md's 6.0 example: the integer DEM it states, coded by the reference encoder of the
    example's day (``harmonic_fill``), is the example's file byte for byte, and decodes to integers
    within 1 of it."""
    data, expected = example_of(b"6.0")
    grid = integer_dem_of_the_spec()
    assert dwt2d.encode_whole(grid, max_error=1, level=1, compact=False)[0] == data   # 6.0, as tiles write it
    back = api.decode(data).z
    assert np.array_equal(back, expected, equal_nan=True)
    assert np.nanmax(np.abs(back - grid.z)) == 1


# --- GeoTIFF creation options and Cloud Optimized GeoTIFFs --------------------------------


def large_int16_dem(path):
    """A 700 x 900 int16 DEM with no-data cells: big enough for the COG driver's overviews."""
    rng = np.random.default_rng(5)
    r, c = np.mgrid[0:700, 0:900]
    z = np.round(1500 + 300 * np.sin(r / 60) * np.cos(c / 85) + 20 * np.sin(r / 7 + c / 11)
                 + rng.normal(0, 2, r.shape))
    z[300:340, 100:180] = -32768
    return written_int16_dem(path, z)


def coded_by_the_cli(source):
    """(``source``, its --dwt2d --max-error 1 file beside it, coded by ``mzc encode``)."""
    from conftest import run_mzc

    coded = source.with_suffix(".mzw2")
    run_mzc("encode", "--dwt2d", "--max-error", "1", source, "-o", coded, check=True)
    return source, coded


@pytest.fixture(scope="module")
def coded_dem(tmp_path_factory):
    """(the large DEM, its --dwt2d --max-error 1 file)."""
    return coded_by_the_cli(large_int16_dem(tmp_path_factory.mktemp("cog") / "dem.tif"))


def structure(path):
    """(tiled, block shape, overview factors, GDAL's IMAGE_STRUCTURE tags, profile) of a GeoTIFF."""
    with rasterio.open(path) as dataset:
        return (dataset.profile.get("tiled", False), dataset.block_shapes[0], dataset.overviews(1),
                dataset.tags(ns="IMAGE_STRUCTURE"), dataset.profile)


def test_creation_options_reach_gdal(mzc, coded_dem, tmp_path):
    _, coded = coded_dem
    plain, zstd = tmp_path / "plain.tif", tmp_path / "zstd.tif"
    mzc("decode", coded, "-o", plain, check=True)
    mzc("decode", coded, "-o", zstd, "--co", "COMPRESS=ZSTD", "--co", "zstd_level=9", "--co", "TILED=YES",
        "--co", "BLOCKXSIZE=256", "--co", "BLOCKYSIZE=256", check=True)
    tiled, block, _, tags, _ = structure(zstd)
    assert tiled and block == (256, 256) and tags["COMPRESSION"] == "ZSTD"
    assert structure(plain)[3]["COMPRESSION"] == "DEFLATE"
    assert read_tif(zstd)[0].tobytes() == read_tif(plain)[0].tobytes()


def test_cog_is_tiled_with_overviews_and_the_same_raster(mzc, coded_dem, tmp_path):
    source, coded = coded_dem
    plain, cog = tmp_path / "plain.tif", tmp_path / "cog.tif"
    mzc("decode", coded, "-o", plain, check=True)
    mzc("decode", coded, "--format", "tif", "--cog", "-o", cog, check=True)
    tiled, block, overviews, tags, profile = structure(cog)
    assert tiled and block == (512, 512) and overviews == [2] and tags["LAYOUT"] == "COG"
    assert tags["COMPRESSION"] == "DEFLATE" and tags["PREDICTOR"] == "2"
    plain_profile = structure(plain)[4]
    for key in ("dtype", "nodata", "crs", "transform", "width", "height"):
        assert profile[key] == plain_profile[key], key
    assert profile["dtype"] == "int16" and profile["nodata"] == -32768
    assert read_tif(cog)[0].tobytes() == read_tif(plain)[0].tobytes()
    assert np.array_equal(read_tif(cog)[1], read_tif(source)[1])
    with rasterio.open(cog) as dataset:   # the overview holds the terrain, not no-data or zeros
        overview = dataset.read(1, out_shape=(350, 450), masked=True)
        assert abs(float(overview.mean()) - float(read_tif(source)[0][read_tif(source)[1]].mean())) < 5


def test_cog_takes_creation_options_of_the_cog_driver(mzc, tmp_path):
    coded, cog = tmp_path / "dem.mzw2", tmp_path / "cog.tif"
    mzc("encode", "--dwt2d", "--max-error", "1", SRTM, "-o", coded, check=True)
    mzc("decode", coded, "-o", cog, "--cog", "--co", "BLOCKSIZE=128", "--co", "COMPRESS=LZW", check=True)
    tiled, block, overviews, tags, _ = structure(cog)
    assert tiled and block == (128, 128) and overviews == [2] and tags["COMPRESSION"] == "LZW"


@pytest.mark.parametrize("args, message", [
    (("--co", "FOO=1"), "co: GDAL: driver GTiff does not support creation option FOO"),
    (("--co", "COMPRESS=SQUEEZE"), "co: GDAL: 'SQUEEZE' is an unexpected value for COMPRESS"),
    (("--co", "PREDICTOR=3"), "co: GDAL: cannot write it: PREDICTOR=3 is only supported with Float32 or Float64"),
    (("--co", "NODATA=0"), "co: NODATA is not a GeoTIFF creation option"),
    (("--co", "COMPRESS"), "co: 'COMPRESS' is not KEY=VALUE"),
    (("--cog", "--co", "BLOCKSIZE=7"), "co: GDAL: '7' is an unexpected value for BLOCKSIZE"),
    (("--format", "asc", "--co", "DECIMALS=2"), "co: creation options and --cog are a GeoTIFF's; asc takes none"),
    (("--format", "zg", "--cog"), "cog: creation options and --cog are a GeoTIFF's; zgrid takes none"),
])
def test_bad_geotiff_options_are_refused_in_one_line_and_nothing_is_written(mzc, tmp_path, args, message):
    coded, out = tmp_path / "dem.mzw2", tmp_path / "out.tif"
    mzc("encode", "--dwt2d", "--max-error", "1", SRTM, "-o", coded, check=True)
    result = mzc("decode", coded, "-o", out, *args)
    error = result.stderr.decode()
    assert result.returncode == 1 and error.count("\n") == 1 and message in error, error
    assert "Traceback" not in error and not list(tmp_path.glob("out*"))


def test_the_api_and_batch_decode_write_what_decode_writes(mzc, tmp_path):
    """One home: decode --cog --co, mzc.write(creation_options=, cog=) and batch decode --cog --co
    give the same bytes, and a batch records its options in its settings."""
    archive = tmp_path / "archive"
    archive.mkdir()
    coded = archive / "dem.mzw2"
    mzc("encode", "--dwt2d", "--max-error", "1", SRTM, "-o", coded, check=True)
    mzc("decode", coded, "-o", tmp_path / "cli.tif", "--cog", "--co", "COMPRESS=ZSTD", check=True)
    api.write(tmp_path / "api.tif", api.decode(coded.read_bytes()), creation_options={"compress": "zstd"}, cog=True)
    mzc("batch", "decode", archive, "-o", tmp_path / "batch", "--format", "tif", "--cog", "--co", "COMPRESS=ZSTD",
        "--workers", "1", check=True)
    cli = (tmp_path / "cli.tif").read_bytes()
    assert (tmp_path / "api.tif").read_bytes() == cli == (tmp_path / "batch" / "dem.tif").read_bytes()
    assert '""co"":{""COMPRESS"":""ZSTD""},""cog"":true' in (tmp_path / "batch" / "manifest.csv").read_text()
    with pytest.raises(MzcError, match="asc takes none"):
        api.batch_decode([archive], tmp_path / "b2", file_format="asc", creation_options=["COMPRESS=ZSTD"])
    with pytest.raises(MzcError, match="must be True or False"):
        api.write(tmp_path / "x.tif", api.decode(coded.read_bytes()), cog="yes")
    assert not (tmp_path / "x.tif").exists() and not (tmp_path / "b2").exists()


def test_values_at_the_ends_of_their_type_come_back_in_it():
    """uint8 zeros and 255s coded at E = 3 would round to -3 or 258 without the clamp."""
    z = np.where(np.indices((40, 50)).sum(axis=0) % 7 < 3, 0.0, 255.0)
    grid = ZGrid(z, d1=1.0, d2=1.0, raster=Raster(sample="uint8"))
    back = api.decode(api.encode(grid, "dwt2d", max_error=3.0)).z
    assert back.min() >= 0 and back.max() <= 255 and np.abs(back - z).max() <= 3


def test_a_rounding_line_needs_a_raster_of_integers():
    data = dwt2d.encode_whole(api.read(SRTM), max_error=1.0, compact=False)[0]   # 6.0: text lines
    for edit in (b"raster area down float32\n", b""):
        bad = rechecksummed(data.replace(b"raster area down int16\n", edit, 1))
        with pytest.raises(MzcError, match="rounds a raster of integer samples") as error:
            api.decode(bad)
        assert error.value.field == "rounding"


@pytest.mark.parametrize("command", [("slice",), ("densify", "-n", "1")])
def test_slice_and_densify_take_the_geotiff_options_too(mzc, tmp_path, command):
    source = SRTM if command[0] == "slice" else tmp_path / "dem.zg"
    if command[0] == "densify":
        mzc("slice", SRTM, "-o", source, check=True)
    out = tmp_path / "out.tif"
    mzc(*command, source, "-o", out, "--co", "COMPRESS=LZW", "--cog", check=True)
    tiled, _, _, tags, _ = structure(out)
    assert tiled and tags["LAYOUT"] == "COG" and tags["COMPRESSION"] == "LZW"


# --- tiled integer rasters (mzc-dwt2d 5.1) -------------------------------------------------------


def tiled_int16_dem(path):
    """A 1100 x 1030 int16 DEM with no-data cells, larger than one default tile (1024): 2 x 2 tiles."""
    rng = np.random.default_rng(11)
    r, c = np.mgrid[0:1100, 0:1030]
    z = np.round(700 + 250 * np.sin(r / 80) * np.cos(c / 95) + rng.normal(0, 2, r.shape))
    z[1000:1060, 40:90] = -32768   # across the boundary between the two rows of tiles (row 1024 of the grid)
    return written_int16_dem(path, z)


@pytest.fixture(scope="module")
def tiled_dem(tmp_path_factory):
    """(the tiled DEM, its --dwt2d --max-error 1 file coded window by window by the CLI)."""
    return coded_by_the_cli(tiled_int16_dem(tmp_path_factory.mktemp("tiled") / "dem.tif"))


def test_a_tiled_int16_dem_decodes_tile_by_tile_to_int16_with_its_no_data(mzc, tiled_dem, tmp_path):
    source, coded = tiled_dem
    data = coded.read_bytes()
    assert data.startswith(b"mzc-dwt2d 5.1\n") and b"\nrounding integer\nmax_error 1\n" in data
    assert data == api.encode(api.read(source), "dwt2d", max_error=1)   # the windows give the API's bytes
    back = tmp_path / "back.tif"
    mzc("decode", coded, "-o", back, check=True)
    values, valid, dtype, nodata = read_tif(back)
    original, original_valid, _, _ = read_tif(source)
    assert (dtype, nodata) == ("int16", -32768)
    assert np.array_equal(valid, original_valid) and (values[~valid] == -32768).all()
    assert np.abs(values[valid].astype(int) - original[valid]).max() == 1
    whole = api.decode(data)
    assert whole.z.tobytes() == api.read(back).z.tobytes() and whole.raster.sample == "int16"


def test_a_window_of_a_tiled_int16_dem_is_int16_through_cli_and_api(mzc, tiled_dem, tmp_path):
    source, coded = tiled_dem
    window = (1000, 1000, 60, 30)   # across all four tiles
    cut = tmp_path / "cut.tif"
    mzc("decode", coded, "--window", *window, "-o", cut, check=True)
    values, valid, dtype, nodata = read_tif(cut)
    assert (dtype, nodata, values.shape) == ("int16", -32768, (60, 30))
    by_api = api.read(coded, window=window)
    assert by_api.z.tobytes() == api.read(cut).z.tobytes()
    assert np.array_equal(by_api.z, api.decode(coded.read_bytes()).z[1000:1060, 1000:1030], equal_nan=True)
    assert np.array_equal(api.decode(coded.read_bytes(), window=window).z, by_api.z, equal_nan=True)


def test_a_tiled_int16_dem_in_rounded_tiles_is_smaller_than_in_float_ones(tiled_dem):
    """At E = 1 the rounded tiles code at 1.5 - 16 ulp, as a whole 6.0 file does (Guarantees)."""
    from dataclasses import replace

    grid = api.read(tiled_dem[0])
    rounded = tiled_dem[1].read_bytes()
    floats = api.encode(replace(grid, raster=None), "dwt2d", max_error=1)   # the same values, no type
    assert floats.startswith(b"mzc-dwt2d 5.0\n") and len(rounded) < 0.8 * len(floats)   # 238,910 and 339,520 B


@settings(max_examples=15, deadline=None)
@given(rows=st.integers(1, 30), cols=st.integers(1, 30), tile=st.integers(4, 12), max_error=st.sampled_from(
    [0.5, 1, 2.7]), sample=st.sampled_from(["int16", "uint8", "int32"]), seed=st.integers(0, 99))
def test_tiled_integer_grids_round_trip_to_integers_within_floor_of_the_bound(rows, cols, tile, max_error, sample,
                                                                              seed):
    rng = np.random.default_rng(seed)
    z = np.round(rng.uniform(0, 200, (rows, cols)))
    z[rng.random((rows, cols)) < 0.1] = np.nan
    grid = ZGrid(z, d1=1.0, d2=1.0, nodata="250" if sample == "uint8" else "-9999",
                 raster=Raster("area", "down", sample))
    data = api.encode(grid, "dwt2d", max_error=max_error, tile=tile)
    assert split_magic(data, "t")[1:] == (5, 1)
    back = api.decode(data)
    valid = ~np.isnan(z)
    assert np.array_equal(np.isnan(back.z), ~valid) and back.raster == grid.raster
    assert np.array_equal(back.z[valid], np.rint(back.z[valid]))
    assert np.abs(back.z - z)[valid].max(initial=0) <= np.floor(max_error)


def test_a_tiled_grid_of_fractions_or_an_rmse_target_keeps_float_tiles():
    z = np.round(np.random.default_rng(2).uniform(0, 50, (12, 10)))
    grid = ZGrid(z, d1=1.0, d2=1.0, raster=Raster("area", "down", "int16"))
    assert api.encode(grid.with_z(z + 0.5), "dwt2d", max_error=1, tile=4).startswith(b"mzc-dwt2d 5.0\n")
    assert api.encode(grid, "dwt2d", rmse=0.5, tile=4).startswith(b"mzc-dwt2d 5.0\n")


def test_a_rounded_tiled_file_whose_tiles_lie_is_refused():
    """A 5.1 header's rounding needs 6.0 tiles of its raster; a 5.0 header takes 3.x tiles only."""
    from test_tiles import with_header

    z = np.round(np.random.default_rng(4).uniform(0, 50, (6, 9)))
    grid = ZGrid(z, d1=1.0, d2=1.0, raster=Raster("area", "down", "int16"))
    data = api.encode(grid, "dwt2d", max_error=1, tile=4)
    with pytest.raises(MzcError, match=r"a tile of this file is a dwt2d 3.x stream"):
        api.decode(with_header(data, (b"rounding integer\n", b"")))
    with pytest.raises(MzcError, match=r"a tile of this file is a dwt2d 3.x stream"):
        api.decode(with_header(data, (b"mzc-dwt2d 5.1", b"mzc-dwt2d 5.0")))
    with pytest.raises(MzcError, match="the block the header places there"):
        api.decode(with_header(data, (b"raster area down int16", b"raster area down int32")))
    with pytest.raises(MzcError, match="rounding: rounds a raster of integer samples"):
        api.decode(with_header(data, (b"raster area down int16", b"raster area down float32")))


def test_the_spec_example_of_5_1_is_the_6_0_input_in_rounded_tiles():
    """spec/dwt2d.md's 5.1 example: the 6.0 example's integer DEM in tiles of 4, coded by the
    reference encoder, is the example's file byte for byte; it decodes to integers within 1 of it."""
    data, expected = example_of(b"5.1")
    grid = integer_dem_of_the_spec()
    assert dwt2d.write(grid, max_error=1, tile=4) == data
    back = api.decode(data)
    assert np.array_equal(back.z, expected, equal_nan=True) and back.raster == grid.raster
    assert np.nanmax(np.abs(back.z - grid.z)) == 1
