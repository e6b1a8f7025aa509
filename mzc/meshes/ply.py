"""PLY, ascii and binary: vertices, faces (``vertex_indices`` or ``vertex_index``) and
triangle strips, read and written (binary) by our own vectorised code.

Ours reads every dialect meshio reads and more (vertex-only files, ``vertex_index``,
extra properties, 64-bit types, ``\\r`` line ends) and spares the 0.2 s import of meshio,
so nothing falls back to meshio: a PLY file ours refuses is refused, with the reason.
The header's counts are promises the body must keep, checked before anything is
allocated: a body that ends early is "truncated" (naming the element, how many records
it declares and how many the file holds), and data after the last element is refused.
"""

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from mzc.colours import to_8_bits
from mzc.errors import MzcError
from mzc.meshes import Mesh
from mzc.meshes.common import as_indices, decode_text, fan_triangulate_ragged, flat_numbers
from mzc.numbers import is_count, real_array

NAME = "ply"
EXTENSIONS = (".ply",)


def read(data: bytes, source: str) -> Mesh:
    """The mesh or point cloud of PLY ``data``; a broken file is an MzcError saying why."""
    elements, body_format, body, body_line = parse_ply_header(data, source)
    if body_format == "ascii":
        tables = read_ply_ascii(elements, body, body_line, source)
    else:
        tables = read_ply_binary(elements, body, "<" if body_format == "binary_little_endian" else ">", source)
    return ply_mesh(elements, tables, source, texture_file(data[:len(data) - len(body)]))


def texture_file(header):
    """The image a PLY header names in a ``comment TextureFile NAME`` line (MeshLab's, Open3D's),
    or None."""
    found = re.search(rb"(?m)^comment[ \t]+TextureFile[ \t]+([^\r\n]+?)[ \t]*\r?$", header)
    return found.group(1).decode("utf-8", "replace") if found else None


def write(mesh: Mesh) -> Iterator:
    """Binary little-endian PLY of ``mesh`` as chunks of bytes (its ``parts``, which a grid's
    mesh makes a strip at a time; ``mzc.streams`` writes them as they come): double x y z per
    vertex (and ``uchar red green blue`` when it has colours), then (unless it is a point cloud)
    a face element of uint8 counts and int32 indices, the layout meshio writes and every PLY
    reader knows, without meshio's import or the time stamp it puts in a comment (the same
    mesh gives the same bytes)."""
    vertex_count, triangle_count, point_chunks, triangle_chunks = mesh.parts()
    colors = mesh.colors
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {vertex_count}",
              "property double x", "property double y", "property double z"]
    if colors is not None:
        header += [f"property uchar {name}" for name in COLOURS]
    if vertex_count > np.iinfo(np.int32).max:
        raise MzcError(f"PLY's int32 indices cannot number {vertex_count} vertices")
    if triangle_count:
        header += [f"element face {triangle_count}", "property list uint8 int32 vertex_indices"]

    def chunks():
        yield "\n".join(header + ["end_header", ""]).encode("ascii")
        done = 0
        for points in point_chunks:
            if colors is None:
                yield np.ascontiguousarray(points, dtype="<f8").reshape(-1).view(np.uint8)
                continue
            records = np.empty(len(points), dtype=COLOURED_VERTEX)
            records["xyz"], records["rgb"] = points, colors[done:done + len(points)]
            done += len(points)
            yield records.view(np.uint8)
        for triangles in triangle_chunks if triangle_count else ():
            faces = np.empty(len(triangles), dtype=FACE_RECORD)
            faces["count"], faces["indices"] = 3, triangles
            yield faces.view(np.uint8)

    return chunks()


FACE_RECORD = np.dtype([("count", "u1"), ("indices", "<i4", (3,))])   # a triangle as PLY writes it: 13 bytes
COLOURED_VERTEX = np.dtype([("xyz", "<f8", (3,)), ("rgb", "u1", (3,))])   # a vertex with its colour: 27 bytes
PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "int64": "i8", "uint64": "u8", "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
BODY_FORMATS = ("ascii", "binary_little_endian", "binary_big_endian")
FACE_LIST_NAMES = ("vertex_indices", "vertex_index")
PLY_ELEMENTS = ("vertex", "face", "tristrips")
PLURALS = {"vertex": "vertices", "face": "faces"}


