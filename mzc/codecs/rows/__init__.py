"""The row layout shared by the per-row codec formats (poly, dft, dct, dwt) and the legacy reader.

A codec file is: magic line, codec header lines, grid header lines, ``data``, then one
line per grid row ``v1 v2 numbers...`` (1-based first and last valid column; ``0 0`` for
a row with no valid node), then optionally a ``holes`` section recording the invalid
runs inside the spans. See spec/dct.md (the layout is described once there and referred
to by the other specs).

A codec is a :class:`RowCodec`: how to read and write its header options, how to turn a
stack of equal-length spans into the numbers of their row lines, how to check a row's
numbers and lay them out as one coefficient vector, and how to invert a stack of those.
Rows are batched by span length so each transform runs once per length, not per row.
"""

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from mzc.codecs.base import Codec, Option
from mzc.codecs.rows.transforms import fill_holes
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
from mzc.formats.zgrid import body_lines
from mzc.grid import ZGrid
from mzc.numbers import floats, parse_int

DEFAULT_PRECISION = 4
MAX_PRECISION = 17
VERSION = (1, 1)             # every row codec: planar grids (1.0 without the crc32 line)
PROJECTED_VERSION = (2, 1)   # 1.1 with the projection lines (mzc.formats.header)
GEOREFERENCED_VERSION = (1, 2)   # 1.1 with the crs and raster lines of a grid read from a raster
GEOREF_SINCE = dict([GEOREFERENCED_VERSION])   # major -> the first minor with the crs and raster lines
OLDEST_MAJOR = 1
CHECKSUM_SINCE = {1: 1, 2: 1}   # 1.0 and 2.0 files have no crc32 line; from 1.1 and 2.1 on it is required
QUALITY = Option("quality", int, 100, 1, 100, metavar="Q",
                 help="Percentage of coefficients kept, 1..100.")
PRECISION = Option("precision", int, DEFAULT_PRECISION, 0, MAX_PRECISION, metavar="DIGITS",
                   help="Decimals of the written coefficients.")


@dataclass(frozen=True)
class RowCodec:
    """The codec-specific parts of a row format.

    ``read_options(header) -> dict``; ``header_lines(options) -> [str]``;
    ``encode(spans (k, m), firsts (k,) 1-based, d2, options) -> [[str], ...]`` the tokens
    after ``v1 v2`` for each span; ``unpack(values, m, options) -> 1D array`` the row's
    coefficient vector with dropped coefficients as zeros (raise MzcError with a field
    for a bad row); ``decode(vectors (k, n), m, firsts, d2, options) -> (k, m)``.
    """

    kind: str
    read_options: Callable
    header_lines: Callable
    encode: Callable
    unpack: Callable
    decode: Callable



@dataclass
class RowRecord:
    """One decoded row line: 0-based grid row, 0-based first column, span length, coefficients."""

    row: int
    first: int
    length: int
    vector: np.ndarray
    line: int


def codec_of(row_codec, extension, summary, options=(QUALITY, PRECISION), **settings):
    """The registered Codec of a row format: options checked by the Codec, files written and read
    through the shared row layout; ``settings`` are further Codec fields (selector, check_options)."""
    return Codec(row_codec.kind, partial(write_options, row_codec), partial(read_grid, codec=row_codec),
                 version=PROJECTED_VERSION, oldest_major=OLDEST_MAJOR, extension=extension, summary=summary,
                 spec=f"spec/{row_codec.kind}.md", options=options, **settings)


# --- writing ----------------------------------------------------------------------------

def format_values(values, precision=None):
    """Tokens for ``values``: rounded to ``precision`` decimals (None: exact), trailing zeros stripped."""
    values = np.asarray(values, dtype=float)
    if precision is not None:
        values = np.round(values, precision) + 0.0  # + 0.0 turns -0.0 into 0.0
    return [format_number(v) for v in values.tolist()]


def spans(z):
    """(first, last) 0-based valid columns of every row; (-1, -1) for a row with none."""
    valid = ~np.isnan(z)
    has = valid.any(axis=1)
    first = np.where(has, valid.argmax(axis=1), -1)
    last = np.where(has, z.shape[1] - 1 - valid[:, ::-1].argmax(axis=1), -1)
    return first, last


