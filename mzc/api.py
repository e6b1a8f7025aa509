"""The Python API: the work of the ``mzc`` commands as functions over grids, meshes and bytes.

Every command is a thin wrapper over one of these; they take and return in-memory objects
(``ZGrid``, ``Mesh``, ``bytes``) and raise ``MzcError`` (a ``ValueError``) for bad input,
never a command-line message: each argument is checked here (``number``, ``vector``,
``path_of``, ``as_grid``, ``as_mesh``) as the command line's options are by click, before
any work, rather than failing inside it with a TypeError or a numpy warning. Anything with
``vertices`` and ``faces`` (a trimesh mesh), a ``(points, triangles)`` pair, an (n, 3) array of
points or a path is a surface.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Literal, TypedDict

from mzc.codecs import DEFAULT_CODEC
from mzc.errors import MzcError
from mzc.limits import check_colour_scale
from mzc.streams import path_of

if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import Unpack

    import numpy as np

    from mzc.grid import ZGrid
    from mzc.meshes import Mesh

PathLike = str | os.PathLike


class EncodeOptions(TypedDict, total=False):
    """The options of the built-in codecs, as :func:`encode` and :func:`batch_encode` take them
    (each codec takes its own: ``mzc encode --help`` says which; a codec refuses the others)."""

    max_error: float     # dwt2d: |decoded - input| <= max_error at every valid node
    rmse: float          # dwt2d: the RMS surface error aimed at [default: a tenth of the node spacing]
    size: int            # dwt2d: the file size aimed at, in bytes
    slope_limit: float   # dwt2d: steps grow as 1/sqrt(cos lean) up to this many times
    tile: int            # dwt2d: the side of independent tiles (0: the grid whole)
    progressive: bool    # dwt2d: write 9.0, levels in sections coarsest first (a prefix decodes coarser)
    colour_psnr: float   # dwt2d: the PSNR of the grid's colours, dB [default: 36]
    colour_max_error: int   # dwt2d: |decoded - input| <= this many 8-bit levels in every colour channel
    wavelet: str         # dwt2d: bior4.4 or bior2.2; dwt: a PyWavelets name
    level: int           # dwt2d and dwt: wavelet levels
    quality: int         # dft, dct, dwt: the percentage of coefficients kept
    degree: int          # poly: the polynomial's degree
    basis: str           # poly: chebyshev or power
    precision: int       # the row codecs: decimals written
BYTES_SOURCE = "<bytes>"
MESH_SOURCE = "<mesh>"   # a surface given in memory, in error messages


def as_mesh(surface: Any) -> Mesh:
    """A ``Mesh`` of a surface given as a path, a ZGrid, a Mesh, a trimesh-like object, a pair or an
    array (``given``): a grid's mesh keeps its grid, so it is compared at the grid's own nodes."""
    from mzc.formats import read_file
    from mzc.grid import ZGrid

    item = given(surface)
    item = read_file(item) if isinstance(item, str) else item
    return triangulate(item, vertices="all") if isinstance(item, ZGrid) else item


def as_meshes(first: Any, second: Any) -> tuple[Mesh, Mesh]:
    """The ``Mesh`` of each of two surfaces to compare (``as_mesh``), with two geographic grids
    placed in metres about one centre, the first's (``mzc.georef.metric_frame``): each about its
    own would shift one against the other by the distance between their centres."""
    from mzc.formats import read_file
    from mzc.georef import centre_of, is_geographic, metric_frame
    from mzc.grid import ZGrid

    items = [given(surface) for surface in (first, second)]
    items = [read_file(item) if isinstance(item, str) else item for item in items]
    geographic = [item for item in items if isinstance(item, ZGrid) and is_geographic(item)]
    if len(geographic) == 2:
        centre = centre_of(items[0])
        items = [metric_frame(item, centre) for item in items]
    return as_mesh(items[0]), as_mesh(items[1])


def given(surface: Any) -> str | ZGrid | Mesh:
    """A surface as it was given, before any file is read: a path as a str (``path_of``), a ZGrid as
    it is, and anything else as a Mesh held to what a mesh file is (``mzc.meshes.checked``: points,
    finite coordinates, triangles that index them)."""
    from mzc.grid import ZGrid
    from mzc.meshes import checked

    if isinstance(surface, (str, os.PathLike)):
        return path_of(surface, "surface")
    if isinstance(surface, ZGrid):
        return surface
    mesh = mesh_in_memory(surface)
    return mesh if mesh.grid is not None else checked(mesh, MESH_SOURCE)


def mesh_in_memory(surface: Any) -> Mesh:
    """The ``Mesh`` of what Python's geometry libraries hold a surface in: a Mesh; a
    (points, triangles) pair; an (n, 3) array of points, or (n, 6) of points and normals (an
    Open3D-style oriented cloud); any object with ``vertices`` or ``points`` and, for a mesh,
    ``faces`` or ``triangles`` or meshio's ``cells`` (trimesh's Trimesh and PointCloud,
    meshio.Mesh, Open3D's TriangleMesh and PointCloud), with its ``normals`` when it has them."""
    import numpy as np

    from mzc.meshes import Mesh

    if isinstance(surface, Mesh):
        return surface
    if isinstance(surface, tuple) and len(surface) == 2:
        return Mesh(*surface)
    if isinstance(surface, (np.ndarray, list)):
        return array_cloud(np.asarray(surface))
    points = next((getattr(surface, name) for name in ("vertices", "points") if hasattr(surface, name)), None)
    if points is None:
        raise MzcError(f"cannot read a surface from a {type(surface).__name__}: give a path, a Mesh, an object "
                       "with vertices or points (and faces or triangles), (points, triangles) or an (n, 3) array")
    return Mesh(points, object_triangles(surface), normals=object_normals(surface, len(np.asarray(points))))


