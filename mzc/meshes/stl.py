"""STL, binary and ascii, read by our own vectorised readers; written (ascii) by meshio.

A binary STL is an 80-byte header, a little-endian uint32 triangle count and 50 bytes per
triangle, so its size follows from its count: a file of any other size is refused, not
read as far as it goes (a binary header may start with ``solid`` too; the size decides,
as in meshio). An ascii STL (``solid`` ... ``endsolid``) must hold facets of exactly three
vertices and end with ``endsolid``. As in meshio, equal corners of the triangles become
one vertex, in the order they first appear.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.meshes import Mesh, meshio_fallback
from mzc.meshes.common import decode_text, is_text
from mzc.numbers import bad_token, to_floats

NAME = "stl"
EXTENSIONS = (".stl",)

HEADER = 84   # 80 bytes of anything, then the uint32 triangle count
TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def sniff(data: bytes) -> bool | None:
    """True for ascii STL text or bytes whose size fits a binary STL's triangle count; else None: a
    binary STL has no magic, and one cut short fits no count (its reader says so)."""
    return True if is_binary(data) or is_ascii(data) else None


def is_binary(data: bytes) -> bool:
    """True when the size of ``data`` matches the triangle count of a binary STL."""
    return len(data) >= HEADER and len(data) == HEADER + TRIANGLE.itemsize * declared_triangles(data)


def is_ascii(data: bytes) -> bool:
    """True when ``data`` is text starting with ``solid``."""
    head = data[:4096]
    return head.lstrip().startswith(b"solid") and is_text(head)


def declared_triangles(data: bytes) -> int:
    """The triangle count in a binary STL header."""
    return int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])


def read(data: bytes, source: str) -> Mesh:
    """The triangles of binary or ascii STL ``data``; a size that contradicts the count is refused."""
    if is_binary(data):
        return mesh_of_corners(np.frombuffer(data, dtype=TRIANGLE, offset=HEADER)["corners"])
    if is_ascii(data):
        return read_ascii(decode_text(data, source), source)
    if len(data) < HEADER:
        raise MzcError(f"not an STL file: {len(data)} bytes, neither text starting with 'solid' nor "
                       f"a binary header ({HEADER} bytes)", source=source)
    held = len(data) - HEADER
    raise MzcError(f"binary STL declares {declared_triangles(data)} triangles but holds {held} bytes "
                   f"for {held // TRIANGLE.itemsize} ({TRIANGLE.itemsize} bytes each)", source=source)


def write(mesh: Mesh) -> bytes:
    """Ascii STL bytes of ``mesh``, written by meshio."""
    return meshio_fallback.write_as("stl", mesh)


def read_ascii(text: str, source: str) -> Mesh:
    """The facets of ascii STL text, found among its words without a loop per facet."""
    words = np.array(text.split())
    vertex, end_facet = np.flatnonzero(words == "vertex"), np.flatnonzero(words == "endfacet")
    end_solid = np.flatnonzero(words == "endsolid")
    if not len(end_solid) or end_solid[-1] < max(vertex[-1:].tolist() + end_facet[-1:].tolist() + [0]):
        raise MzcError("truncated: ascii STL ends without 'endsolid'", source=source,
                       line=text.count("\n") + 1)
    facets_before = np.searchsorted(end_facet, vertex)    # the facet each vertex belongs to
    complete = len(vertex) == 3 * len(end_facet) and (facets_before == np.arange(len(vertex)) // 3).all()
    if not complete or (len(vertex) and vertex[-1] + 3 >= len(words)):
        raise MzcError("ascii STL facets must each hold 3 vertices of 3 coordinates", source=source)
    tokens = words[vertex[:, None] + np.arange(1, 4)].ravel().tolist()
    try:
        corners = to_floats(tokens)
    except ValueError:
        bad = bad_token(tokens)
        if bad is None:
            raise
        word = int(vertex[bad // 3]) + 1 + bad % 3
        raise MzcError(f"not a number: {tokens[bad][:40]!r}", source=source, line=line_of_word(text, word)) from None
    return mesh_of_corners(corners.reshape(-1, 3, 3))


def line_of_word(text: str, word: int) -> int:
    """The line number of the ``word``-th whitespace-separated word of ``text`` (errors only)."""
    seen = 0
    for number, line in enumerate(text.splitlines(), 1):
        seen += len(line.split())
        if seen > word:
            return number
    return number


def mesh_of_corners(corners: np.ndarray) -> Mesh:
    """The mesh of (m, 3, 3) triangle corners, equal corners merged in first-seen order (as meshio)."""
    corners = corners.reshape(-1, 3)
    if not len(corners):
        return Mesh(corners)
    _, first, inverse = np.unique(corners, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    return Mesh(corners[first[order]], np.argsort(order)[inverse.reshape(-1)].reshape(-1, 3))
