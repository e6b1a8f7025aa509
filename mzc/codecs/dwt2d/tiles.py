"""Tiled dwt2d files (``mzc-dwt2d 5.0``): a grid of any size as independent square tiles, each a
whole dwt2d 3.x file of its block, behind a header and an index of their lengths (spec/dwt2d.md,
Tiled files); of a grid with colours, ``mzc-dwt2d 11.0``, whose tiles are whole 10.x files, each
with its block's colours (the nodes'; colours finer than the nodes are not tiled).

A grid larger than one default tile is coded tile by tile, as GDAL's tiled GeoTIFFs, COGs and
SPERR's chunks are: memory is that of one tile however large the grid, the tiles may be coded
anywhere (a Dask task each), and a window decodes by reading the header, the index and only the
tiles it touches. Every tile is coded by the dwt2d encoder of whole grids and decoded by its
decoder; this module only cuts, places and indexes them. A bound on every value holds per tile,
so over the grid; an RMS target per tile bounds the grid's RMS (a mean of squares each within
the target's square); a size target cannot be shared out before the tiles are coded, and is
refused.

The text header's ``crc32`` covers the header, the index carries its own CRC-32, and each tile its
own ``crc32`` line: every byte is checked, and a window is checked without reading the rest.
"""

import math
import os
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from mzc.codecs.dwt2d import COLOURED_TILED_VERSION, ROUNDED_TILED_VERSION, TIGHT_VERSION, TILED_VERSION
from mzc.errors import MzcError
from mzc.limits import check_grid_size

DEFAULT_TILE = 1024        # a 1024 x 1024 tile encodes in about 0.25 GB (1.6 M nodes whole: 0.3 GB)
FINE_COLOURED_WHOLE = 4 * DEFAULT_TILE * DEFAULT_TILE   # nodes of a grid with colours finer than its nodes
                                                        # coded whole by default: it keeps them, which tiles
                                                        # (11.0, the nodes' colours) do not (2.1 M nodes: 0.63 GB)
MIN_TILE, MAX_TILE = 4, 4096
MAX_TILES = 1 << 22        # an index of at most 32 MB (a 10^6 x 10^6 grid in 1024-node tiles has 10^6)
HEADER_LIMIT = 1 << 20     # the text header's bytes (a crs line is at most 16 KB)
LENGTH = struct.Struct("<Q")
INDEX_CHECK = struct.Struct("<I")
COPY_CHUNK = 1 << 22       # bytes of tiles moved at a time from the spill file to the output
TASKS_AHEAD = 64           # Dask tasks submitted at a time: their results wait, in order, for the spill file


def tile_side(shape, tile, charted=False, fine_coloured=False):
    """The side of the tiles of a grid of ``shape`` coded with the ``tile`` option (None: tiles of
    DEFAULT_TILE for a grid larger than one of them, unless it is ``charted``, whose charts are
    blocks of their own, or ``fine_coloured`` (colours finer than its nodes, which a file coded
    whole keeps) and of at most FINE_COLOURED_WHOLE nodes; 0: never), or None when it is coded whole.
    A grid with its nodes' colours alone is tiled as any other: 11.0's tiles keep them, and on the
    TUM frame's 1039 x 2065 grid the tiles were as small and fast as the whole file in 0.37 GB, not 0.64."""
    nodes = shape[0] * shape[1]
    whole = charted or nodes <= DEFAULT_TILE * DEFAULT_TILE or (fine_coloured and nodes <= FINE_COLOURED_WHOLE)
    if tile == 0 or (tile is None and whole):
        return None
    return tile or DEFAULT_TILE


def grid_tile_side(grid, tile):
    """``tile_side`` of a ZGrid in memory, from its shape, charts and colour scale."""
    return tile_side(grid.shape, tile, charted=grid.charts is not None, fine_coloured=grid.colour_scale > 1)


def check_tile_option(tile):
    """Refuse a ``tile`` option that is neither 0 (whole) nor a side MIN_TILE..MAX_TILE."""
    if tile is not None and tile != 0 and not MIN_TILE <= tile <= MAX_TILE:
        raise MzcError(f"{tile} is not 0 (code the grid whole) nor a tile side of {MIN_TILE}..{MAX_TILE} nodes",
                       field="tile")


