"""GeoTIFFs too large to hold, read and written window by window through rasterio (GDAL).

``GeoTiffSource`` gives the blocks of a GeoTIFF on disk to a codec that codes a grid a window at
a time (``Codec.window_writer``: dwt2d's tiles); ``write_tiles`` writes the tiles of a tiled file
into a tiled GeoTIFF as they are decoded. GDAL's block cache is held to CACHE_MB, so memory is
that of a tile and the cache, whatever the raster's size.
"""

import functools
import os
import warnings

import numpy as np

from mzc.errors import MzcError
from mzc.rasters import grid_fields, layout_of, node_values
from mzc.rasters.geotiff import PREDICTORS, check_readable, layout_from, one_line, rasterio

CACHE_MB = 256      # GDAL's block cache (its default is 5% of the machine's memory)
BLOCK = 256         # the written GeoTIFF's internal tiles (GDAL's and COG's usual 256 or 512)
COPY_CHUNK = 1 << 22


def settings():
    """The rasterio environment of every window read and write: a bounded cache, no sidecar files."""
    return rasterio().Env(GDAL_CACHEMAX=CACHE_MB, GDAL_PAM_ENABLED="NO")


class GeoTiffSource:
    """Band 1 of a GeoTIFF on disk as a Frame (mzc.codecs.dwt2d.tiles) and its blocks, in the grid's
    row order (a north-up raster's last row is the grid's first)."""

    colors = None   # a raster's values alone: its tiles carry no colours (mzc.codecs.dwt2d.tiles.coloured_tiles)

    def __init__(self, path, source):
        from rasterio.errors import CRSError, RasterioError

        from mzc.codecs.dwt2d.tiles import Frame

        self.source, self.spill_dir = source, os.path.dirname(os.path.abspath(path))
        self.env = settings()
        self.env.__enter__()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self.dataset = rasterio().open(path)
            check_readable(self.dataset, source, whole=False)
            self.layout = layout_from(self.dataset, source)
            crs = self.dataset.crs.to_wkt() if self.dataset.crs else None
            fields = grid_fields(self.layout, self.dataset.height, self.dataset.dtypes[0], self.dataset.nodata, crs)
        except (RasterioError, CRSError, UnicodeError) as error:
            self.close()
            raise MzcError(f"not a readable GeoTIFF: {one_line(error)}", source=source) from None
        except BaseException as error:
            self.close()
            if isinstance(error, MzcError):
                raise error.located(source=source) from None
            raise
        self.frame = Frame(self.dataset.height, self.dataset.width, fields)
        self.opener = functools.partial(GeoTiffSource, os.path.abspath(path), source)   # opened on a Dask worker

    def integer_samples(self):
        """True: the values are the raster's own samples, read as they are (an integer GeoTIFF's
        are integers of its type)."""
        return True

    def block(self, rows, cols):
        """The heights of grid rows ``rows`` and columns ``cols`` (each a (start, stop)): one window
        of the raster, its no-data cells and masked cells NaN."""
        from rasterio.windows import Window

        height = self.frame.rows
        first = height - rows[1] if self.layout.rows == "down" else rows[0]
        window = Window(cols[0], first, cols[1] - cols[0], rows[1] - rows[0])
        from rasterio.errors import RasterioError

        try:
            values = self.dataset.read(1, window=window)
            invalid = self.dataset.read_masks(1, window=window) == 0
        except RasterioError as error:
            raise MzcError(f"not a readable GeoTIFF: {one_line(error)}", source=self.source) from None
        if values.dtype.kind == "f":
            invalid |= np.isnan(values)
        return node_values(values, invalid, self.layout)

    def close(self):
        """Close the dataset and leave rasterio's environment."""
        if getattr(self, "dataset", None) is not None:
            self.dataset.close()
            self.dataset = None
        if self.env is not None:
            self.env.__exit__(None, None, None)
            self.env = None