def array_cloud(array: np.ndarray) -> Mesh:
    """The cloud of an (n, 3) array of points, or of an (n, 6) one of points and their normals."""
    from mzc.meshes import Mesh

    if array.ndim == 2 and array.shape[1] == 6:
        return Mesh(array[:, :3], normals=array[:, 3:])
    return Mesh(array)   # Mesh checks the points are numbers, in threes (real_array)


def object_triangles(surface: Any) -> Any:
    """The triangles of an object's ``faces``, ``triangles`` or meshio ``cells`` (quads and
    polygons fanned into triangles); none for a point cloud."""
    import numpy as np

    for name in ("faces", "triangles"):
        if hasattr(surface, name):
            return np.asarray(getattr(surface, name))
    if hasattr(surface, "cells"):
        from mzc.meshes.meshio_fallback import surface_triangles

        return surface_triangles(surface.cells)
    return np.empty((0, 3), dtype=np.int64)


def object_normals(surface: Any, count: int) -> Any:
    """An object's per-point ``normals`` (Open3D's, say) when it has one for each point, else None."""
    import numpy as np

    normals = getattr(surface, "normals", None)
    if normals is None or callable(normals):
        return None
    normals = np.asarray(normals)
    return normals if normals.size and normals.size == 3 * count else None


def number(value: Any, name: str, kind: type = float, low: float | None = None, high: float | None = None,
           low_open: bool = False) -> Any:
    """An argument as a number of ``kind`` (int or float) within ``low``..``high`` (None stays None),
    as a codec's options are checked (``mzc.codecs.base.Option``): a string, a bool, a fraction
    for a whole number or a NaN is an MzcError naming it."""
    from mzc.codecs.base import Option

    return None if value is None else Option(name, kind, None, low, high, low_open).check(value)


def vector(value: Any, name: str) -> tuple[float, float, float] | None:
    """An argument of three finite numbers (a centre, an axis), None staying None."""
    from mzc.grid import finite

    return None if value is None else tuple(finite(value, name, 3).tolist())


def as_grid(grid: ZGrid | np.ndarray) -> ZGrid:
    """``grid`` itself, or a 2D array as a planar z-grid of unit spacing (NaN = no value), its
    shape and values checked as every ZGrid's are."""
    from mzc.grid import ZGrid

    return grid if isinstance(grid, ZGrid) else ZGrid(z=grid, d1=1.0, d2=1.0)


