"""GeoTIFF through rasterio (GDAL), the optional extra ``geo``.

GDAL reads every GeoTIFF a GIS user has (strips or tiles, every compression, BigTIFF, a CRS
given by EPSG code or in full, GDAL's no-data tag and masks) and writes GeoTIFFs every GIS
tool opens. Its geotransform is always a corner's: for a pixel-is-point raster it has already
moved the tie point half a cell, and moves it back when writing one (``AREA_OR_POINT``), so
both kinds of cell reach mzc.rasters as a corner and a cell kind. Its messages go to Python's
logging (a NullHandler here keeps them off stderr: mzc reports a failure itself, in one line).
"""

import contextlib
import logging
import re
import threading
import warnings

import numpy as np

from mzc.errors import MzcError
from mzc.grid import SAMPLES
from mzc.limits import MAX_DIMENSION, check_grid_size
from mzc.rasters import Layout, grid_of, layout_of, no_data_marker, raster_rows, sample_type

EXTRA = "geo"
EXTENSIONS = (".tif", ".tiff")
MEMORY_NAME = re.compile(r"[\w/.-]*[0-9a-f]{8}(?:-[0-9a-f]{4}){3}-[0-9a-f]{12}[\w.]*:?\s*")   # a MemoryFile's name
PREDICTORS = {"f": 3, "i": 2, "u": 2}   # floating-point and horizontal differencing: smaller DEFLATE files
COG_DEFAULTS = {"compress": "deflate", "predictor": "yes"}   # the COG driver's own default is LZW, no predictor
PROFILE_KEYS = ("driver", "width", "height", "count", "dtype", "crs", "transform", "nodata")   # rasterio's, not GDAL's
COMPLAINTS = ("CPLE_NotSupported", "CPLE_IllegalArg")   # GDAL's warnings about a creation option it then ignores


def rasterio():
    """The rasterio module, or a one-line error naming the extra that installs it."""
    try:
        import rasterio as module
    except ImportError:
        raise MzcError(f"GeoTIFF needs rasterio: pip install 'mzc[{EXTRA}]'") from None
    logging.getLogger("rasterio").addHandler(logging.NullHandler())
    return module


def read(data, source):
    """The ZGrid of GeoTIFF bytes: band 1, its cells, no-data and mask, geotransform and CRS."""
    module = rasterio()
    from rasterio.errors import CRSError, RasterioError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # NotGeoreferencedWarning, from open: a plain TIFF has unit cells
            with module.MemoryFile(data) as memory, memory.open() as dataset:
                check_readable(dataset, source)
                values = dataset.read(1)
                invalid = dataset.read_masks(1) == 0
                layout = layout_from(dataset, source)
                nodata, crs = dataset.nodata, dataset.crs.to_wkt() if dataset.crs else None
    except (RasterioError, CRSError, UnicodeError) as error:   # a CRS that GDAL cannot parse, or not UTF-8
        raise MzcError(f"not a readable GeoTIFF: {one_line(error)}", source=source) from None
    if values.dtype.kind == "f":
        invalid |= np.isnan(values)
    try:
        return grid_of(values, invalid, layout, str(values.dtype), nodata=nodata, crs=crs)
    except MzcError as error:
        raise error.located(source=source) from None


def check_readable(dataset, source, whole=True):
    """Refuse what is not one grid of heights, before its values are read: read ``whole``, a grid
    within mzc.limits' nodes (read by windows, within its sides)."""
    if whole:
        check_grid_size(dataset.height, dataset.width, source=source, field="size")
    elif max(dataset.height, dataset.width) > MAX_DIMENSION:
        raise MzcError(f"{dataset.height} x {dataset.width} cells: this mzc reads at most {MAX_DIMENSION} per side",
                       source=source, field="size")
    if dataset.count != 1:
        raise MzcError(f"it has {dataset.count} bands: mzc reads a raster of one band of heights (a DEM); "
                       "take the band you mean first (gdal_translate -b N)", source=source, field="bands")
    if dataset.dtypes[0] not in SAMPLES:
        raise MzcError(f"its samples are {dataset.dtypes[0]}: mzc reads {', '.join(SAMPLES)}", source=source,
                       field="sample")


def layout_from(dataset, source):
    """The Layout of a dataset's geotransform (GDAL's: the outer corner of its first row and column)."""
    step_x, skew_x, x, skew_y, step_y, y = tuple(dataset.transform)[:6]
    if skew_x or skew_y:
        raise MzcError("its geotransform is rotated or sheared: mzc reads rasters whose rows run east-west "
                       "(gdalwarp it to a north-up grid first)", source=source, field="transform")
    if step_x < 0:
        raise MzcError(f"its columns run west (x step {step_x:g}): flip it first (gdalwarp)", source=source,
                       field="transform")
    cells = "point" if dataset.tags().get("AREA_OR_POINT", "Area").lower() == "point" else "area"
    return Layout(x, y, step_x, abs(step_y), cells, "down" if step_y < 0 else "up", top=step_y < 0)


