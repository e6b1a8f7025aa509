"""Parsing and writing of the text header shared by every mzc format.

Every mzc file starts with a magic line ``mzc-KIND MAJOR.MINOR``, then header lines
``keyword value...`` (``#`` starts a comment line), then a line ``data`` after which the
body follows. Readers ignore header keywords they do not know (files from a newer minor
version stay readable) and refuse a newer major version. The grid fields (rows, cols,
d1, d2, origin, projection, radius, transform, units, nodata) are common to the z-grid and
the compressed formats; see spec/zgrid.md.

The version rule for projections: a grid on central cutting surfaces needs a major version
of its format that knows them (``mzc-zgrid 2.0``, ``mzc-dct 2.0``, ``mzc-dwt2d 3.0``); a
reader that predates projections would ignore the ``projection`` line and decode a wrong
surface, and the major version makes it refuse the file instead. Each format module names
the version its writer gives planar grids (``VERSION``: the older one where the bytes did
not change, so older readers keep reading them), the one it gives projected grids
(``PROJECTED_VERSION``) and the oldest major it reads (``OLDEST_MAJOR``).

The version rule for charts is the same: a multi-chart grid's ``charts`` line changes the
surface a file decodes to, so it needs a major version that knows it (``CHARTED_VERSION``
of the z-grid and of dwt2d; the thesis's row codecs code one chart).

The georeferencing lines (``crs``, ``raster``) of a planar grid read from a raster describe
the same nodes, so they came in a minor version of each format (``GEOREF_SINCE``: major ->
first minor that reads them; older readers ignore them and decode the same surface); a grid
without them keeps its format's older version, byte for byte.

The source's vertex count (``source_vertices``, the size of the mesh or cloud a grid was sliced
from, which the rebuild comes back near) describes the same nodes too: a minor version of the
z-grid (``COUNTED_SINCE``: major -> first minor), and a field of ``mzc-dwt2d`` 8.0 from its start.
Writers write it only for a grid that has one (``grid_header_lines(..., counted=True)``), so every
other grid keeps its version byte for byte; the thesis's row codecs and dwt2d's tiles leave it out.

The integrity rule: a compressed format's file carries a ``crc32`` header line, the CRC-32
of every byte of the file but that line (``with_checksum``); ``read_header`` checks it
before anything reads the body, whatever the version, and refuses a file of a version that
must carry it (``CHECKSUM_SINCE`` of each format module: major -> first minor) without it.
So a flipped bit, a cut, appended bytes or line ends converted to CRLF anywhere in the file
are refused instead of decoding to a wrong surface.
"""

import math
import re
import zlib

import numpy as np

from mzc import projections
from mzc.errors import MzcError
from mzc.grid import (
    IDENTITY_TRANSFORM,
    MAX_CHARTS,
    MAX_SOURCE_VERTICES,
    Chart,
    Raster,
    check_charts,
    check_crs,
    check_token,
)
from mzc.limits import MAX_DIMENSION, check_grid_size, length_problem
from mzc.numbers import parse_int
from mzc.vectors import determinant, matrix_product

RIGID_TOLERANCE = 1e-6
CHECKSUM = "crc32"   # the header keyword of a file's checksum


def split_magic(data, source):
    """Return (kind, major, minor) from the first line of ``data`` (bytes), or raise."""
    first = data[:200].split(b"\n", 1)[0].strip()
    parts = first.split()
    if len(parts) != 2 or not parts[0].startswith(b"mzc-"):
        raise MzcError("not an mzc file: missing magic line 'mzc-KIND VERSION'", source=source, line=1)
    kind = parts[0][4:].decode("ascii", "replace")
    version = re.fullmatch(rb"(\d{1,6})\.(\d{1,6})", parts[1])
    if not version:
        raise MzcError(f"bad version {parts[1].decode('ascii', 'replace')!r} in magic line (expected MAJOR.MINOR)",
                       source=source, line=1)
    return kind, int(version[1]), int(version[2])


