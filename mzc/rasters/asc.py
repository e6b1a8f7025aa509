"""ESRI ASCII grids (``.asc``, Arc/Info ASCII Grid): a few ``keyword value`` header lines, then
the values, the north row first.

The header (keywords in any case and order, as GDAL reads them): ``ncols``, ``nrows``; the
south-west corner of the grid's cells (``xllcorner``, ``yllcorner``: cells are areas) or the
centre of its south-west cell (``xllcenter``, ``yllcenter``: cells are points); ``cellsize``,
or ``dx`` and ``dy`` for cells that are not square (GDAL's extension); and optionally
``NODATA_value``, the value of a cell with no data (without it no cell is no-data, as GDAL
reads it). The values are a stream of numbers separated by white space, ``ncols`` to a row,
however the lines break. The CRS, when there is one, is WKT in a ``.prj`` file beside the grid
(``mzc.rasters.sidecar_crs``).

Values whose every valid value and no-data value is an integer in int32's range are recorded
as int32 samples (a GeoTIFF written from the grid takes that type), others as float64.
"""

import re

import numpy as np

from mzc.errors import MzcError
from mzc.formats.header import format_number
from mzc.formats.zgrid import format_rows
from mzc.limits import MAX_DIMENSION, check_grid_size, length_problem
from mzc.numbers import bad_token, parse_int, to_floats, unpadded
from mzc.rasters import Layout, grid_of, holds, layout_of, no_data_marker

KEYWORDS = ("ncols", "nrows", "xllcorner", "yllcorner", "xllcenter", "yllcenter", "cellsize", "dx", "dy",
            "nodata_value")
HEAD = re.compile(rb"\A\s*(" + b"|".join(k.encode() for k in KEYWORDS) + rb")[ \t]+[-+.0-9]", re.IGNORECASE)
DEFAULT_MARKER = -9999.0   # the no-data value written when the grid's own marker is not a number
EXTENSIONS = (".asc",)


def sniff(data):
    """True when ``data`` starts with an ESRI ASCII grid header line, else False: an ESRI grid always
    does (an .asc of x y z lines is a point cloud)."""
    return HEAD.match(data[:256]) is not None


def read(data, source, crs=None):
    """The ZGrid of an ESRI ASCII grid's bytes, with the CRS ``crs`` (the WKT of the ``.prj`` beside
    it, which mzc.formats reads) when given; a bad header or value is an MzcError naming the line
    and the keyword."""
    try:
        text = unpadded(data).decode("utf-8")
    except UnicodeDecodeError:
        raise MzcError("an ESRI ASCII grid is text, and this is not UTF-8", source=source) from None
    header, body, first_line = read_header(text, source)
    rows, cols = header["nrows"][0], header["ncols"][0]
    values = read_values(body, first_line, rows, cols, source)
    nodata = header.get("nodata_value", (None,))[0]
    invalid = np.isnan(values) if nodata is None else (np.isnan(values) | (values == nodata))
    sample = "int32" if holds("int32", np.append(values[~invalid], [] if nodata is None else [nodata])) else "float64"
    try:
        return grid_of(values, invalid, layout(header, source), sample, nodata=nodata, crs=crs)
    except MzcError as error:
        raise error.located(source=source) from None


def read_header(text, source):
    """({keyword: (value, line)}, the text after the header, its first line number); every
    keyword checked, the grid's size before anything is allocated for it."""
    header, position, line = {}, 0, 0
    while True:
        end = text.find("\n", position)
        end = len(text) if end < 0 else end
        tokens = text[position:end].split()
        if tokens and tokens[0].lower() not in KEYWORDS:
            break
        line += 1
        if tokens:
            header_line(header, tokens, source, line)
        if end == len(text):
            break
        position = end + 1
    for keyword in ("ncols", "nrows"):
        if keyword not in header:
            raise MzcError("required header line missing", source=source, field=keyword)
    check_grid_size(header["nrows"][0], header["ncols"][0], source=source, line=header["nrows"][1], field="nrows")
    return header, text[position:], line + 1


def header_line(header, tokens, source, line):
    """Add the ``keyword value`` line ``tokens`` to ``header``, its value checked."""
    keyword = tokens[0].lower()
    if len(tokens) != 2:
        raise MzcError(f"expected one value, found {len(tokens) - 1}", source=source, line=line, field=tokens[0])
    if keyword in header:
        raise MzcError(f"given twice (first on line {header[keyword][1]})", source=source, line=line,
                       field=tokens[0])
    if keyword in ("ncols", "nrows"):
        value = parse_int(tokens[1])
        if value is None or not 1 <= value <= MAX_DIMENSION:
            raise MzcError(f"{tokens[1][:40]!r} is not a whole number in 1..{MAX_DIMENSION}", source=source,
                           line=line, field=tokens[0])
    else:
        try:
            value = float(to_floats(tokens[1:])[0])
        except ValueError:
            raise MzcError(f"not a number: {tokens[1][:40]!r}", source=source, line=line, field=tokens[0]) from None
        problem = (length_problem(value) if keyword in ("cellsize", "dx", "dy")
                   else None if np.isfinite(value) or keyword == "nodata_value" and np.isnan(value)
                   else "must be finite")
        if problem:
            raise MzcError(problem, source=source, line=line, field=tokens[0])
    header[keyword] = (value, line)