def spans(count, tile):
    """The (start, stop) of each tile along an axis of ``count`` nodes."""
    return [(start, min(start + tile, count)) for start in range(0, count, tile)]


@dataclass(frozen=True)
class Frame:
    """A grid without its values: ``rows`` x ``cols`` nodes (any number of them: a tiled grid need
    not fit in memory) and ``fields``, the keyword arguments of ZGrid but z."""

    rows: int
    cols: int
    fields: dict

    @property
    def shape(self):
        return self.rows, self.cols

    def described(self):
        """An object with the attributes of a ZGrid but z (grid_header_lines, the raster layouts)."""
        from mzc.grid import IDENTITY_TRANSFORM

        defaults = {"origin": (0.0, 0.0), "transform": IDENTITY_TRANSFORM, "units": None, "nodata": "nan",
                    "projection": "planar", "radius": None, "crs": None, "raster": None, "charts": None,
                    "source_vertices": None}
        return SimpleNamespace(shape=self.shape, **{**defaults, **self.fields})

    def block_fields(self, row, col, rounded=False):
        """The fields of the grid of the block whose node (0, 0) is node (``row``, ``col``): the
        spacings and projection, its own origin, and nothing the values do not need (a tile's
        stream holds no transform, units or CRS: the tiled file's header does), but, in a
        ``rounded`` file, the raster line whose integer type the tile's values are rounded to."""
        fields = self.fields
        x0, y0 = fields.get("origin", (0.0, 0.0))
        block = {"d1": fields["d1"], "d2": fields["d2"], "origin": (x0 + col * fields["d2"], y0 + row * fields["d1"])}
        if fields.get("projection", "planar") != "planar":
            block.update(projection=fields["projection"], radius=fields["radius"])
        if rounded:
            block["raster"] = fields["raster"]
        return block


def frame_of(grid):
    """The Frame of a ZGrid."""
    fields = {name: getattr(grid, name) for name in ("d1", "d2", "origin", "transform", "units", "nodata",
                                                     "projection", "radius", "crs", "raster")}
    return Frame(*grid.shape, fields)


class GridSource:
    """The values of a grid in memory, block by block: a tiled file's source."""

    def __init__(self, grid):
        if grid.charts is not None:
            raise MzcError("a multi-chart grid is coded whole: its charts are blocks of their own (--tile 0)",
                           field="tile")
        self.frame, self.z, self.colors = frame_of(grid), grid.z, grid.colors

    def integer_samples(self):
        """True when every valid value is one of the grid's raster's samples (an integer raster
        read as it is, not values computed since)."""
        from mzc.rasters import holds

        raster = self.frame.fields["raster"]
        return raster is not None and holds(raster.sample, self.z[~np.isnan(self.z)])

    def block(self, rows, cols):
        """The values of rows ``rows`` and columns ``cols`` (each a (start, stop)), NaN at invalid nodes."""
        return self.z[rows[0]:rows[1], cols[0]:cols[1]]

    def block_colours(self, rows, cols):
        """The nodes' colours of that block (None without colours)."""
        return None if self.colors is None else self.colors[rows[0]:rows[1], cols[0]:cols[1]]


# --------------------------------------------------------------------------- encoder


def check_targets(frame, options):
    """Refuse a target a tiled file cannot keep (``size``), and a surface target on a grid whose CRS
    is geographic (each tile, which has no CRS, would judge it by its values alone)."""
    from mzc.codecs.dwt2d import check_shared_unit

    if options.get("size") is not None:
        raise MzcError("--size aims at one file's bytes, and a grid this large is coded in independent tiles: "
                       "give --rmse or --max-error, or --tile 0 to code it whole (at most 10^8 nodes)", field="size")
    if options.get("max_error") is None and frame.fields.get("crs") is not None:
        check_shared_unit(frame.described(), "rmse")


def rounds(source, options):
    """True when the tiles of ``source`` are coded as rounded 6.0 files (``ROUNDED_TILED_VERSION``):
    a raster of integer samples read as it is (``source.integer_samples()``), coded with a max
    error, decodes to its own integers, as a grid coded whole does (spec/dwt2d.md, Rounding)."""
    raster = source.frame.fields.get("raster")
    return (options.get("max_error") is not None and raster is not None
            and np.dtype(raster.sample).kind in "iu" and source.integer_samples())


