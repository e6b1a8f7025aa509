"""The z-grid format (extension ``.zg``): see spec/zgrid.md.

The uncompressed format that flows between mzc commands: the grid header, a ``data``
line, then the heights, in one of two bodies (as netpbm's plain and raw variants):

- plain (``mzc-zgrid 1.0``, ``2.0`` for central projections): one text line per row with
  ``cols`` heights separated by spaces, invalid nodes written as the no-data marker;
- raw (``mzc-zgrid 3.0``, any projection): a ``raw float64`` (or ``float32``) header line and
  the file's ``crc32`` line, then rows x cols little-endian IEEE 754 values, row by row, NaN
  for invalid nodes. A new major version, so readers that only know text bodies refuse it.

A planar grid read from a raster adds the ``crs`` and ``raster`` lines, a minor version of
each body (1.1, 3.1); other grids keep 1.0, 2.0 and 3.0 byte for byte. A multi-chart grid
(``charts``) is ``mzc-zgrid 4.0``: 3.0 with the ``charts`` line, a raw body only. A grid with
colours at its nodes is ``mzc-zgrid 5.0``: 4.0 (any projection, charts, crs and raster as they
come) with the ``colours rgb8`` line, its raw body's heights followed by each node's red, green
and blue bytes, row by row; 5.1 when it has the ``crs`` and ``raster`` lines. The count of
the source's vertices (``source_vertices``) is a minor version of each (1.2, 2.1, 3.2, 4.1, 5.2),
written only for a grid that has it. A grid whose colours are sampled finer than its nodes
(``fine_colors``, colour scale K > 1) is ``mzc-zgrid 6.0``: 5.2 with the ``colour_scale K`` line,
its colour bytes the ((rows - 1) K + 1) x ((cols - 1) K + 1) samples; K = 1 keeps 5.x.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.formats.header import (
    counted_version,
    file_bytes,
    file_version,
    format_number,
    grid_header_lines,
    magic_line,
    read_grid_fields,
    read_header,
    split_magic,
)
from mzc.grid import ZGrid
from mzc.limits import check_grid_magnitudes
from mzc.numbers import floats, unpadded

KIND = "zgrid"
EXTENSIONS = (".zg",)
VERSION = (1, 0)             # planar grids, byte for byte as before projections
PROJECTED_VERSION = (2, 0)   # 1.0 with the projection lines (mzc.formats.header)
OLDEST_MAJOR = 1
RAW_VERSION = (3, 0)         # 2.0's header with a raw binary body, planar or projected
GEOREFERENCED_VERSION = (1, 1)       # 1.0 with the crs and raster lines of a grid read from a raster
RAW_GEOREFERENCED_VERSION = (3, 1)   # 3.0 with them
CHARTED_VERSION = (4, 0)     # 3.0 with the charts line of a multi-chart grid
COLOURED_VERSION = (5, 0)    # 4.0 with the colours line and each node's colour after the heights
COLOURED_GEOREFERENCED_VERSION = (5, 1)   # 5.0 with the crs and raster lines (a coloured LAS cloud's grid)
FINE_COLOURED_VERSION = (6, 0)   # 5.2 with the colour_scale line, the colours sampled that much finer
GEOREF_SINCE = {**dict([GEOREFERENCED_VERSION, RAW_GEOREFERENCED_VERSION, COLOURED_GEOREFERENCED_VERSION]),
                FINE_COLOURED_VERSION[0]: 0}   # major -> the minor that adds the crs and raster lines
COUNTED_SINCE = {1: 2, 2: 1, 3: 2, 4: 1, 5: 2, 6: 0}   # major -> the minor that adds the source_vertices line
CHECKSUM_SINCE = {RAW_VERSION[0]: 0, CHARTED_VERSION[0]: 0, COLOURED_VERSION[0]: 0,
                  FINE_COLOURED_VERSION[0]: 0}   # a raw body: never without crc32
COLOUR_LAYOUTS = {"rgb8": 3}   # the colours line's value -> bytes a node (red, green, blue, 8 bits each)
SAMPLES = {"float64": "<f8", "float32": "<f4"}   # the raw line's value -> numpy dtype of the body


def parse_values(tokens, nodata, source, line):
    """Turn a row's text tokens into floats; the no-data marker and ``nan`` become NaN."""
    if nodata.lower() != "nan":
        tokens = ["nan" if t == nodata else t for t in tokens]
    values = floats(tokens, source, line)
    if np.isinf(values).any():
        column = int(np.flatnonzero(np.isinf(values))[0]) + 1
        raise MzcError(f"value {column} is infinite", source=source, line=line)
    return values


