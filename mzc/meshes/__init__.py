"""Triangle meshes and point clouds at the edges of mzc: reading and writing them.

``read_mesh`` accepts OBJ, PLY (ascii and binary), VTK, STL and OFF through meshio, and
point clouds (a PLY with vertices only, or ``x y z`` text). Real files come in many
dialects, so OBJ and PLY are read by the vectorised readers below (meshio misreads
negative OBJ indices and refuses valid PLY files: vertex-only, ``vertex_index``, extra
properties); meshio reads the rest and what our PLY reader refuses. Polygons are
fan-triangulated; other cell types are ignored. Every problem becomes an MzcError naming
the file, and the line where it is known.
"""

import contextlib
import io
import logging
import os
import re
import struct
import sys
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np

from mzc.errors import MzcError
from mzc.streams import atomic_path, display_name, is_stdio, read_input

POINT_CLOUD_EXTENSIONS = (".xyz", ".txt", ".pts", ".asc")
MESHIO_FORMATS = {".obj": "obj", ".ply": "ply", ".vtk": "vtk", ".stl": "stl", ".off": "off"}
WRITE_FORMATS = ("obj", "ply", "vtk", "stl", "off")


@dataclass
class Mesh:
    """Vertices ``points`` (n, 3) and ``triangles`` (m, 3) indexing them; (0, 3) for a point
    cloud, whose file may give ``normals`` (n, 3) (they tell a slice which side it was seen from)."""

    points: np.ndarray
    triangles: np.ndarray = field(default_factory=lambda: np.empty((0, 3), dtype=np.int64))
    normals: np.ndarray | None = None

    def __post_init__(self):
        self.points = np.asarray(self.points, dtype=np.float64).reshape(-1, 3)
        self.triangles = np.asarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        if self.normals is not None:
            self.normals = np.asarray(self.normals, dtype=np.float64).reshape(self.points.shape)

    @property
    def is_point_cloud(self):
        """True when there are no triangles."""
        return len(self.triangles) == 0


# --------------------------------------------------------------------------- reading


def read_mesh(path):
    """Read a mesh or point cloud from ``path`` (``-`` for stdin, recognised by its bytes)."""
    source = display_name(path)
    data = read_input(path)
    if not data.strip():
        raise MzcError("empty input: expected a mesh or point cloud", source=source)
    kind = guess_format(None if is_stdio(path) else path, data)
    if kind == "obj":
        mesh = parse_obj(data, source)
    elif kind == "xyz":
        mesh = parse_xyz(data, source)
    elif kind == "ply":
        mesh = read_ply(path, data, source)
    elif kind in ("vtk", "stl", "off"):
        mesh = read_with_meshio(path, data, kind, source)
    else:
        raise MzcError("unrecognised mesh format (expected OBJ, PLY, VTK, STL, OFF or x y z text)",
                       source=source)
    return checked(mesh, source)


def guess_format(path, data):
    """The format of a mesh file: by its extension, else by sniffing its first bytes."""
    extension = os.path.splitext(str(path))[1].lower() if path else ""
    if extension in MESHIO_FORMATS:
        return MESHIO_FORMATS[extension]
    if extension in POINT_CLOUD_EXTENSIONS:
        return "xyz"
    return sniff_format(data)


def sniff_format(data):
    """Recognise a mesh format from its content; None when nothing fits."""
    head = data[:4096]
    if head.startswith(b"ply"):
        return "ply"
    if head.startswith(b"# vtk DataFile"):
        return "vtk"
    if re.match(rb"\s*[NCST4]*OFF\b", head):
        return "off"
    if head.lstrip().startswith(b"solid") or is_binary_stl(data):
        return "stl"
    if re.search(rb"(^|\n)\s*v\s", head):
        return "obj"
    if re.search(rb"(^|\n)\s*[-+.\d][^\n]*", head) and is_text(head):
        return "xyz"
    return None


def is_binary_stl(data):
    """True when the size of ``data`` matches the triangle count of a binary STL."""
    if len(data) < 84:
        return False
    count = struct.unpack("<I", data[80:84])[0]
    return len(data) == 84 + 50 * count


def is_text(data):
    """True when ``data`` looks like text rather than binary."""
    return b"\0" not in data