def write_tiles(path, tiled, float32=False):
    """Write the grid of ``tiled`` (a TiledFile) to ``path`` as a tiled GeoTIFF, tile by tile: GDAL
    writes a hidden file beside the output, which is then copied to it as every output is written
    (mzc.streams: whole or not at all), a few MB at a time. Its samples are those of
    ``tiled_sample``."""
    from mzc.rasters import check_writable
    from mzc.streams import forget, is_stdio, output_name, remember, write_output

    described = tiled.frame.described()
    check_writable_frame(described, check_writable)
    if tiled.coloured:
        from mzc.colours import warn_raster_drops

        warn_raster_drops("tif")
    folder = None if is_stdio(path) else os.path.dirname(os.path.realpath(path))
    import tempfile

    handle, temp = tempfile.mkstemp(prefix=".mzc-", suffix=".tif", dir=folder)
    os.close(handle)
    remember(temp)
    from rasterio.errors import RasterioError

    try:
        with settings():
            write_blocks(temp, described, tiled, tiled_sample(tiled, described, float32))
        write_output(path, file_chunks(temp))
    except RasterioError as error:   # GDAL's own failure to write (a full disk)
        raise MzcError(f"cannot write the GeoTIFF: {one_line(error)}", source=output_name(path)) from None
    finally:
        os.unlink(temp)
        forget(temp)


def tiled_sample(tiled, described, float32=False):
    """The sample type a tiled file's raster is written in, chosen before any tile is decoded:
    float32 when asked; the raster's own integer type for a file whose tiles are rounded to it
    (mzc-dwt2d 5.1) and whose no-data value it holds (an int16 DEM coded at --max-error >= 0.5
    comes back int16 with its no-data value; without a no-data value, the invalid nodes a
    tile may have need float's NaN); else float64, which holds every value of a lossy file."""
    from mzc.rasters import holds

    if float32:
        return "float32"
    if tiled.rounded and described.nodata != "nan" and holds(described.raster.sample,
                                                              np.array([float(described.nodata)])):
        return described.raster.sample
    return "float64"


def check_writable_frame(described, check_writable):
    """Refuse a grid no raster holds (``check_writable``'s rules: planar, in its input's frame), from
    its fields alone."""
    from mzc.grid import ZGrid

    fields = {name: getattr(described, name) for name in ("d1", "d2", "origin", "transform", "projection", "radius")}
    check_writable(ZGrid(z=np.zeros((1, 1)), **fields))


def write_blocks(path, described, tiled, sample):
    """Write every tile of ``tiled`` into a new GeoTIFF at ``path`` of ``sample`` values."""
    from affine import Affine

    module = rasterio()
    marker = float(described.nodata) if described.nodata != "nan" else np.nan
    place = layout_of(described, top=described.raster is None or described.raster.rows == "down", centred=False)
    step_y = -described.d1 if place.rows == "down" else described.d1
    height, width = described.shape
    profile = {"driver": "GTiff", "width": width, "height": height, "count": 1, "dtype": sample,
               "transform": Affine(described.d2, 0.0, place.x, 0.0, step_y, place.y), "nodata": marker,
               "compress": "deflate", "predictor": PREDICTORS[np.dtype(sample).kind], "tiled": True,
               "blockxsize": BLOCK, "blockysize": BLOCK, "bigtiff": "IF_SAFER"}
    if described.crs is not None:
        profile["crs"] = module.crs.CRS.from_wkt(described.crs)
    from rasterio.windows import Window

    with warnings.catch_warnings(), module.open(path, "w", **profile) as dataset:
        warnings.simplefilter("ignore")
        if place.cells == "point":
            dataset.update_tags(AREA_OR_POINT="Point")
        for (rows, cols), values in tiled.blocks():
            first = height - rows[1] if place.rows == "down" else rows[0]
            values = values[::-1] if place.rows == "down" else values
            samples = np.where(np.isnan(values), marker, values).astype(sample)
            if np.isinf(samples).any():
                raise MzcError(f"a value does not fit {sample}", field="float32")
            dataset.write(samples, 1, window=Window(cols[0], first, cols[1] - cols[0], rows[1] - rows[0]))


def file_chunks(path):
    """The bytes of the file at ``path``, a few MB at a time."""
    with open(path, "rb") as file:
        while chunk := file.read(COPY_CHUNK):
            yield chunk