def slice(surface: Any, d1: float | None = None, d2: float | None = None, *, rows: int | None = None,
          cols: int | None = None, align: str = "none", projection: str = "auto", view: str = "auto",
          center: tuple[float, float, float] | None = None, axis: tuple[float, float, float] | None = None,
          units: str | None = None, thesis_grid: bool = False, classes: Sequence[int] | None = None,
          cloud: str = "auto", charts: str | int = "auto", tap: bool = False, colour_scale: int = 1,
          prior: Any = None) -> ZGrid:
    """Cut a surface into a z-grid (``mzc slice``): spacings d1 (rows) and d2 (columns) default to
    the data's own, the cutting surfaces (``projection``) to the ones that see it best; ``classes``
    keeps those ASPRS classes of a LAS/LAZ cloud (2: ground), ``cloud`` (auto, bin, delaunay)
    says how a point cloud becomes a surface; ``charts`` (1, N or auto) whether a closed or
    many-part object is cut into charts, planar grids each seeing its own piece (``ZGrid.charts``);
    ``tap`` aligns the cells of a map grid on whole multiples of the spacing (gdalwarp's -tap);
    ``colour_scale`` K (1..8) samples a coloured surface's colour K times finer than the nodes, for
    texture detail (one grid; ``ZGrid.fine_colors``).

    A grid (a ZGrid, or a path of a z-grid, a compressed file or a raster: a GeoTIFF or ESRI ASCII
    grid) already is one: it is returned as it is, node for node (with ``units`` when given), and
    an option that would cut it otherwise is refused (resample a raster first; triangulate a
    z-grid and slice its mesh).

    ``prior`` (a prior file's path or bytes, or a ``mzc.prior.Prior``) cuts the surface (a grid's
    mesh) on the prior's lattice, for ``encode`` with it; the options that shape a grid are refused
    beside it."""
    from mzc.formats import read_file
    from mzc.meshes import warn_dropped
    from mzc.ops.slicing import slice_surface

    numbers = slicing_numbers({"d1": d1, "d2": d2, "rows": rows, "cols": cols, "center": center, "axis": axis,
                               "classes": classes, "tap": tap, "colour_scale": colour_scale})
    if prior is not None:
        from mzc.prior import as_prior, refuse_shaping, sliced

        shaping = {"d1": d1, "d2": d2, "rows": rows, "cols": cols, "center": center, "axis": axis,
                   "align": align != "none" or None, "projection": projection != "auto" or None,
                   "view": view != "auto" or None, "thesis_grid": thesis_grid or None,
                   "charts": charts not in ("auto", 1) or None, "tap": tap or None,
                   "colour_scale": colour_scale != 1 or None}
        refuse_shaping(name for name, value in shaping.items() if value is not None)
        return sliced(as_mesh(surface), as_prior(prior), numbers.get("classes"), units)
    surface = given(surface)
    read = read_file(surface) if isinstance(surface, str) else surface
    grid = slice_surface(read, align=align, units=units, projection=projection, view=view, thesis_grid=thesis_grid,
                         cloud=cloud, charts=charts, colour_scale=numbers.pop("colour_scale", 1), **numbers)
    warn_dropped(read)   # once the grid is made: a refused slice is one line, its error alone
    return grid


def train(surfaces: Sequence[Any], d1: float | None = None, d2: float | None = None) -> Any:
    """The prior of a collection of like surfaces (``mzc train``): their mean on one lattice, that of
    their union's default slice (spacings ``d1``, ``d2`` when given) grown to cover them all, as a
    ``mzc.prior.Prior`` (its file's bytes ``data``, for :func:`write`; ``mean``, the mean grid)."""
    from mzc.prior import train as train_prior

    if isinstance(surfaces, (str, os.PathLike, bytes)) or not hasattr(surfaces, "__iter__"):
        raise MzcError("must be a list of surfaces (paths or meshes)", field="surfaces")
    d1, d2 = (number(value, name, float, 0, low_open=True) for value, name in ((d1, "d1"), (d2, "d2")))
    return train_prior([as_mesh(surface) for surface in surfaces], d1, d2)


def slicing_numbers(options: dict[str, Any]) -> dict[str, Any]:
    """``options`` of :func:`slice` with its numbers checked and converted (spacings, counts, the
    centre and axis, the ASPRS classes), for slice and for batch_encode's ``slice_options``; the
    slicer itself says which spacings and counts make a grid (mzc.limits)."""
    checked = dict(options)
    for name, value in options.items():
        if name in ("d1", "d2"):
            checked[name] = number(value, name, float)
        elif name in ("rows", "cols"):
            checked[name] = number(value, name, int)
        elif name in ("center", "axis"):
            checked[name] = vector(value, name)
        elif name == "colour_scale":
            checked[name] = check_colour_scale(value, 1, 1, field=name)
        elif name == "tap" and not isinstance(value, bool):
            raise MzcError(f"must be True or False, not {value!r}", field="tap")
        elif name == "classes" and value is not None:
            if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
                raise MzcError(f"must be ASPRS class codes (say [2, 9]), not {value!r}", field="classes")
            checked[name] = tuple(number(code, "classes", int, 0, 255) for code in value)
    return checked


