"""Helpers the mesh format modules share: text checks, number and index parsing, fan
triangulation."""

from itertools import chain

import numpy as np

from mzc.errors import MzcError
from mzc.numbers import bad_token, to_floats, unpadded

# Indices beyond this are no vertex of any mesh (and would not survive a cast to int64).
LARGEST_INDEX = 2.0 ** 53


def is_text(data: bytes) -> bool:
    """True when ``data`` looks like text rather than binary (it holds no NUL byte but the
    padding at its end)."""
    return b"\0" not in unpadded(data)


def decode_text(data: bytes, source: str) -> str:
    """Text of ``data`` without the NUL padding at its end; binary garbage is refused."""
    data = unpadded(data)
    if not is_text(data[:65536]):
        raise MzcError("binary data where text was expected", source=source)
    return data.decode("utf-8", "replace")


def flat_numbers(rows: list, line_numbers, source: str) -> np.ndarray:
    """All the number tokens of ``rows`` (lists of tokens, any lengths) as one float array,
    converted in one call; on failure the first bad line is named."""
    try:
        return to_floats(list(chain.from_iterable(rows)))
    except ValueError:
        for row, number in zip(rows, line_numbers):
            if bad_token(row) is not None:
                raise MzcError(f"not a number in {' '.join(row)[:60]!r}", source=source, line=int(number)) from None
        raise


def numbers_or_error(rows: list, width: int, line_numbers, source: str) -> np.ndarray:
    """Convert rows of ``width`` number tokens to a (len(rows), width) float array (also when
    there are no rows), naming the first bad line on failure."""
    return flat_numbers(rows, line_numbers, source).reshape(len(rows), width)


def as_indices(values: np.ndarray, what: str, source: str) -> np.ndarray:
    """Vertex indices read as ``values`` (integers, or floats from text) as int64; a NaN,
    infinite, fractional or huge one is refused, naming ``what`` holds it."""
    if values.dtype.kind == "f":
        bad = ~(np.abs(values) <= LARGEST_INDEX) | (values != np.round(values))
        if bad.any():
            raise MzcError(f"{what} vertex index {values[bad][0]!r} is not a whole number", source=source)
    return values.astype(np.int64)


def fan_triangulate(polygons) -> np.ndarray:
    """Split (m, k) polygons into (m*(k-2), 3) triangles fanning out from the first corner."""
    polygons = np.asarray(polygons, dtype=np.int64)
    corners = polygons.shape[1]
    if corners == 3:
        return polygons
    first = np.repeat(polygons[:, :1], corners - 2, axis=1)
    fan = np.stack([first, polygons[:, 1:-1], polygons[:, 2:]], axis=-1)
    return fan.reshape(-1, 3)


def fan_triangulate_ragged(flat: np.ndarray, counts) -> np.ndarray:
    """Fan-triangulate polygons stored as a flat index list and a corner count per polygon."""
    counts = np.asarray(counts, dtype=np.int64)
    if len(counts) and (counts == counts[0]).all():   # one polygon size (a mesher's file): rows of the list
        return fan_triangulate(flat.reshape(len(counts), int(counts[0])))
    starts = np.cumsum(counts) - counts
    pieces = counts - 2
    owner_start = np.repeat(starts, pieces)
    step = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 1
    return np.stack([flat[owner_start], flat[owner_start + step], flat[owner_start + step + 1]], axis=1)
