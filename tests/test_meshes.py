"""Reading and writing meshes and point clouds: the dialects real files come in, and bad input."""

import importlib.util
import struct

import hypothesis.extra.numpy as hnp
import hypothesis.strategies as st
import meshio
import numpy as np
import pytest
from hypothesis import given

from mzc.errors import MzcError
from mzc.meshes import Mesh, mesh_from_bytes, mesh_to_bytes, read_mesh, write_mesh

from conftest import REPO, face_path

# A unit square as two triangles, plus an off-square apex: 5 points, 4 triangles (a quad split
# and a fan of 2 more) - small enough to write by hand in every dialect.
POINTS = np.array([[0, 0, 0], [1, 0, 0.5], [1, 1, 1], [0, 1, 0.25], [2, 0.5, -1]], dtype=float)
TRIANGLES = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2]])


def write(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return path


def assert_same_mesh(mesh, points=POINTS, triangles=TRIANGLES):
    np.testing.assert_array_equal(mesh.points, points)
    np.testing.assert_array_equal(mesh.triangles, triangles)


PLAIN_OBJ = """v 0 0 0
v 1 0 0.5
v 1 1 1
v 0 1 0.25
v 2 0.5 -1
f 1 2 3
f 1 3 4
f 2 5 3
"""

OBJ_DIALECTS = {
    "plain": PLAIN_OBJ,
    "slashes and groups": """# exported
mtllib face.mtl
o face
v 0 0 0
v 1 0 0.5
v 1 1 1
v 0 1 0.25
v 2 0.5 -1 1.0
vt 0 0
vt 1 0
vt 1 1
vn 0 0 1
g front
usemtl skin
s 1
f 1/1/1 2/2/1 3/3/1
f 1//1 3//1 4//1
s off
f 2/2 5/1 3/3  # trailing comment
""",
    "quad and negative indices": """v 0 0 0
v 1 0 0.5
v 1 1 1
v 0 1 0.25
f -4 -3 -2 -1
v 2 0.5 -1
f -4 -1 -3
""",
    "crlf and tabs": PLAIN_OBJ.replace("\n", "\r\n").replace("v ", "v\t"),
    "vertex colours, indented lines": PLAIN_OBJ.replace("v 0 0 0", "  v 0 0 0 0.1 0.2 0.3"),
    "odd bytes in comments (ZBrush writes a NUL)": "# ZBrush OBJ\x00 export \xff\x01\n" + PLAIN_OBJ.replace(
        "f 1 2 3", "f 1 2 3 # \x00\x7f"),
}


@pytest.mark.parametrize("dialect", OBJ_DIALECTS)
def test_obj_dialects_read_the_same_mesh(tmp_path, dialect):
    mesh = read_mesh(write(tmp_path, "m.obj", OBJ_DIALECTS[dialect]))
    assert_same_mesh(mesh)


def test_obj_polygon_is_fan_triangulated(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n"
    mesh = read_mesh(write(tmp_path, "p.obj", text))
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])


def test_obj_without_faces_is_a_point_cloud(tmp_path):
    mesh = read_mesh(write(tmp_path, "cloud.obj", "v 1 2 3\nv 4 5 6\n"))
    assert mesh.is_point_cloud and mesh.points.shape == (2, 3)


def ply_header(fmt, vertex_properties, face_property="property list uchar int vertex_indices",
               faces=len(TRIANGLES)):  # noqa: B008 - a constant of this module
    lines = ["ply", f"format {fmt} 1.0", "comment test", f"element vertex {len(POINTS)}",
             *vertex_properties]
    if faces is not None:
        lines += [f"element face {faces}", face_property]
    return ("\n".join(lines) + "\nend_header\n").encode()


def ascii_ply(extra_columns=0, face_property="property list uchar int vertex_indices"):
    properties = ["property float x", "property float y", "property float z"]
    properties += [f"property uchar extra{i}" for i in range(extra_columns)]
    body = "".join(" ".join(f"{v:g}" for v in p) + " 7" * extra_columns + "\n" for p in POINTS)
    body += "".join("3 " + " ".join(map(str, t)) + "\n" for t in TRIANGLES)
    return ply_header("ascii", properties, face_property) + body.encode()