def file_version(grid, planar, projected, georeferenced, charted=None):
    """The version a format writes ``grid`` with: its ``planar`` one, its ``projected`` one, its
    ``georeferenced`` one for a planar grid with a CRS or raster layout, or its ``charted`` one
    for a multi-chart grid (refused by a format that has none)."""
    if grid.charts is not None:
        if charted is None:
            raise MzcError(f"this format codes one chart; the grid has {len(grid.charts)} (code it with --dwt2d, "
                           "or slice with --charts 1)", field="charts")
        return tuple(charted)
    if grid.projection != "planar":
        return tuple(projected)
    return tuple(georeferenced) if grid.georeferenced else tuple(planar)


def magic_line(kind, version):
    """The first line of an mzc file: ``mzc-KIND MAJOR.MINOR``."""
    return f"mzc-{kind} {version[0]}.{version[1]}"


class Header:
    """The keyword lines of a header, with the line number of each for error messages.

    ``major`` and ``minor`` are the file's version; ``projected`` is True when it may hold a central
    projection, ``georeferenced`` when its version reads the ``crs`` and ``raster`` lines,
    ``charted`` when it may hold charts, ``counted`` when it reads ``source_vertices``.
    """

    def __init__(self, source, major=1, projected=False, georeferenced=False, charted=False, minor=0,
                 counted=False):
        self.source = source
        self.fields = {}
        self.major, self.minor = major, minor
        self.projected = projected
        self.georeferenced = georeferenced
        self.charted = charted
        self.counted = counted

    def add(self, keyword, values, line):
        if keyword in self.fields:
            raise MzcError(f"header keyword given twice (first on line {self.fields[keyword][1]})",
                           source=self.source, line=line, field=keyword)
        self.fields[keyword] = (values, line)

    def has(self, keyword):
        return keyword in self.fields

    def error(self, keyword, message):
        line = self.fields[keyword][1] if keyword in self.fields else None
        return MzcError(message, source=self.source, line=line, field=keyword)

    def tokens(self, keyword, count=None, required=True):
        """The value tokens of ``keyword``; None when optional and absent."""
        if keyword not in self.fields:
            if required:
                raise MzcError("required header line missing", source=self.source, field=keyword)
            return None
        values = self.fields[keyword][0]
        if count is not None and len(values) != count:
            raise self.error(keyword, f"expected {count} value(s), found {len(values)}")
        return values

    def integer(self, keyword, low=None, high=None, required=True, default=None):
        """An integer field checked against [low, high]."""
        values = self.tokens(keyword, 1, required)
        if values is None:
            return default
        try:
            value = integer_word(values[0])
        except MzcError as error:
            raise self.error(keyword, error.message) from None
        if (low is not None and value < low) or (high is not None and value > high):
            raise self.error(keyword, f"{value} is outside {low}..{high}")
        return value

    def floats(self, keyword, count, required=True, default=None):
        """``count`` finite floats."""
        values = self.tokens(keyword, count, required)
        if values is None:
            return default
        try:
            numbers = [float(v) for v in values]
        except ValueError:
            raise self.error(keyword, f"not a number in {' '.join(values)!r}") from None
        if not all(math.isfinite(v) for v in numbers):
            raise self.error(keyword, "values must be finite")
        return numbers

    def positive(self, keyword, required=True, default=None):
        """One finite float > 0."""
        values = self.floats(keyword, 1, required)
        if values is None:
            return default
        if values[0] <= 0:
            raise self.error(keyword, f"must be > 0, found {values[0]}")
        return values[0]

    def length(self, keyword, required=True):
        """A spacing or radius: a float within mzc.limits' range of lengths."""
        value = self.positive(keyword, required)
        problem = None if value is None else length_problem(value)
        if problem:
            raise self.error(keyword, problem)
        return value

    def word(self, keyword, choices=None, required=True, default=None):
        """One token, optionally from ``choices``."""
        values = self.tokens(keyword, 1, required)
        if values is None:
            return default
        if choices is not None and values[0] not in choices:
            raise self.error(keyword, f"{values[0]!r} is not one of {', '.join(choices)}")
        return values[0]