def body_lines(body, first_line, source):
    """Split a text body into (line number, text) pairs, skipping blank trailing lines and the NUL
    bytes that may pad its end."""
    try:
        text = unpadded(body).decode("utf-8")
    except UnicodeDecodeError:
        raise MzcError("data is not UTF-8 text", source=source, line=first_line) from None
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    return [(first_line + i, line) for i, line in enumerate(lines)]


def read(data, source="<bytes>"):
    """Parse z-grid bytes (a plain or a raw body) into a ZGrid; raise MzcError naming the line
    and field on bad input."""
    major = split_magic(data, source)[1]
    raw = major >= RAW_VERSION[0]
    header, body, first_line = read_header(data, source, KIND, FINE_COLOURED_VERSION[0],
                                           projected_major=PROJECTED_VERSION[0], checksum_since=CHECKSUM_SINCE,
                                           binary=raw, georef_since=GEOREF_SINCE, charted_major=CHARTED_VERSION[0],
                                           counted_since=COUNTED_SINCE)
    fields, rows, cols = read_grid_fields(header)
    if major >= COLOURED_VERSION[0]:
        scale = colour_scale(header, rows, cols) if major >= FINE_COLOURED_VERSION[0] else 1
        body, fields["fine_colors"] = read_colours(body, header, (rows - 1) * scale + 1, (cols - 1) * scale + 1)
    z = read_raw(body, header, rows, cols) if raw else read_plain(body, first_line, fields["nodata"], rows, cols,
                                                                  source)
    return ZGrid(z=z, **fields)


def colour_scale(header, rows, cols):
    """The ``colour_scale`` line of a 6.0 header (required): K in 2..8, its image within the limits."""
    from mzc.limits import MAX_COLOUR_SCALE, check_colour_scale

    scale = header.integer("colour_scale", 2, MAX_COLOUR_SCALE)
    return check_colour_scale(scale, rows, cols, source=header.source, field="colour_scale")


def read_colours(body, header, rows, cols):
    """(the heights' part of a 5.0 or 6.0 raw body, its (rows, cols, 3) uint8 colour samples): the
    ``colours`` line (required) names their layout, and the body's last rows x cols x 3 bytes hold
    them, the length checked (with the heights', ``read_raw``) before anything is allocated."""
    size = rows * cols * COLOUR_LAYOUTS[header.word("colours", tuple(COLOUR_LAYOUTS))]
    if len(body) < size:
        raise MzcError(f"the raw body has {len(body)} bytes, fewer than the {size} of the nodes' colours alone "
                       "(cut short)", source=header.source, field="data")
    colours = np.frombuffer(body, np.uint8, offset=len(body) - size).reshape(rows, cols, 3)
    return memoryview(body)[:len(body) - size], colours


def read_plain(body, first_line, nodata, rows, cols, source):
    """The rows x cols heights of a text body, one line per row."""
    lines = body_lines(body, first_line, source)
    if len(lines) != rows:
        raise MzcError(f"header says rows {rows} but the data has {len(lines)} row line(s)",
                       source=source, line=first_line + min(len(lines), rows))
    z = np.empty((rows, cols))
    for r, (line_number, line) in enumerate(lines):
        tokens = line.split()
        if len(tokens) != cols:
            raise MzcError(f"header says cols {cols} but this row has {len(tokens)} value(s)",
                           source=source, line=line_number)
        z[r] = parse_values(tokens, nodata, source, line_number)
    return z


def read_raw(body, header, rows, cols):
    """The rows x cols heights of a raw body, as float64; its length is checked against the
    declared sizes before anything is allocated, and an infinite value is refused."""
    sample = header.word("raw", tuple(SAMPLES))
    dtype = np.dtype(SAMPLES[sample])
    expected = rows * cols * dtype.itemsize
    if len(body) != expected:
        cause = "cut short" if len(body) < expected else "with bytes added"
        raise MzcError(f"the raw body has {len(body)} bytes, but rows {rows} x cols {cols} of {sample} take "
                       f"{expected} ({cause})", source=header.source, field="data")
    z = np.frombuffer(body, dtype).reshape(rows, cols).astype(np.float64)
    infinite = np.isinf(z)
    if infinite.any():
        r, c = (int(i) for i in np.argwhere(infinite)[0])
        raise MzcError(f"the value at row {r + 1}, column {c + 1} is infinite", source=header.source, field="data")
    return z


