"""Reading the files the thesis's MATLAB code writes (Tables 6.1, 7.1, 7.2, §5.3.1): see spec/legacy.md.

These files carry no magic line, so the kind must be named (``mzc decode --legacy dwt``).
The DFT, DCT and DWT files start with one line ``D1 D2 k1 k2 Q`` (as the MATLAB writers
print it), the polynomial file with four lines ``k1 N``, ``k2 N``, ``D1 X``, ``D2 X``; then
one line per grid row, numbers separated by tabs or spaces. Every quirk of the MATLAB
decoders that decides which numbers a row holds is reproduced here (the floating-point
``floor((Q/100)*L)``, the DWT's dropping from the start of each band); the thesis's
half-resolution DFT reconstruction is not: rows are rebuilt at their true length.
"""

import math

import numpy as np

from mzc.codecs import rows
from mzc.codecs.rows import dct, dft, poly
from mzc.codecs.rows.transforms import dft_length, dwt_inverse
from mzc.errors import MzcError
from mzc.formats.header import format_number
from mzc.formats.zgrid import body_lines
from mzc.grid import ZGrid
from mzc.limits import MAX_DIMENSION, check_grid_magnitudes, check_grid_size

KINDS = ("poly", "dft", "dct", "dwt")
LEGACY_WAVELET = "db1"
LEGACY_LEVEL = 3


def matlab_kept(quality, count):
    """floor((quality/100)*count) in doubles, as the MATLAB DFT/DCT code computes it (0.29*100 -> 28)."""
    return math.floor((quality / 100) * count)


# --- one function per kind: a row's numbers -> coefficient vector, or None (invalid row) ---

def dft_row(values, length, quality):
    """``a0 aN L an(1..K) bn(1..K)``; spans of 1 or 2 samples were never coded (MATLAB wrote zeros)."""
    if values.size < 3:
        raise rows.count_error("at least 3", values.size, "numbers (a0 aN L)")
    big_l = rows.integer_field(values[2], "L")
    if length <= 2:
        return None
    if big_l != dft_length(length):
        raise MzcError(f"L is {big_l} but a span of {length} samples has L = {dft_length(length)}", field="L")
    count = matlab_kept(quality, big_l)
    if values.size != 3 + 2 * count:
        raise rows.count_error(3 + 2 * count, values.size, f"numbers (a0 aN L and {count} an, {count} bn)")
    return dft.pack(values[0], values[1], values[3:3 + count], values[3 + count:], big_l)


def dct_row(values, length, quality):
    """``B(1..K)``, K = floor((Q/100)*m)."""
    expected = matlab_kept(quality, length)
    if values.size != expected:
        raise rows.count_error(expected, values.size, f"DCT coefficients (span {length}, quality {quality})")
    return values


def thesis_lengths(length):
    """MATLAB wavedec(s, 3, 'db1') lengths [A3 D3 D2 D1 m]: halving, rounded up, never capped."""
    d1 = (length + 1) // 2
    d2 = (d1 + 1) // 2
    d3 = (d2 + 1) // 2
    return [d3, d3, d2, d1, length]


def dwt_kept_mask(lengths, quality):
    """Which entries of C the MATLAB decoder reads: it blanks the first entries of D1, then D2, then D3."""
    a3, d3, d2, d1 = lengths[:4]
    details = d3 + d2 + d1
    drop = details - math.floor(quality * details / 100)
    mask = np.ones(a3 + details, dtype=bool)
    if drop > d1 + d2:
        mask[a3 + d3:] = False
        mask[a3:a3 + drop - d1 - d2] = False
    elif drop > d1:
        mask[a3 + d3 + d2:] = False
        mask[a3 + d3:a3 + d3 + drop - d1] = False
    else:
        mask[a3 + d3 + d2:a3 + d3 + d2 + drop] = False
    return mask


def dwt_row(values, length, quality):
    """``L1 L2 L3 L4 L5 Lc C(kept...)``, checked against db1's lengths for the span."""
    if values.size < 6:
        raise rows.count_error("at least 6", values.size, "numbers (L1..L5 Lc)")
    found = [rows.integer_field(v, "lengths") for v in values[:6]]
    expected = thesis_lengths(length)
    if found[:5] != expected or found[5] != sum(expected[:4]):
        raise MzcError(f"lengths {' '.join(map(str, found))} do not add up for a span of {length} "
                       f"(db1, 3 levels: {' '.join(map(str, expected))} {sum(expected[:4])})", field="lengths")
    mask = dwt_kept_mask(expected, quality)
    if values.size - 6 != mask.sum():
        raise rows.count_error(int(mask.sum()), values.size - 6, "coefficients C")
    vector = np.zeros(mask.size)
    vector[mask] = values[6:]
    return vector


def decode_dwt(vectors, length, firsts, d2, options):
    """Inverse of the thesis's uncapped 3-level db1 decomposition."""
    return dwt_inverse(vectors, thesis_lengths(length), LEGACY_WAVELET)


ROW_READERS = {"dft": (dft_row, dft.decode), "dct": (dct_row, dct.decode), "dwt": (dwt_row, decode_dwt)}


# --- headers ------------------------------------------------------------------------------

def size_field(k1):
    """The field to blame for a grid too large: k1 when it alone is out of range, else k2."""
    return "k1" if not 1 <= k1 <= MAX_DIMENSION else "k2"