def hole_runs(row, first, last):
    """1-based inclusive (start, end) runs of NaN strictly inside columns first..last."""
    inside = np.isnan(row[first:last + 1]).astype(np.int8)
    edges = np.diff(np.concatenate([[0], inside, [0]]))
    starts = np.flatnonzero(edges == 1) + first + 1
    ends = np.flatnonzero(edges == -1) + first
    return list(zip(starts.tolist(), ends.tolist()))


def encode_rows(grid, codec, options):
    """The row lines of ``grid`` and its holes section, each row coded by ``codec``."""
    first, last = spans(grid.z)
    lines = ["0 0"] * grid.shape[0]
    by_length = defaultdict(list)
    for r in np.flatnonzero(first >= 0).tolist():
        by_length[last[r] - first[r] + 1].append(r)
    for length, members in by_length.items():
        stack = fill_holes(np.stack([grid.z[r, first[r]:first[r] + length] for r in members]))
        tokens = codec.encode(stack, first[members] + 1, grid.d2, options)
        for r, row_tokens in zip(members, tokens):
            lines[r] = " ".join([str(first[r] + 1), str(last[r] + 1), *row_tokens])
    holes = []
    for r in np.flatnonzero(first >= 0).tolist():
        runs = hole_runs(grid.z[r], first[r], last[r])
        if runs:
            holes.append(" ".join([str(r + 1), *(f"{a} {b}" for a, b in runs)]))
    return lines, (["holes " + str(len(holes)), *holes] if holes else [])


def write_options(codec, grid, **options):
    """Encode ``grid`` into the bytes of a ``codec`` file with checked ``options``."""
    return write_grid(grid, codec, options)


def write_grid(grid, codec, options):
    """Encode ``grid`` into the bytes of a ``codec`` file."""
    rows, holes = encode_rows(grid, codec, options)
    version = file_version(grid, VERSION, PROJECTED_VERSION, GEOREFERENCED_VERSION)
    lines = [magic_line(codec.kind, version), *codec.header_lines(options),
             *grid_header_lines(grid), "data", *rows, *holes]
    return file_bytes(lines)


# --- reading ----------------------------------------------------------------------------

def parse_numbers(tokens, source, line, allow_nan=False):
    """Floats of ``tokens``; a non-number, inf, or (unless ``allow_nan``) NaN is an error."""
    values = floats(tokens, source, line, "number")
    bad = np.isinf(values) if allow_nan else ~np.isfinite(values)
    if bad.any():
        position = int(np.flatnonzero(bad)[0])
        raise MzcError(f"number {position + 1} of the row is {tokens[position]!r}: coefficients must be finite",
                       source=source, line=line)
    return values


def integer_field(value, field):
    """``value`` (a parsed float) as an int, or an MzcError naming ``field``."""
    if value != int(value) or value < 0:
        raise MzcError(f"must be a whole number >= 0, found {format_number(value)}", field=field)
    return int(value)


def parse_span(v1, v2, cols, source, line):
    """Check a row's 1-based (v1, v2); return (0-based first, length), or None for ``0 0``."""
    first, last = parse_int(v1), parse_int(v2)
    if first is None or last is None:
        raise MzcError(f"v1 v2 must be integers, found {v1[:20]!r} {v2[:20]!r}", source=source,
                       line=line, field="v1")
    v1, v2 = first, last
    if v1 == 0 and v2 == 0:
        return None
    if not 1 <= v1 <= cols:
        raise MzcError(f"{v1} is outside the grid's columns 1..{cols}", source=source, line=line, field="v1")
    if not v1 <= v2 <= cols:
        raise MzcError(f"{v2} is not in v1..cols = {v1}..{cols}", source=source, line=line, field="v2")
    return v1 - 1, v2 - v1 + 1


def read_record(r, tokens, cols, codec, options, source, line):
    """The RowRecord of one row line ``v1 v2 numbers...`` (None for an empty row)."""
    if len(tokens) < 2:
        raise MzcError("a row line needs at least 'v1 v2'", source=source, line=line, field="v1")
    span = parse_span(tokens[0], tokens[1], cols, source, line)
    if span is None:
        if len(tokens) > 2:
            raise MzcError("an empty row ('0 0') has no coefficients", source=source, line=line)
        return None
    values = parse_numbers(tokens[2:], source, line)
    try:
        vector = codec.unpack(values, span[1], options)
    except MzcError as error:
        raise error.located(source=source, line=line) from None
    return RowRecord(r, span[0], span[1], vector, line)