@dataclass
class PlyElement:
    """One ``element`` of a PLY header: its name, count and properties.

    Each property is (name, type) for a scalar or (name, (count type, item type)) for a list;
    ``names`` holds their names, so that a header of 100,000 properties is checked for a name
    given twice in linear time (a scan of the list for each took 90 s).
    """

    name: str
    count: int
    properties: list = field(default_factory=list)
    names: set = field(default_factory=set)

    def add(self, prop):
        """Add the property ``prop`` (name, type)."""
        self.properties.append(prop)
        self.names.add(prop[0])


class Lists(NamedTuple):
    """The values of one list property of every record: all items in a row, and each record's count."""

    values: np.ndarray
    counts: np.ndarray


def truncated(element, held, source, line=None):
    """The MzcError for a body that ends after ``held`` records of ``element``."""
    return MzcError(f"truncated: element {element.name} declares {element.count} "
                    f"{PLURALS.get(element.name, 'records')}, the file holds {held}", source=source, line=line)


def parse_ply_header(data, source):
    """Parse the PLY header into elements; return them, the body format, a view of the body's
    bytes and its first line.

    The line end of the ``ply`` line (``\\n``, ``\\r\\n`` or ``\\r``) is the header's: a
    binary body may start with either byte, so ``end_header`` must end the same way.
    """
    magic = re.match(rb"ply[ \t]*(\r\n|\r|\n)", data)
    cr_only = magic is not None and magic.group(1) == b"\r"
    match = re.search(rb"\rend_header[ \t]*\r" if cr_only else rb"\nend_header[ \t]*\r?\n", data)
    if not magic or not match:
        raise MzcError("not a PLY file: missing 'ply' or 'end_header'", source=source, line=1)
    header_lines = data[:match.start()].decode("utf-8", "replace").splitlines()
    elements, body_format = [], None
    for number, line in enumerate(header_lines, 1):
        words = line.split()
        if number == 1 or not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format" and len(words) in (2, 3) and body_format is None:
            body_format = words[1]
        elif (words[0] == "element" and len(words) == 3 and is_count(words[2])
              and all(element.name != words[1] for element in elements)):
            elements.append(PlyElement(words[1], int(words[2])))
        elif words[0] == "property" and elements:
            elements[-1].add(ply_property(words, elements[-1], source, number))
        else:
            raise MzcError(f"bad PLY header line {line.strip()[:40]!r}", source=source, line=number)
    if body_format not in BODY_FORMATS:
        raise MzcError(f"unknown PLY format {body_format!r} (expected one of {', '.join(BODY_FORMATS)})",
                       source=source)
    empty = next((element for element in elements if element.count and not element.properties), None)
    if empty is not None:
        raise MzcError(f"element {empty.name} declares {empty.count} records but no properties", source=source)
    return elements, body_format, memoryview(data)[match.end():], len(header_lines) + 2   # no copy of the body


def ply_property(words, element, source, line):
    """(name, numpy type) or (name, (count type, item type)) of a ``property`` header line;
    a list's count must be an integer type and every name is new in its element."""
    if words[-1] in element.names:
        raise MzcError(f"element {element.name} has a second property {words[-1]!r}", source=source, line=line)
    if len(words) == 5 and words[1] == "list" and words[2] in PLY_TYPES and words[3] in PLY_TYPES:
        if PLY_TYPES[words[2]].startswith("f"):
            raise MzcError(f"list {words[4]!r} has a count type {words[2]!r}: counts are integers",
                           source=source, line=line)
        return words[4], (PLY_TYPES[words[2]], PLY_TYPES[words[3]])
    if len(words) == 3 and words[1] in PLY_TYPES:
        return words[2], PLY_TYPES[words[1]]
    raise MzcError(f"bad PLY property {' '.join(words)[:60]!r} (types: {', '.join(PLY_TYPES)})",
                   source=source, line=line)


def read_ply_ascii(elements, body, first_line, source):
    """{element: {property: values}} of an ascii PLY body: one record per line, blank lines
    skipped, every record holding exactly its properties and the body nothing more."""
    numbered = enumerate(decode_text(bytes(body), source).splitlines(), first_line)
    rows = [(number, words) for number, words in ((number, line.split()) for number, line in numbered) if words]
    end_line = rows[-1][0] + 1 if rows else first_line
    tables, start = {}, 0
    for element in elements:
        records = rows[start:start + element.count]
        if len(records) < element.count:
            raise truncated(element, len(records), source, line=end_line)
        tables[element.name] = ascii_element(element, records, source)
        start += element.count
    if start < len(rows):
        raise MzcError(f"{len(rows) - start} lines after the last element", source=source, line=rows[start][0])
    return tables


