"""Rasters are grids: GeoTIFF and ESRI ASCII grids read as the z-grid they are, and written back.

A DEM raster already is a regular grid of heights, so it is read node for node, never
re-triangulated: its cells become nodes (at their centres, or at their points for a
pixel-is-point raster), its no-data cells invalid nodes, its rows in the z-grid's order
(v up: a north-up raster's last row is the grid's first), and the grid keeps the raster's
CRS and layout (``ZGrid.crs``, ``ZGrid.raster``; spec/zgrid.md), so that writing it back
gives the same raster: the same cells, georeferencing, no-data value and sample type.

GeoTIFF is read and written by rasterio (GDAL: every compression, tiling, BigTIFF and CRS
encoding GIS tools write), in the optional extra ``geo``; ESRI ASCII grids by mzc's own
vectorised reader and writer (``asc``). Both are rows of the table of file formats
(``mzc.formats``), which recognises each by its bytes, not its name (an ``.asc`` file may also
be an ``x y z`` point cloud) and reads an ESRI grid's CRS from the ``.prj`` beside it.

Georeferencing is exact both ways: a node's coordinate is the raster's reference (a cell
corner, or a centre) plus an offset of half a cell or whole rows, computed one way
(``node_coordinate``); writing recovers the shortest reference that gives the same
coordinate back (``raster_reference``), which is the raster's own for any reference written
in up to 15 significant digits.
"""

import os
import re
from dataclasses import dataclass, replace

import numpy as np

from mzc.errors import MzcError
from mzc.grid import IDENTITY_TRANSFORM, SAMPLES, Raster, ZGrid
from mzc.limits import check_grid_magnitudes
from mzc.numbers import real_array

ULPS = 4   # how far from the plain inverse raster_reference looks for the shortest reference


@dataclass(frozen=True)
class Layout:
    """Where a raster's cells lie: ``x`` and ``y``, its reference (the outer corner of its west
    column and of its south or, with ``top``, north row; with ``centred``, the centre of that
    corner's cell), the steps ``d2`` along x and ``d1`` along y (both > 0), and its ``cells``
    and ``rows`` (``down`` for a north-up raster) as in ``mzc.grid.Raster``."""

    x: float
    y: float
    d2: float
    d1: float
    cells: str
    rows: str
    top: bool
    centred: bool = False

    def offsets(self, rows):
        """(x, y) from the reference to the grid's node (0, 0), the centre of its south-west cell."""
        half = 0.0 if self.centred else 0.5
        return half * self.d2, (-(rows - 1 + half) if self.top else half) * self.d1


def grid_of(values, invalid, layout, sample, nodata=None, crs=None):
    """A ZGrid from a raster's ``values`` (its rows in file order), ``invalid`` mask, Layout and
    ``sample`` type, its no-data value ``nodata`` (None when it has none) and ``crs`` (WKT)."""
    grid = ZGrid(node_values(values, invalid, layout), **grid_fields(layout, values.shape[0], sample, nodata, crs))
    check_grid_magnitudes(grid)
    return grid


def grid_fields(layout, rows, sample, nodata=None, crs=None):
    """The fields of the ZGrid (keyword arguments but z) of a raster of ``rows`` rows, as grid_of's."""
    for name in ("d2", "d1"):
        if not getattr(layout, name) > 0:
            raise MzcError(f"its cells are {getattr(layout, name):g} wide along {'x' if name == 'd2' else 'y'}",
                           field="transform")
    dx, dy = layout.offsets(rows)
    origin = (node_coordinate(layout.x, dx), node_coordinate(layout.y, dy))
    return dict(d1=layout.d1, d2=layout.d2, origin=origin, nodata=nodata_token(nodata), crs=crs,
                raster=Raster(layout.cells, layout.rows, sample))


def node_values(values, invalid, layout):
    """A raster's ``values`` (rows in file order) as a grid's heights: NaN where ``invalid``, the
    rows in the grid's order."""
    z = np.where(invalid, np.nan, real_array(values, "data"))
    return z[::-1] if layout.rows == "down" else z


def node_coordinate(reference, offset):
    """A node's coordinate from its raster reference (corner or centre) and offset: the one
    rounding both ways of mzc's georeferencing go through."""
    return reference + offset


def raster_reference(coordinate, offset):
    """The raster reference r with node_coordinate(r, offset) == coordinate: of those within
    ULPS units in the last place of the plain inverse, the shortest in decimal (then the
    nearest), so a reference a raster read as a short decimal comes back as that decimal."""
    guess = coordinate - offset
    candidates = [guess]
    for direction in (np.inf, -np.inf):
        value = guess
        for _ in range(ULPS):
            value = float(np.nextafter(value, direction))
            candidates.append(value)
    exact = [c for c in candidates if node_coordinate(c, offset) == coordinate] or [guess]
    return min(exact, key=lambda c: (len(repr(c)), abs(c - guess)))


def layout_of(grid, top, centred):
    """The Layout of the raster that holds ``grid`` (its reference on the north row with ``top``,
    a cell's centre with ``centred``): the inverse of grid_of's, with the grid's raster layout
    (a north-up raster of area cells for a grid that has none)."""
    raster = grid.raster or Raster()
    layout = Layout(0.0, 0.0, grid.d2, grid.d1, raster.cells, raster.rows, top, centred)
    dx, dy = layout.offsets(grid.shape[0])
    return replace(layout, x=raster_reference(grid.origin[0], dx), y=raster_reference(grid.origin[1], dy))


def raster_rows(grid):
    """The grid's values in the raster's row order (its first row first)."""
    return grid.z if grid.raster is not None and grid.raster.rows == "up" else grid.z[::-1]


