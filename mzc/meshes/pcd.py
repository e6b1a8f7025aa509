"""PCD, the Point Cloud Library's format (what Kinect and range-scanning software write):
``ascii``, ``binary`` and ``binary_compressed`` bodies, read by our own vectorised code.

The header (``VERSION``, ``FIELDS``, ``SIZE``, ``TYPE``, ``COUNT``, ``WIDTH``, ``HEIGHT``,
``VIEWPOINT``, ``POINTS``, ``DATA``) declares the fields of every point; mzc takes ``x y z``
among any others (``rgb``, ``intensity``, ``normal_x normal_y normal_z``, which a cloud
keeps: they tell a slice which side it was seen from, and ``_`` padding). Points with a NaN
coordinate (a depth camera's pixels that saw nothing) are dropped.

A ``binary`` body is the points one after another, little-endian; ``binary_compressed`` is
two uint32 (compressed and uncompressed sizes), then LZF (``_lzf.c``) of the fields one
after another, each for every point (``_`` fields left out), as PCL's writer lays them
out. PCL pads both binary bodies with zeros to a page, so bytes after the data are
allowed. Every declared size is checked before anything is allocated: WIDTH x HEIGHT
must be POINTS, a binary body must hold POINTS records, a compressed body's sizes must be
those of POINTS records and within what its compressed bytes can expand to.

An organised cloud (HEIGHT > 1: the rows and columns of a depth camera's image) is its
own grid: its points are triangulated along the image's lattice, two triangles a cell,
as ``mzc triangulate`` joins a z-grid's nodes, never re-triangulated by Delaunay; a cell
is left open where a corner saw nothing or across a depth jump, an edge within
JUMP_ANGLE (3 degrees, ``mzc.ops.triangulation``) of the line of sight from the sensor,
and each triangle faces the sensor. The sensor is at the VIEWPOINT's origin; its rotation
is not applied: points stay in the file's frame, as PCL keeps them (PCL's OpenNI grabber
writes camera-frame points, z forward, with a VIEWPOINT turned 180 degrees about x).
Why not a range image sliced node for node: a camera's pixels lie on rays of equal steps
in tan(angle), which is none of mzc's projections (equal steps in angle or in length), so
the lattice's triangles, sliced like any mesh, are the exact way from those pixels to a
z-grid.
"""

import re
from dataclasses import dataclass

import numpy as np

from mzc.colours import unpack_rgb
from mzc.errors import MzcError
from mzc.limits import MAX_FIELD_VALUES, check_magnitude
from mzc.meshes import Mesh
from mzc.meshes.common import decode_text
from mzc.numbers import bad_token, is_count, real_array, to_floats

NAME = "pcd"
EXTENSIONS = (".pcd",)
write = None   # mzc reads PCD clouds; what it writes are meshes

