"""Hostile mesh files: every reader either reads a file correctly or refuses it with one
MzcError line; none raises anything else, warns, hangs, allocates what the file does not
hold, or accepts a truncated file as complete. The tests build every file's bytes."""

import struct
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mzc.errors import MzcError
from mzc.meshes import mesh_from_bytes

from conftest import face_path
from test_cli import assert_one_line_error

# A unit square as two triangles: 4 points, 2 triangles, exact in float32.
POINTS = np.array([[0, 0, 0], [1, 0, 0.5], [1, 1, 1], [0, 1, 0.25]])
TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]])
FACE_LIST = "property list uchar int vertex_indices"


def obj(eol="\n"):
    lines = [f"v {x:g} {y:g} {z:g}" for x, y, z in POINTS] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in TRIANGLES]
    return (eol.join(lines) + eol).encode()


def ply_header(fmt="ascii", vertices=4, faces=2, face_property=FACE_LIST, eol="\n", extra=()):
    lines = ["ply", f"format {fmt} 1.0", *extra, f"element vertex {vertices}", "property float x",
             "property float y", "property float z", f"element face {faces}", face_property, "end_header"]
    return (eol.join(lines) + eol).encode()


def ascii_ply(eol="\n", rows=None, **header):
    rows = rows if rows is not None else ([" ".join(f"{v:g}" for v in p) for p in POINTS]
                                          + ["3 " + " ".join(map(str, t)) for t in TRIANGLES])
    return ply_header("ascii", eol=eol, **header) + (eol.join(rows) + eol).encode()


def exporter_ply():
    """A binary PLY as MeshLab-like exporters write it: vertex normals and RGBA colours, faces
    with texture coordinates and a colour, and an edge and a material element after them."""
    header = "\n".join([
        "ply", "format binary_little_endian 1.0", "comment exported", "element vertex 4",
        *[f"property float {name}" for name in ("x", "y", "z", "nx", "ny", "nz")],
        *[f"property uchar {name}" for name in ("red", "green", "blue", "alpha")],
        "element face 2", "property list uchar int vertex_indices", "property list uchar float texcoord",
        "property uchar red", "element edge 1", "property int vertex1", "property int vertex2",
        "element material 1", "property uchar ambient_red", "end_header", ""]).encode()
    vertices = b"".join(struct.pack("<6f4B", *p, 0, 0, 1, 200, 100, 50, 255) for p in POINTS)
    faces = b"".join(struct.pack("<B3iB6fB", 3, *t, 6, *[0.5] * 6, 7) for t in TRIANGLES)
    return header + vertices + faces + struct.pack("<2iB", 0, 1, 9)


def binary_ply(order="<", faces_body=None, **header):
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    if faces_body is None:
        faces_body = b"".join(struct.pack(order + "B3i", 3, *t) for t in TRIANGLES)
    return ply_header(fmt, **header) + POINTS.astype(order + "f4").tobytes() + faces_body