def ascii_element(element, records, source):
    """{property: values} of one ascii element: a column per scalar, Lists per list property.

    An element of scalars only (vertices) is one table converted in a single call. One with
    lists has each record walked to find where its lists end (a loop over the lines' word
    lists only); all the numbers are then converted in one call per property.
    """
    numbers = [number for number, _ in records]
    if not any(isinstance(kind, tuple) for _, kind in element.properties):
        width = len(element.properties)
        wrong = next((number for number, words in records if len(words) != width), None)
        if wrong is not None:
            raise MzcError(f"element {element.name}: expected {width} values on the line", source=source, line=wrong)
        table = flat_numbers([words for _, words in records], numbers, source).reshape(-1, width)
        return {name: table[:, i] for i, (name, _) in enumerate(element.properties)}
    tokens = {name: [] for name, _ in element.properties}
    counts = {name: [] for name, kind in element.properties if isinstance(kind, tuple)}
    for number, words in records:
        position = 0
        for name, kind in element.properties:
            length = 1
            if isinstance(kind, tuple):
                count = words[position] if position < len(words) else "nothing"
                if not is_count(count):
                    raise MzcError(f"element {element.name}: list {name!r} has count {count[:20]!r}, "
                                   "expected a whole number >= 0", source=source, line=number)
                length = int(count)
                counts[name].append(length)
                position += 1
            if position + length > len(words):
                raise MzcError(f"element {element.name}: the line ends inside property {name!r}",
                               source=source, line=number)
            tokens[name].append(words[position:position + length])
            position += length
        if position != len(words):
            raise MzcError(f"element {element.name}: {len(words) - position} values after the last property",
                           source=source, line=number)
    columns = {}
    for name, kind in element.properties:
        if isinstance(kind, tuple):
            columns[name] = Lists(flat_numbers(tokens[name], numbers, source), np.array(counts[name], dtype=np.int64))
        else:
            columns[name] = flat_numbers(tokens[name], numbers, source)
    return columns


def read_ply_binary(elements, body, order, source):
    """{element: {property: values}} of a binary PLY body, which must end with its last element."""
    tables, offset = {}, 0
    for element in elements:
        tables[element.name], offset = binary_element(element, body, offset, order, source)
    if offset < len(body):
        raise MzcError(f"{len(body) - offset} bytes after the last element", source=source)
    return tables