def coloured_tiles(source, rounded):
    """True when the tiles of ``source`` carry its colours (11.0): it has them (a grid in memory's,
    ``GridSource.colors``), and its tiles are not rounded 6.0 files, which code the shape alone."""
    return source.colors is not None and not rounded


def coded_tiles(source, tile, options, rounded, client=None):
    """The bytes of every tile of ``source`` (row by row of tiles, from the grid's first row), each
    a whole dwt2d file of its block coded with the dwt2d ``options`` (checked, without tile), a
    ``rounded`` one (``rounds``) when told: here, or as Dask tasks of ``client`` (a
    distributed.Client), each worker reading its block itself through ``source.opener`` (a source
    on disk that every worker sees), TASKS_AHEAD at a time."""
    frame = source.frame
    unit_checked = frame.fields.get("crs") is not None
    places = [(rows, cols) for rows in spans(frame.rows, tile) for cols in spans(frame.cols, tile)]
    if client is None:
        coloured = coloured_tiles(source, rounded)
        for rows, cols in places:
            colours = source.block_colours(rows, cols) if coloured else None
            yield coded_block(source.block(rows, cols), frame, rows, cols, options, unit_checked, rounded, colours)
        return
    for start in range(0, len(places), TASKS_AHEAD):
        futures = [client.submit(coded_remotely, source.opener, rows, cols, options, unit_checked, rounded,
                                 pure=False) for rows, cols in places[start:start + TASKS_AHEAD]]
        for future in futures:
            yield future.result()


def coded_block(values, frame, rows, cols, options, unit_checked, rounded=False, colours=None):
    """The dwt2d file of the block of ``frame`` at ``rows`` and ``cols`` (each a (start, stop)) holding
    ``values``, its heights and decoded heights held to mzc.limits as ``Codec.encode`` holds a
    whole grid's: a 3.x file; ``rounded``: a 6.0 file whose values decode to the raster's integers
    (its raster line lets encode_whole round them); with the block's ``colours``, a 10.x file
    with its colour section at the options' colour target."""
    from mzc.codecs.dwt2d import encode_whole
    from mzc.grid import ZGrid
    from mzc.limits import check_grid_magnitudes, check_magnitude

    grid = ZGrid(z=values, colors=colours, **frame.block_fields(rows[0], cols[0], rounded))
    check_grid_magnitudes(grid)
    data, decoded = encode_whole(grid, **options, unit_checked=unit_checked, compact=colours is not None)
    check_magnitude(decoded, "decoded heights", field="z")
    return data


def coded_remotely(opener, rows, cols, options, unit_checked, rounded):
    """A Dask task: the file of one tile of the source ``opener()`` opens, read and coded here."""
    source = opener()
    try:
        return coded_block(source.block(rows, cols), source.frame, rows, cols, options, unit_checked, rounded)
    finally:
        source.close()


def header_bytes(frame, tile, lengths, options, rounded=False, coloured=False):
    """The text header (through its ``data`` line, with its crc32) and the index of ``lengths``;
    ``rounded``: the 5.1 header of tiles rounded to integers, whose bound is floor(max_error);
    ``coloured``: the 11.0 header of tiles with colours."""
    from mzc.codecs.dwt2d import ROUNDING
    from mzc.formats.header import file_bytes, format_number, grid_header_lines, magic_line

    version = ROUNDED_TILED_VERSION if rounded else COLOURED_TILED_VERSION if coloured else TILED_VERSION
    lines = [magic_line("dwt2d", version),
             *grid_header_lines(frame.described(), write_defaults=False),
             f"tile {tile}", f"tiles {len(spans(frame.rows, tile))} {len(spans(frame.cols, tile))}"]
    if rounded:
        lines.append(f"rounding {ROUNDING}")
    if options.get("max_error") is not None:
        bound = float(math.floor(options["max_error"])) if rounded else options["max_error"]
        lines.append(f"max_error {format_number(bound)}")
    index = b"".join(LENGTH.pack(length) for length in lengths)
    return file_bytes([*lines, "data"]) + index + INDEX_CHECK.pack(zlib.crc32(index))


def encode(source, tile, options):
    """The bytes of a tiled file of ``source`` (a grid in memory: its bytes are too)."""
    check_targets(source.frame, options)
    rounded = rounds(source, options)
    tiles = list(coded_tiles(source, tile, options, rounded))
    return header_bytes(source.frame, tile, [len(t) for t in tiles], options, rounded,
                        coloured_tiles(source, rounded)) + b"".join(tiles)