def checked(mesh, source):
    """Refuse a mesh with no points, non-finite coordinates or face indices out of range."""
    if len(mesh.points) == 0:
        raise MzcError("the mesh has no points", source=source)
    finite = np.isfinite(mesh.points).all(axis=1)
    if not finite.all():
        vertex = int(np.flatnonzero(~finite)[0]) + 1
        raise MzcError(f"vertex {vertex} has a NaN or infinite coordinate", source=source)
    if len(mesh.triangles):
        bad = (mesh.triangles < 0) | (mesh.triangles >= len(mesh.points))
        if bad.any():
            face = int(np.flatnonzero(bad.any(axis=1))[0])
            index = int(mesh.triangles[face][bad[face]][0])
            raise MzcError(f"triangle {face + 1} refers to vertex {index + 1}, but there are only "
                           f"{len(mesh.points)} vertices", source=source)
    return mesh


def fan_triangulate(polygons):
    """Split (m, k) polygons into (m*(k-2), 3) triangles fanning out from the first corner."""
    polygons = np.asarray(polygons, dtype=np.int64)
    corners = polygons.shape[1]
    if corners == 3:
        return polygons
    first = np.repeat(polygons[:, :1], corners - 2, axis=1)
    fan = np.stack([first, polygons[:, 1:-1], polygons[:, 2:]], axis=-1)
    return fan.reshape(-1, 3)


def fan_triangulate_ragged(flat, counts):
    """Fan-triangulate polygons stored as a flat index list and a corner count per polygon."""
    counts = np.asarray(counts, dtype=np.int64)
    starts = np.cumsum(counts) - counts
    pieces = counts - 2
    owner_start = np.repeat(starts, pieces)
    step = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 1
    return np.stack([flat[owner_start], flat[owner_start + step], flat[owner_start + step + 1]], axis=1)


# --- meshio


@contextlib.contextmanager
def quiet():
    """Silence meshio's warnings, log messages and prints: stdout carries data only."""
    logging.disable(logging.CRITICAL)
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("ignore")
            yield
    finally:
        logging.disable(logging.NOTSET)


@contextlib.contextmanager
def readable_file(path, data, kind):
    """A file name meshio can open: ``path`` itself, or a temporary copy of stdin's bytes."""
    if not is_stdio(path):
        yield str(path)
        return
    with tempfile.TemporaryDirectory(prefix="mzc-") as directory:
        temp = os.path.join(directory, f"stdin.{kind}")
        with open(temp, "wb") as handle:
            handle.write(data)
        yield temp


def read_with_meshio(path, data, kind, source):
    """Read with meshio; any failure becomes an MzcError."""
    import meshio

    if kind == "off" and not off_has_counts_line(data):
        raise MzcError("OFF file ends before its counts line 'vertices faces edges'", source=source)
    reader = getattr(meshio, kind).read  # meshio.read would print to stdout and sys.exit on failure
    try:
        with readable_file(path, data, kind) as name, quiet():
            result = reader(name)
    except Exception as error:  # noqa: BLE001 - meshio raises many types on bad data
        message = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise MzcError(f"cannot read as {kind.upper()}: {message}", source=source) from None
    return Mesh(xyz_of(result.points), surface_triangles(result.cells))


def off_has_counts_line(data):
    """True when an OFF file has a line after ``OFF`` that is neither blank nor a comment.

    meshio's OFF reader skips such lines in a loop that never stops at the end of the file.
    """
    lines = data.split(b"\n")[1:]
    return any(line.strip() and not line.strip().startswith(b"#") for line in lines)


