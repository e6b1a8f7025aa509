"""Rasters written the way GIS users have them (issue 30): an integer DEM coded with a max error
comes back as integers of its own type with its no-data value (mzc-dwt2d 5.0, spec/dwt2d.md,
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

from codec_contract import rechecksummed

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
    """An int16 DEM in UTM with a block of no-data cells (-32768), written by GDAL."""
    rng = np.random.default_rng(3)
    r, c = np.mgrid[0:70, 0:90]
    z = np.round(900 + 60 * np.sin(r / 9) * np.cos(c / 13) + rng.normal(0, 3, r.shape)).astype("int16")
    z[10:16, 20:31] = -32768
    profile = {"driver": "GTiff", "width": 90, "height": 70, "count": 1, "dtype": "int16", "nodata": -32768,
               "transform": Affine(30, 0, 440720, 0, -30, 3751320), "crs": CRS.from_epsg(32611)}
    with rasterio.open(path, "w", **profile) as dataset:
        dataset.write(z, 1)
    return path


# --- integer samples come back as integers -----------------------------------------------


@pytest.mark.parametrize("max_error, kept", [(0.25, 0), (0.5, 0), (0.99, 0), (1, 1), (1.7, 1), (3, 3)])
def test_an_int16_dem_at_a_max_error_comes_back_int16_within_it(mzc, tmp_path, max_error, kept):
    """SRTM-style int16 in, int16 out: every value an integer within floor(E) <= E of the input's."""
    coded, back = tmp_path / "dem.mzw2", tmp_path / "back.tif"
    mzc("encode", "--dwt2d", "--max-error", max_error, SRTM, "-o", coded, check=True)
    assert split_magic(coded.read_bytes(), "dem")[1:] == (5, 0)
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
    assert split_magic(data, "g")[1:] == (3, 2)
    assert np.abs(api.decode(data).z - fractions.z).max() <= 1.0


def test_rmse_and_size_targets_do_not_round(tmp_path):
    grid = ZGrid(np.round(api.slice(api.sample("jacksboro")).z), d1=30.0, d2=30.0, raster=Raster(sample="int16"))
    for options in ({"rmse": 1.0}, {"size": 3000}):
        assert split_magic(api.encode(grid, "dwt2d", **options), "g")[1:] == (3, 2)


def test_a_rounding_line_means_nothing_before_5_0_and_is_one_word_in_it():
    grid = api.read(SRTM)
    fractions = grid.with_z(grid.z + 0.3)
    old = api.encode(fractions, "dwt2d", max_error=1.0)
    marked = rechecksummed(old.replace(b"\ndata\n", b"\nrounding integer\ndata\n", 1))
    assert api.decode(marked).z.tobytes() == api.decode(old).z.tobytes()
    new = api.encode(grid, "dwt2d", max_error=1.0)
    with pytest.raises(MzcError, match="rounding") as error:
        api.decode(rechecksummed(new.replace(b"rounding integer\n", b"rounding nearest\n", 1)))
    assert error.value.field == "rounding"


def test_the_spec_example_of_5_0_is_its_input_rounded_back_within_its_bound():
    """spec/dwt2d.md's 5.0 example: the integer DEM it states, coded by the reference encoder, is the
    example's file byte for byte, and decodes to integers within 1 of it."""
    from codec_contract import SPEC, spec_examples

    data, expected, _id = [e for e in spec_examples("dwt2d") if e[0].startswith(b"mzc-dwt2d 5.0")][0]
    page = (SPEC / "dwt2d.md").read_text()
    stated = page.split("## Worked example of version 5.0")[1].split("```\n")[1]
    z = np.array([[float(v) for v in line.split()] for line in stated.strip().splitlines()])
    grid = ZGrid(z, d1=30.0, d2=30.0, origin=(440735.0, 3750015.0), units="m", nodata="-32768",
                 raster=Raster("area", "down", "int16"))
    assert dwt2d.write(grid, max_error=1, level=1) == data
    back = api.decode(data).z
    assert np.array_equal(back, expected, equal_nan=True)
    assert np.nanmax(np.abs(back - z)) == 1