def read_header(data, source, kind, supported_major, oldest_major=1, projected_major=None, checksum_since=None,
                binary=False, georef_since=None, charted_major=None, counted_since=None):
    """Parse magic and header lines of ``data``; return (Header, body bytes, first body line number).

    Majors above ``supported_major`` are refused (upgrade mzc), and so are majors below
    ``oldest_major``, drafts of a format that this mzc no longer reads. From
    ``projected_major`` on, the grid header may hold a central projection. A ``crc32`` line
    is checked against the whole file; from ``checksum_since[major]`` (a minor version) on
    it is required. A ``binary`` body (dwt2d's payload) refuses CRLF line ends: a text-mode copy
    changed its bytes. From ``georef_since[major]`` on, the ``crs`` and ``raster`` lines are read
    (an older version's reader ignored them); from ``charted_major`` on, the ``charts`` line; from
    ``counted_since[major]`` on, the ``source_vertices`` line.
    """
    found, major, minor = split_magic(data, source)
    if found != kind:
        raise MzcError(f"expected an mzc-{kind} file, found mzc-{found}", source=source, line=1)
    if major > supported_major:
        raise MzcError(f"mzc-{kind} version {major}.x is newer than this mzc reads "
                       f"({supported_major}.x); upgrade mzc", source=source, line=1)
    if major < oldest_major:
        raise MzcError(f"mzc-{kind} {major}.x was a draft of this format and is not read; encode the grid again",
                       source=source, line=1)
    header = Header(source, major, projected=projected_major is not None and major >= projected_major,
                    georeferenced=reads_since(georef_since, major, minor),
                    charted=charted_major is not None and major >= charted_major, minor=minor,
                    counted=reads_since(counted_since, major, minor))
    position = data.index(b"\n") + 1 if b"\n" in data else len(data)
    line_number = 1
    checksum_line = None
    while True:
        if position >= len(data):
            raise MzcError("header ends without a 'data' line", source=source, line=line_number)
        end = data.find(b"\n", position)
        end = len(data) if end < 0 else end
        line_number += 1
        try:
            text = data[position:end].decode("utf-8").strip()
        except UnicodeDecodeError:
            raise MzcError("header line is not UTF-8 text", source=source, line=line_number) from None
        line_start, position = position, end + 1
        if not text or text.startswith("#"):
            continue
        if text == "data":
            since = (checksum_since or {}).get(major)
            check_checksum(data, header, checksum_line, required=since is not None and minor >= since)
            if binary and b"\r\n" in data[:position]:
                raise MzcError("the header's line ends are CRLF: the file was copied as text, which changes its "
                               "binary payload; copy mzc files as binary", source=source, line=1)
            return header, data[position:], line_number + 1
        keyword, *values = text.split()
        header.add(keyword, values, line_number)
        if keyword == CHECKSUM:
            checksum_line = (line_start, position)



def reads_since(since, major, minor):
    """True when version major.minor reads the lines that ``since`` (major -> first minor) brought."""
    first = (since or {}).get(major)
    return first is not None and minor >= first


def counted_version(grid, version, since):
    """``version``, raised to the first minor that reads ``source_vertices`` (``since``: major -> minor)
    when ``grid`` has the line: a grid without it keeps its version, byte for byte."""
    if grid.source_vertices is None:
        return tuple(version)
    return version[0], max(version[1], since[version[0]])


def file_bytes(lines, payload=b"", checksum=True):
    """The bytes of an mzc file: its magic and header ``lines`` through ``data`` (and, for the text
    formats, the body's lines), UTF-8 (a unit may be ``µm``), then a binary ``payload``; with
    ``checksum``, its ``crc32`` line added (with_checksum)."""
    data = ("\n".join(lines) + "\n").encode("utf-8") + payload
    return with_checksum(data) if checksum else data


