"""Rasters are grids: GeoTIFF and ESRI ASCII grids read node for node and written back the same.

Real files from public repositories (tests/data/public/README.md) and generated GeoTIFFs of
every variant (pixel-is-point, north-up and south-up, no-data, float32 and int16, geographic
CRS), each checked against the original with the library that reads it (rasterio: GDAL), the
spec's georeferencing examples, hypothesis round trips of the ESRI grid parser, and bad input
refused in one line naming the file, line and field.
"""

import re
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.formats.header import format_number
from mzc.georef import crs_kind, metric_frame
from mzc.grid import Raster, ZGrid
from mzc.rasters import Layout, asc, grid_of, layout_of, raster_rows

from codec_contract import SPEC, rechecksummed, spec_examples

rasterio = pytest.importorskip("rasterio")
from rasterio.crs import CRS  # noqa: E402
from rasterio.transform import Affine  # noqa: E402

PUBLIC = Path(__file__).resolve().parent / "data" / "public"
PUBLIC_TIFS = ["srtm_blurred_res.tif", "rasterio_float.tif", "rasterio_float_nodata.tif"]
PUBLIC_ASCS = ["hugo_site.asc", "west_bijou_escarpment_snippet.asc", "dem_kootenai_37x50_1x1.asc"]


# --- helpers ------------------------------------------------------------------------------


def original(path):
    """(values, invalid mask, transform, crs, nodata, AREA_OR_POINT, dtype) of a GeoTIFF, as GDAL reads it."""
    with rasterio.open(path) as dataset:
        values = dataset.read(1)
        invalid = dataset.read_masks(1) == 0
        if values.dtype.kind == "f":
            invalid |= np.isnan(values)
        return (values, invalid, dataset.transform, dataset.crs, dataset.nodata,
                dataset.tags().get("AREA_OR_POINT", "Area"), dataset.dtypes[0])


def assert_same_raster(got_path, want_path, tolerance=None):
    """The same grid, no-data cells, georeferencing and CRS; valid values bit for bit (or within
    ``tolerance``) and, when equal, of the same sample type."""
    got, want = original(got_path), original(want_path)
    assert got[0].shape == want[0].shape
    assert np.array_equal(got[1], want[1]), "the no-data cells differ"
    assert got[2] == want[2], f"geotransform {got[2]} != {want[2]}"
    assert got[3] == want[3] and got[5] == want[5]
    valid = ~want[1]
    if tolerance is None:
        assert got[6] == want[6]
        assert got[0][valid].tobytes() == want[0][valid].tobytes()
        assert (got[4] == want[4]) or (np.isnan(got[4]) and np.isnan(want[4])) or not want[1].any()
    else:
        assert np.abs(got[0][valid].astype(float) - want[0][valid].astype(float)).max() <= tolerance


def write_tif(path, values, transform, crs=None, nodata=None, point=False):
    """A GeoTIFF written by GDAL (rasterio), as a GIS tool writes one."""
    profile = {"driver": "GTiff", "width": values.shape[1], "height": values.shape[0], "count": 1,
               "dtype": str(values.dtype), "transform": transform, "crs": crs, "nodata": nodata}
    with rasterio.open(path, "w", **profile) as dataset:
        if point:
            dataset.update_tags(AREA_OR_POINT="Point")
        dataset.write(values, 1)
    return path