def file_chunks(source, tile, options, spill_dir=None, scheduler=None) -> Iterator[bytes]:
    """The bytes of a tiled file of ``source`` in chunks, for a source too large to hold: the tiles
    are coded one at a time (or as Dask tasks on the ``scheduler`` at that address) into an unnamed
    spill file (in ``spill_dir``), then the header and the index are given, then the tiles read
    back a few MB at a time."""
    import tempfile
    from contextlib import nullcontext

    check_targets(source.frame, options)
    rounded = rounds(source, options)
    if scheduler is not None:
        from mzc.cluster import dask_client
    with tempfile.TemporaryFile(dir=spill_dir) as spill, \
            (nullcontext() if scheduler is None else dask_client(scheduler)) as client:
        lengths = []
        for data in coded_tiles(source, tile, options, rounded, client):
            spill.write(data)
            lengths.append(len(data))
        yield header_bytes(source.frame, tile, lengths, options, rounded, coloured_tiles(source, rounded))
        spill.seek(0)
        while chunk := spill.read(COPY_CHUNK):
            yield chunk


# --------------------------------------------------------------------------- decoder


class Bytes:
    """A file's bytes in memory, read at any offset."""

    def __init__(self, data):
        self.data = memoryview(data)
        self.size = len(self.data)

    def read(self, offset, length):
        return bytes(self.data[offset:offset + length])

    def close(self):
        """Nothing to release."""