def nodata_token(value):
    """The z-grid's ``nodata`` token of a raster's no-data value (None: ``nan``)."""
    if value is None or np.isnan(value):
        return "nan"
    from mzc.formats.header import format_number

    if np.isinf(value):
        raise MzcError("the no-data value is infinite: mzc keeps a finite one or NaN", field="nodata")
    return format_number(value)


def check_writable(grid):
    """Refuse a grid that no raster holds: a raster is one planar grid in its CRS's own frame, with
    heights and coordinates mzc reads back (mzc.limits)."""
    check_grid_magnitudes(grid)
    if grid.charts is not None:
        raise MzcError("a raster holds one planar grid, and this one is charts of a whole object (separate pieces "
                       "side by side): triangulate it, or write it as a z-grid", field="charts")
    if grid.projection != "planar":
        raise MzcError(f"a raster holds planar grids; this one is {grid.projection}: triangulate it, or slice "
                       "with --projection planar", field="projection")
    if not np.array_equal(grid.transform, IDENTITY_TRANSFORM):
        raise MzcError("the grid's frame is turned or shifted from its input's (a transform): a raster holds "
                       "grids in the input's own frame (slice the surface with --align none)", field="transform")


def no_data_marker(grid):
    """The value a raster writes for the grid's invalid nodes: its numeric ``nodata`` token, NaN for
    ``nan`` when it has invalid nodes, or None (no no-data value) when it has none."""
    try:
        marker = float(grid.nodata)
    except ValueError:
        marker = np.nan
    if np.isnan(marker):
        return np.nan if not grid.valid.all() else None
    return marker


def sample_type(grid, marker, float32=False):
    """The sample type to write ``grid`` in: ``float32`` when asked; else the raster's own when it
    holds every valid value and the no-data ``marker`` exactly (an int16 DEM decoded losslessly
    stays int16); else float64, which holds every value mzc computes."""
    if float32:
        return "float32"
    own = grid.raster.sample if grid.raster is not None else "float64"
    values = grid.z[grid.valid]
    if marker is not None:
        values = np.append(values, marker)
    return own if holds(own, values) else "float64"


def holds(sample, values):
    """True when every one of ``values`` (float64) is a ``sample`` value exactly."""
    if sample not in SAMPLES:
        return False
    dtype = np.dtype(sample)
    if dtype.kind == "f":
        with np.errstate(over="ignore"):
            return bool(np.array_equal(values.astype(dtype).astype(np.float64), values, equal_nan=True))
    info = np.iinfo(dtype)
    return bool(np.all((values == np.round(values)) & (values >= info.min) & (values <= info.max)))


def write_raster(path, grid, file_format, float32=False, options=None, cog=False):
    """Write ``grid`` as the raster format ``file_format`` (tif or asc) to ``path`` (or stdout),
    atomically with its sidecar when it has one (``raster_files``)."""
    from mzc.streams import write_outputs

    write_outputs(*raster_files(path, grid, file_format, float32, options, cog))


def geotiff_options(pairs, cog, file_format):
    """({KEY: value}, cog) of a GeoTIFF's creation options, given as ``KEY=VALUE`` strings
    (gdal_translate's -co; mzc's --co) or as a dict, keys in upper case as GDAL spells them,
    and its Cloud Optimized layout ``cog``; both refused for a ``file_format`` other than tif
    (an ESRI grid or z-grid has none). GDAL itself refuses, when writing, a key or value it
    does not take (mzc.rasters.geotiff)."""
    if not isinstance(cog, bool):
        raise MzcError(f"must be True or False, not {cog!r}", field="cog")
    if (pairs or cog) and file_format != "tif":
        raise MzcError(f"creation options and --cog are a GeoTIFF's; {file_format} takes none",
                       field="co" if pairs else "cog")
    return creation_options(pairs or {}), cog


def creation_options(pairs):
    """{KEY: value} of creation options given as KEY=VALUE strings or a dict (geotiff_options)."""
    items = pairs.items() if isinstance(pairs, dict) else (split_option(pair) for pair in pairs)
    options = {}
    for key, value in items:
        if not isinstance(key, str) or not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", key):
            raise MzcError(f"{key!r} is not a creation option's name (KEY=VALUE, as gdal_translate -co)", field="co")
        options[key.upper()] = str(value)
    return options


def split_option(pair):
    """(KEY, VALUE) of one ``KEY=VALUE`` creation option."""
    if not isinstance(pair, str) or "=" not in pair:
        raise MzcError(f"{pair!r} is not KEY=VALUE (as gdal_translate -co)", field="co")
    key, value = pair.split("=", 1)
    return key.strip(), value.strip()


def raster_files(path, grid, file_format, float32=False, options=None, cog=False):
    """[(path, bytes)] of ``grid`` as the raster format ``file_format`` (tif or asc; mzc.formats) at
    ``path``: the raster, then the sidecar beside it that holds the grid's CRS, for a format that
    keeps it there (an ESRI grid's .prj; not on stdout; a GeoTIFF holds its own). A GeoTIFF takes
    GDAL's creation ``options`` and, with ``cog``, is Cloud Optimized (geotiff_options)."""
    from mzc.formats import named
    from mzc.streams import is_stdio

    options, cog = geotiff_options(options, cog, file_format)
    check_writable(grid)
    if grid.colors is not None:
        from mzc.colours import warn_raster_drops

        warn_raster_drops(file_format)
    row = named(file_format)
    extras = {"options": options, "cog": cog} if options or cog else {}
    files = [(path, row.load().write(grid, float32, **extras))]
    if row.sidecar and grid.crs is not None and not is_stdio(path):
        files.append((os.path.splitext(os.fspath(path))[0] + row.sidecar, (grid.crs + "\n").encode("utf-8")))
    return files