def terrain(rows, cols, dtype, seed=0):
    """A bumpy terrain of ``dtype`` heights in metres."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:rows, 0:cols]
    z = 800 + 40 * np.sin(r / 5) * np.cos(c / 7) + rng.normal(0, 2, (rows, cols))
    return np.round(z).astype(dtype) if np.dtype(dtype).kind == "i" else z.astype(dtype)


def variants(folder):
    """Generated GeoTIFFs of every variant: name -> path."""
    utm, wgs84 = CRS.from_epsg(32611), CRS.from_epsg(4326)
    int16 = terrain(40, 50, "int16")
    int16[5:9, 10:14] = -32768
    float32 = terrain(33, 47, "float32", 1)
    float32[0, :3] = np.nan
    float32[20, 30] = -9999
    arcsec = 1 / 3600
    made = {
        "north_up_int16_nodata": write_tif(folder / "a.tif", int16, Affine(30, 0, 440720, 0, -30, 3751320), utm,
                                           nodata=-32768),
        "south_up_float32": write_tif(folder / "b.tif", float32, Affine(2.5, 0, 1000.25, 0, 2.5, 2000.75), utm,
                                      nodata=-9999),
        "pixel_is_point": write_tif(folder / "c.tif", int16, Affine(30, 0, 440705, 0, -30, 3751305), utm,
                                    nodata=-32768, point=True),
        "geographic_float32_nan": write_tif(folder / "d.tif", float32,
                                            Affine(arcsec, 0, -104.34180555555556, 0, -arcsec, 39.52472222222222),
                                            wgs84, nodata=np.nan),
        "no_crs_float64": write_tif(folder / "e.tif", terrain(9, 11, "float64", 2), Affine(0.5, 0, -3.25, 0, -0.5, 7)),
    }
    return made


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    return variants(tmp_path_factory.mktemp("variants"))


# --- real files: each slices and round-trips ----------------------------------------------


@pytest.mark.parametrize("name", PUBLIC_TIFS)
def test_a_public_geotiff_comes_back_the_same_through_a_z_grid(mzc, tmp_path, name):
    """tif -> slice -> decode --format tif (lossless: the z-grid is exact): the same grid, no-data
    cells, georeferencing, CRS and sample type, the values bit for bit."""
    grid_file, back = tmp_path / "dem.zg", tmp_path / "back.tif"
    assert mzc("slice", PUBLIC / name, "-o", grid_file).returncode == 0
    result = mzc("decode", grid_file, "--format", "tif", "-o", back)
    assert result.returncode == 0, result.stderr.decode()
    assert_same_raster(back, PUBLIC / name)


@pytest.mark.parametrize("name", PUBLIC_TIFS)
def test_a_public_geotiff_is_read_node_for_node(name):
    values, invalid, transform, crs, _nodata, _cells, dtype = original(PUBLIC / name)
    grid = mzc.slice(PUBLIC / name)
    north_up = transform.e < 0
    assert grid.shape == values.shape and grid.raster.sample == dtype
    assert grid.raster.rows == ("down" if north_up else "up")
    z = grid.z[::-1] if north_up else grid.z
    assert np.array_equal(np.isnan(z), invalid)
    assert np.array_equal(z[~invalid], values[~invalid].astype(float))
    # the node of the raster's first row and column is the centre of its cell
    first = (grid.origin[0], grid.ys()[-1] if north_up else grid.origin[1])
    assert first == pytest.approx(transform @ (0.5, 0.5), rel=1e-15)
    assert (grid.crs is None) == (crs is None)


@pytest.mark.parametrize("name", PUBLIC_ASCS)
def test_a_public_esri_grid_comes_back_the_same(mzc, tmp_path, name):
    """asc -> slice -> decode --format asc: the same header numbers (as numbers), no-data cells
    and values; and the CRS of a .prj beside it comes back beside the output."""
    grid_file, back = tmp_path / "dem.zg", tmp_path / "back.asc"
    assert mzc("slice", PUBLIC / name, "-o", grid_file).returncode == 0
    assert mzc("decode", grid_file, "-o", back).returncode == 0   # the extension says asc
    first, second = read_esri(PUBLIC / name), read_esri(back)
    assert first[0] == second[0]
    assert np.array_equal(first[1], second[1], equal_nan=True)
    prj = PUBLIC / name.replace(".asc", ".prj")
    if prj.exists():
        assert " ".join((tmp_path / "back.prj").read_text().split()) == " ".join(prj.read_text().split())
    else:
        assert not (tmp_path / "back.prj").exists()


def read_esri(path):
    """({keyword: number}, the values with no-data as NaN) of an ESRI grid, read independently."""
    lines = path.read_text().splitlines()
    header = {}
    while lines[0].split()[0].lower() in asc.KEYWORDS:
        keyword, value = lines.pop(0).split()
        header[keyword.lower()] = float(value)
    values = np.array(" ".join(lines).split(), dtype=float)
    if "nodata_value" in header:
        values[values == header.pop("nodata_value")] = np.nan
    return header, values


def test_the_geographic_esri_grid_takes_its_crs_from_its_prj():
    grid = mzc.read(PUBLIC / "west_bijou_escarpment_snippet.asc")
    assert crs_kind(grid.crs) == "geographic" and grid.crs.startswith('GEOGCS["GCS_WGS_1984"')
    assert grid.raster == Raster("area", "down", "int32") and grid.nodata == "-32768"
    assert grid.origin == (-104.341805555546 + 0.000277777778 / 2, 39.505972222219 + 0.000277777778 / 2)


def test_a_public_esri_grid_and_its_geotiff_are_one_grid(tmp_path):
    """asc -> tif (GDAL reads it back as the ESRI grid's own values and corner) -> asc."""
    grid = mzc.read(PUBLIC / "hugo_site.asc")
    mzc.write(tmp_path / "hugo.tif", grid)
    values, invalid, transform, crs, nodata, _cells, dtype = original(tmp_path / "hugo.tif")
    assert (transform.c, transform.f, transform.a, transform.e) == (0, 550, 10, -10)
    assert (dtype, nodata, crs) == ("int32", -9999, None)
    assert np.array_equal(invalid, np.isnan(grid.z[::-1]))
    again = mzc.read(tmp_path / "hugo.tif")
    assert np.array_equal(again.z, grid.z, equal_nan=True) and again.origin == grid.origin
    mzc.write(tmp_path / "hugo.asc", again)
    assert read_esri(tmp_path / "hugo.asc")[0] == read_esri(PUBLIC / "hugo_site.asc")[0]


def test_an_asc_point_cloud_is_still_a_point_cloud(tmp_path):
    (tmp_path / "cloud.asc").write_text("0 0 1\n1 0 2\n0 1 3\n1 1 4\n")
    assert isinstance(mzc.read(tmp_path / "cloud.asc"), mzc.Mesh)


# --- generated variants -------------------------------------------------------------------


@pytest.mark.parametrize("variant", ["north_up_int16_nodata", "south_up_float32", "pixel_is_point",
                                     "geographic_float32_nan", "no_crs_float64"])
def test_every_variant_comes_back_the_same(generated, tmp_path, variant):
    grid = mzc.slice(generated[variant])
    mzc.write(tmp_path / "back.tif", grid)
    assert_same_raster(tmp_path / "back.tif", generated[variant])
    back = mzc.decode(zgrid.write(grid, raw="float64"))   # through a z-grid file, as the commands pass it
    assert (back.crs, back.raster, back.nodata) == (grid.crs, grid.raster, grid.nodata)


def test_variants_record_their_layout(generated):
    assert mzc.read(generated["pixel_is_point"]).raster == Raster("point", "down", "int16")
    assert mzc.read(generated["south_up_float32"]).raster == Raster("area", "up", "float32")
    point, area = mzc.read(generated["pixel_is_point"]), mzc.read(generated["north_up_int16_nodata"])
    assert area.origin == (440735.0, 3751320 - 39.5 * 30)   # a cell's centre
    assert point.origin == (440720.0, 3751290 - 39 * 30)    # a point's tie point (GDAL: corner + half a cell)
    geographic = mzc.read(generated["geographic_float32_nan"])
    assert crs_kind(geographic.crs) == "geographic" and geographic.nodata == "nan"
    assert np.isnan(geographic.z).sum() == 3   # NaN cells; -9999 is a value there (its no-data is NaN)


@pytest.mark.parametrize("variant", ["north_up_int16_nodata", "pixel_is_point", "south_up_float32"])
@pytest.mark.parametrize("codec", [("--dwt2d", "--max-error", "0.25"), ("--dct", "-q", "100", "--precision", "6")])
def test_tif_slice_encode_decode_tif_keeps_the_georeferencing(mzc, generated, tmp_path, variant, codec):
    """tif -> slice -> encode -> decode --format tif: the same cells, no-data cells, georeferencing and
    CRS, each value within the codec's error."""
    coded, back = tmp_path / "dem.mzc", tmp_path / "back.tif"
    sliced = mzc("slice", generated[variant])
    assert mzc("encode", *codec, "-o", coded, input=sliced.stdout).returncode == 0
    result = mzc("decode", coded, "--format", "tif", "-o", back)
    assert result.returncode == 0, result.stderr.decode()
    assert_same_raster(back, generated[variant], tolerance=0.25 if codec[0] == "--dwt2d" else 1e-4)


def test_float32_samples_on_request(generated, tmp_path, mzc):
    coded = tmp_path / "dem.mzw2"
    sliced = mzc("slice", generated["north_up_int16_nodata"])
    mzc("encode", "--dwt2d", "--max-error", "0.5", "-o", coded, input=sliced.stdout, check=True)
    mzc("decode", coded, "--float32", "-o", tmp_path / "back.tif", check=True)
    assert original(tmp_path / "back.tif")[6] == "float32"


def test_a_grid_sliced_from_a_mesh_is_written_as_a_north_up_raster(tmp_path):
    grid = mzc.slice(mzc.sample("topobathy"))
    mzc.write(tmp_path / "t.tif", grid)
    values, invalid, transform, crs, nodata, cells, dtype = original(tmp_path / "t.tif")
    assert transform.e == -grid.d1 and transform.a == grid.d2 and crs is None and dtype == "float64"
    assert np.array_equal(values[~invalid], grid.z[::-1][~invalid])
    assert mzc.read(tmp_path / "t.tif").z.tobytes() == grid.z.tobytes()


# --- the spec's worked examples -------------------------------------------------------------


def raster_examples():
    """(example bytes, expected-raster block) of spec/zgrid.md's georeferenced examples."""
    text = (SPEC / "zgrid.md").read_text()
    blocks = re.findall(r"```mzc-example\n([^`]*)```\s*```expected\n[^`]*```\s*```expected-raster\n([^`]*)```", text)
    assert len(blocks) == 2
    return [(example.encode(), block) for example, block in blocks]


@pytest.mark.parametrize("example, block", raster_examples())
def test_the_spec_examples_give_their_rasters(example, block, tmp_path):
    grid = read_any(example, "spec")
    lines = block.strip().splitlines()
    expected = dict(line.split(" ", 1) for line in lines[:3])
    centred = grid.raster.cells == "point"
    north, south = layout_of(grid, top=True, centred=centred), layout_of(grid, top=False, centred=centred)
    assert [format_number(north.x), format_number(north.y)] == expected["north"].split()
    assert [format_number(south.x), format_number(south.y)] == expected["south"].split()
    assert crs_kind(grid.crs) == expected["crs"]
    stored = np.array([[float(v) for v in line.split()] for line in lines[4:]])
    marker = float(grid.nodata)
    np.testing.assert_array_equal(np.where(np.isnan(raster_rows(grid)), marker, raster_rows(grid)), stored)
    mzc.write(tmp_path / "spec.tif", grid)   # and GDAL reads the raster the block describes
    values, invalid, transform, crs, nodata, cells, dtype = original(tmp_path / "spec.tif")
    corner = (north.x, north.y) if not centred else (north.x - grid.d2 / 2, north.y + grid.d1 / 2)
    assert (transform.c, transform.f) == pytest.approx(corner, rel=1e-15)
    assert dtype == grid.raster.sample and cells.lower() == grid.raster.cells
    assert crs.to_epsg() == CRS.from_wkt(grid.crs).to_epsg() and crs.is_geographic == (expected["crs"] == "geographic")


def test_spec_examples_of_the_georeferenced_versions_are_on_the_page():
    assert sum(data.startswith(b"mzc-zgrid 1.1") for data, _, _ in spec_examples("zgrid")) == 2


# --- the ESRI grid parser: round trips (hypothesis) ----------------------------------------


values_strategy = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@st.composite
def esri_grids(draw):
    """The grid of a raster: values, holes, square or oblong cells, a corner or centre anywhere."""
    rows, cols = draw(st.integers(1, 7)), draw(st.integers(1, 7))
    z = np.array(draw(st.lists(values_strategy, min_size=rows * cols, max_size=rows * cols))).reshape(rows, cols)
    if draw(st.booleans()):
        z = np.round(z)
    holes = np.array(draw(st.lists(st.booleans(), min_size=rows * cols, max_size=rows * cols))).reshape(rows, cols)
    step = draw(st.sampled_from([1.0, 30.0, 0.000277777778, 2.5, 1 / 3]))
    d1 = draw(st.sampled_from([step, step * 2]))
    cells = draw(st.sampled_from(["area", "point"]))
    nodata = draw(st.sampled_from([None, -9999.0, -32768.0]))
    if nodata is not None and (z == nodata).any():
        nodata = None
    reference = Layout(draw(st.floats(-1e6, 1e6)), draw(st.floats(-1e6, 1e6)), step, d1, cells, "down", top=False,
                       centred=cells == "point")
    return grid_of(z, holes, reference, "float64", nodata=nodata)


@settings(max_examples=200, deadline=None)
@given(esri_grids())
def test_esri_grids_round_trip(grid):
    back = asc.read(asc.write(grid), "hypothesis.asc")
    assert np.array_equal(back.z, grid.z, equal_nan=True)
    assert (back.d1, back.d2, back.origin, back.raster.cells) == (grid.d1, grid.d2, grid.origin, grid.raster.cells)
    assert asc.write(back) == asc.write(grid)


@settings(max_examples=100, deadline=None)
@given(esri_grids(), st.sampled_from(["lower", "upper", "title"]), st.integers(1, 5),
       st.sampled_from([" ", "\t", "  "]))
def test_esri_grids_are_read_however_they_are_laid_out(grid, case, per_line, space):
    """Keywords in any case, values wrapped at any count per line, any blank between them, CRLF."""
    lines = asc.write(grid).decode().splitlines()
    header = [line for line in lines if line.split()[0].lower() in asc.KEYWORDS]
    tokens = " ".join(lines[len(header):]).split()
    header = [getattr(line.split()[0], case)() + space + line.split()[1] for line in header]
    body = [space.join(tokens[i:i + per_line]) for i in range(0, len(tokens), per_line)]
    back = asc.read("\r\n".join(header + body).encode(), "laid-out.asc")
    assert np.array_equal(back.z, grid.z, equal_nan=True) and back.origin == grid.origin


# --- bad input: one line naming file, line and field --------------------------------------

GOOD = "ncols 3\nnrows 2\nxllcorner 10\nyllcorner 20\ncellsize 5\nNODATA_value -9999\n1 2 3\n4 -9999 6\n"
BAD_ASC = {
    "cut short": (GOOD.rsplit(" ", 1)[0] + "\n", "8", "nrows", "cut short"),
    "values added": (GOOD + "7\n", "9", "nrows", "more values"),
    "bad number": (GOOD.replace("4 -9999", "4 x9"), "8", None, "value 2 is not a number: 'x9'"),
    "bad ncols": (GOOD.replace("ncols 3", "ncols 3.5"), "1", "ncols", "not a whole number"),
    "no cellsize": (GOOD.replace("cellsize 5\n", ""), None, "cellsize", "missing"),
    "negative cellsize": (GOOD.replace("cellsize 5", "cellsize -5"), "5", "cellsize", "positive"),
    "bad corner": (GOOD.replace("yllcorner 20", "yllcorner twenty"), "4", "yllcorner", "not a number"),
    "corner and centre": (GOOD.replace("yllcorner", "yllcenter"), "4", "yllcenter", "both corners"),
    "keyword twice": (GOOD.replace("cellsize 5\n", "cellsize 5\ncellsize 5\n"), "6", "cellsize", "twice"),
    "infinite value": (GOOD.replace("1 2 3", "1 inf 3"), None, "data", "infinite"),
    "huge grid": (GOOD.replace("nrows 2", "nrows 1000000").replace("ncols 3", "ncols 1000000"), "2", "nrows",
                  "too large"),
}


@pytest.mark.parametrize("name", BAD_ASC)
def test_a_bad_esri_grid_is_refused_in_one_line(mzc, tmp_path, name):
    text, line, field, words = BAD_ASC[name]
    path = tmp_path / "bad.asc"
    path.write_text(text)
    result = mzc("slice", path, "-o", tmp_path / "out.zg")
    stderr = result.stderr.decode()
    assert result.returncode == 1 and len(stderr.splitlines()) == 1 and "Traceback" not in stderr
    location = f"mzc: {path}" + (f":{line}" if line else "") + ": " + (f"{field}: " if field else "")
    assert stderr.startswith(location) and words in stderr, stderr
    assert not (tmp_path / "out.zg").exists()


def bad_tifs(folder, generated):
    data = Path(generated["north_up_int16_nodata"]).read_bytes()
    (folder / "cut.tif").write_bytes(data[:len(data) // 2])
    (folder / "header.tif").write_bytes(data[:40])
    with rasterio.open(folder / "rgb.tif", "w", driver="GTiff", width=4, height=4, count=3, dtype="uint8") as rgb:
        rgb.write(np.zeros((3, 4, 4), "uint8"))
    write_tif(folder / "rotated.tif", np.zeros((4, 4), "float32"), Affine(1, 0.5, 0, 0.5, -1, 4))
    write_tif(folder / "complex.tif", np.zeros((4, 4), "complex64"), Affine(1, 0, 0, 0, -1, 4))
    return {"cut.tif": (None, "not a readable GeoTIFF"), "header.tif": (None, "not a readable GeoTIFF"),
            "rgb.tif": ("bands", "3 bands"), "rotated.tif": ("transform", "rotated"),
            "complex.tif": ("sample", "complex64")}


def test_bad_geotiffs_are_refused_in_one_line(mzc, tmp_path, generated):
    for name, (field, words) in bad_tifs(tmp_path, generated).items():
        result = mzc("slice", tmp_path / name, "-o", tmp_path / "out.zg")
        stderr = result.stderr.decode()
        assert result.returncode == 1 and len(stderr.splitlines()) == 1 and "Traceback" not in stderr, stderr
        assert stderr.startswith(f"mzc: {tmp_path / name}: " + (f"{field}: " if field else "")), stderr
        assert words in stderr and not re.search(r"[0-9a-f]{8}-[0-9a-f]{4}-", stderr), stderr   # no MemoryFile name
        assert not (tmp_path / "out.zg").exists()


@pytest.mark.parametrize("option", [("--d1", "3"), ("--rows", "10"), ("--projection", "spherical"),
                                    ("--align", "pca"), ("--view", "-z"), ("--thesis-grid",),
                                    ("--center", "0", "0", "0")])
def test_slicing_options_are_refused_for_a_raster(mzc, option):
    result = mzc("slice", PUBLIC / "hugo_site.asc", *option)
    stderr = result.stderr.decode()
    assert result.returncode == 1 and len(stderr.splitlines()) == 1
    assert "node for node" in stderr and "resample the raster first" in stderr


def test_units_and_the_default_options_apply_to_a_raster(mzc):
    result = mzc("slice", PUBLIC / "hugo_site.asc", "--units", "m", "--projection", "planar", "--plain")
    assert result.returncode == 0 and b"\nunits m\n" in result.stdout


@pytest.mark.parametrize("name, file_format, written", [
    ("a.bin", "tiff", "tif"), ("a.bin", "TIF", "tif"), ("a.bin", "asc", "asc"), ("A.TIFF", None, "tif"),
    ("a.asc", "zg", "zg"),
])
def test_write_picks_the_raster_format_by_name_in_any_spelling(tmp_path, name, file_format, written):
    mzc.write(tmp_path / name, mzc_grid(), file_format=file_format)
    data = (tmp_path / name).read_bytes()
    assert {"tif": data[:4] in (b"II*\0", b"MM\0*"), "asc": data.startswith(b"ncols"),
            "zg": data.startswith(b"mzc-zgrid")}[written]


def test_a_raster_needs_a_planar_grid_in_its_own_frame(tmp_path):
    sphere = mzc.slice(mzc.sample("blob"))
    with pytest.raises(MzcError, match="planar grids") as error:
        mzc.write(tmp_path / "x.tif", sphere)
    assert error.value.field == "projection" and not (tmp_path / "x.tif").exists()
    turned = mzc.slice(mzc.sample("bump"), align="pca")
    with pytest.raises(MzcError, match="transform"):
        mzc.write(tmp_path / "x.asc", turned)


def test_slice_and_densify_write_rasters_as_mzc_write_does(tmp_path):
    from conftest import run_mzc

    pytest.importorskip("laspy")
    survey, dem = PUBLIC / "autzen_geo_proj.las", tmp_path / "dem.tif"
    assert run_mzc("slice", survey, "-o", dem).returncode == 0   # a LAS survey gridded to a GeoTIFF DEM
    mzc.write(tmp_path / "want.tif", mzc.slice(survey))
    assert_same_raster(dem, tmp_path / "want.tif")
    assert original(dem)[3] == CRS.from_epsg(2994)
    sliced = run_mzc("slice", PUBLIC / "west_bijou_escarpment_snippet.asc", check=True).stdout
    assert run_mzc("densify", "-n", "1", "--format", "asc", "-o", tmp_path / "fine.asc", input=sliced).returncode == 0
    mzc.write(tmp_path / "want.asc", mzc.densify(mzc.read(PUBLIC / "west_bijou_escarpment_snippet.asc"), 1))
    for name in ("fine.asc", "fine.prj"):
        assert (tmp_path / name).read_bytes() == (tmp_path / name.replace("fine", "want")).read_bytes()
    central = run_mzc("slice", mzc_sample_path(tmp_path), "-o", tmp_path / "blob.tif")
    assert central.returncode == 1 and b"blob.tif: projection: a raster holds planar grids" in central.stderr
    assert not (tmp_path / "blob.tif").exists()


def mzc_sample_path(folder):
    """The blob sample (a closed surface, sliced spherical) as a file."""
    path = folder / "blob.ply"
    mzc.write(path, mzc.sample("blob"))
    return path


def test_decode_refuses_text_options_with_a_raster_output(mzc):
    result = mzc("decode", "--format", "asc", "--plain", input=zgrid.write(mzc_grid()))
    assert result.returncode == 2 and b"--format asc writes a raster" in result.stderr


def mzc_grid():
    return ZGrid(np.arange(6.0).reshape(2, 3), 1, 1)


def test_without_rasterio_a_geotiff_is_one_line_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rasterio", None)
    with pytest.raises(MzcError, match=re.escape("pip install 'mzc[geo]'")):
        read_any((PUBLIC / "rasterio_float.tif").read_bytes(), "x.tif")
    grid = mzc.read(PUBLIC / "hugo_site.asc")   # an ESRI grid needs no library
    assert grid.shape == (55, 76)


# --- geographic grids: never measured as if degrees were metres ----------------------------


def test_a_geographic_grid_takes_every_target_as_a_vertical_error_in_metres():
    """--rmse and --size of an SRTM tile in EPSG:4326 are aimed at its heights alone (tests/test_geographic.py
    measures them); the bound of --max-error holds as before."""
    grid = mzc.read(PUBLIC / "srtm_blurred_res.tif")
    decoded = mzc.decode(mzc.encode(grid, rmse=3.0)).z - grid.z
    assert float(np.sqrt(np.mean(decoded ** 2))) == pytest.approx(3.0, rel=0.03)
    assert len(mzc.encode(grid, size=8000)) <= 8000
    coded = mzc.encode(grid, max_error=0.5)   # a bound on heights alone needs no common unit
    assert np.nanmax(np.abs(mzc.decode(coded).z - grid.z)) <= 0.5


def test_a_projected_grid_is_judged_by_its_crs_not_its_numbers(generated):
    """Steep heights over a small projected grid are lengths all the same: --rmse runs."""
    grid = mzc.read(generated["north_up_int16_nodata"])
    steep = grid.with_z(grid.z * 1000, d1=0.01, d2=0.01)
    assert len(mzc.encode(steep, rmse=50.0)) > 0
    with pytest.raises(MzcError, match="share one unit"):   # without a CRS the heuristic refuses it
        mzc.encode(steep.with_z(steep.z, crs=None, raster=None), rmse=50.0)


def test_a_geographic_grid_is_triangulated_in_metres_about_its_centre():
    grid = mzc.read(PUBLIC / "west_bijou_escarpment_snippet.asc")
    mesh = mzc.triangulate(grid)
    x, y = mesh.points[:, 0], mesh.points[:, 1]
    rows, cols = grid.shape
    # 1 arc-second is 30.9 m of latitude and 23.9 m of longitude at 39.5 degrees north
    assert np.ptp(y) == pytest.approx((rows - 1) * 30.86, rel=2e-3)
    assert np.ptp(x) == pytest.approx((cols - 1) * 23.86, rel=2e-3)
    assert abs(np.median(x)) < 200 and abs(np.median(y)) < 200
    assert len(mesh.triangles) > 0.9 * 2 * grid.valid.sum()   # no slope in degrees makes every edge a jump
    degrees = grid.with_z(grid.z, crs=None)
    assert len(mzc.triangulate(degrees).triangles) < 0.1 * len(mesh.triangles)   # what mixing units did


def test_a_geographic_grid_is_densified_in_metres_and_keeps_its_degrees():
    grid = mzc.read(PUBLIC / "west_bijou_escarpment_snippet.asc")
    dense = mzc.densify(grid, 1)
    assert (dense.crs, dense.raster, dense.origin, dense.d2) == (grid.crs, grid.raster, grid.origin, grid.d2)
    assert dense.d1 == grid.d1 / 2
    metric = mzc.densify(metric_frame(grid), 1)
    assert np.array_equal(dense.z, metric.z, equal_nan=True)
    assert np.isfinite(dense.z[1::2]).sum() > 0.9 * np.isfinite(grid.z).sum()   # rows are inserted


# --- the header lines: checked where they are read -----------------------------------------


@pytest.mark.parametrize("line, field, words", [
    ("raster area sideways int16", "raster", "'sideways' is not one of down, up"),
    ("raster area down", "raster", "expected 3 value(s)"),
    ("raster area down complex64", "raster", "not one of uint8"),
])
def test_a_bad_raster_line_is_refused_naming_its_line(line, field, words):
    data = f"mzc-zgrid 1.1\nrows 1\ncols 2\nd1 1\nd2 1\n{line}\ndata\n1 2\n".encode()
    with pytest.raises(MzcError) as error:
        read_any(data, "hand.zg")
    assert (error.value.line, error.value.field) == (6, field) and words in error.value.message


def test_the_georeferencing_lines_belong_to_planar_grids_and_their_versions():
    cylinder = ZGrid(np.ones((2, 3)), 1, 1, projection="cylindrical", radius=10)
    raw = zgrid.write(cylinder, raw="float64").replace(b"mzc-zgrid 3.0\n", b"mzc-zgrid 3.1\n")
    with pytest.raises(MzcError, match="belong to planar grids") as error:
        read_any(rechecksummed(raw.replace(b"\nraw ", b"\nraster area down int16\nraw ")), "p.zg")
    assert error.value.field == "raster" and error.value.line is not None
    with pytest.raises(MzcError, match="belong to planar grids"):
        cylinder.with_z(cylinder.z, crs='GEOGCS["x"]')
    old = read_any(b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\nraster area sideways\ndata\n1 2\n", "old.zg")
    assert old.raster is None   # a 1.0 reader ignored the line, and so does this one for a 1.0 file
    grid = ZGrid(np.ones((2, 2)), 1, 1, crs="GEOGCS[\"x\"]", raster=Raster())
    assert zgrid.write(grid).startswith(b"mzc-zgrid 1.1\n")
    assert zgrid.write(grid.with_z(grid.z, crs=None, raster=None)).startswith(b"mzc-zgrid 1.0\n")