def encode(grid: ZGrid | Mesh | np.ndarray, codec: str = DEFAULT_CODEC, *, prior: Any = None,
           **options: Unpack[EncodeOptions]) -> bytes:
    """Compress a z-grid (or a 2D array) with a registered codec (``mzc encode``); ``options`` are
    the codec's, e.g. ``max_error=0.01`` for dwt2d, ``quality=20`` for dct. With ``prior`` (a prior
    file's path or bytes, or a ``mzc.prior.Prior``: :func:`train`) a grid cut on the prior's lattice
    is coded by dwt2d alone and as its residual from the prior's mean, the smaller written
    (``mzc.prior.encode``). A ``Mesh`` (a mesh or cloud, as :func:`read` gives) is sliced first: with
    dwt2d's ``rmse`` at the spacing that codes it within that RMS error over its whole surface in the
    fewest bytes (``mzc.targets``), else as :func:`slice` cuts it."""
    from mzc.codecs import get_codec
    from mzc.colours import warn_uncoded
    from mzc.meshes import Mesh

    chosen = get_codec(codec)
    if isinstance(grid, Mesh):
        from mzc.targets import encode_surface

        return encode_surface(grid, chosen, prior, chosen.checked(options))
    grid = as_grid(grid)
    if prior is not None:
        if chosen.name != "dwt2d":
            raise MzcError(f"codes with dwt2d alone, not {chosen.name}", field="prior", options=("prior",))
        from mzc.prior import as_prior
        from mzc.prior import encode as encode_with_prior

        return encode_with_prior(grid, as_prior(prior), **options)
    data = chosen.encode(grid, **options)
    warn_uncoded(grid, chosen, options)
    return data


def decode(data: bytes, legacy: str | None = None, *, window: Any = None, levels: int | None = None,
           prior: Any = None) -> ZGrid:
    """The z-grid of any mzc file's bytes, or of a raster's (``mzc decode``); ``legacy`` names the
    kind of a thesis file (poly, dft, dct, dwt), which has no magic line; ``window`` (row, col,
    rows, cols) decodes only those rows and columns (of a tiled file, only the tiles they touch);
    ``levels`` K decodes a progressive file (mzc-dwt2d 9.0) to band 0 and its K coarsest detail levels;
    ``prior`` (a path, bytes or ``mzc.prior.Prior``) the prior a residual file was coded against."""
    try:
        contents = bytes(memoryview(data).cast("B"))
    except TypeError:
        raise MzcError(f"must be the bytes of an mzc file, not a {type(data).__name__}", field="data") from None
    window = window_argument(window)
    if prior is not None:
        from mzc.prior import RESIDUAL_MAGIC, as_prior
        from mzc.prior import decode as decode_residual

        if contents.startswith(RESIDUAL_MAGIC):   # any other file decodes alone
            return windowed(decode_residual(contents, BYTES_SOURCE, as_prior(prior)), window)
    if levels is not None:
        if legacy is not None:
            raise MzcError("decodes a progressive mzc-dwt2d 9.0 file, not a legacy one", field="levels")
        from mzc.codecs.dwt2d import read

        return windowed(read(contents, BYTES_SOURCE, wanted=number(levels, "levels", int, 0)), window)
    if legacy is not None:
        from mzc.codecs.rows.legacy import read_legacy

        return windowed(read_legacy(contents, BYTES_SOURCE, legacy), window)
    from mzc.codecs.dwt2d.tiles import Bytes, TiledFile, is_tiled
    from mzc.formats import read_any

    if window is not None and is_tiled(contents):
        return TiledFile(Bytes(contents), BYTES_SOURCE).window(*window)
    return windowed(read_any(contents, BYTES_SOURCE), window)


def window_argument(window: Any) -> tuple[int, int, int, int] | None:
    """A ``window`` argument: None, or four whole numbers (row, col, rows, cols)."""
    if window is None:
        return None
    try:
        row, col, rows, cols = window
    except (TypeError, ValueError):
        raise MzcError(f"must be (row, col, rows, cols), not {window!r}", field="window") from None
    return (number(row, "window", int, 0), number(col, "window", int, 0), number(rows, "window", int, 1),
            number(cols, "window", int, 1))