def transform_header(lines, source):
    """(d1, d2, k1, k2, Q) from the line ``D1 D2 k1 k2 Q``."""
    number, text = lines[0]
    tokens = text.split()
    names = ("D1", "D2", "k1", "k2", "Q")
    if len(tokens) != 5:
        raise MzcError(f"expected the header 'D1 D2 k1 k2 Q', found {len(tokens)} value(s)",
                       source=source, line=number, field="header")
    values = rows.parse_numbers(tokens, source, number)
    for name, value in zip(names[2:], values[2:]):
        if value != int(value):
            raise MzcError(f"must be an integer, found {format_number(value)}", source=source, line=number, field=name)
    d1, d2, k1, k2, quality = values[0], values[1], int(values[2]), int(values[3]), int(values[4])
    for name, value in (("D1", d1), ("D2", d2)):
        if value <= 0:
            raise MzcError(f"must be > 0, found {value}", source=source, line=number, field=name)
    check_grid_size(k1, k2, source=source, line=number, field=size_field(k1))
    if not 1 <= quality <= 100:
        raise MzcError(f"{quality} is outside 1..100", source=source, line=number, field="Q")
    return d1, d2, k1, k2, quality


def poly_header(lines, source):
    """(d1, d2, k1, k2) from the four lines ``k1 N``, ``k2 N``, ``D1 X``, ``D2 X``."""
    values = {}
    for name, (number, text) in zip(("k1", "k2", "D1", "D2"), lines):
        tokens = text.split()
        if len(tokens) != 2 or tokens[0] != name:
            raise MzcError(f"expected the header line '{name} VALUE'", source=source, line=number, field=name)
        value = rows.parse_numbers(tokens[1:], source, number)[0]
        if value <= 0 or (name[0] == "k" and value != int(value)):
            raise MzcError(f"must be a positive {'integer' if name[0] == 'k' else 'number'}",
                           source=source, line=number, field=name)
        values[name] = value
    if len(values) < 4:
        raise MzcError("the polynomial header needs the lines k1, k2, D1, D2", source=source,
                       line=len(lines) + 1, field=("k1", "k2", "D1", "D2")[len(values)])
    k1 = int(values["k1"])
    check_grid_size(k1, int(values["k2"]), source=source, line=lines[0 if size_field(k1) == "k1" else 1][0],
                    field=size_field(k1))
    return values["D1"], values["D2"], int(values["k1"]), int(values["k2"])


# --- rows ---------------------------------------------------------------------------------

def transform_record(r, tokens, cols, kind, quality, source, line):
    """RowRecord of a DFT/DCT/DWT row ``v1 v2 numbers...`` (None: no valid node)."""
    if len(tokens) < 2:
        raise MzcError("a row line needs at least 'v1 v2'", source=source, line=line, field="v1")
    span = rows.parse_span(tokens[0], tokens[1], cols, source, line)
    values = rows.parse_numbers(tokens[2:], source, line, allow_nan=True)
    if span is None or np.isnan(values).any():  # MATLAB writes an empty row as '1 1 NaN'
        return None
    try:
        vector = ROW_READERS[kind][0](values, span[1], quality)
    except MzcError as error:
        raise error.located(source=source, line=line) from None
    return None if vector is None else rows.RowRecord(r, span[0], span[1], vector, line)


def poly_record(r, tokens, cols, source, line):
    """RowRecord of a polynomial row ``coefficients... v1 v2`` (power basis, highest first)."""
    values = rows.parse_numbers(tokens, source, line, allow_nan=True)
    if values.size < 3:
        raise MzcError("a polynomial row needs at least one coefficient, then v1 v2", source=source, line=line)
    ends = [str(int(v)) if np.isfinite(v) and v == int(v) else repr(v) for v in values[-2:].tolist()]
    span = rows.parse_span(*ends, cols, source, line)
    if span is None or np.isnan(values[:-2]).any():
        return None
    return rows.RowRecord(r, span[0], span[1], values[:-2], line)


def read_legacy(data, source, kind):
    """Decode a thesis file of ``kind`` (poly, dft, dct or dwt) into a ZGrid."""
    if kind not in KINDS:
        raise MzcError(f"unknown legacy kind {kind!r} (one of {', '.join(KINDS)})", source=source)
    lines = body_lines(data, 1, source)
    lines = [(number, text) for number, text in lines if text.strip()]
    if not lines:
        raise MzcError("empty file: expected a thesis header line", source=source, line=1)
    if kind == "poly":
        d1, d2, k1, k2 = poly_header(lines[:4], source)
        body = lines[4:]
    else:
        d1, d2, k1, k2, quality = transform_header(lines, source)
        d2 = d2 / 2 if kind == "dft" else d2  # the MATLAB DFT writer prints 2*D2
        body = lines[1:]
    if len(body) != k1:
        raise MzcError(f"header says k1 = {k1} rows but the file has {len(body)} row line(s)",
                       source=source, line=body[min(len(body), k1) - 1][0] if body else lines[-1][0])
    if kind == "poly":
        records = [poly_record(r, text.split(), k2, source, number) for r, (number, text) in enumerate(body)]
        decode, options = poly.decode, {"basis": "power"}
    else:
        records = [transform_record(r, text.split(), k2, kind, quality, source, number)
                   for r, (number, text) in enumerate(body)]
        decode, options = ROW_READERS[kind][1], {}
    z = rows.decode_records([rec for rec in records if rec is not None], k1, k2, d2, decode, options, source)
    grid = ZGrid(z=z, d1=d1, d2=d2)
    check_grid_magnitudes(grid, source=source)
    return grid