def with_checksum(data):
    """The bytes of a whole file, ``data``, with its ``crc32`` line added just before the
    ``data`` line: the CRC-32 (as zlib, gzip and PNG compute it) of ``data`` itself."""
    at = data.index(b"\ndata\n") + 1
    return data[:at] + f"{CHECKSUM} {zlib.crc32(data):08x}\n".encode("ascii") + data[at:]


def check_checksum(data, header, span, required):
    """Refuse ``data`` when its ``crc32`` line (bytes ``span``) does not match the rest of the
    file, or when it has none and ``required``."""
    if span is None:
        if required:
            raise MzcError("required header line missing (the file's checksum)", source=header.source,
                           field=CHECKSUM)
        return
    stated = header.word(CHECKSUM)
    if not re.fullmatch(r"[0-9a-f]{8}", stated):
        raise header.error(CHECKSUM, f"expected 8 lowercase hexadecimal digits, found {stated[:20]!r}")
    view = memoryview(data)
    found = zlib.crc32(view[span[1]:], zlib.crc32(view[:span[0]]))
    if found != int(stated, 16):
        hint = (" (its line ends were changed to CRLF: copy mzc files as binary, not as text)"
                if b"\r\n" in data[:span[1]] else " (damaged, cut short or with bytes added)")
        raise MzcError(f"checksum mismatch: the file is corrupt{hint}", source=header.source,
                       line=header.fields[CHECKSUM][1], field=CHECKSUM)


def read_grid_fields(header, whole=True):
    """The grid header fields as keyword arguments for ZGrid (without z), plus (rows, cols).

    Declared sizes are checked here, before any caller allocates memory for them: the sides, and
    the nodes of a grid read ``whole`` (a tiled file's are bounded by its tiles').
    """
    rows = header.integer("rows", 1, MAX_DIMENSION)
    cols = header.integer("cols", 1, MAX_DIMENSION)
    if whole:
        check_grid_size(rows, cols, source=header.source, line=header.fields["cols"][1], field="cols")
    transform = header.floats("transform", 12, required=False)
    if transform is None:
        transform = IDENTITY_TRANSFORM
    else:
        transform = np.array(transform).reshape(3, 4)
        rotation = transform[:, :3]
        if (np.abs(rotation).max() > 1 + RIGID_TOLERANCE   # no rotation has such entries, whose products overflow
                or np.abs(matrix_product(rotation.T, rotation) - np.eye(3)).max() > RIGID_TOLERANCE
                or determinant(rotation) < 0):
            raise header.error("transform", "the 3x3 part is not a rotation (orthonormal, det +1)")
    projected = read_projection(header, rows, cols)
    fields = dict(
        d1=header.length("d1"),
        d2=header.length("d2"),
        origin=tuple(header.floats("origin", 2, required=False, default=[0.0, 0.0])),
        transform=transform,
        units=header.word("units", required=False),
        nodata=header.word("nodata", required=False, default="nan"),
        **projected,
        **read_georeference(header, projected.get("projection", "planar")),
        **read_charts(header, rows, cols),
    )
    if header.counted:
        fields["source_vertices"] = header.integer("source_vertices", 1, MAX_SOURCE_VERTICES, required=False)
    for name in ("units", "nodata"):
        try:
            check_token(fields[name], name)
        except MzcError as error:
            raise header.error(name, error.message) from None
    return fields, rows, cols


def read_projection(header, rows, cols):
    """``projection`` and ``radius`` of the header, checked against the version and the grid.

    A central projection needs the projected major version and a radius; its columns may
    span at most one turn, and a spherical grid's rows must lie between the poles.
    """
    projection = header.word("projection", projections.PROJECTIONS, required=False, default="planar")
    if projection == "planar":
        if header.has("radius"):
            raise header.error("radius", "a radius needs a central projection (cylindrical or spherical)")
        return {}
    if not header.projected:
        raise header.error("projection", f"a {projection} grid needs a newer major version of this "
                                         "format (older readers would read it as planar)")
    radius = header.length("radius")
    v0 = header.floats("origin", 2, required=False, default=[0.0, 0.0])[1]
    problem = projections.extent_problem(projection, radius, rows, cols, header.positive("d1"),
                                         header.positive("d2"), v0)
    if problem:
        raise header.error(*problem)
    return {"projection": projection, "radius": radius}