def windowed(grid: ZGrid, window: tuple[int, int, int, int] | None) -> ZGrid:
    """``grid``, or its ``window``."""
    if window is None:
        return grid
    from mzc.codecs.dwt2d.tiles import window_of

    return window_of(grid, window)


def densify(grid: ZGrid | np.ndarray, n: int, method: str = "biharmonic", *, iterations: int = 100,
            tol: float | None = None, jump_angle: float | None = None) -> ZGrid:
    """``grid`` (or a 2D array) with ``n`` rows inserted between each pair of rows (``mzc densify``,
    the PDE step)."""
    from mzc.limits import MAX_INSERTED, MAX_ITERATIONS
    from mzc.ops.densify import densify_grid

    return densify_grid(as_grid(grid), number(n, "n", int, 0, MAX_INSERTED), method,
                        iterations=number(iterations, "iterations", int, 0, MAX_ITERATIONS),
                        tol=number(tol, "tol", float, 0, low_open=True), jump_angle=angle(jump_angle))


def triangulate(grid: ZGrid | np.ndarray, jump_angle: float | None = None, *,
                vertices: int | Literal["all"] | None = None) -> Mesh:
    """The triangle mesh of a z-grid (or a 2D array) in its input surface's frame (``mzc triangulate``):
    about ``vertices`` vertices, fewer where the surface is flat (``mzc.ops.simplify``), or with
    ``vertices="all"`` one at every valid node; by default about the vertex count of the mesh or
    cloud the grid was sliced from (``ZGrid.source_vertices``, which its files keep), every valid node
    when it records none."""
    from mzc.limits import MAX_NODES
    from mzc.ops.simplify import ALL, rebuilt

    if vertices != ALL:
        vertices = number(vertices, "vertices", int, 4, MAX_NODES)
    return rebuilt(as_grid(grid), angle(jump_angle), vertices)


def angle(jump_angle: float | None) -> float | None:
    """A ``jump_angle`` argument: degrees, 0..90, as ``--jump-angle`` takes them."""
    return number(jump_angle, "jump_angle", float, 0, 90)


def compare(a: Any, b: Any, *, surface: bool = True, heightfield: bool = False, samples: int = 100_000,
            seed: int = 0, d1: float | None = None, d2: float | None = None) -> dict[str, Any]:
    """How far surface ``b`` is from ``a`` (``mzc diff``): the symmetric point-to-surface distance
    (``surface_*``; ``surface=False`` leaves it out on planar grids), then the statistics of B - A
    along A's node lines (``grid_*``); a dict of name -> value. ``d1``, ``d2``: the spacing of the
    common grid, in A's units, in metres for two geographic grids (compared in metres, never degrees)."""
    from mzc.limits import MAX_SAMPLES
    from mzc.measure import compare_surfaces

    samples, seed = number(samples, "samples", int, 100, MAX_SAMPLES), number(seed, "seed", int, 0, 2**63 - 1)
    d1, d2 = (number(value, name, float, 0, low_open=True) for value, name in ((d1, "d1"), (d2, "d2")))
    return compare_surfaces(*as_meshes(a, b), surface=surface, heightfield=heightfield,
                            samples=samples, seed=seed, d1=d1, d2=d2).report


def sample(name: str = "bump") -> Mesh:
    """A built-in sample surface (``mzc sample``): jacksboro, topobathy, bump, blob or tube."""
    from mzc.samples import SAMPLES, sample_mesh

    if not isinstance(name, str) or name not in SAMPLES:
        raise MzcError(f"no sample named {name!r} (known: {', '.join(SAMPLES)})")
    return sample_mesh(name)


def read(path: PathLike, *, window: Any = None) -> ZGrid | Mesh:
    """Read a file, of any format mzc knows (``mzc.formats``): an mzc file (z-grid or compressed)
    or a raster (GeoTIFF, ESRI ASCII grid) as its ZGrid, a mesh or cloud as a Mesh; ``window``
    (row, col, rows, cols) reads only those rows and columns of a grid (of a tiled file, seeking
    only the tiles they touch)."""
    from mzc.formats import GRIDS, read_file

    window = window_argument(window)
    if window is None:
        return read_file(path_of(path))
    from mzc.codecs.dwt2d.tiles import open_tiled

    tiled = open_tiled(path_of(path))
    if tiled is None:
        return windowed(read_file(path_of(path), GRIDS), window)
    try:
        return tiled.window(*window)
    finally:
        tiled.close()