def decode_records(records, rows, cols, d2, decode, options, source):
    """The (rows x cols) heights of ``records``, inverted by ``decode`` in batches of equal shape.

    Finite but huge coefficients can overflow the inverse transform: such a row is an error.
    """
    z = np.full((rows, cols), np.nan)
    groups = defaultdict(list)
    for record in records:
        groups[(record.length, record.vector.shape[0])].append(record)
    for (length, _count), members in groups.items():
        firsts = np.array([m.first + 1 for m in members])
        with np.errstate(over="ignore", invalid="ignore"):
            decoded = decode(np.stack([m.vector for m in members]), length, firsts, d2, options)
        overflowed = ~np.isfinite(decoded).all(axis=1)
        if overflowed.any():
            raise MzcError("coefficients too large: the decoded heights overflow", source=source,
                           line=members[int(np.flatnonzero(overflowed)[0])].line)
        for member, values in zip(members, decoded):
            z[member.row, member.first:member.first + length] = values
    return z


def apply_holes(z, lines, source):
    """Parse a ``holes K`` section (its lines as (number, text)) and set those runs to NaN."""
    if not lines:
        return
    number, text = lines[0]
    words = text.split()
    if words[:1] != ["holes"] or len(words) != 2 or parse_int(words[1]) is None:
        raise MzcError("expected 'holes COUNT' after the row lines", source=source, line=number, field="holes")
    if parse_int(words[1]) != len(lines) - 1:
        raise MzcError(f"says {words[1]} hole line(s) but {len(lines) - 1} follow", source=source,
                       line=number, field="holes")
    for number, text in lines[1:]:
        _apply_hole_line(z, text.split(), source, number)


def _apply_hole_line(z, tokens, source, line):
    """One ``r c1 c2 [c1 c2 ...]`` line: runs strictly inside row r's span, in increasing order."""
    numbers = [parse_int(t) for t in tokens]
    if None in numbers or not numbers:
        raise MzcError("hole lines hold integers 'row start end ...'", source=source, line=line, field="holes")
    r, *columns = numbers
    if not 1 <= r <= z.shape[0] or not columns or len(columns) % 2:
        raise MzcError("expected 'row start end [start end ...]' with a row in 1..rows", source=source,
                       line=line, field="holes")
    valid = np.flatnonzero(~np.isnan(z[r - 1])) + 1
    low, high = (valid[0], valid[-1]) if valid.size else (0, 0)
    previous = low
    for start, end in zip(columns[::2], columns[1::2]):
        if not previous < start <= end < high:
            raise MzcError(f"run {start}..{end} is not inside row {r}'s span {low}..{high} in increasing order",
                           source=source, line=line, field="holes")
        z[r - 1, start - 1:end] = np.nan
        previous = end + 1


def read_grid(data, source, codec):
    """Decode the bytes of a ``codec`` file into a ZGrid."""
    header, body, first_line = read_header(data, source, codec.kind, PROJECTED_VERSION[0],
                                           projected_major=PROJECTED_VERSION[0], checksum_since=CHECKSUM_SINCE,
                                           georef_since=GEOREF_SINCE)
    fields, rows, cols = read_grid_fields(header)
    options = codec.read_options(header)
    lines = body_lines(body, first_line, source)
    if len(lines) < rows:
        raise MzcError(f"header says rows {rows} but the data has {len(lines)} row line(s)",
                       source=source, line=first_line + len(lines))
    records = [read_record(r, text.split(), cols, codec, options, source, number)
               for r, (number, text) in enumerate(lines[:rows])]
    z = decode_records([rec for rec in records if rec is not None], rows, cols, fields["d2"], codec.decode,
                       options, source)
    apply_holes(z, lines[rows:], source)
    return ZGrid(z=z, **fields)


def common_options(header):
    """The ``quality`` (1..100, required) and ``precision`` (informative) header fields."""
    return {"quality": header.integer("quality", 1, 100),
            "precision": header.integer("precision", 0, MAX_PRECISION, required=False)}


def common_header_lines(options):
    """``quality`` and ``precision`` lines for a writer."""
    lines = [f"quality {options['quality']}"]
    if options.get("precision") is not None:
        lines.append(f"precision {options['precision']}")
    return lines


def count_error(expected, found, what):
    """The MzcError for a row whose number count disagrees with its header and span."""
    return MzcError(f"expected {expected} {what}, found {found}", field="coefficients")