def xyz_of(points):
    """(n, 3) coordinates of meshio points: 2D points get z = 0, nothing read gives (0, 3)."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.size == 0:
        return np.empty((0, 3))
    if points.shape[1] < 3:
        return np.hstack([points, np.zeros((len(points), 3 - points.shape[1]))])
    return points[:, :3]


def surface_triangles(cells):
    """The triangles of meshio cell blocks: triangles, quads and polygons, fan-triangulated."""
    pieces = [fan_triangulate(block.data) for block in cells
              if (block.type in ("triangle", "quad") or block.type.startswith("polygon"))
              and np.asarray(block.data).ndim == 2 and np.asarray(block.data).shape[1] >= 3]
    if not pieces:
        return np.empty((0, 3), dtype=np.int64)
    return np.concatenate(pieces).astype(np.int64)


# --- plain x y z text


def parse_xyz(data, source):
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


def decode_text(data, source):
    """Text of ``data``; binary garbage is refused."""
    if not is_text(data[:65536]):
        raise MzcError("binary data where text was expected", source=source)
    return data.decode("utf-8", "replace")


def numbers_or_error(rows, width, line_numbers, source):
    """Convert rows of ``width`` number tokens to a (len(rows), width) float array (also when
    there are no rows), naming the first bad line on failure."""
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), width)
    except ValueError:
        for row, number in zip(rows, line_numbers):
            try:
                [float(token) for token in row]
            except ValueError:
                raise MzcError(f"not a number in {' '.join(row)[:60]!r}", source=source,
                               line=number) from None
        raise


# --- OBJ

OBJ_WHITESPACE = np.frombuffer(b" \t\r\n\v\f", dtype=np.uint8)


def parse_obj(data, source):
    """Read Wavefront OBJ: ``v`` and ``f`` lines in any dialect (v/vt/vn, negative indices,
    polygons, CRLF, trailing comments); every other statement (vt, vn, o, g, s, usemtl,
    l, ...) is ignored. Works on whole byte arrays: no Python loop per vertex or face."""
    if not is_text(data):
        raise MzcError("binary data where OBJ text was expected", source=source)
    tokens = ObjTokens(data)
    vertex_lines, face_lines = tokens.lines_of("v"), tokens.lines_of("f")
    if len(vertex_lines) == 0:
        raise MzcError("no 'v' lines: the OBJ file has no vertices", source=source)
    points = obj_vertices(tokens, vertex_lines, source)
    triangles = obj_triangles(tokens, face_lines, vertex_lines, source)
    return Mesh(points, triangles)


class ObjTokens:
    """The whitespace-separated tokens of OBJ bytes: where each starts and ends, and its line.

    Comments (``#`` to the end of the line) are blanked first.
    """

    def __init__(self, data):
        text = np.frombuffer(data, dtype=np.uint8)
        newlines = np.flatnonzero(text == ord("\n"))
        if b"#" in data:
            after_hash = last_index(text == ord("#")) > last_index(text == ord("\n"))
            text = np.where(after_hash, ord(" "), text).astype(np.uint8)
        self.text = text
        space = np.isin(text, OBJ_WHITESPACE)
        begins = ~space
        begins[1:] &= space[:-1]
        self.starts = np.flatnonzero(begins)
        self.ends = np.flatnonzero(~space & np.r_[space[1:], True]) + 1
        self.token_of_byte = np.cumsum(begins, dtype=np.int32) - 1  # -1 before the first token
        self.line = np.searchsorted(newlines, self.starts)
        self.first_on_line = np.r_[True, self.line[1:] != self.line[:-1]]

    def lines_of(self, keyword):
        """Sorted line indices (0-based) whose first token is the one-letter ``keyword``."""
        is_keyword = (self.first_on_line & (self.ends - self.starts == 1)
                      & (self.text[self.starts] == ord(keyword)))
        return self.line[is_keyword]

    def arguments(self, lines):
        """Token indices of the arguments (all tokens but the keyword) on ``lines``."""
        on_lines = np.isin(self.line, lines) & ~self.first_on_line
        return np.flatnonzero(on_lines)

    def numbers(self, token_indices, dtype, cut_at_slash=False):
        """Parse the chosen tokens as numbers in one call; None when one does not parse.

        ``cut_at_slash`` keeps only what precedes the first ``/`` of each token (v/vt/vn).
        """
        chosen = np.zeros(len(self.starts) + 1, dtype=bool)  # the extra last slot: no token
        chosen[token_indices] = True
        keep = chosen[self.token_of_byte]
        if cut_at_slash:
            keep &= last_index(self.text == ord("/")) < self.starts[self.token_of_byte]
        buffer = np.where(keep, self.text, ord(" ")).astype(np.uint8).tobytes()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                values = np.fromstring(buffer, dtype=dtype, sep=" ")
            except (DeprecationWarning, ValueError):
                return None
        return values if len(values) == len(token_indices) else None

    def token_text(self, index):
        """The text of one token, for error messages."""
        return self.text[self.starts[index]:self.ends[index]].tobytes().decode("utf-8", "replace")


def last_index(mask):
    """For every position, the index of the latest True at or before it (-1 when none)."""
    return np.maximum.accumulate(np.where(mask, np.arange(len(mask), dtype=np.int32), np.int32(-1)))


def obj_vertices(tokens, vertex_lines, source):
    """(n, 3) x y z of the ``v`` lines; w and colour columns are ignored."""
    arguments = tokens.arguments(vertex_lines)
    line = tokens.line[arguments]
    position = arguments - np.searchsorted(tokens.line, line)  # 1 = first argument
    counts = np.bincount(np.searchsorted(vertex_lines, line), minlength=len(vertex_lines))
    if (counts < 3).any():
        raise MzcError("a vertex needs x y z", source=source,
                       line=int(vertex_lines[np.argmax(counts < 3)]) + 1)
    xyz = arguments[position <= 3]
    values = tokens.numbers(xyz, np.float64)
    if values is None:
        raise first_bad_token(tokens, xyz, float, "not a number", source)
    return values.reshape(-1, 3)


def obj_triangles(tokens, face_lines, vertex_lines, source):
    """The fan-triangulated ``f`` lines, with 1-based and negative (relative) indices resolved."""
    if len(face_lines) == 0:
        return np.empty((0, 3), dtype=np.int64)
    corners = tokens.arguments(face_lines)
    corner_line = tokens.line[corners]
    counts = np.bincount(np.searchsorted(face_lines, corner_line), minlength=len(face_lines))
    if (counts < 3).any():
        raise MzcError("a face needs at least 3 vertices", source=source,
                       line=int(face_lines[np.argmax(counts < 3)]) + 1)
    flat = tokens.numbers(corners, np.int64, cut_at_slash=True)
    if flat is None:
        raise first_bad_token(tokens, corners, int_before_slash, "bad vertex index", source)
    # A negative index counts back from the vertices defined so far in the file.
    defined_before = np.searchsorted(vertex_lines, corner_line)
    flat = np.where(flat < 0, flat + defined_before, flat - 1)
    invalid = (flat < 0) | (flat >= len(vertex_lines))
    if invalid.any():
        raise MzcError(f"face refers to a vertex that does not exist (there are {len(vertex_lines)})",
                       source=source, line=int(corner_line[np.argmax(invalid)]) + 1)
    return fan_triangulate_ragged(flat, counts)


def int_before_slash(token):
    """The vertex index of an OBJ face corner such as ``7/3/2``."""
    return int(token.split("/", 1)[0])


def first_bad_token(tokens, indices, convert, message, source):
    """The MzcError for the first token that ``convert`` refuses (the slow path, errors only)."""
    for index in indices:
        text = tokens.token_text(index)
        try:
            convert(text)
        except ValueError:
            return MzcError(f"{message}: {text[:40]!r}", source=source, line=int(tokens.line[index]) + 1)
    return MzcError(message, source=source)


# --- PLY


def read_ply(path, data, source):
    """Read PLY with our own vectorised reader; hand a body it refuses to meshio.

    Ours goes first: it reads the dialects meshio refuses (vertex-only files,
    ``vertex_index``, extra properties) and spares the 0.2 s import of meshio. A broken
    header is final: meshio would loop forever looking for ``end_header``.
    """
    elements, body_format, body, body_line = parse_ply_header(data, source)
    try:
        return parse_ply_body(elements, body_format, body, body_line, source)
    except MzcError as own_error:
        try:
            return read_with_meshio(path, data, "ply", source)
        except MzcError:
            raise own_error from None


PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
FACE_LIST_NAMES = ("vertex_indices", "vertex_index")
PLY_ELEMENTS = ("vertex", "face", "tristrips")


@dataclass
class PlyElement:
    """One ``element`` of a PLY header: its name, count and properties.

    Each property is (name, type) for a scalar or (name, (count type, item type)) for a list.
    """

    name: str
    count: int
    properties: list = field(default_factory=list)


def parse_ply_body(elements, body_format, body, body_line, source):
    """Read the body of a PLY file (ascii or binary): vertices, and faces when present."""
    if body_format == "ascii":
        tables = read_ply_ascii(elements, body, body_line, source)
    else:
        order = "<" if body_format == "binary_little_endian" else ">"
        tables = read_ply_binary(elements, body, order, source)
    return ply_mesh(elements, tables, source)


def parse_ply_header(data, source):
    """Parse the PLY header into elements; return them, the body format, body bytes and line."""
    match = re.search(rb"(^|\n)end_header[ \t]*\r?\n", data)
    if not data.startswith(b"ply") or not match:
        raise MzcError("not a PLY file: missing 'ply' or 'end_header'", source=source, line=1)
    header_lines = data[:match.start()].decode("ascii", "replace").splitlines()
    elements, body_format = [], None
    for number, line in enumerate(header_lines, 1):
        words = line.split()
        if not words or words[0] in ("ply", "comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) >= 2:
            body_format = words[1]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append(PlyElement(words[1], int(words[2])))
        elif words[0] == "property" and elements:
            elements[-1].properties.append(ply_property(words, source, number))
        else:
            raise MzcError(f"bad PLY header line {line.strip()[:40]!r}", source=source, line=number)
    if body_format not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise MzcError(f"unknown PLY format {body_format!r}", source=source)
    return elements, body_format, data[match.end():], len(header_lines) + 2


def ply_property(words, source, line):
    """(name, numpy type) or (name, (count type, item type)) of a ``property`` header line."""
    try:
        if len(words) == 5 and words[1] == "list":
            return words[4], (PLY_TYPES[words[2]], PLY_TYPES[words[3]])
        if len(words) == 3:
            return words[2], PLY_TYPES[words[1]]
    except KeyError:
        pass
    raise MzcError(f"bad PLY property {' '.join(words)[:60]!r}", source=source, line=line)


def read_ply_ascii(elements, body, first_line, source):
    """Rows of number tokens of every element of an ascii PLY body."""
    lines = [line.split() for line in decode_text(body, source).splitlines()]
    tables, start = {}, 0
    for element in elements:
        rows = lines[start:start + element.count]
        if len(rows) < element.count:
            raise MzcError(f"PLY body ends inside element '{element.name}'", source=source,
                           line=first_line + len(lines))
        tables[element.name] = ascii_element(element, rows, first_line + start, source)
        start += element.count
    return tables


def ascii_element(element, rows, first_line, source):
    """{property: values} of one ascii element; list properties become lists of index arrays."""
    if all(not isinstance(kind, tuple) for _, kind in element.properties):
        width = len(element.properties)
        if any(len(row) < width for row in rows):
            raise MzcError(f"too few values in element '{element.name}'", source=source, line=first_line)
        values = numbers_or_error([row[:width] for row in rows], width,
                                  np.arange(len(rows)) + first_line, source)
        return {name: values[:, i] for i, (name, _) in enumerate(element.properties)}
    return ascii_rows_with_lists(element, rows, first_line, source)


def ascii_rows_with_lists(element, rows, first_line, source):
    """Walk the rows of an element with list properties one row at a time (lists vary in length)."""
    columns = {name: [] for name, _ in element.properties}
    for number, row in enumerate(rows, first_line):
        position = 0
        try:
            for name, kind in element.properties:
                if isinstance(kind, tuple):
                    length = int(row[position])
                    columns[name].append(np.array(row[position + 1:position + 1 + length], dtype=float))
                    position += 1 + length
                else:
                    columns[name].append(float(row[position]))
                    position += 1
        except (ValueError, IndexError):
            raise MzcError(f"bad or missing value in element '{element.name}'", source=source,
                           line=number) from None
    return columns


def read_ply_binary(elements, body, order, source):
    """{element: {property: values}} of a binary PLY body."""
    tables, offset = {}, 0
    for element in elements:
        tables[element.name], offset = binary_element(element, body, offset, order, source)
    return tables


def binary_element(element, body, offset, order, source):
    """Read one binary element starting at ``offset``; return its columns and the next offset.

    Fast path: when every list of the element has the length of the first record's list
    (triangle meshes), the element is one structured numpy array read in a single call.
    """
    first_lengths = list_lengths_of_first_record(element, body, offset, order, source)
    fields = []
    for name, kind in element.properties:
        if isinstance(kind, tuple):
            fields.append((name + "#count", order + kind[0]))
            fields.append((name, order + kind[1], (first_lengths[name],)))
        else:
            fields.append((name, order + kind))
    dtype = np.dtype(fields)
    end = offset + dtype.itemsize * element.count
    if element.count == 0 or end <= len(body):
        records = np.frombuffer(body, dtype=dtype, count=element.count, offset=offset)
        if all((records[name + "#count"] == length).all() for name, length in first_lengths.items()):
            return {name: records[name] for name, _ in element.properties}, end
    return binary_records_one_by_one(element, body, offset, order, source)


def list_lengths_of_first_record(element, body, offset, order, source):
    """The length of each list property in the element's first record."""
    lengths = {}
    if element.count == 0:
        return {name: 0 for name, kind in element.properties if isinstance(kind, tuple)}
    for name, kind in element.properties:
        if isinstance(kind, tuple):
            count_type = np.dtype(order + kind[0])
            length = int(unpack(body, offset, count_type, 1, element, source)[0])
            lengths[name] = length
            offset += count_type.itemsize + length * np.dtype(kind[1]).itemsize
        else:
            offset += np.dtype(kind).itemsize
    return lengths


def unpack(body, offset, dtype, count, element, source):
    """``count`` values of ``dtype`` at ``offset``, or an error when the body ends early."""
    if offset + dtype.itemsize * count > len(body):
        raise MzcError(f"PLY body ends inside element '{element.name}'", source=source)
    return np.frombuffer(body, dtype=dtype, count=count, offset=offset)


def binary_records_one_by_one(element, body, offset, order, source):
    """Read an element whose lists vary in length, one record at a time (mixed polygons)."""
    columns = {name: [] for name, _ in element.properties}
    for _ in range(element.count):
        for name, kind in element.properties:
            if isinstance(kind, tuple):
                count_type, item_type = np.dtype(order + kind[0]), np.dtype(order + kind[1])
                length = int(unpack(body, offset, count_type, 1, element, source)[0])
                offset += count_type.itemsize
                columns[name].append(unpack(body, offset, item_type, length, element, source))
                offset += item_type.itemsize * length
            else:
                scalar_type = np.dtype(order + kind)
                columns[name].append(unpack(body, offset, scalar_type, 1, element, source)[0])
                offset += scalar_type.itemsize
    return columns, offset


def ply_mesh(elements, tables, source):
    """Build the Mesh from the 'vertex', 'face' and 'tristrips' elements of a parsed PLY file.

    Any other element holding records is refused by name: read as a bare cloud, a file whose
    surface lives in an element mzc does not know would be re-triangulated into noise. A
    cloud keeps the normals its vertices carry (nx, ny, nz)."""
    unknown = [element for element in elements if element.name not in PLY_ELEMENTS and element.count]
    if unknown:
        raise MzcError(f"PLY element '{unknown[0].name}' ({unknown[0].count} records) is not one mzc reads "
                       f"({', '.join(PLY_ELEMENTS)})", source=source)
    vertex = tables.get("vertex")
    if vertex is None or not all(axis in vertex for axis in "xyz"):
        raise MzcError("PLY file has no 'vertex' element with x, y, z", source=source)
    points = np.column_stack([np.asarray(vertex[axis], dtype=np.float64) for axis in "xyz"])
    faces, strips = index_lists(tables, "face"), index_lists(tables, "tristrips")
    triangles = ([ply_face_triangles(faces, source)] if faces is not None else []) + \
        ([strip_triangles(strips)] if strips is not None else [])
    if triangles:
        return Mesh(points, np.concatenate(triangles))
    normals = None
    if all(axis in vertex for axis in ("nx", "ny", "nz")):
        normals = np.column_stack([np.asarray(vertex[axis], dtype=np.float64) for axis in ("nx", "ny", "nz")])
    return Mesh(points, normals=normals)


def index_lists(tables, element):
    """The vertex-index lists of a PLY ``element`` (its first FACE_LIST_NAMES property), or None."""
    table = tables.get(element, {})
    return next((table[name] for name in FACE_LIST_NAMES if name in table), None)


def strip_triangles(strips):
    """Triangles of PLY triangle strips (``element tristrips``): each record's list holds
    strips separated by -1; triangle i of a strip is (v_i, v_i+1, v_i+2), its odd ones
    written (v_i+1, v_i, v_i+2) so all face the same way, the degenerate ones (a repeated
    vertex, used to join strips) dropped."""
    records = [np.append(np.asarray(record, dtype=np.int64), -1) for record in strips]
    flat = np.concatenate(records) if records else np.empty(0, dtype=np.int64)
    if len(flat) < 3:
        return np.empty((0, 3), dtype=np.int64)
    position = np.arange(len(flat))
    strip_start = np.maximum.accumulate(np.where(flat < 0, position, -1)) + 1
    a, b, c = flat[:-2], flat[1:-1], flat[2:]
    odd = ((position[:-2] - strip_start[:-2]) % 2).astype(bool)
    triangles = np.stack([np.where(odd, b, a), np.where(odd, a, b), c], axis=1)
    whole = (a >= 0) & (b >= 0) & (c >= 0) & (a != b) & (b != c) & (a != c)
    return triangles[whole]


def ply_face_triangles(faces, source):
    """Triangles of PLY face lists: a 2D array (equal lengths) or a list of index arrays."""
    if isinstance(faces, np.ndarray) and faces.ndim == 2:
        if faces.shape[1] < 3 and len(faces):
            raise MzcError("PLY faces need at least 3 vertices", source=source)
        return fan_triangulate(faces.astype(np.int64))
    counts = np.array([len(face) for face in faces], dtype=np.int64)
    if (counts < 3).any():
        raise MzcError(f"PLY face {int(np.argmax(counts < 3)) + 1} has fewer than 3 vertices",
                       source=source)
    if not len(faces):
        return np.empty((0, 3), dtype=np.int64)
    return fan_triangulate_ragged(np.concatenate(faces).astype(np.int64), counts)


# --------------------------------------------------------------------------- writing


def write_mesh(path, mesh, file_format=None):
    """Write ``mesh`` to ``path`` (format from ``file_format`` or the extension) atomically.

    ``-`` or None writes OBJ text to stdout. OBJ is written by our own vectorised writer
    (the fastest one); PLY is written binary; VTK, STL and OFF go through meshio.
    """
    if is_stdio(path):
        sys.stdout.buffer.write(obj_text(mesh))
        sys.stdout.buffer.flush()
        return
    file_format = output_format(path, file_format)
    with atomic_path(path) as temp:
        if file_format == "obj":
            with open(temp, "wb") as handle:
                handle.write(obj_text(mesh))
        else:
            write_with_meshio(temp, mesh, file_format, path)


def output_format(path, file_format):
    """The format to write: ``file_format`` if given, else the extension of ``path``."""
    if file_format is None:
        file_format = os.path.splitext(str(path))[1].lower().lstrip(".")
    if file_format not in WRITE_FORMATS:
        raise MzcError(f"cannot write mesh format {file_format!r} (choose one of "
                       f"{', '.join(WRITE_FORMATS)})", source=path)
    return file_format


def write_with_meshio(temp, mesh, file_format, path):
    """Write through meshio; STL needs triangles."""
    import meshio

    if file_format == "stl" and mesh.is_point_cloud:
        raise MzcError("STL cannot hold a point cloud (no triangles)", source=path)
    # int32 indices: PLY has no 64-bit integers, and meshio would warn on stderr.
    cells = [("triangle", mesh.triangles.astype(np.int32))] if len(mesh.triangles) else []
    options = {"binary": True} if file_format == "ply" else {}
    with quiet():
        meshio.write(temp, meshio.Mesh(mesh.points, cells), file_format=file_format, **options)


def obj_text(mesh):
    """OBJ bytes of ``mesh``: one string-format call over the whole arrays, shortest exact floats."""
    vertices = ("v %r %r %r\n" * len(mesh.points)) % tuple(mesh.points.ravel().tolist())
    faces = ("f %d %d %d\n" * len(mesh.triangles)) % tuple((mesh.triangles.ravel() + 1).tolist())
    return (vertices + faces).encode("ascii")