def binary_ply(order="<", with_faces=True):
    properties = ["property double x", "property double y", "property double z",
                  "property uchar red"]
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    header = ply_header(fmt, properties, "property list uchar uint vertex_index",
                        faces=len(TRIANGLES) if with_faces else None)
    body = b"".join(struct.pack(order + "dddB", *p, 200) for p in POINTS)
    if with_faces:
        body += b"".join(struct.pack(order + "BIII", 3, *t) for t in TRIANGLES)
    return header + body


@pytest.mark.parametrize("content", [ascii_ply(), ascii_ply(extra_columns=2),
                                     ascii_ply(face_property="property list uchar int vertex_index"),
                                     binary_ply("<"), binary_ply(">")],
                         ids=["ascii", "ascii extra columns", "ascii vertex_index",
                              "binary little", "binary big"])
def test_ply_dialects_read_the_same_mesh(tmp_path, content):
    assert_same_mesh(read_mesh(write(tmp_path, "m.ply", content)))


def test_vertex_only_ply_is_a_point_cloud(tmp_path):
    mesh = read_mesh(write(tmp_path, "cloud.ply", binary_ply(with_faces=False)))
    assert mesh.is_point_cloud
    np.testing.assert_array_equal(mesh.points, POINTS)


def test_binary_ply_with_mixed_polygons(tmp_path):
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 2\n"
              b"property list uchar int vertex_indices\nend_header\n")
    body = b"".join(struct.pack("<fff", *p) for p in POINTS)
    body += struct.pack("<B4i", 4, 0, 1, 2, 3) + struct.pack("<B3i", 3, 1, 4, 2)
    mesh = read_mesh(write(tmp_path, "mixed.ply", header + body))
    np.testing.assert_array_equal(mesh.triangles, TRIANGLES)


@pytest.mark.parametrize("extension", ["vtk", "stl", "off", "ply", "obj"])
def test_write_then_read_round_trips(tmp_path, extension):
    path = tmp_path / f"m.{extension}"
    write_mesh(path, Mesh(POINTS, TRIANGLES))
    mesh = read_mesh(path)
    if extension == "stl":  # STL stores every triangle's corners on its own, in float32
        np.testing.assert_allclose(mesh.points[mesh.triangles], POINTS[TRIANGLES], atol=1e-6)
    else:
        assert_same_mesh(mesh)


def test_meshio_reads_what_we_write(tmp_path):
    path = tmp_path / "m.ply"
    write_mesh(path, Mesh(POINTS, TRIANGLES))
    assert path.read_bytes().startswith(b"ply\nformat binary")
    result = meshio.read(path)
    np.testing.assert_array_equal(result.points, POINTS)
    np.testing.assert_array_equal(result.cells[0].data, TRIANGLES)


@given(points=hnp.arrays(np.float64, hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=30).map(
           lambda shape: (shape[0], 3)), elements=st.floats(allow_nan=False, allow_infinity=False)),
       faces=st.integers(0, 40), seed=st.integers(0, 2**32 - 1))
def test_ply_written_reads_back_exactly_and_the_same_mesh_gives_the_same_bytes(points, faces, seed):
    """Our PLY writer: every double and index comes back, a vertex-only PLY is a point cloud, and
    two writes of one mesh are identical bytes (no time stamp)."""
    triangles = np.random.default_rng(seed).integers(0, len(points), (faces, 3))
    data = mesh_to_bytes(Mesh(points, triangles), "ply")
    mesh = mesh_from_bytes(data, "m.ply")
    np.testing.assert_array_equal(mesh.points, points)
    np.testing.assert_array_equal(mesh.triangles, triangles.reshape(-1, 3))
    assert mesh.is_point_cloud == (faces == 0)
    assert mesh_to_bytes(Mesh(points, triangles), "ply") == data