def read_georeference(header, projection):
    """``crs`` (one line of WKT) and ``raster`` (cells, row order, sample type) of a version that
    reads them; they belong to planar grids (``projection``, as ``read_projection`` read it)."""
    if not header.georeferenced:
        return {}
    fields = {}
    if header.has("crs"):
        fields["crs"] = " ".join(header.tokens("crs"))
        try:
            check_crs(fields["crs"])
        except MzcError as error:
            raise header.error("crs", error.message) from None
    if header.has("raster"):
        try:
            fields["raster"] = Raster(*header.tokens("raster", 3))
        except MzcError as error:
            raise header.error("raster", error.message) from None
    if fields and projection != "planar":
        keyword = next(iter(fields))
        raise header.error(keyword, f"a {projection} grid has no raster or CRS: they belong to planar grids")
    return fields


def read_charts(header, rows, cols):
    """``charts`` of a version that holds them: seven values per chart (view, row0, col0, rows,
    cols, i0, j0), checked against the grid (mzc.grid.Chart); {} without the line."""
    if not header.has("charts"):
        return {}
    if not header.charted:
        raise header.error("charts", "a multi-chart grid needs a newer major version of this format (older "
                                     "readers would read its charts as one grid)")
    words = header.tokens("charts")
    if not words or len(words) % 7:
        raise header.error("charts", f"expected 7 values per chart, found {len(words)}")
    if len(words) // 7 > MAX_CHARTS:
        raise header.error("charts", f"{len(words) // 7} charts: at most {MAX_CHARTS}")
    try:
        charts = tuple(Chart(words[at], *(integer_word(word) for word in words[at + 1:at + 7]))
                       for at in range(0, len(words), 7))
        check_charts(charts, (rows, cols))
    except MzcError as error:
        raise header.error("charts", error.message) from None
    return {"charts": charts}


def integer_word(word):
    """An integer of a header line, or an error quoting the word."""
    value = parse_int(word)
    if value is None:
        raise MzcError(f"not an integer: {word[:40]!r}")
    return value


def format_number(value):
    """The shortest text that reads back as ``value`` (``3`` rather than ``3.0``)."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def grid_header_lines(grid, write_defaults=True, chart_records=True, counted=False):
    """Header lines for the grid fields of ``grid`` (rows and cols come from z's shape);
    without ``write_defaults``, ``nodata`` is left out when it holds its default, nan; without
    ``chart_records`` a multi-chart grid's charts are left to the format (dwt2d codes them); with
    ``counted``, the ``source_vertices`` line of a grid that has one (a version that reads it)."""
    rows, cols = grid.shape
    lines = [
        f"rows {rows}",
        f"cols {cols}",
        f"d1 {format_number(grid.d1)}",
        f"d2 {format_number(grid.d2)}",
        f"origin {format_number(grid.origin[0])} {format_number(grid.origin[1])}",
    ]
    if grid.projection != "planar":
        lines += [f"projection {grid.projection}", f"radius {format_number(grid.radius)}"]
    if not np.array_equal(grid.transform, IDENTITY_TRANSFORM):
        lines.append("transform " + " ".join(format_number(v) for v in grid.transform.ravel()))
    if grid.units:
        lines.append(f"units {grid.units}")
    if write_defaults or grid.nodata != "nan":
        lines.append(f"nodata {grid.nodata}")
    if grid.crs is not None:
        lines.append(f"crs {grid.crs}")
    if grid.raster is not None:
        lines.append(f"raster {grid.raster.words()}")
    if grid.charts is not None and chart_records:
        lines.append("charts " + " ".join(word for chart in grid.charts for word in chart.words()))
    if counted and grid.source_vertices is not None:
        lines.append(f"source_vertices {grid.source_vertices}")
    return lines