def write(path: PathLike, item: ZGrid | Mesh | bytes, file_format: str | None = None,
          precision: int | None = None, *, plain: bool = False, float32: bool = False,
          creation_options: Any = None, cog: bool = False) -> None:
    """Write a ZGrid as a z-grid, or as a raster when ``path`` ends in .tif, .tiff or .asc (or
    ``file_format`` is tif or asc: mzc.rasters, ``float32`` samples for GeoTIFF, GDAL's
    ``creation_options`` ({KEY: value} or KEY=VALUE strings, as gdal_translate -co) and, with
    ``cog``, a Cloud Optimized GeoTIFF), a Mesh in the format of ``path``'s extension (or
    ``file_format``), each format chosen from the table of formats (``mzc.formats``), or bytes
    (a compressed file) as they are; atomically: nothing is left on failure.

    A z-grid's heights are written raw by default (``mzc-zgrid 3.0``: exact little-endian
    float64, or float32 with ``float32``); ``plain`` writes them as text rows (1.0, 2.0), which
    ``precision`` (decimals) rounds. ``precision`` without ``plain`` is an MzcError."""
    from mzc.codecs.rows import MAX_PRECISION
    from mzc.formats import GRIDS, writer_for
    from mzc.grid import ZGrid
    from mzc.streams import write_output

    path, precision = path_of(path), number(precision, "precision", int, 0, MAX_PRECISION)
    row = writer_for(path, file_format, GRIDS) if isinstance(item, ZGrid) else None
    geotiff = geotiff_settings(creation_options, cog, row.name if row is not None else file_format)
    if isinstance(item, (bytes, bytearray)):
        write_output(path, bytes(item))
        return
    if not isinstance(item, ZGrid):
        from mzc.meshes import write_mesh

        write_mesh(path, as_mesh(item), file_format)
        return
    if row is not None and row.kind == "raster":
        from mzc.rasters import write_raster

        write_raster(path, item, row.name, float32=float32, options=geotiff.get("co"), cog="cog" in geotiff)
        return
    from mzc.formats import zgrid

    if plain and float32:
        raise MzcError("float32 is a raw body and plain a text one: give one", field="float32")
    raw = None if plain else "float32" if float32 else "float64"
    write_output(path, zgrid.write(item, precision=precision, raw=raw))


def batch_encode(sources: Any, dest: PathLike, codec: str = DEFAULT_CODEC, *,
                 slice_options: dict[str, Any] | None = None, verify: bool = False, scheduler: Any = None,
                 workers: int | None = None, chunk_size: int | None = None, listener: Any = None,
                 prior: PathLike | None = None, **codec_options: Unpack[EncodeOptions]) -> Any:
    """Slice and encode every mesh, cloud and raster of ``sources`` (paths, folders, globs, ``@list``
    files) into the folder ``dest`` on Dask (``mzc batch encode``): ``slice_options`` are :func:`slice`'s,
    ``codec_options`` :func:`encode`'s. It runs on ``scheduler`` (a scheduler's address or a
    ``distributed.Client``, which is left open), else on the current client when there is one and
    no ``workers`` are asked for, else on a local cluster of ``workers`` processes. Returns the
    ``mzc.batch.Summary`` (its ``rows`` are the manifest's, ``dest``/manifest.csv); a bad file is
    a failed row, never an exception. ``prior`` (a prior file's path, which the workers read) cuts
    every surface on its lattice and codes it against it, as ``slice --prior | encode --prior``."""
    import inspect

    from mzc.codecs import get_codec
    from mzc.ops.slicing import slice_surface

    chosen = get_codec(codec)
    defaults = {name: p.default for name, p in inspect.signature(slice_surface).parameters.items() if name != "surface"}
    unknown = sorted(set(slice_options or {}) - set(defaults))
    if unknown:
        raise MzcError(f"slice takes no option {unknown[0]!r} (it takes: {', '.join(sorted(defaults))})",
                       field=unknown[0])
    # the options that differ from slice's defaults: the same settings however they were spelled
    given = slicing_numbers(slice_options or {})
    slicing = {k: v for k, v in given.items() if v not in (None, ()) and v != defaults[k]}
    settings = {"codec": chosen.name, "codec_options": chosen.checked(codec_options), "slice_options": slicing}
    if prior is not None:
        from mzc.prior import refuse_shaping

        if chosen.name != "dwt2d":
            raise MzcError(f"codes with dwt2d alone, not {chosen.name}", field="prior", options=("prior",))
        refuse_shaping(slicing)
        settings["prior"] = batch_prior(prior)
    return run_batch_job("encode", sources, dest, settings, sliceable_extensions(), chosen.extension, verify=verify,
                         scheduler=scheduler, workers=workers, chunk_size=chunk_size, listener=listener)