def test_write_to_stdout_is_obj_text(capsysbinary):
    write_mesh("-", Mesh(POINTS, TRIANGLES))
    text = capsysbinary.readouterr().out.decode()
    assert text.splitlines()[0] == "v 0.0 0.0 0.0"
    assert text.splitlines()[-1] == "f 2 5 3"


def test_obj_writer_keeps_every_bit(tmp_path):
    points = np.random.default_rng(1).normal(size=(50, 3)) * 1e3
    path = tmp_path / "r.obj"
    write_mesh(path, Mesh(points, np.array([[0, 1, 2]])))
    np.testing.assert_array_equal(read_mesh(path).points, points)


def test_unknown_output_format_is_refused(tmp_path):
    with pytest.raises(MzcError, match="cannot write"):
        write_mesh(tmp_path / "m.xyz", Mesh(POINTS, TRIANGLES))
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("name,text", [
    ("cloud.xyz", "# scan\n0 0 0\n1 0 0.5 255 0 0\n\n1 1 1\n0 1 0.25\n2 0.5 -1\n"),
    ("cloud.txt", "0,0,0\n1,0,0.5\n1,1,1\n0,1,0.25\n2,0.5,-1\n"),
    ("cloud.dat", "0 0 0\r\n1 0 0.5\r\n1 1 1\r\n0 1 0.25\r\n2 0.5 -1\r\n"),
])
def test_xyz_text_point_clouds(tmp_path, name, text):
    mesh = read_mesh(write(tmp_path, name, text))
    assert mesh.is_point_cloud
    np.testing.assert_array_equal(mesh.points, POINTS)


@pytest.mark.parametrize("content", [PLAIN_OBJ.encode(), ascii_ply(), binary_ply(),
                                     b"0 0 0\n1 0 0.5\n1 1 1\n"], ids=["obj", "ply", "binary ply", "xyz"])
def test_stdin_is_recognised_by_its_bytes(monkeypatch, content):
    import io
    import sys

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(content)))
    mesh = read_mesh("-")
    assert len(mesh.points) in (3, len(POINTS))


@pytest.mark.parametrize("name,content,message,line", [
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "does not exist", 4),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n", "not a number", 3),
    ("bad.obj", "v 0 0 0\nv 1 0\nv 0 1 0\n", "needs x y z", 2),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3", 3),
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "does not exist", 4),
    ("bad.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN", None),
    ("bad.obj", "# nothing here\n", "no 'v' lines", None),
    ("bad.xyz", "0 0 0\n1 2\n", "at least 3 numbers", 2),
    ("bad.xyz", "0 0 0\n1 2 inf\n", "infinite", None),
    ("bad.xyz", "0 0 0\n1 2 three\n", "not a number", 2),
    ("bad.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n", "end_header", 1),
    ("bad.stl", b"\x00\x01garbage" * 10, "binary STL declares .* triangles but holds 6 bytes", None),
    ("bad.ply", ascii_ply().replace(b"3 1 4 2", b"3 1 9 2"), "only 5 vertices", None),
    ("empty.obj", "", "empty", None),
    ("noise.bin", b"\x00\xff" * 100, "unrecognised", None),
])
def test_bad_input_names_file_and_line(tmp_path, name, content, message, line):
    path = write(tmp_path, name, content)
    with pytest.raises(MzcError, match=message) as caught:
        read_mesh(path)
    assert caught.value.source == str(path)
    assert caught.value.line == line


def test_missing_file(tmp_path):
    with pytest.raises(MzcError, match="no such file"):
        read_mesh(tmp_path / "absent.obj")


def test_real_faces_read_like_meshio():
    for name in ("f18.ply", "example.obj"):
        path = face_path(name)
        mesh, reference = read_mesh(path), meshio.read(path)
        np.testing.assert_array_equal(mesh.points, reference.points)
        np.testing.assert_array_equal(mesh.triangles, reference.cells[0].data)
        assert mesh.points.shape == (30204, 3) and mesh.triangles.shape == (59697, 3)


