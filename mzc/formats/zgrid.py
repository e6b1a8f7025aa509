"""The z-grid text format (``mzc-zgrid 1.0``, extension ``.zg``): see spec/zgrid.md.

The uncompressed format that flows between mzc commands: the grid header, a ``data``
line, then one line per row with ``cols`` heights separated by spaces, invalid nodes
written as the no-data marker.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.formats.header import (
    file_bytes,
    file_version,
    format_number,
    grid_header_lines,
    magic_line,
    read_grid_fields,
    read_header,
)
from mzc.grid import ZGrid
from mzc.numbers import floats

KIND = "zgrid"
VERSION = (1, 0)             # planar grids, byte for byte as before projections
PROJECTED_VERSION = (2, 0)   # 1.0 with the projection lines (mzc.formats.header)
OLDEST_MAJOR = 1


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
    """Split a text body into (line number, text) pairs, skipping blank trailing lines."""
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError:
        raise MzcError("data is not UTF-8 text", source=source, line=first_line) from None
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    return [(first_line + i, line) for i, line in enumerate(lines)]


def read(data, source="<bytes>"):
    """Parse z-grid bytes into a ZGrid; raise MzcError naming the line and field on bad input."""
    header, body, first_line = read_header(data, source, KIND, PROJECTED_VERSION[0],
                                           projected_major=PROJECTED_VERSION[0])
    fields, rows, cols = read_grid_fields(header)
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
        z[r] = parse_values(tokens, fields["nodata"], source, line_number)
    return ZGrid(z=z, **fields)


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


def write(grid, precision=None):
    """Serialise a ZGrid to z-grid bytes; ``precision`` (decimals) rounds the heights."""
    lines = [magic_line(KIND, file_version(grid, VERSION, PROJECTED_VERSION)), *grid_header_lines(grid), "data",
             *format_rows(grid.z, grid.nodata, precision)]
    return file_bytes(lines, checksum=False)