def batch_prior(prior: PathLike) -> dict[str, str]:
    """{path, sha256} of a batch's ``prior`` file, read and checked now: the workers read it from
    that path (and refuse it if it changed), and the manifest's settings name it by its hash."""
    from mzc.prior import as_prior

    path = os.path.abspath(path_of(prior, "prior"))
    return {"path": path, "sha256": as_prior(path).name}


def sliceable_extensions() -> list[str]:
    """The extensions of the files ``mzc batch encode`` takes from a folder: rasters, meshes and
    point clouds."""
    from mzc.formats import SURFACES, extensions

    return extensions(("raster", *SURFACES))


def batch_decode(sources: Any, dest: PathLike, *, densify: int = 0, method: str = "biharmonic",
                 file_format: str = "ply", jump_angle: float | None = None, creation_options: Any = None,
                 cog: bool = False, scheduler: Any = None, workers: int | None = None,
                 chunk_size: int | None = None, listener: Any = None, prior: PathLike | None = None) -> Any:
    """Decode every mzc file of ``sources`` into a mesh in the folder ``dest`` on Dask (``mzc batch
    decode``): decoded, densified with ``densify`` rows between planes, triangulated into
    ``file_format``, or written as a raster when it is tif or asc (a GeoTIFF with GDAL's
    ``creation_options`` and Cloud Optimized with ``cog``, as ``write``); on Dask as
    :func:`batch_encode` runs (``scheduler``: an address, a ``distributed.Client``, or the current
    client); ``prior`` (a prior file's path, which the workers read) decodes the residual files
    coded against it. Returns the ``mzc.batch.Summary``."""
    from mzc.codecs import codec_names, get_codec
    from mzc.formats import SURFACES, extensions, writable
    from mzc.limits import MAX_INSERTED

    known = writable(("raster", *SURFACES))
    if file_format not in known:
        raise MzcError(f"cannot write format {file_format!r} (known: {', '.join(known)})", field="file_format")
    densify = number(densify, "densify", int, 0, MAX_INSERTED)
    settings = {"densify": densify, "method": method, "format": file_format, "jump_angle": jump_angle,
                **geotiff_settings(creation_options, cog, file_format)}
    if prior is not None:
        settings["prior"] = batch_prior(prior)
    decoded = [*extensions(("grid",)), *(get_codec(name).extension for name in codec_names())]
    return run_batch_job("decode", sources, dest, settings, decoded, "." + file_format, scheduler=scheduler,
                         workers=workers, chunk_size=chunk_size, listener=listener)


def geotiff_settings(creation_options: Any, cog: Any, file_format: str | None) -> dict[str, Any]:
    """{"co": {KEY: value}, "cog": True} of a GeoTIFF's creation options and COG layout, each only
    when asked (a batch's settings name what shapes its outputs), checked now
    (mzc.rasters.geotiff_options)."""
    if not creation_options and cog is False:
        return {}
    from mzc.rasters import geotiff_options

    options, cog = geotiff_options(creation_options, cog, file_format)
    settings: dict[str, Any] = {"co": options} if options else {}
    return {**settings, "cog": True} if cog else settings


def run_batch_job(action: str, sources: Any, dest: PathLike, settings: dict[str, Any], extensions: list[str],
                  output_extension: str, verify: bool = False, **engine: Any) -> Any:
    """Collect the items of ``sources`` and run ``action`` on them (mzc.batch)."""
    from mzc.batch import Job, run_batch
    from mzc.batch.items import collect

    if isinstance(sources, (str, os.PathLike)):
        sources = [sources]
    if isinstance(sources, (bytes, dict)) or not hasattr(sources, "__iter__"):
        raise MzcError(f"must be paths, folders or globs, not a {type(sources).__name__}", field="sources")
    sources = [path_of(source, "sources") for source in sources]
    dest = os.path.abspath(path_of(dest, "dest"))
    items = collect(sources, extensions, output_extension, dest)
    return run_batch(Job(action, dest, settings, verify), items, **engine)