def layout(header, source):
    """The Layout of the header's corner or centre and cell size."""
    kinds = {axis: [k for k in (f"{axis}llcorner", f"{axis}llcenter") if k in header] for axis in "xy"}
    for axis, found in kinds.items():
        if len(found) != 1:
            raise MzcError(f"expected one of {axis}llcorner or {axis}llcenter, found "
                           f"{' and '.join(found) or 'neither'}", source=source, field=f"{axis}llcorner")
    if kinds["x"][0][3:] != kinds["y"][0][3:]:
        raise MzcError(f"{kinds['x'][0]} with {kinds['y'][0]}: give both corners or both centres", source=source,
                       line=header[kinds["y"][0]][1], field=kinds["y"][0])
    if "cellsize" in header:
        if "dx" in header or "dy" in header:
            raise MzcError("cellsize with dx or dy: give one", source=source, line=header["cellsize"][1],
                           field="cellsize")
        d2 = d1 = header["cellsize"][0]
    elif "dx" in header and "dy" in header:
        d2, d1 = header["dx"][0], header["dy"][0]
    else:
        raise MzcError("required header line missing (or dx and dy)", source=source, field="cellsize")
    cells = "area" if kinds["x"][0].endswith("corner") else "point"
    return Layout(header[kinds["x"][0]][0], header[kinds["y"][0]][0], d2, d1, cells, "down", top=False,
                  centred=cells == "point")


def read_values(body, first_line, rows, cols, source):
    """The rows x cols values of the body, a stream of numbers (converted in one call; the first
    bad one is found, and its line named, only on failure)."""
    tokens = body.split()
    try:
        values = to_floats(tokens)
    except ValueError:
        line, column, token = first_bad(body, first_line)
        raise MzcError(f"value {column} is not a number: {token[:40]!r}", source=source, line=line) from None
    if len(values) != rows * cols:
        cause = "cut short" if len(values) < rows * cols else "more values than the grid has"
        raise MzcError(f"the data holds {len(values)} values, but nrows {rows} x ncols {cols} take {rows * cols} "
                       f"({cause})", source=source, line=first_line + body.rstrip().count("\n"), field="nrows")
    infinite = np.isinf(values)
    if infinite.any():
        index = int(np.flatnonzero(infinite)[0])
        raise MzcError(f"the value of row {index // cols + 1}, column {index % cols + 1} is infinite",
                       source=source, field="data")
    return values.reshape(rows, cols)


def first_bad(body, first_line):
    """(line number, position on the line, token) of the body's first token that is not a number."""
    for number, line in enumerate(body.splitlines(), first_line):
        tokens = line.split()
        index = bad_token(tokens)
        if index is not None:
            return number, index + 1, tokens[index]
    raise AssertionError("no bad token in a body that failed to convert")


def write(grid, float32=False):
    """The bytes of ``grid`` as an ESRI ASCII grid (a grid mzc.rasters.check_writable accepts):
    its raster's corner or centre, the cell size (dx and dy when not square), the no-data value
    when it has one, then the rows north first, every number in its shortest exact form. Text
    holds no float32 samples: ``float32`` is refused."""
    if float32:
        raise MzcError("an ESRI ASCII grid is text: float32 is for GeoTIFF samples", field="float32",
                       options=("float32",))
    cells = grid.raster.cells if grid.raster is not None else "area"
    place = layout_of(grid, top=False, centred=cells == "point")
    kind = "corner" if place.cells == "area" else "center"
    lines = [f"ncols {grid.shape[1]}", f"nrows {grid.shape[0]}", f"xll{kind} {format_number(place.x)}",
             f"yll{kind} {format_number(place.y)}"]
    if grid.d1 == grid.d2:
        lines.append(f"cellsize {format_number(grid.d2)}")
    else:
        lines += [f"dx {format_number(grid.d2)}", f"dy {format_number(grid.d1)}"]
    marker = no_data_marker(grid)
    if marker is not None and np.isnan(marker):
        marker = unused_marker(grid)
    if marker is not None:
        lines.append(f"NODATA_value {format_number(marker)}")
    token = format_number(marker) if marker is not None else "nan"
    return ("\n".join([*lines, *format_rows(grid.z[::-1], token)]) + "\n").encode("ascii")


def unused_marker(grid):
    """A no-data value for a grid whose marker is not a number: -9999, or below every valid value."""
    values = grid.z[grid.valid]
    if not (values == DEFAULT_MARKER).any():
        return DEFAULT_MARKER
    return float(np.floor(values.min()) - 1)
