"""Point clouds as plain text: one ``x y z`` line per point.

Extra columns (colours, intensities), commas between numbers, ``#`` comments and any of
``\n``, ``\r\n`` or ``\r`` as line ends are accepted. mzc reads these files but does not write them.
"""

import re

import numpy as np

from mzc.errors import MzcError
from mzc.meshes import Mesh
from mzc.meshes.common import decode_text, is_text, numbers_or_error
from mzc.numbers import to_floats

NAME = "xyz"
EXTENSIONS = (".xyz", ".txt", ".pts", ".asc")
write = None   # a point cloud is read, never written


def sniff(data: bytes) -> bool | None:
    """True for text whose first line that is not a ``#`` comment starts like a number (ranked last:
    most such text is x y z); else None: x y z text has no magic, and text under a header (a PCD's
    that is damaged) is for the reader its name gives."""
    head = data[:4096]
    return True if re.match(rb"(?:\s*#[^\r\n]*[\r\n])*\s*[-+.\d]", head) and is_text(head) else None


def read(data: bytes, source: str) -> Mesh:
    """A point cloud from text lines of 3+ numbers (extra columns and ``#`` comments ignored):
    ``columns`` read an ASCII file without comments whose lines hold one count of numbers (a
    GIS export of millions of lines, 8x faster), ``read_lines`` any other, line by line."""
    text = decode_text(data, source)
    points = columns(text)
    return Mesh(points) if points is not None else read_lines(text, source)


# by ASCII code: the bytes that end a line (as str.splitlines sees them), and those between tokens
# (as str.split sees them, and the comma)
LINE_END = np.isin(np.arange(256), [10, 11, 12, 13, 28, 29, 30])
SEPARATOR = LINE_END | np.isin(np.arange(256), [9, 31, 32, 44])


def columns(text: str) -> np.ndarray | None:
    """(n, 3) points of ``text`` when it is ASCII without ``#`` and every line that holds a token
    holds the same number of them, 3 or more (counted over its bytes at once), and every token
    is a number; else None, for ``read_lines`` (which names a bad line)."""
    if not text.isascii() or "#" in text:
        return None
    codes = np.frombuffer(text.encode("ascii"), dtype=np.uint8)
    separator = SEPARATOR[codes]
    starts = ~separator & np.r_[True, separator[:-1]]
    ends = LINE_END[codes] & ~((codes == 10) & np.r_[False, codes[:-1] == 13])   # CR LF is one end
    counts = np.bincount(np.searchsorted(np.flatnonzero(ends), np.flatnonzero(starts)))   # tokens a line
    counts = counts[counts > 0]
    if not len(counts) or counts[0] < 3 or (counts != counts[0]).any():
        return None
    try:
        values = to_floats(text.replace(",", " ").split())
    except ValueError:
        return None
    return values.reshape(len(counts), int(counts[0]))[:, :3]


def read_lines(text: str, source: str) -> Mesh:
    """A point cloud from ``text``'s lines of 3+ numbers, each split alone: comments, ragged
    columns, and the first bad line named."""
    numbered = [(number, line.split("#", 1)[0].replace(",", " ").split())
                for number, line in enumerate(text.splitlines(), 1)]
    numbered = [(number, tokens) for number, tokens in numbered if tokens]
    short = [number for number, tokens in numbered if len(tokens) < 3]
    if short:
        raise MzcError("expected at least 3 numbers (x y z) on the line", source=source, line=short[0])
    points = numbers_or_error([tokens[:3] for _, tokens in numbered], 3,
                              [number for number, _ in numbered], source)
    return Mesh(points)