def format_rows(z, nodata, precision=None):
    """Text lines for the rows of ``z``: shortest round-trip numbers, rounded when ``precision`` is given."""
    if precision is not None:
        z = np.round(z, precision) + 0.0  # + 0.0 turns -0.0 into 0.0
    check_marker_unused(z, nodata)
    return [" ".join(nodata if v != v else format_number(v) for v in row.tolist()) for row in z]


def check_marker_unused(z, nodata):
    """Refuse to write a valid value as the no-data marker's very token, which would read back as
    invalid (``nodata 0`` with ``--precision 0`` once turned every height under 0.5 into a hole)."""
    try:
        marker = float(nodata)
    except ValueError:
        return   # a word such as NA: no number is written as it
    same = z == marker
    if same.any() and format_number(marker) == nodata:
        r, c = (int(i) for i in np.argwhere(same)[0])
        raise MzcError(f"the valid value at row {r + 1}, column {c + 1} would be written as {nodata}, the no-data "
                       f"marker, and read back as invalid: choose another marker or more precision", field="nodata")


def write(grid, precision=None, raw=None):
    """Serialise a ZGrid to z-grid bytes: plain text (``raw`` None; ``precision`` decimals round
    the heights), or a raw body of ``raw`` samples, "float64" (exact) or "float32". Heights or
    coordinates beyond mzc.limits' are refused: no reader would take them back."""
    check_grid_magnitudes(grid)
    if raw is None:
        if grid.charts is not None or grid.colors is not None:
            what, version = ("multi-chart", 4) if grid.colors is None else ("coloured", 5)
            raise MzcError(f"a {what} grid is written with a raw body (mzc-zgrid {version}.0), not as text rows",
                           field="plain")
        version = file_version(grid, VERSION, PROJECTED_VERSION, GEOREFERENCED_VERSION)
        lines = [magic_line(KIND, counted_version(grid, version, COUNTED_SINCE)),
                 *grid_header_lines(grid, counted=True), "data",
                 *format_rows(grid.z, grid.nodata, precision)]
        return file_bytes(lines, checksum=False)
    if precision is not None:
        raise MzcError("precision rounds the text of a plain body; a raw body holds the values exactly",
                       field="precision")
    if grid.fine_colors is not None:
        lines = [magic_line(KIND, FINE_COLOURED_VERSION), *grid_header_lines(grid, counted=True), f"raw {raw}",
                 "colours rgb8", f"colour_scale {grid.colour_scale}", "data"]
        return file_bytes(lines, bytes(raw_body(grid.z, raw)) + grid.fine_colors.tobytes())
    if grid.colors is not None:
        version = counted_version(grid, COLOURED_GEOREFERENCED_VERSION if grid.georeferenced else COLOURED_VERSION,
                                  COUNTED_SINCE)
        lines = [magic_line(KIND, version), *grid_header_lines(grid, counted=True), f"raw {raw}", "colours rgb8",
                 "data"]
        return file_bytes(lines, bytes(raw_body(grid.z, raw)) + grid.colors.tobytes())
    version = counted_version(grid, file_version(grid, RAW_VERSION, RAW_VERSION, RAW_GEOREFERENCED_VERSION,
                                                 CHARTED_VERSION), COUNTED_SINCE)
    lines = [magic_line(KIND, version), *grid_header_lines(grid, counted=True), f"raw {raw}", "data"]
    return file_bytes(lines, raw_body(grid.z, raw))


def raw_body(z, sample):
    """The raw body of ``sample`` values (a buffer to append to the header): little-endian, row
    by row, every invalid node the one quiet NaN (so equal grids give equal files); refuses a
    value float32 cannot hold. A float64 ``z`` whose NaNs all are that one is written from its
    own memory, not a copy: on a dense grid of 50 M nodes the copy took 400 MB."""
    if sample not in SAMPLES:
        raise MzcError(f"{sample!r} is not one of {', '.join(SAMPLES)}", field="raw")
    with np.errstate(over="ignore"):
        values = np.ascontiguousarray(z, dtype=SAMPLES[sample])
    overflow = np.isinf(values)
    if overflow.any():
        r, c = (int(i) for i in np.argwhere(overflow)[0])
        raise MzcError(f"the value at row {r + 1}, column {c + 1}, {z[r, c]:g}, does not fit {sample} (values "
                       f"are finite)", field="raw")
    invalid = np.isnan(values)
    bits = values.view(f"<u{values.itemsize}")
    if (bits[invalid] != np.array(np.nan, values.dtype).view(bits.dtype)).any():
        if np.shares_memory(values, z):
            values = values.copy()
        values[invalid] = np.nan
    return memoryview(values).cast("B")