class File:
    """A file on disk, read at any offset (os.pread): a window reads only its tiles."""

    def __init__(self, path):
        from mzc.streams import failure

        try:
            self.fd = os.open(path, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
            self.size = os.fstat(self.fd).st_size
        except OSError as error:
            raise failure(error, path) from None

    def read(self, offset, length):
        parts, done = [], 0
        while done < length:
            part = os.pread(self.fd, length - done, offset + done)
            if not part:
                break
            parts.append(part)
            done += len(part)
        return b"".join(parts)

    def close(self):
        os.close(self.fd)


def is_tiled(head):
    """True when bytes starting a file are those of a tiled dwt2d file's magic line (5.x, 11.x)."""
    return any(head.startswith(b"mzc-dwt2d %d." % major) for major in (TILED_VERSION[0], COLOURED_TILED_VERSION[0]))


class TiledFile:
    """A tiled dwt2d file opened from ``reader`` (Bytes or File): its header and index read and
    checked, its tiles decoded on demand."""

    def __init__(self, reader, source):
        from mzc.codecs.dwt2d import read_rounding

        self.reader, self.source = reader, source
        head = reader.read(0, min(reader.size, HEADER_LIMIT))
        end = head.find(b"\ndata\n")
        self.header, self.frame, self.tile, counts = self.read_header(head[:end + 6] if end >= 0 else head)
        self.coloured = self.header.major == COLOURED_TILED_VERSION[0]   # 11.0 has no rounding line
        self.rounded = not self.coloured and read_rounding(self.header, self.frame.fields, ROUNDED_TILED_VERSION)
        index_start = end + 6
        count = counts[0] * counts[1]
        if index_start + LENGTH.size * count + INDEX_CHECK.size > reader.size:
            raise MzcError(f"the file ends inside its index of {count} tiles (cut short)", source=source,
                           field="data")
        index = reader.read(index_start, LENGTH.size * count + INDEX_CHECK.size)
        if zlib.crc32(index[:-INDEX_CHECK.size]) != INDEX_CHECK.unpack(index[-INDEX_CHECK.size:])[0]:
            raise MzcError("the tile index's checksum does not match: the file is corrupt", source=source,
                           field="data")
        lengths = np.frombuffer(index, dtype="<u8", count=count).astype(np.int64)
        self.offsets = index_start + len(index) + np.concatenate([[0], np.cumsum(lengths)])
        if (lengths < 1).any() or lengths.max(initial=0) > reader.size or self.offsets[-1] != reader.size:
            raise MzcError(f"the tiles' lengths add up to {int(self.offsets[-1] - self.offsets[0])} bytes, and "
                           f"{reader.size - int(self.offsets[0])} follow the index (cut short or added to)",
                           source=source, field="data")
        self.row_spans, self.col_spans = spans(self.frame.rows, self.tile), spans(self.frame.cols, self.tile)

    def read_header(self, head):
        """(Header, Frame, tile side, (tile rows, tile columns)) of the text header, checked."""
        from mzc.codecs.dwt2d import CHECKSUM_SINCE, KIND, OLDEST_MAJOR, PROJECTED_VERSION
        from mzc.formats.header import integer_word, read_grid_fields, read_header

        header, _body, _line = read_header(head, self.source, KIND, COLOURED_TILED_VERSION[0],
                                           oldest_major=OLDEST_MAJOR, projected_major=PROJECTED_VERSION[0],
                                           checksum_since=CHECKSUM_SINCE, binary=True,
                                           georef_since={TILED_VERSION[0]: 0, COLOURED_TILED_VERSION[0]: 0})
        fields, rows, cols = read_grid_fields(header, whole=False)
        tile = header.integer("tile", MIN_TILE, MAX_TILE)
        try:
            counts = tuple(integer_word(word) for word in header.tokens("tiles", 2))
        except MzcError as error:
            raise header.error("tiles", error.message) from None
        if counts != (math.ceil(rows / tile), math.ceil(cols / tile)):
            raise header.error("tiles", f"{rows} x {cols} nodes in tiles of {tile} make "
                                        f"{math.ceil(rows / tile)} x {math.ceil(cols / tile)} tiles, not "
                                        f"{counts[0]} x {counts[1]}")
        if counts[0] * counts[1] > MAX_TILES:
            raise header.error("tiles", f"{counts[0] * counts[1]} tiles: this mzc reads at most {MAX_TILES}")
        return header, Frame(rows, cols, fields), tile, counts

    @property
    def counts(self):
        return len(self.row_spans), len(self.col_spans)

    def tile_bytes(self, i, j):
        """The bytes of tile (``i``, ``j``), the ``j``-th of the ``i``-th row of tiles."""
        k = i * len(self.col_spans) + j
        return self.reader.read(int(self.offsets[k]), int(self.offsets[k + 1] - self.offsets[k]))

    def tile_grid(self, i, j):
        """The decoded grid of tile (``i``, ``j``) (NaN at invalid nodes; of an 11.0 file, with its
        colours), its stream checked to be the block the header places there."""
        from mzc.codecs.dwt2d import ROUNDED_VERSION, compact
        from mzc.codecs.dwt2d import read as read_stream
        from mzc.formats.header import split_magic
        from mzc.grid import IDENTITY_TRANSFORM

        name = f"{self.source} (tile {i}, {j})"
        data = self.tile_bytes(i, j)
        major = ROUNDED_VERSION[0] if self.rounded else TIGHT_VERSION[0] if self.coloured else 3
        found_major = compact.major(data) if self.coloured else split_magic(data, name)[1]
        if found_major != major:
            raise MzcError(f"a tile of this file is a dwt2d {major}.x stream", source=name, line=1)
        grid = read_stream(data, name)
        rows, cols = self.row_spans[i], self.col_spans[j]
        expected = self.frame.block_fields(rows[0], cols[0], self.rounded)
        found = {"d1": grid.d1, "d2": grid.d2, "origin": grid.origin}
        if grid.projection != "planar":
            found.update(projection=grid.projection, radius=grid.radius)
        if self.rounded:
            found["raster"] = grid.raster
        if grid.shape != (rows[1] - rows[0], cols[1] - cols[0]) or found != expected:
            raise MzcError(f"the tile's grid ({grid.shape[0]} x {grid.shape[1]} nodes at {grid.origin}) is not "
                           f"the block the header places there", source=name, field="rows")
        if (grid.units, grid.nodata, grid.crs, None if self.rounded else grid.raster) != (None, "nan", None, None) \
                or not np.array_equal(grid.transform, IDENTITY_TRANSFORM):
            raise MzcError("the tile has lines of its own (transform, units, nodata, crs or raster) that only the "
                           "file's header may have", source=name, field="data")
        valid = grid.valid
        if self.rounded and not np.array_equal(grid.z[valid], np.rint(grid.z[valid])):
            raise MzcError("the tile's values are not rounded to integers, as the file's rounding line says",
                           source=name, field="rounding")
        if self.coloured and (grid.colors is None or grid.fine_colors is not None):
            raise MzcError("a tile of this file has no colour section of its nodes' colours", source=name,
                           field="colour")
        return grid

    def window(self, row=0, col=0, rows=None, cols=None):
        """The ZGrid of rows ``row``..``row + rows - 1`` and columns ``col``..``col + cols - 1`` (the
        whole grid by default), decoding only the tiles they touch."""
        rows = self.frame.rows - row if rows is None else rows
        cols = self.frame.cols - col if cols is None else cols
        check_window(self.frame.shape, (row, col, rows, cols), source=self.source)
        z = np.empty((rows, cols))
        colours = np.empty((rows, cols, 3), dtype=np.uint8) if self.coloured else None
        for i, (r0, r1) in enumerate(self.row_spans):
            for j, (c0, c1) in enumerate(self.col_spans):
                top, bottom, left, right = max(r0, row), min(r1, row + rows), max(c0, col), min(c1, col + cols)
                if top < bottom and left < right:
                    grid, inside = self.tile_grid(i, j), (slice(top - r0, bottom - r0), slice(left - c0, right - c0))
                    z[top - row:bottom - row, left - col:right - col] = grid.z[inside]
                    if colours is not None:
                        colours[top - row:bottom - row, left - col:right - col] = grid.colors[inside]
        return window_grid(self.frame, z, row, col, colours)

    def blocks(self):
        """((row span, column span), values) of every tile, row by row of tiles."""
        for i, rows in enumerate(self.row_spans):
            for j, cols in enumerate(self.col_spans):
                yield (rows, cols), self.tile_grid(i, j).z

    def close(self):
        self.reader.close()


def check_window(shape, window, source=None):
    """Refuse a window (row, col, rows, cols) that does not lie in a grid of ``shape``, or that is
    larger than a grid in memory may be."""
    row, col, rows, cols = window
    if min(row, col) < 0 or min(rows, cols) < 1 or row + rows > shape[0] or col + cols > shape[1]:
        raise MzcError(f"rows {row}..{row + rows - 1} and columns {col}..{col + cols - 1} are not a window of "
                       f"the grid's {shape[0]} x {shape[1]} nodes", source=source, field="window")
    check_grid_size(rows, cols, advice="decode a window of it (mzc decode --window), or write it as a GeoTIFF "
                                       "(mzc decode --format tif), which is written tile by tile", source=source,
                    field="window")


def window_grid(frame, z, row, col, colors=None, fine_colors=None):
    """The ZGrid of the values ``z`` (and ``colors`` or ``fine_colors``, when the grid has them) of
    the window at node (``row``, ``col``) of ``frame``: its fields, its own origin."""
    from mzc.grid import ZGrid

    fields = {**frame.fields, "origin": frame.block_fields(row, col)["origin"]}
    return ZGrid(z=z, colors=colors, fine_colors=fine_colors, **fields)


def window_of(grid, window):
    """The ZGrid of the ``window`` (row, col, rows, cols) of a grid in memory."""
    if grid.charts is not None:
        raise MzcError("a multi-chart grid's window would cut its charts: decode it whole", field="window")
    row, col, rows, cols = window
    check_window(grid.shape, window)
    colours = None if grid.colors is None else grid.colors[row:row + rows, col:col + cols]
    fine, k = grid.fine_colors, grid.colour_scale   # the samples of the window's cells, K a spacing
    fine = None if fine is None else fine[row * k:(row + rows - 1) * k + 1, col * k:(col + cols - 1) * k + 1]
    return window_grid(frame_of(grid), grid.z[row:row + rows, col:col + cols], row, col, colours, fine)


def open_tiled(path):
    """The TiledFile of the file at ``path``, or None when it is not a tiled dwt2d file or ``path``
    is stdin (whose bytes are read whole, and decoded as any file's)."""
    from mzc.streams import display_name, is_stdio

    if is_stdio(path) or not os.path.isfile(path):
        return None
    reader = File(path)
    if not is_tiled(reader.read(0, 16)):
        reader.close()
        return None
    try:
        return TiledFile(reader, display_name(path))
    except BaseException:
        reader.close()
        raise


def read(data, source="<bytes>"):
    """The ZGrid of a tiled file's bytes (the whole grid, at most 10^8 nodes: a window otherwise)."""
    return TiledFile(Bytes(data), source).window()
