"""Point clouds as plain text: one ``x y z`` line per point.

Extra columns (colours, intensities), commas between numbers, ``#`` comments and any of
``\n``, ``\r\n`` or ``\r`` as line ends are accepted. mzc reads these files but does not write them.
"""

import re

from mzc.errors import MzcError
from mzc.meshes import Mesh
from mzc.meshes.common import decode_text, is_text, numbers_or_error

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
    """A point cloud from text lines of 3+ numbers (extra columns and ``#`` comments ignored)."""
    numbered = [(number, line.split("#", 1)[0].replace(",", " ").split())
                for number, line in enumerate(decode_text(data, source).splitlines(), 1)]
    numbered = [(number, tokens) for number, tokens in numbered if tokens]
    short = [number for number, tokens in numbered if len(tokens) < 3]
    if short:
        raise MzcError("expected at least 3 numbers (x y z) on the line", source=source, line=short[0])
    points = numbers_or_error([tokens[:3] for _, tokens in numbered], 3,
                              [number for number, _ in numbered], source)
    return Mesh(points)