def binary_stl(declared=None, triangles=2, header=b"binary"):
    records = np.zeros(triangles, dtype=[("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    records["corners"] = POINTS[np.resize(TRIANGLES, (triangles, 3))]
    count = triangles if declared is None else declared
    return header.ljust(80, b" ") + struct.pack("<I", count) + records.tobytes()


def ascii_stl(eol="\n"):
    lines = ["solid square"]
    for triangle in TRIANGLES:
        lines += ["facet normal 0 0 1", "outer loop", *(f"vertex {x:g} {y:g} {z:g}" for x, y, z in POINTS[triangle]),
                  "endloop", "endfacet"]
    return (eol.join([*lines, "endsolid square"]) + eol).encode()


def xyz(eol="\n"):
    return (eol.join(f"{x:g} {y:g} {z:g}" for x, y, z in POINTS) + eol).encode()


VALID = {"m.obj": obj(), "m.ply": ascii_ply(), "binary.ply": binary_ply("<"), "big.ply": binary_ply(">"),
         "m.stl": binary_stl(), "text.stl": ascii_stl(), "m.xyz": xyz()}
DECLARES_ITS_COUNTS = ("m.ply", "binary.ply", "big.ply", "m.stl", "text.stl")


def read(data, name):
    """mesh_from_bytes with every warning an error: none may reach stderr."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return mesh_from_bytes(data, name)


def assert_sane(mesh):
    assert mesh.points.ndim == 2 and mesh.points.shape[1] == 3 and np.isfinite(mesh.points).all()
    assert mesh.triangles.ndim == 2 and mesh.triangles.shape[1] == 3
    assert ((mesh.triangles >= 0) & (mesh.triangles < len(mesh.points))).all()


def assert_refused(data, name, fragment=None):
    """The error is an MzcError of one line naming the source, containing ``fragment``."""
    with pytest.raises(MzcError) as caught:
        read(data, name)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(name), message
    if fragment is not None:
        assert fragment in message, message
    return caught.value


# --- every valid file, in every line end, reads the same mesh ----------------------------

SAME_IN_EVERY_LINE_END = {"m.obj": obj, "m.ply": ascii_ply, "text.stl": ascii_stl, "m.xyz": xyz}


@pytest.mark.parametrize("eol", ["\n", "\r\n", "\r"], ids=["LF", "CRLF", "CR"])
@pytest.mark.parametrize("name", SAME_IN_EVERY_LINE_END)
@pytest.mark.parametrize("sniffed", [False, True], ids=["by extension", "by content"])
def test_text_formats_read_the_same_mesh_with_any_line_end(name, eol, sniffed):
    """\\n, \\r\\n and a lone \\r end lines alike in OBJ, ascii PLY, ascii STL and xyz text."""
    mesh = read(SAME_IN_EVERY_LINE_END[name](eol), "<stdin>" if sniffed else name)
    np.testing.assert_array_equal(mesh.points, POINTS)
    np.testing.assert_array_equal(mesh.triangles, np.empty((0, 3)) if name == "m.xyz" else TRIANGLES)


@pytest.mark.parametrize("name", VALID)
def test_the_valid_files_read(name):
    """The corpus starts from files that read as the square."""
    mesh = read(VALID[name], name)
    np.testing.assert_array_equal(mesh.points, POINTS)
    assert len(mesh.triangles) == (0 if name == "m.xyz" else len(TRIANGLES))


# --- truncation and extra data ------------------------------------------------------------

@pytest.mark.parametrize("name", ["binary.ply", "big.ply", "m.stl"])
@pytest.mark.parametrize("cut", range(1, 120, 3))
def test_a_binary_file_cut_short_is_refused(name, cut):
    """A binary PLY or STL missing any of its last bytes is never read as complete."""
    data = VALID[name]
    assert_refused(data[:len(data) - cut], name)


@pytest.mark.parametrize("cut", range(1, 27))
def test_a_binary_ply_cut_in_its_faces_names_the_element_and_the_counts(cut):
    """Cut inside the faces: 'truncated: element face declares 2 faces, the file holds K'."""
    held = 1 if cut <= 13 else 0
    assert_refused(binary_ply()[:-cut], "m.ply", f"truncated: element face declares 2 faces, the file holds {held}")


@pytest.mark.parametrize("declared,held,element", [(5, 3, "vertex"), (4, 3, "vertex"), (9, 2, "face")])
def test_an_ascii_ply_holding_fewer_records_than_declared_is_truncated(declared, held, element):
    """An ascii PLY declaring 5 vertices and holding 3 says so, with the line where it ends."""
    rows = [" ".join(f"{v:g}" for v in p) for p in POINTS[:held]] if element == "vertex" else None
    header = {"vertices": declared, "faces": 0} if element == "vertex" else {"faces": declared}
    plural = "vertices" if element == "vertex" else "faces"
    error = assert_refused(ascii_ply(rows=rows, **header), "m.ply",
                           f"truncated: element {element} declares {declared} {plural}, the file holds {held}")
    assert error.line is not None


@pytest.mark.parametrize("name,extra,fragment", [
    ("binary.ply", b"\0", "1 bytes after the last element"),
    ("binary.ply", b"\n\n", "2 bytes after the last element"),
    ("big.ply", bytes(13), "13 bytes after the last element"),
    ("m.ply", b"3 0 1 2\n", "1 lines after the last element"),
    ("m.ply", b"0 0 0\n1 1 1\n", "2 lines after the last element"),
    ("m.stl", bytes(50), "binary STL declares 2 triangles but holds 150 bytes for 3"),
    ("m.stl", bytes(7), "holds 107 bytes"),
])
def test_data_after_the_last_element_is_refused(name, extra, fragment):
    """Bytes or lines the header does not account for are an error, not ignored."""
    assert_refused(VALID[name] + extra, name, fragment)


def test_trailing_blank_lines_of_an_ascii_ply_are_no_data():
    """Blank lines carry no record: an ascii PLY may end with some."""
    assert len(read(ascii_ply() + b"\n \n\r\n", "m.ply").triangles) == 2


@pytest.mark.parametrize("declared,triangles", [(1000, 10), (10, 1000), (0, 3), (3, 0), (2**32 - 1, 1)])
def test_a_binary_stl_with_a_lying_triangle_count_is_refused(declared, triangles):
    """'binary STL declares N triangles but holds K bytes for M', also behind a 'solid' header."""
    for header in (b"binary", b"solid but binary\0"):
        assert_refused(binary_stl(declared, triangles, header), "m.stl",
                       f"binary STL declares {declared} triangles but holds {50 * triangles} bytes for {triangles}")


@pytest.mark.parametrize("cut,declared", [(0.1, "vertex declares 30204 vertices"),
                                         (0.5, "face declares 59697 faces"), (0.9, "face declares 59697 faces")])
def test_a_shared_face_cut_short_is_truncated(cut, declared):
    """f18.ply cut at 10 % (in its vertices), 50 and 90 % (in its faces) names the element and its count."""
    data = face_path("f18.ply").read_bytes()
    assert_refused(data[:int(len(data) * cut)], "f18.ply", f"truncated: element {declared}, the file holds ")


# --- counts and numbers -------------------------------------------------------------------

@pytest.mark.parametrize("count", ["3.5", "nan", "-1", "inf", "-inf", "1e0", "+3", "²", "³", "٣", "３", "0x3", ""])
def test_an_ascii_list_count_that_is_not_a_whole_number_is_named(count):
    """A list count must be ASCII digits: the error names the element and the line."""
    rows = [" ".join(f"{v:g}" for v in p) for p in POINTS] + [f"{count} 0 1 2", "3 0 2 3"]
    error = assert_refused(ascii_ply(rows=rows), "m.ply", "element face")
    assert error.line == 14


@pytest.mark.parametrize("count_type", ["float", "double", "float32", "float64"])
def test_a_float_list_count_type_is_refused(count_type):
    """A binary list whose count is a float type is refused at its header line."""
    data = binary_ply(face_property=f"property list {count_type} int vertex_indices")
    assert assert_refused(data, "m.ply", "counts are integers").line == 8


@pytest.mark.parametrize("count_type,count,fragment", [
    ("char", -1, "has count -1"), ("char", -128, "has count -128"), ("int", -(2**31), "has count"),
    ("uint", 2**32 - 1, "truncated: element face"), ("uint64", 2**64 - 1, "truncated: element face"),
    ("uchar", 255, "truncated: element face"), ("uchar", 2, "8 bytes after the last element"),
    ("uchar", 0, "24 bytes after"),
])
def test_a_binary_list_count_that_lies_is_refused(count_type, count, fragment):
    """Negative, huge or wrong binary list counts are errors, read no further than the body."""
    code = {"char": "b", "int": "i", "uint": "I", "uint64": "Q", "uchar": "B"}[count_type]
    faces_body = struct.pack(f"<{code}3i", count, 0, 1, 2) * 2
    data = binary_ply(faces_body=faces_body, face_property=f"property list {count_type} int vertex_indices")
    assert_refused(data, "m.ply", fragment)


BAD_DIGITS = ["²", "³", "٣", "１", "1_0", "0x1", "--1", "1e", "½", "1.2.3"]


@pytest.mark.parametrize("digit", BAD_DIGITS)
@pytest.mark.parametrize("fmt,line", [("m.obj", 2), ("m.ply", 11), ("m.xyz", 2), ("text.stl", 4)])
def test_a_number_that_is_not_ascii_is_refused_with_its_line(fmt, line, digit):
    """Superscripts, other scripts' digits, '_' and friends are not numbers anywhere."""
    data = VALID[fmt].decode()
    target = {"m.obj": "v 1 0 0.5", "m.ply": "1 0 0.5", "m.xyz": "1 0 0.5", "text.stl": "vertex 0 0 0"}[fmt]
    data = data.replace(target, target[:-1] + digit if fmt != "text.stl" else "vertex 0 0 " + digit, 1)
    assert assert_refused(data.encode(), fmt).line == line


@pytest.mark.parametrize("digit", ["²", "٣", "+-1", "1.5", "nan", "99999999999999999999"])
def test_an_obj_face_index_that_is_not_an_ascii_integer_is_refused(digit):
    """OBJ face corners take ASCII integers only, named with their line."""
    assert assert_refused(obj().replace(b"f 1 3 4", f"f 1 3 {digit}".encode()), "m.obj").line == 6


@pytest.mark.parametrize("index", ["4", "-1", "nan", "inf", "2.5", "1e30", "-1e30", "²"])
def test_an_ascii_ply_face_index_out_of_range_or_not_whole_is_refused(index):
    """A face index must be a whole number naming an existing vertex."""
    rows = [" ".join(f"{v:g}" for v in p) for p in POINTS] + [f"3 0 1 {index}", "3 0 2 3"]
    assert_refused(ascii_ply(rows=rows), "m.ply")


@pytest.mark.parametrize("index", [np.nan, np.inf, 2.5, 1e30, -1.0, 4.0])
def test_a_binary_ply_float_face_index_that_is_no_vertex_is_refused(index):
    """Float item types are read, but an index that is not a whole vertex number is an error."""
    faces = struct.pack("<B3f", 3, 0, 1, index) + struct.pack("<B3f", 3, 0, 2, 3)
    assert_refused(binary_ply(faces_body=faces, face_property="property list uchar float vertex_indices"), "m.ply")


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "NaN", "1e999"])
@pytest.mark.parametrize("fmt", ["m.obj", "m.ply", "m.xyz", "text.stl"])
def test_a_vertex_coordinate_that_is_not_finite_is_refused(fmt, value):
    """Every reader refuses NaN and infinite coordinates the same way, naming the vertex."""
    target = "vertex 1 0 0.5" if fmt == "text.stl" else "1 0 0.5"
    data = VALID[fmt].replace(target.encode(), target.replace("0.5", value).encode(), 1)
    assert_refused(data, fmt, "vertex 2 has a NaN or infinite coordinate")


# --- headers and odd files ----------------------------------------------------------------

HOSTILE = {
    "empty": ("m.ply", b"", "empty"),
    "spaces only": ("m.obj", b" \n\r\n\t", "empty"),
    "only a header": ("m.ply", ply_header(), "truncated: element vertex declares 4 vertices, the file holds 0"),
    "only a binary header": ("m.ply", ply_header("binary_little_endian"), "truncated: element vertex"),
    "no end_header": ("m.ply", ply_header().replace(b"end_header", b"end"), "end_header"),
    "vertex 10^12": ("m.ply", ascii_ply(vertices="10^12"), "bad PLY header line"),
    "vertex 10**12 binary": ("m.ply", binary_ply(vertices=10**12), "declares 1000000000000 vertices, the file holds"),
    "vertex 10**12 ascii": ("m.ply", ascii_ply(vertices=10**12), "declares 1000000000000 vertices"),
    "face 10**12 binary": ("m.ply", binary_ply(faces=10**12), "declares 1000000000000 faces, the file holds 2"),
    "vertex count ²": ("m.ply", ascii_ply(vertices="²"), "bad PLY header line 'element vertex ²'"),
    "vertex count ٤": ("m.ply", ascii_ply(vertices="٤"), "bad PLY header line 'element vertex ٤'"),
    "vertex count -4": ("m.ply", ascii_ply(vertices=-4), "bad PLY header line"),
    "duplicate element": ("m.ply", ascii_ply(extra=("element vertex 4",)), "bad PLY header line"),
    "duplicate format": ("m.ply", ascii_ply(extra=("format ascii 1.0",)), "bad PLY header line"),
    "duplicate property": ("m.ply", ply_header(face_property=FACE_LIST + "\nproperty int vertex_indices"),
                           "second property"),
    "second ply line": ("m.ply", ascii_ply(extra=("ply",)), "bad PLY header line"),
    "no format": ("m.ply", ascii_ply().replace(b"format ascii 1.0\n", b""), "unknown PLY format None"),
    "format binary": ("m.ply", ascii_ply().replace(b"format ascii", b"format binary"), "unknown PLY format"),
    "property type int128": ("m.ply", ascii_ply().replace(b"float x", b"int128 x"), "bad PLY property"),
    "property type Float": ("m.ply", ascii_ply().replace(b"float x", b"Float x"), "bad PLY property"),
    "list type string": ("m.ply", ascii_ply(face_property="property list uchar string vertex_indices"),
                         "bad PLY property"),
    "property before element": ("m.ply", ascii_ply(extra=("property float w",)), "bad PLY header line"),
    "element without properties": ("m.ply", ascii_ply(extra=("element ghost 10",)), "no properties"),
    "unknown element and no faces": ("m.ply", ascii_ply(faces=0, rows=[" ".join(f"{v:g}" for v in p) for p in POINTS])
                                     .replace(b"end_header", b"element cube 1\nproperty float side\nend_header")
                                     + b"1\n", "element 'cube'"),
    "x as a list": ("m.ply", ascii_ply().replace(b"property float x", b"property list uchar float x"),
                    "element vertex"),
    "scalar face indices": ("m.ply", ascii_ply(face_property="property int vertex_indices",
                                               rows=["0 0 0", "1 0 0", "0 1 0", "1 1 0", "0", "1"]), "must be a list"),
    "no vertex element": ("m.ply", b"ply\nformat ascii 1.0\nelement face 0\n" + FACE_LIST.encode()
                          + b"\nend_header\n", "no 'vertex' element"),
    "no z": ("m.ply", ascii_ply(rows=["0 0", "1 0", "1 1", "0 1", "3 0 1 2", "3 0 2 3"]).replace(
        b"property float z\n", b""), "with x, y, z"),
    "CR header, LF end": ("m.ply", ply_header(eol="\r").replace(b"end_header\r", b"end_header\n"), "end_header"),
    "NUL in the ascii body": ("m.ply", ascii_ply().replace(b"0 1 0.25", b"0 1 0\x0025"), "binary data"),
    "too many values": ("m.ply", ascii_ply().replace(b"0 1 0.25", b"0 1 0.25 7"), "expected 3 values"),
    "too few values": ("m.ply", ascii_ply().replace(b"0 1 0.25", b"0 1"), "expected 3 values"),
    "list longer than declared": ("m.ply", ascii_ply().replace(b"3 0 1 2", b"3 0 1 2 3"), "values after"),
    "list shorter than declared": ("m.ply", ascii_ply().replace(b"3 0 1 2", b"4 0 1 2"), "ends inside property"),
    "index past the vertices": ("m.ply", ascii_ply().replace(b"3 0 1 2", b"3 0 1 4"), "only 4 vertices"),
    "negative index": ("m.ply", ascii_ply().replace(b"3 0 1 2", b"3 0 1 -5"), "negative vertex index (-5)"),
    "OBJ index past the vertices": ("m.obj", obj().replace(b"f 1 3 4", b"f 1 3 5"), "does not exist"),
    "OBJ negative index before the first": ("m.obj", obj().replace(b"f 1 3 4", b"f 1 3 -5"), "does not exist"),
    "OBJ index 0": ("m.obj", obj().replace(b"f 1 3 4", b"f 1 3 0"), "does not exist"),
    "OBJ binary": ("m.obj", obj() + b"\0\x01\x02\n", "binary data"),   # NUL padding at the end is read past
    "OBJ NUL in a vertex": ("m.obj", obj().replace(b"v 1 0 0", b"v 1 0\x00 0"), "2: binary data (a NUL byte)"),
    "OBJ without v": ("m.obj", b"f 1 2 3\n", "no 'v' lines"),
    "xyz two columns": ("m.xyz", b"1 2\n", "at least 3 numbers"),
    "ascii STL without endsolid": ("text.stl", ascii_stl().replace(b"endsolid square", b""), "endsolid"),
    "ascii STL cut in a facet": ("text.stl", ascii_stl()[:120], "endsolid"),
    "ascii STL facet of 2 vertices": ("text.stl", ascii_stl().replace(b"vertex 0 0 0\n", b"", 1), "3 vertices"),
    "ascii STL facet of 4 vertices": ("text.stl", ascii_stl().replace(b"vertex 0 0 0\n", b"vertex 0 0 0\n" * 2, 1),
                                      "3 vertices"),
    "ascii STL vertex at the end": ("text.stl", b"solid\nendsolid\nvertex 1 2", "endsolid"),
    "ascii STL with NUL": ("text.stl", ascii_stl().replace(b"square", b"sq\0are"), "binary STL declares"),
    "STL too short": ("m.stl", b"\0" * 83, "not an STL file: 83 bytes"),
    "STL with no triangles": ("m.stl", binary_stl(0, 0), "no points"),
    "solid alone": ("m.stl", b"solid", "endsolid"),
    "solid endsolid": ("m.stl", b"solid x\nendsolid x\n", "no points"),
}
for size in (1, 3, 84, 134, 1000):
    for extension in ("ply", "obj", "stl", "xyz", "bin"):
        HOSTILE[f"{size} zero bytes .{extension}"] = (f"zeros.{extension}", bytes(size), None)
RANDOM = np.random.default_rng(13)
for number in range(20):
    for extension in ("ply", "obj", "stl", "xyz", "bin"):
        noise = RANDOM.integers(0, 256, 10 + 37 * number, dtype=np.uint8).tobytes()
        HOSTILE[f"random {number} .{extension}"] = (f"noise.{extension}", noise, None)


@pytest.mark.parametrize("case", HOSTILE)
def test_a_hostile_file_is_refused_in_one_line(case):
    """Each hostile file is refused by an MzcError of one line saying what is wrong."""
    name, data, fragment = HOSTILE[case]
    assert_refused(data, name, fragment)


READ_CORRECTLY = {
    "big-endian PLY": ("m.ply", binary_ply(">"), 2),
    "element face 0": ("m.ply", ascii_ply(faces=0, rows=[" ".join(f"{v:g}" for v in p) for p in POINTS]), 0),
    "binary element face 0": ("m.ply", binary_ply(faces=0, faces_body=b""), 0),
    "NUL in a comment": ("m.ply", binary_ply(extra=("comment made by\0someone",)), 2),
    "CR-only binary header": ("m.ply", binary_ply(eol="\r"), 2),
    "CRLF binary header": ("m.ply", binary_ply(eol="\r\n"), 2),
    "int64 indices": ("m.ply", binary_ply(face_property="property list uchar int64 vertex_indices",
                                          faces_body=b"".join(struct.pack("<B3q", 3, *t) for t in TRIANGLES)), 2),
    "float indices": ("m.ply", binary_ply(face_property="property list uchar float vertex_indices",
                                          faces_body=b"".join(struct.pack("<B3f", 3, *t) for t in TRIANGLES)), 2),
    "a quad and a triangle": ("m.ply", binary_ply(faces=2, faces_body=struct.pack("<B4i", 4, 0, 1, 2, 3)
                                                  + struct.pack("<B3i", 3, 0, 1, 2)), 3),
    "edges and a material beside the faces, colours, normals, texcoords": ("m.ply", exporter_ply(), 2),
    "OBJ forward reference": ("m.obj", b"f 1 2 3\nv 0 0 0\nv 1 0 0.5\nv 1 1 1\nv 0 1 0.25\nf 1 3 4\n", 2),
    "OBJ # at the end": ("m.obj", obj() + b"# end", 2),
    "STL with a solid header": ("m.stl", binary_stl(header=b"solid square"), 2),
}


@pytest.mark.parametrize("case", READ_CORRECTLY)
def test_an_odd_but_valid_file_is_read_correctly(case):
    """Files that look hostile but are valid read with all their triangles."""
    name, data, triangles = READ_CORRECTLY[case]
    mesh = read(data, name)
    assert_sane(mesh)
    assert len(mesh.triangles) == triangles and len(mesh.points) == len(POINTS)
    np.testing.assert_array_equal(mesh.points, POINTS)


# --- mutations ----------------------------------------------------------------------------

@st.composite
def mutated(draw):
    """A valid file with one mutation: cut at a byte, a byte replaced, or bytes inserted."""
    name = draw(st.sampled_from(sorted(VALID)))
    data = VALID[name]
    at = draw(st.integers(0, len(data)))
    kind = draw(st.sampled_from(["cut", "flip", "insert"]))
    if kind == "cut":
        data = data[:at]
    elif kind == "flip" and at < len(data):
        data = data[:at] + bytes([draw(st.integers(0, 255))]) + data[at + 1:]
    else:
        data = data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    return draw(st.sampled_from([name, "<stdin>"])), data


@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_a_mutated_file_is_read_sanely_or_refused(case):
    """Any mutation of a valid OBJ/PLY/STL/xyz file gives a sane mesh or an MzcError, nothing else."""
    name, data = case
    try:
        mesh = read(data, name)
    except MzcError as error:
        assert "\n" not in str(error)
        return
    assert_sane(mesh)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(DECLARES_ITS_COUNTS), st.data())
