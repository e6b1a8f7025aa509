"""PLY, ascii and binary: vertices, faces (``vertex_indices`` or ``vertex_index``) and
triangle strips, read by our own vectorised reader; written binary through meshio.

Ours reads the dialects meshio refuses (vertex-only files, ``vertex_index``, extra
properties) and spares the 0.2 s import of meshio; a body it refuses goes to meshio.
"""

import re
from dataclasses import dataclass, field

import numpy as np

from mzc.errors import MzcError
from mzc.meshes import Mesh, meshio_fallback
from mzc.meshes.common import decode_text, fan_triangulate, fan_triangulate_ragged, numbers_or_error

NAME = "ply"
EXTENSIONS = (".ply",)


def sniff(data: bytes) -> bool:
    """True when ``data`` starts with the PLY magic word."""
    return data.startswith(b"ply")


def read(data: bytes, source: str) -> Mesh:
    """Read PLY with our own reader; hand a body it refuses to meshio.

    A broken header is final: meshio would loop forever looking for ``end_header``.
    """
    elements, body_format, body, body_line = parse_ply_header(data, source)
    try:
        return parse_ply_body(elements, body_format, body, body_line, source)
    except MzcError as own_error:
        try:
            return meshio_fallback.read_as("ply", data, source)
        except MzcError:
            raise own_error from None


def write(mesh: Mesh) -> bytes:
    """Binary little-endian PLY bytes of ``mesh``, written by meshio."""
    return meshio_fallback.write_as("ply", mesh)


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