def write(grid, float32=False, options=None, cog=False):
    """The bytes of ``grid`` as a GeoTIFF (DEFLATE with a predictor): its raster's cells, row
    order, sample type (float64 when that type cannot hold its values: sample_type) and
    no-data value, its CRS; with GDAL's creation ``options`` ({KEY: value}, as
    mzc.rasters.geotiff_options gives them) and, with ``cog``, as a Cloud Optimized GeoTIFF."""
    module = rasterio()
    from affine import Affine

    marker = no_data_marker(grid)
    sample = sample_type(grid, marker, float32)
    place = layout_of(grid, top=grid.raster is None or grid.raster.rows == "down", centred=False)
    step_y = -grid.d1 if place.rows == "down" else grid.d1
    values = raster_rows(grid)
    if marker is not None:
        values = np.where(np.isnan(values), marker, values)
    with np.errstate(over="ignore", invalid="ignore"):
        samples = values.astype(sample)
    if np.dtype(sample).kind == "f" and np.isinf(samples[~np.isinf(values)]).any():
        raise MzcError(f"a value does not fit {sample}", field="float32" if float32 else "sample")
    profile = {"driver": "GTiff", "width": grid.shape[1], "height": grid.shape[0], "count": 1, "dtype": sample,
               "transform": Affine(grid.d2, 0.0, place.x, 0.0, step_y, place.y), "nodata": marker,
               "compress": "deflate", "predictor": PREDICTORS[np.dtype(sample).kind]}
    if grid.crs is not None:
        profile["crs"] = module.crs.CRS.from_wkt(grid.crs)
    if cog:   # the COG driver copies a plain GeoTIFF, compressing it and its overviews itself
        profile.update(compress="none", predictor=1)
    else:
        profile.update(creation_profile(options))
    checked = refusing_complaints() if options or cog else contextlib.nullcontext()
    with warnings.catch_warnings(), module.MemoryFile() as memory, checked:
        warnings.simplefilter("ignore")
        with memory.open(**profile) as dataset:
            if place.cells == "point":
                dataset.update_tags(AREA_OR_POINT="Point")
            dataset.write(samples, 1)
        return cloud_optimized(memory, options) if cog else memory.read()


def creation_profile(options):
    """rasterio's keyword arguments for GDAL's creation ``options`` ({KEY: value}); a key that
    rasterio takes as the dataset's own (its size, type, georeferencing: mzc sets those from
    the grid) is refused, so that no option silently changes what the raster holds."""
    profile = {}
    for key, value in (options or {}).items():
        if key.lower() in PROFILE_KEYS:
            raise MzcError(f"{key} is not a GeoTIFF creation option: mzc writes the grid's own {key.lower()}",
                           field="co")
        profile[key.lower()] = value
    return profile


def cloud_optimized(memory, options):
    """The bytes of the GeoTIFF in ``memory`` as a Cloud Optimized GeoTIFF (GDAL's COG driver:
    tiles, overviews down to one tile, the IFDs first), DEFLATE with a predictor unless the
    creation ``options`` say otherwise."""
    from rasterio.shutil import copy

    with memory.open() as source, rasterio().MemoryFile() as out:
        copy(source, out.name, driver="COG", **{**COG_DEFAULTS, **creation_profile(options)})
        return out.read()


@contextlib.contextmanager
def refusing_complaints():
    """Run a GeoTIFF's writing, and refuse it in one line when GDAL complained about a creation
    option (an unknown key, a value it does not take), which it otherwise ignores, or failed
    on one; only this thread's complaints count (a batch writes on several threads)."""
    # GDAL's own errors, which rasterio raises as they are (a COG's bad tile size)
    from rasterio._err import CPLE_BaseError
    from rasterio.errors import RasterioError

    complaints, thread = [], threading.get_ident()

    class Complaints(logging.Handler):
        def emit(self, record):
            message = record.getMessage()
            if record.thread == thread and record.levelno >= logging.WARNING and message.startswith(COMPLAINTS):
                complaints.append(message.split(" in ", 1)[-1])

    handler, logger = Complaints(), logging.getLogger("rasterio._env")
    logger.addHandler(handler)
    try:
        yield
    except (RasterioError, CPLE_BaseError) as error:   # its complaint, which came first, says why
        complaint = " ".join(complaints[0].split()) if complaints else f"cannot write it: {one_line(error)}"
        raise MzcError(f"GDAL: {complaint}", field="co") from None
    finally:
        logger.removeHandler(handler)
    if complaints:
        raise MzcError(f"GDAL: {' '.join(complaints[0].split())}", field="co")


def one_line(error):
    """GDAL's own message (the innermost of rasterio's chained errors) as one line, without the
    name of the in-memory file it was read from."""
    while error.__cause__ is not None or error.__context__ is not None:
        error = error.__cause__ or error.__context__
    return " ".join(MEMORY_NAME.sub("", str(error)).split())[:300]
