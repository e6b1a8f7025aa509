"""Helpers the mesh format modules share: text checks, number parsing, fan triangulation."""

import numpy as np

from mzc.errors import MzcError
from mzc.numbers import bad_token


def is_text(data: bytes) -> bool:
    """True when ``data`` looks like text rather than binary (it holds no NUL byte)."""
    return b"\0" not in data


def decode_text(data: bytes, source: str) -> str:
    """Text of ``data``; binary garbage is refused."""
    if not is_text(data[:65536]):
        raise MzcError("binary data where text was expected", source=source)
    return data.decode("utf-8", "replace")


def numbers_or_error(rows: list, width: int, line_numbers, source: str) -> np.ndarray:
    """Convert rows of ``width`` number tokens to a (len(rows), width) float array (also when
    there are no rows), naming the first bad line on failure."""
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), width)
    except ValueError:
        for row, number in zip(rows, line_numbers):
            if bad_token(row) is not None:
                raise MzcError(f"not a number in {' '.join(row)[:60]!r}", source=source, line=number) from None
        raise


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
    starts = np.cumsum(counts) - counts
    pieces = counts - 2
    owner_start = np.repeat(starts, pieces)
    step = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 1
    return np.stack([flat[owner_start], flat[owner_start + step], flat[owner_start + step + 1]], axis=1)