KEYWORDS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA")
BODIES = ("ascii", "binary", "binary_compressed")
TYPES = {("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4", ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2",
         ("U", 4): "u4", ("U", 8): "u8", ("F", 4): "f4", ("F", 8): "f8"}
NORMALS = ("normal_x", "normal_y", "normal_z")
PADDING = "_"
LZF_MAX_EXPANSION = 88   # LZF's densest run: 3 bytes that copy 264 (a back-reference of the longest length)
LZF_ERRORS = {-1: "the compressed data ends inside a run", -2: "the compressed data expands past its declared size",
              -3: "the compressed data refers back before its start"}


@dataclass
class Field:
    """One PCD field: its name, numpy type (little-endian) and values per point."""

    name: str
    dtype: str
    count: int

    @property
    def size(self):
        """Bytes per point."""
        return np.dtype(self.dtype).itemsize * self.count


@dataclass
class Header:
    """A parsed PCD header: the fields, the lattice (``height`` rows of ``width``), the
    sensor's origin (``VIEWPOINT``'s first three numbers), the body's kind, where it starts
    (byte offset) and its first line's number."""

    fields: list
    width: int
    height: int
    origin: np.ndarray
    body: str
    start: int
    first_line: int

    @property
    def points(self):
        """How many points the body holds."""
        return self.width * self.height


def sniff(data: bytes) -> bool | None:
    """True when the first line that is not a ``#`` comment starts with a PCD keyword; else None:
    a PCD whose header is damaged is for its reader to refuse."""
    return True if re.match(rb"(?:[ \t]*#[^\n]*\n|[ \t]*\r?\n)*[ \t]*(VERSION|FIELDS)\b", data[:4096]) else None


def read(data: bytes, source: str) -> Mesh:
    """The cloud (or, organised, the lattice mesh) of PCD ``data``; a broken file is an
    MzcError naming the line and keyword, or the body's problem."""
    header = parse_header(data, source)
    colour = colour_field(header)
    names = ("x", "y", "z") + (NORMALS if all(name in field_names(header) for name in NORMALS) else ()) + \
        ((colour.name,) if colour is not None else ())
    if header.body == "ascii":
        columns = ascii_columns(header, data, names, source)
    elif header.body == "binary":
        columns = binary_columns(header, data, names, source)
    else:
        columns = compressed_columns(header, data, names, source)
    points = np.column_stack([real_array(columns[name], name) for name in ("x", "y", "z")])
    normals = np.column_stack([real_array(columns[name], name) for name in NORMALS]) \
        if NORMALS[0] in columns else None
    colors = None if colour is None else unpack_rgb(np.asarray(columns[colour.name]).astype(colour.dtype))
    others = [name for name in field_names(header) if name not in (*names, *NORMALS, "_")]   # "_": padding
    return cloud_or_lattice(header, points, normals, source, others, colors)


def colour_field(header):
    """The field of PCL's packed colour, ``rgb`` or ``rgba``, one 4-byte value a point (a float32
    or uint32 whose bytes are blue, green, red, alpha: ``mzc.colours.unpack_rgb``), or None."""
    return next((field for field in header.fields if field.name in ("rgb", "rgba") and field.count == 1
                 and np.dtype(field.dtype).itemsize == 4), None)


def field_names(header):
    """The names of the header's fields."""
    return [field.name for field in header.fields]


def parse_header(data, source):
    """The Header of PCD ``data``: every keyword once (COUNT, VIEWPOINT and POINTS may be left
    out), FIELDS, SIZE, TYPE and COUNT of one length, x y z among the fields with one value
    each; an error names the line and keyword."""
    values, lines, position, number = {}, {}, 0, 0
    while "DATA" not in values:
        end = data.find(b"\n", position)
        if end < 0:
            raise MzcError("the header ends without a DATA line", source=source, line=number + 1)
        number += 1
        words = data[position:end].decode("ascii", "replace").split()
        position = end + 1
        if not words or words[0].startswith("#"):
            continue
        keyword = words[0]
        if keyword not in KEYWORDS:
            raise MzcError(f"unknown header line {' '.join(words)[:40]!r} (expected one of {', '.join(KEYWORDS)})",
                           source=source, line=number)
        if keyword in values:
            raise MzcError("given twice", source=source, line=number, field=keyword)
        values[keyword], lines[keyword] = words[1:], number
    for keyword in ("FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT"):
        if keyword not in values:
            raise MzcError(f"the header has no {keyword} line", source=source, line=lines["DATA"])

    def problem(keyword, message):
        return MzcError(message, source=source, line=lines[keyword], field=keyword)

    fields = header_fields(values, problem)
    width, height = (header_count(values, keyword, problem) for keyword in ("WIDTH", "HEIGHT"))
    if "POINTS" in values and header_count(values, "POINTS", problem) != width * height:
        raise problem("POINTS", f"{values['POINTS'][0]} points, but WIDTH x HEIGHT is {width} x {height}")
    origin = np.zeros(3)
    if "VIEWPOINT" in values:
        viewpoint = values["VIEWPOINT"]
        if len(viewpoint) != 7 or bad_token(viewpoint) is not None:
            raise problem("VIEWPOINT", "expected 7 numbers (tx ty tz qw qx qy qz)")
        origin = to_floats(viewpoint[:3])
        if not np.isfinite(origin).all():
            raise problem("VIEWPOINT", "the sensor's position must be finite")
        check_magnitude(origin, "coordinates", source=source, line=lines["VIEWPOINT"], field="VIEWPOINT")
    if values["DATA"] not in ([body] for body in BODIES):
        raise problem("DATA", f"{' '.join(values['DATA'])[:30]!r} is not one of {', '.join(BODIES)}")
    return Header(fields, width, height, origin, values["DATA"][0], position, number + 1)


def header_fields(values, problem):
    """The Fields of FIELDS, SIZE, TYPE and COUNT (1 each when it is left out)."""
    names = values["FIELDS"]
    counts = values.get("COUNT", ["1"] * len(names))
    for keyword, given in (("SIZE", values["SIZE"]), ("TYPE", values["TYPE"]), ("COUNT", counts)):
        if len(given) != len(names):
            raise problem(keyword, f"{len(given)} values for {len(names)} fields")
    fields = []
    for name, size, kind, count in zip(names, values["SIZE"], values["TYPE"], counts):
        dtype = TYPES.get((kind, int(size) if is_count(size) else 0))
        if dtype is None:
            raise problem("TYPE", f"field {name!r}: type {kind} of size {size} is none of PCD's "
                                  f"(I and U of 1, 2, 4, 8 bytes; F of 4, 8)")
        if not is_count(count) or not 1 <= int(count) <= MAX_FIELD_VALUES:
            raise problem("COUNT", f"field {name!r}: count {count[:20]!r} is not a whole number from 1 to "
                                   f"{MAX_FIELD_VALUES}")
        if name != PADDING and name in (field.name for field in fields):
            raise problem("FIELDS", f"field {name!r} is given twice")
        fields.append(Field(name, "<" + dtype, int(count)))
    for axis in ("x", "y", "z"):
        field = next((field for field in fields if field.name == axis), None)
        if field is None:
            raise problem("FIELDS", f"no field {axis!r}: a PCD cloud needs x y z")
        if field.count != 1:
            raise problem("COUNT", f"field {axis!r} has {field.count} values a point, not 1")
    return fields


def header_count(values, keyword, problem):
    """The one whole number of a WIDTH, HEIGHT or POINTS line."""
    given = values[keyword]
    if len(given) != 1 or not is_count(given[0]) or len(given[0]) > 12:
        raise problem(keyword, f"{' '.join(given)[:30]!r} is not a whole number")
    return int(given[0])


def ascii_columns(header, data, names, source):
    """{name: float64 values} of an ascii body (exact for every 4-byte value, which a packed
    colour is): one point a line, each with every field's
    values (blank lines skipped, as PCL does), and nothing after the last point."""
    tokens = decode_text(data[header.start:], source).split()
    width = sum(field.count for field in header.fields)
    if len(tokens) != header.points * width:
        raise ascii_count_error(header, data, width, source)
    positions = column_positions(header.fields, np.ones(len(header.fields), dtype=bool))
    columns = {}
    for name in names:
        chosen = tokens[positions[name]::width]
        try:
            columns[name] = to_floats(chosen)
        except ValueError:
            point = bad_token(chosen)
            raise MzcError(f"point {point + 1}: {name} {chosen[point][:30]!r} is not a number", source=source,
                           line=ascii_line_of(data, header, point)) from None
    return columns


def column_positions(fields, counted):
    """{name: position of its first value in a point} over the fields where ``counted`` holds."""
    sizes = [field.count for field, keep in zip(fields, counted) if keep]
    starts = np.cumsum([0] + sizes[:-1])
    return dict(zip([field.name for field, keep in zip(fields, counted) if keep], starts.tolist()))


def ascii_count_error(header, data, width, source):
    """The MzcError of an ascii body whose values do not make POINTS points of ``width``:
    the first line of another length, or the count of lines (the slow path, errors only)."""
    numbered = [(number, len(line.split())) for number, line in
                enumerate(decode_text(data[header.start:], source).splitlines(), header.first_line)]
    numbered = [(number, length) for number, length in numbered if length]
    wrong = next(((number, length) for number, length in numbered if length != width), None)
    if wrong is not None:
        return MzcError(f"{wrong[1]} values on the line; the fields make {width} a point", source=source,
                        line=wrong[0])
    return MzcError(f"{len(numbered)} points, but the header declares {header.points} (WIDTH x HEIGHT)",
                    source=source, line=numbered[header.points][0] if len(numbered) > header.points else None)


def ascii_line_of(data, header, point):
    """The line number of ascii point ``point`` (0-based; blank lines skipped)."""
    lines = data[header.start:].decode("ascii", "replace").splitlines()
    filled = [number for number, line in enumerate(lines, header.first_line) if line.strip()]
    return filled[point] if point < len(filled) else None


def binary_columns(header, data, names, source):
    """{name: values, of the field's type} of a binary body: POINTS records of every field in turn."""
    dtype = np.dtype([(f"f{i}", field.dtype, (field.count,)) for i, field in enumerate(header.fields)])
    needed, held = header.points * dtype.itemsize, len(data) - header.start
    if held < needed:
        raise MzcError(f"truncated: {header.points} points of {dtype.itemsize} bytes need {needed} bytes of "
                       f"binary data, the file holds {held}", source=source)
    records = np.frombuffer(data, dtype=dtype, count=header.points, offset=header.start)
    index = {field.name: i for i, field in enumerate(header.fields)}
    return {name: records[f"f{index[name]}"][:, 0] for name in names}


def compressed_columns(header, data, names, source):
    """{name: values, of the field's type} of a binary_compressed body (the sizes, then LZF of each field's
    values for every point in turn, ``_`` fields left out)."""
    from mzc.meshes import _lzf

    body = memoryview(data)[header.start:]
    if len(body) < 8:
        raise MzcError(f"truncated: a binary_compressed body starts with 8 bytes of sizes, the file holds "
                       f"{len(body)}", source=source)
    compressed, expanded = (int(size) for size in np.frombuffer(body, dtype="<u4", count=2))
    kept = [field.name != PADDING for field in header.fields]
    needed = header.points * sum(field.size for field, keep in zip(header.fields, kept) if keep)
    if expanded != needed:
        raise MzcError(f"the compressed data declares {expanded} bytes, but {header.points} points make {needed}",
                       source=source)
    if compressed > len(body) - 8:
        raise MzcError(f"truncated: the compressed data declares {compressed} bytes, the file holds "
                       f"{len(body) - 8}", source=source)
    if expanded > LZF_MAX_EXPANSION * compressed:
        raise MzcError(f"the compressed data declares {expanded} bytes, more than {compressed} bytes of LZF "
                       f"can hold", source=source)
    values = bytearray(expanded)
    written = _lzf.decompress(body[8:8 + compressed], values)
    if written != expanded:
        raise MzcError(LZF_ERRORS.get(written, f"the compressed data expands to {written} bytes, not {expanded}"),
                       source=source)
    sizes = {field.name: field.size for field, keep in zip(header.fields, kept) if keep}
    starts = dict(zip(sizes, np.cumsum([0] + list(sizes.values())[:-1]).tolist()))
    fields = {field.name: field for field in header.fields}
    return {name: np.frombuffer(values, dtype=fields[name].dtype, count=header.points,
                                offset=starts[name] * header.points) for name in names}


def cloud_or_lattice(header, points, normals, source, others=(), colors=None):
    """The Mesh of the points: an organised cloud (HEIGHT and WIDTH above 1) triangulated along
    its lattice (``lattice_triangles``, whose sight lines square and multiply the coordinates:
    they must be within mzc.limits'), any other a cloud; points with a NaN or infinite
    coordinate dropped either way. The ``others`` fields, and a lattice's normals (its triangles
    say which way it faces), are named in the Mesh's ``dropped``; ``colors`` (n, 3) are kept."""
    valid = np.isfinite(points).all(axis=1)
    new_index = np.cumsum(valid) - 1
    colors = None if colors is None else colors[valid]
    if header.height > 1 and header.width > 1:
        check_magnitude(points[valid], "coordinates", source=source)
        triangles = lattice_triangles(points.reshape(header.height, header.width, 3),
                                      valid.reshape(header.height, header.width), header.origin)
        if len(triangles):
            unused = [*(NORMALS if normals is not None else ()), *others]
            return Mesh(points[valid], new_index[triangles], dropped=fields_named(unused), colors=colors)
    if normals is not None:
        normals = np.where(np.isfinite(normals), normals, 0.0)[valid]
    return Mesh(points[valid], normals=normals, dropped=fields_named(others), colors=colors)


def fields_named(names):
    """``Mesh.dropped`` of the fields ``names``: one entry naming them, or none."""
    return (f"fields {' '.join(names)}",) if names else ()


def lattice_triangles(points, valid, origin):
    """Triangles (over the flat lattice indices) of an organised cloud's (rows, cols, 3)
    ``points``: a z-grid's two triangles a cell (``mzc.ops.triangulation.grid_triangles``)
    wherever their corners are ``valid``, none with an edge within JUMP_ANGLE of the line of
    sight from the sensor at ``origin``, each wound to face the sensor."""
    from mzc.ops.triangulation import grid_triangles, sight_jumps

    seen = points - origin   # lines of sight are the rays of a spherical grid about the sensor
    triangles = grid_triangles(valid, jumps=sight_jumps(seen))
    flat = seen.reshape(-1, 3)
    a, b, c = (flat[triangles[:, i]] for i in range(3))
    normal, centre = np.cross(b - a, c - a), a + b + c
    away = normal[:, 0] * centre[:, 0] + normal[:, 1] * centre[:, 1] + normal[:, 2] * centre[:, 2] > 0
    triangles[away] = triangles[away][:, ::-1]
    return triangles
