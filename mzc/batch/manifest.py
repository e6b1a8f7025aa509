r"""The manifest of a batch: ``manifest.csv`` in the destination folder, one row per output.

Columns (README, "mzc batch"): the input's path, bytes and SHA-256; the output's path
(relative to the destination) and bytes; the grid's rows, columns and valid nodes; the
settings (compact JSON); the codec's errors at the grid's nodes, and with ``--verify`` the
whole-surface RMS and Hausdorff distances; seconds and the stages' timings; status (ok or
failed), the one-line error of a failed item and any warning.

Every row is one line of UTF-8, whatever the names in it: a cell's text is escaped, a
backslash as ``\\``, CR and LF as ``\r`` and ``\n``, a byte of a file name that is not
UTF-8 (Python's surrogate escape) as ``\xNN`` (80 to ff) and any other lone surrogate as
``\uXXXX``, and read back unescaped, so any name the file system allows is recorded and
read back exactly. A cell keeps at most MAX_CELL characters (a longer error is cut, saying
so), well within what csv reads back (131,072).

Rows are appended (and flushed to disk) as chunks finish, so a batch killed at any moment
leaves the rows of everything it finished; at the end the whole manifest is rewritten
atomically, one row per output, sorted. Reading takes the last row of each output and
ignores a line cut short by a kill.
"""

from __future__ import annotations

import csv
import io
import os
import re

from mzc.errors import MzcError

NAME = "manifest.csv"
COLUMNS = ("input", "input_bytes", "input_sha256", "output", "output_bytes", "rows", "cols", "valid_nodes",
           "settings", "node_rms", "node_max_error", "surface_rms", "surface_hausdorff", "seconds", "timings",
           "status", "error", "warning")
FLOAT_FORMAT = {"seconds": "{:.3f}"}   # everything else: repr, exact
MAX_CELL = 20_000   # characters of an escaped cell: above a path's (4 x 4,096), below csv's limit (131,072)
TO_ESCAPE = re.compile("[\\\\\r\n\ud800-\udfff]")
ESCAPE = re.compile(r"\\(\\|r|n|x[89a-f][0-9a-f]|ud[89a-f][0-9a-f]{2})")


def path_in(dest):
    """The manifest's path in the destination folder ``dest``."""
    return os.path.join(dest, NAME)


def cell(name, value):
    """A row's value as its CSV text."""
    if value is None:
        return ""
    if isinstance(value, float):
        return FLOAT_FORMAT.get(name, "{!r}").format(value)
    return str(value)


def escaped(text):
    """``text`` with its backslashes, line breaks and lone surrogates escaped, cut to MAX_CELL characters."""
    text = TO_ESCAPE.sub(lambda match: escape_of(match[0]), text)
    return text if len(text) <= MAX_CELL else f"{text[:MAX_CELL]}... (cut: {len(text)} characters)"


def escape_of(char):
    """The escape of one character that a cell does not hold as itself."""
    code = ord(char)
    if 0xDC80 <= code <= 0xDCFF:
        return f"\\x{code - 0xDC00:02x}"   # a byte of a name that is not UTF-8
    return {"\\": "\\\\", "\r": "\\r", "\n": "\\n"}.get(char, f"\\u{code:04x}")


def unescaped(text):
    """A cell's text as it was before ``escaped``."""
    return ESCAPE.sub(lambda match: unescape_of(match[1]), text)


def unescape_of(code):
    """The character an escape (without its backslash) stands for."""
    if code[0] in "xu":
        return chr(int(code[1:], 16) + (0xDC00 if code[0] == "x" else 0))
    return {"\\": "\\", "r": "\r", "n": "\n"}[code]


def line_of(row):
    """One row as a CSV line (the COLUMNS, in order, escaped)."""
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerow([escaped(cell(name, row.get(name))) for name in COLUMNS])
    return text.getvalue()


def text_of(rows):
    """A whole manifest: the header line, then ``rows`` sorted by output."""
    header = ",".join(COLUMNS) + "\n"
    return header + "".join(line_of(row) for row in sorted(rows, key=lambda r: r["output"]))


def read(path):
    """output -> row (a dict of COLUMNS -> text) of the manifest at ``path``; {} when there is none.
    A line that is not a whole row (a kill cut it short) is left out."""
    try:
        with open(path, encoding="utf-8", newline="") as file:
            text = file.read()
    except FileNotFoundError:
        return {}
    except (OSError, UnicodeDecodeError) as error:
        raise MzcError(f"cannot read the manifest: {getattr(error, 'strerror', None) or error}", source=path) from None
    if not text.endswith("\n"):
        text = text[:text.rfind("\n") + 1]   # the line a kill cut
    reader = csv.reader(io.StringIO(text))
    try:
        lines = list(reader)
    except csv.Error as error:   # a field longer than csv reads, say: not written by mzc
        raise MzcError(f"cannot read the manifest ({error}): give another -o or move it away", source=path,
                       line=reader.line_num) from None
    if not lines:
        return {}
    if tuple(lines[0]) != COLUMNS:
        raise MzcError(f"not an mzc batch manifest (its first line is not {','.join(COLUMNS[:3])},...): "
                       "give another -o or move it away", source=path, line=1)
    return {unescaped(fields[3]): dict(zip(COLUMNS, map(unescaped, fields)))
            for fields in lines[1:] if len(fields) == len(COLUMNS)}


class Appender:
    """Rows appended to the manifest as they come, each batch of them synced to disk."""

    def __init__(self, path):
        from mzc.streams import destination, failure

        self.path = path
        destination(path)   # refuses a manifest we may not write (read-only, for root too), as its rewrite would
        try:
            self.file = open(path, "a+b", buffering=0)
            cut_partial_line(self.file)
        except OSError as error:
            raise failure(error, path) from None
        if self.file.tell() == 0:
            self.write(",".join(COLUMNS) + "\n")

    def append(self, rows):
        """Write ``rows`` and make them durable."""
        self.write("".join(line_of(row) for row in rows))

    def write(self, text):
        """Append ``text`` and sync it, or an MzcError naming the manifest (a full disk): the rows
        before it stay whole, and a row cut short is dropped when the manifest is read."""
        from mzc.streams import failure, write_all

        try:
            write_all(self.file.fileno(), text.encode("utf-8"))
            os.fsync(self.file.fileno())
        except OSError as error:
            raise failure(error, self.path) from None

    def close(self):
        """Close the file (nothing is left to write: each append was written whole or failed)."""
        self.file.close()


def cut_partial_line(file):
    """Truncate ``file`` (binary, open for appending) after its last newline: a kill may have cut
    its last row short, and rows appended after it must start on a line of their own."""
    file.seek(0)
    data = file.read()
    keep = data.rfind(b"\n") + 1
    if keep != len(data):
        file.truncate(keep)
    file.seek(0, os.SEEK_END)


def rewrite(path, rows):
    """Replace the manifest at ``path`` by ``rows`` (atomically)."""
    from mzc.streams import write_output

    write_output(path, text_of(rows).encode("utf-8"))