def test_ascii_ply_declaring_no_vertices_is_a_clear_error(tmp_path):
    path = tmp_path / "empty.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                     b"property float z\nend_header\n")
    with pytest.raises(MzcError):
        read_mesh(str(path))


def test_a_surface_path_gives_an_mzc_file_as_the_mesh_of_its_grid(tmp_path):
    from mzc.api import as_mesh
    from mzc.formats import zgrid
    from mzc.grid import ZGrid

    path = write(tmp_path, "g.zg", zgrid.write(ZGrid(np.zeros((3, 4)), 1, 1)))
    surface = as_mesh(path)
    assert surface.grid is not None and surface.grid.shape == (3, 4)
    assert len(surface.triangles) == 2 * 2 * 3 and not surface.is_point_cloud
    assert as_mesh(write(tmp_path, "cloud.xyz", "0 0 0\n1 0 0\n")).is_point_cloud


def test_a_surface_on_stdin_is_read_as_a_file_is(monkeypatch):
    """One registry reads every file: a mesh on stdin is identified by its bytes, as 'mzc slice' always
    read it (the API refused it, where the command took it)."""
    import io
    import sys

    from mzc.api import as_mesh

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(PLAIN_OBJ.encode())))
    mesh, expected = as_mesh("-"), mesh_from_bytes(PLAIN_OBJ.encode(), "m.obj")
    np.testing.assert_array_equal(mesh.points, expected.points)
    np.testing.assert_array_equal(mesh.triangles, expected.triangles)


def test_what_a_file_holds_beside_its_shape_is_named_not_dropped_silently(tmp_path):
    """Texture coordinates without their image, a mesh's normals and other properties are read
    past, named in Mesh.dropped, and `mzc slice` says so in one warning; a cloud's normals and
    every vertex colour mzc reads (tests/test_colour.py) are kept, not named; the colours of an
    OBJ whose v lines do not all have them are named."""
    from conftest import run_mzc

    obj = (b"mtllib face.mtl\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
           b"vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n")
    assert mesh_from_bytes(obj, "a.obj").dropped == (
        "3 texture coordinates (vt)", "1 normals (vn; recomputed from the triangles)", "1 materials (mtllib)")
    ply = (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           b"property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n"
           b"property uchar blue\nelement face 1\nproperty list uchar int vertex_indices\n"
           b"property list uchar float texcoord\nend_header\n0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n"
           b"0 1 0 0 0 1 0 0 255\n3 0 1 2 6 0 0 1 0 0 1\n")
    assert mesh_from_bytes(ply, "a.ply").dropped == (
        "vertex normals nx ny nz (recomputed from the triangles)", "face properties texcoord")
    cloud = ply.replace(b"element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float "
                        b"texcoord\n", b"").replace(b"3 0 1 2 6 0 0 1 0 0 1\n", b"")
    assert mesh_from_bytes(cloud, "c.ply").dropped == ()   # normals and colours kept
    plain = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
    assert mesh_from_bytes(plain + b"end_header\n0 0 0\n", "p.ply").dropped == ()
    assert read_mesh(REPO / "tests" / "data" / "public" / "colored_cloud.pcd").dropped == ("fields curvature",)
    if importlib.util.find_spec("laspy"):
        assert read_mesh(REPO / "tests" / "data" / "public" / "simple.laz").dropped == ()   # format 3: RGB kept
        assert read_mesh(REPO / "tests" / "data" / "public" / "autzen_geo_proj.las").dropped == ()       # format 1
    (tmp_path / "a.obj").write_bytes(obj + b"v 1 1 0.2\nf 2 4 3\n")
    stderr = run_mzc("slice", tmp_path / "a.obj", "-o", tmp_path / "a.zg", check=True).stderr.decode()
    assert stderr.count("mzc: warning: not kept, mzc codes the shape and colour alone: 3 vertex colours; ") == 1