def test_a_truncated_file_is_never_read_as_complete(name, data):
    """A PLY or STL cut anywhere is refused, or (cut in its last line end or solid name) read with every face."""
    whole = VALID[name]
    cut = whole[:data.draw(st.integers(0, len(whole) - 1))]
    try:
        mesh = read(cut, name)
    except MzcError:
        return
    assert len(mesh.triangles) == len(TRIANGLES)


# --- the command line ---------------------------------------------------------------------

@pytest.mark.parametrize("name,data,fragment", [
    ("bad.ply", binary_ply()[:-5], "truncated: element face declares 2 faces, the file holds 1"),
    ("bad.ply", ascii_ply().replace(b"3 0 1 2", b"3.5 0 1 2"), "bad.ply:14: element face"),
    ("bad.stl", binary_stl(1000, 10), "binary STL declares 1000 triangles but holds 500 bytes for 10"),
    ("bad.obj", obj().replace(b"v 1 0 0.5", "v 1 0 ²".encode()), "bad.obj:2: not a number"),
])
def test_the_command_line_refuses_a_hostile_file_in_one_line(mzc, tmp_path, name, data, fragment):
    """mzc slice on a hostile file exits 1 with one stderr line: no traceback, no internal error."""
    path = tmp_path / name
    path.write_bytes(data)
    result = mzc("slice", path)
    assert_one_line_error(result, fragment)
    assert b"internal error" not in result.stderr


def test_meshio_prints_nothing_on_stderr(capfd):
    """A VTK file whose cells meshio does not know makes meshio print 'Warning: ...' on its
    rich console; mzc keeps stderr for its own one-line messages."""
    from mzc.meshes import Mesh, mesh_to_bytes

    data = mesh_to_bytes(Mesh(POINTS, TRIANGLES), "vtk")
    data = data.replace(b"CELL_TYPES 2\n\0\0\0\x05", b"CELL_TYPES 2\n\0\0\0\x04")
    try:
        read(data, "odd.vtk")
    except MzcError:
        pass
    assert capfd.readouterr().err == ""