def binary_element(element, body, offset, order, source):
    """Read one binary element starting at ``offset``; return its columns and the next offset.

    Records are read in runs whose lists all have the lengths of the run's first record,
    each run one structured numpy array: a triangle mesh is a few runs of doubling size,
    mixed polygons a run per change of length. No run reaches beyond the body.
    """
    runs, done, span = [], 0, 16
    while done < element.count:
        lengths, size = record_layout(element, body, offset, order, source, done)
        if offset + size > len(body):
            raise truncated(element, done, source)
        dtype = np.dtype([field for i, (_, kind) in enumerate(element.properties)
                          for field in record_fields(i, kind, lengths.get(i), order)])
        fit = min(element.count - done, (len(body) - offset) // size, span)
        records = np.frombuffer(body, dtype=dtype, count=fit, offset=offset)
        same = np.ones(fit, dtype=bool)
        for i, length in lengths.items():
            same &= records[f"c{i}"] == length
        run = fit if same.all() else int(np.argmin(same))
        runs.append(records[:run])
        done, offset, span = done + run, offset + run * size, max(16, 2 * run)
    return element_columns(element, runs, order), offset


def record_layout(element, body, offset, order, source, done):
    """The list lengths ({property index: length}) and byte size of the record at ``offset``."""
    lengths, position = {}, offset
    for i, (name, kind) in enumerate(element.properties):
        if isinstance(kind, tuple):
            count_type = np.dtype(order + kind[0])
            if position + count_type.itemsize > len(body):
                raise truncated(element, done, source)
            length = int(np.frombuffer(body, dtype=count_type, count=1, offset=position)[0])
            if length < 0:
                raise MzcError(f"element {element.name} record {done + 1}: list {name!r} has count {length}",
                               source=source)
            lengths[i] = length
            position += count_type.itemsize + length * np.dtype(kind[1]).itemsize
        else:
            position += np.dtype(kind).itemsize
        if position > len(body):
            raise truncated(element, done, source)
    return lengths, position - offset


def record_fields(i, kind, length, order):
    """The structured-dtype fields of property ``i``: its value, or a list's count and items."""
    if isinstance(kind, tuple):
        return [(f"c{i}", order + kind[0]), (f"p{i}", order + kind[1], (length,))]
    return [(f"p{i}", order + kind)]


def element_columns(element, runs, order):
    """{property: values} of an element read as ``runs`` of records: a column per scalar,
    Lists per list property."""
    columns = {}
    for i, (name, kind) in enumerate(element.properties):
        item = np.dtype(order + (kind[1] if isinstance(kind, tuple) else kind))
        values = np.concatenate([run[f"p{i}"].reshape(-1) for run in runs] + [np.empty(0, dtype=item)])
        if isinstance(kind, tuple):
            counts = np.concatenate([run[f"c{i}"].astype(np.int64) for run in runs] + [np.empty(0, np.int64)])
            columns[name] = Lists(values, counts)
        else:
            columns[name] = values
    return columns


def ply_mesh(elements, tables, source, texture=None):
    """Build the Mesh from the 'vertex', 'face' and 'tristrips' elements of a parsed PLY file.

    Other elements (``edge``, ``material``, ...) are skipped beside faces or strips; without
    them such an element holding records is refused by name: read as a bare cloud, a file
    whose surface lives in an element mzc does not know would be re-triangulated into noise.
    A cloud (no faces, or ``element face 0``) keeps the normals its vertices carry (nx, ny,
    nz). Vertex colours are kept, or else the ``texture`` image sampled at the texture coordinates
    (``ply_texture``); other properties are read past and named in the Mesh's ``dropped``."""
    unknown = [element for element in elements if element.name not in PLY_ELEMENTS and element.count]
    has_surface = any(element.name in ("face", "tristrips") and element.count for element in elements)
    if unknown and not has_surface:
        raise MzcError(f"PLY element '{unknown[0].name}' ({unknown[0].count} records) is not one mzc reads "
                       f"({', '.join(PLY_ELEMENTS)})", source=source)
    vertex = tables.get("vertex", {})
    if not all(isinstance(vertex.get(axis), np.ndarray) for axis in "xyz"):
        raise MzcError("PLY file has no 'vertex' element with x, y, z", source=source)
    points = np.column_stack([real_array(vertex[axis], axis) for axis in "xyz"])
    faces, strips = index_lists(tables, "face", source), index_lists(tables, "tristrips", source)
    triangles = ([ply_face_triangles(faces, source)] if faces is not None else []) + \
        ([strip_triangles(strips, source)] if strips is not None else [])
    colors, textured = ply_colours(elements, vertex), None
    colour_names = COLOURS if colors is not None else ()
    if colors is None and texture is not None and faces is not None:
        colors, textured = ply_texture(texture, tables, faces, len(points), source)
        colour_names = TEXTURE_COORDINATES if colors is not None else ()
    if sum(len(part) for part in triangles):   # an ``element face 0`` leaves a cloud
        return Mesh(points, np.concatenate(triangles), dropped=ply_dropped(elements, colour_names), colors=colors,
                    texture=None if strips is not None else textured)   # strips' triangles: vertex colours
    normals = None
    if all(isinstance(vertex.get(axis), np.ndarray) for axis in NORMALS):
        normals = np.column_stack([real_array(vertex[axis], axis) for axis in NORMALS])
    return Mesh(points, normals=normals, colors=colors,
                dropped=ply_dropped(elements, (*(NORMALS if normals is not None else ()), *colour_names)))


NORMALS = ("nx", "ny", "nz")
COLOURS = ("red", "green", "blue")
TEXTURE_COORDINATES = ("texture_u", "texture_v", "texcoord")   # per vertex, or a face's list of u v per corner


def ply_texture(texture, tables, faces, count, source):
    """((count, 3) uint8 colours of the vertices, the ``Texture`` of the faces) of the ``comment
    TextureFile`` image at the texture coordinates: the vertex properties ``texture_u
    texture_v``, or the face list ``texcoord`` (u v of each corner, in the order of the face's
    vertices; a vertex's colour at one of its corners'), or (None, None) (with one warning when
    the image cannot be read: ``mzc.meshes.texture``)."""
    from mzc.meshes.texture import image_beside, textured

    vertex, face = tables.get("vertex", {}), tables.get("face", {})
    corner_vertex = as_indices(faces.values, "face", source)
    if all(isinstance(vertex.get(name), np.ndarray) for name in TEXTURE_COORDINATES[:2]):
        uv = np.column_stack([real_array(vertex[name], name) for name in TEXTURE_COORDINATES[:2]])
        corner_uv = uv[corner_vertex]
    elif isinstance(face.get("texcoord"), Lists) and np.array_equal(face["texcoord"].counts, 2 * faces.counts):
        corner_uv = real_array(face["texcoord"].values, "texcoord").reshape(-1, 2)
        uv = np.full((count, 2), np.nan)
        uv[corner_vertex] = corner_uv
    else:
        return None, None
    image = image_beside(source, texture, "comment TextureFile")
    if image is None:
        return None, None
    return textured(image, corner_uv[fan_triangulate_ragged(np.arange(len(corner_vertex)), faces.counts)], uv)


def ply_colours(elements, vertex):
    """(n, 3) uint8 colours of the vertex properties ``red green blue`` (``mzc.colours.to_8_bits``
    by the type the header declares for red: uchar as they are, ushort scaled, float as 0..1), or
    None."""
    if not all(isinstance(vertex.get(name), np.ndarray) for name in COLOURS):
        return None
    declared = np.dtype(dict(next(element for element in elements if element.name == "vertex").properties)["red"])
    values = np.column_stack([real_array(vertex[name], name) for name in COLOURS])
    return to_8_bits(values, 8 * declared.itemsize if declared.kind in "iu" else None)


def ply_dropped(elements, kept_vertex):
    """What a PLY file holds beside its shape, which mzc does not keep: each element's other
    properties (a mesh's normals, alpha, texture coordinates, ...) and other elements that
    hold records, by name; ``kept_vertex`` are the vertex properties the Mesh keeps (a cloud's
    normals, colours)."""
    kept = {"vertex": {"x", "y", "z", *kept_vertex}, "face": {*FACE_LIST_NAMES, *kept_vertex},
            "tristrips": set(FACE_LIST_NAMES)}
    dropped = []
    for element in elements:
        if not element.count:
            continue
        names = [name for name, _ in element.properties if name not in kept.get(element.name, ())]
        if element.name not in kept:
            dropped.append(f"{element.count:,} {element.name} records")
        elif names and set(NORMALS) <= set(names) and element.name == "vertex":   # a mesh's: recomputed
            rest = [name for name in names if name not in NORMALS]
            dropped.append("vertex normals nx ny nz (recomputed from the triangles)"
                           + (f"; vertex properties {' '.join(rest)}" if rest else ""))
        elif names:
            dropped.append(f"{element.name} properties {' '.join(names)}")
    return tuple(dropped)


def index_lists(tables, element, source):
    """The vertex-index Lists of a PLY ``element`` (its first FACE_LIST_NAMES property), or None."""
    table = tables.get(element, {})
    name = next((name for name in FACE_LIST_NAMES if name in table), None)
    if name is None:
        return None
    if not isinstance(table[name], Lists):
        raise MzcError(f"PLY {element} property {name!r} must be a list", source=source)
    return table[name]


def strip_triangles(strips, source):
    """Triangles of PLY triangle strips (``element tristrips``): each record's list holds
    strips separated by -1; triangle i of a strip is (v_i, v_i+1, v_i+2), its odd ones
    written (v_i+1, v_i, v_i+2) so all face the same way, the degenerate ones (a repeated
    vertex, used to join strips) dropped."""
    values = as_indices(strips.values, "tristrips", source)
    flat = np.insert(values, np.cumsum(strips.counts), -1)
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
    """Fan-triangulated PLY face lists; a face of fewer than 3 vertices is refused."""
    if (faces.counts < 3).any():
        raise MzcError(f"PLY face {int(np.argmax(faces.counts < 3)) + 1} has fewer than 3 vertices",
                       source=source)
    return fan_triangulate_ragged(as_indices(faces.values, "face", source), faces.counts)
