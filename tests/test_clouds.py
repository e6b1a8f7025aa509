"""Point clouds as users have them: PCD (ascii, binary, binary_compressed, organised), LAS/LAZ
(scale, offset, classes, CRS), dense clouds sliced by binning, and the exporters' OBJ and PLY."""

import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.api import read as mzc_read
from mzc.errors import MzcError, MzcWarning
from mzc.meshes import Mesh, mesh_from_bytes, read_mesh
from mzc.meshes.pcd import LZF_MAX_EXPANSION
from mzc.ops import binning
from mzc.ops.slicing import BIN_POINTS, lattice_steps, slice_surface

from test_cli import assert_one_line_error

PUBLIC = Path(__file__).parent / "data" / "public"


# --------------------------------------------------------------------------- a PCD writer for the tests


def lzf(data):
    """LZF of ``data`` by a greedy matcher (longest match among earlier positions of the same
    3 bytes, up to 264 bytes and 8192 back): the back-references PCL's coder writes."""
    out, literal, last, i = bytearray(), bytearray(), {}, 0

    def flush():
        for start in range(0, len(literal), 32):
            piece = literal[start:start + 32]
            out.append(len(piece) - 1)
            out.extend(piece)
        literal.clear()

    while i < len(data):
        key, length = data[i:i + 3], 0
        j = last.get(key)
        if j is not None and i - j <= 8192 and len(key) == 3:
            while length < 264 and i + length < len(data) and data[j + length] == data[i + length]:
                length += 1
        last[key] = i
        if length >= 3:
            flush()
            distance, code = i - j - 1, length - 2
            if code < 7:
                out.extend([(code << 5) | (distance >> 8), distance & 255])
            else:
                out.extend([(7 << 5) | (distance >> 8), code - 7, distance & 255])
            i += length
        else:
            literal.append(data[i])
            i += 1
    flush()
    return bytes(out)


def pcd(columns, body="ascii", width=None, height=1, viewpoint="0 0 0 1 0 0 0", padding=0):
    """PCD bytes of ``columns``: (name, numpy dtype, (points, count) values) in field order."""
    points = len(columns[0][2])
    width = points // height if width is None else width
    kinds = [(np.dtype(dtype).kind.upper().replace("I", "I").replace("U", "U"), np.dtype(dtype).itemsize)
             for _, dtype, _ in columns]
    counts = [np.asarray(values).reshape(points, -1).shape[1] for _, _, values in columns]
    header = ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
              f"FIELDS {' '.join(name for name, _, _ in columns)}\n"
              f"SIZE {' '.join(str(size) for _, size in kinds)}\nTYPE {' '.join(kind for kind, _ in kinds)}\n"
              f"COUNT {' '.join(map(str, counts))}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT {viewpoint}\n"
              f"POINTS {points}\nDATA {body}\n").encode()
    arrays = [np.asarray(values, dtype=dtype).reshape(points, -1) for _, dtype, values in columns]
    if body == "ascii":
        rows = np.hstack([a.astype(np.float64) for a in arrays])
        return header + "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows).encode()
    if body == "binary":
        record = np.dtype([(f"f{i}", "<" + a.dtype.str[1:], (a.shape[1],)) for i, a in enumerate(arrays)])
        table = np.zeros(points, dtype=record)
        for i, a in enumerate(arrays):
            table[f"f{i}"] = a
        return header + table.tobytes() + bytes(padding)
    plain = b"".join(a.astype("<" + a.dtype.str[1:]).tobytes() for (name, _, _), a in zip(columns, arrays)
                     if name != "_")
    packed = lzf(plain)
    return header + struct.pack("<II", len(packed), len(plain)) + packed + bytes(padding)


def xyz_columns(points, dtype="f4"):
    return [("x", dtype, points[:, 0]), ("y", dtype, points[:, 1]), ("z", dtype, points[:, 2])]


# --------------------------------------------------------------------------- PCD


def test_lzf_of_the_test_writer_round_trips_through_the_decoder():
    from mzc.meshes import _lzf

    data = bytes(np.random.default_rng(1).integers(0, 4, 5000, dtype=np.uint8)) + b"abc" * 300 + bytes(700)
    out = bytearray(len(data))
    assert _lzf.decompress(lzf(data), out) == len(data) and bytes(out) == data


@pytest.mark.parametrize("body", ["ascii", "binary", "binary_compressed"])
def test_pcd_bodies_read_the_same_cloud(body):
    points = np.random.default_rng(2).normal(size=(500, 3)).astype(np.float32)
    columns = xyz_columns(points) + [("rgb", "f4", np.full(500, 4.2108e+06)), ("intensity", "u2", np.arange(500))]
    mesh = mesh_from_bytes(pcd(columns, body, padding=4096 - 1), "c.pcd")
    assert mesh.is_point_cloud and np.array_equal(mesh.points, points.astype(np.float64))


@settings(max_examples=60, deadline=None)
@given(count=st.integers(1, 300), body=st.sampled_from(["ascii", "binary", "binary_compressed"]),
       coordinate=st.sampled_from(["f4", "f8"]), extra=st.sampled_from(["u1", "i2", "u4", "i8", "f8"]),
       extra_count=st.integers(1, 3), holes=st.floats(0, 0.5), normals=st.booleans(), seed=st.integers(0, 2**16))
def test_pcd_round_trips_through_a_writer(count, body, coordinate, extra, extra_count, holes, normals, seed):
    """Any PCD of x y z among other fields (any type and count, padding, normals) reads back the
    points the writer wrote, NaN points dropped and the normals of those left."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1e3, 1e3, (count, 3)).astype(coordinate)
    points[rng.random(count) < holes] = np.nan
    columns = [("_", extra, rng.integers(0, 100, (count, extra_count)))] + xyz_columns(points, coordinate)
    direction = rng.normal(size=(count, 3)).astype("f4")
    if normals:
        columns += [(name, "f4", direction[:, i]) for i, name in enumerate(("normal_x", "normal_y", "normal_z"))]
    kept = np.isfinite(points).all(axis=1)
    if not kept.any():
        with pytest.raises(MzcError, match="no points"):
            mesh_from_bytes(pcd(columns, body), "c.pcd")
        return
    mesh = mesh_from_bytes(pcd(columns, body), "c.pcd")
    assert np.array_equal(mesh.points, points[kept].astype(np.float64))
    assert (mesh.normals is not None) == normals
    if normals:
        assert np.array_equal(mesh.normals, direction[kept].astype(np.float64))


@pytest.mark.parametrize("name, points, normals", [
    ("bun0.pcd", 397, True),               # PCL: ascii, normals and curvature
    ("milk.pcd", 13704, False),            # PCL: binary_compressed
    ("colored_cloud.pcd", 1000, True),     # PCL: binary, rgb, normals; WIDTH 1 x HEIGHT 1000, a column
    ("ascii_with_underscore.pcd", 213, False),   # pypcd4: a '_' padding field
])
def test_public_pcd_files_read_and_slice(name, points, normals):
    mesh = read_mesh(PUBLIC / name)
    assert len(mesh.points) == points and mesh.is_point_cloud and (mesh.normals is not None) == normals
    if np.ptp(mesh.points[:, 2]) > 0:
        grid = slice_surface(mesh)
        assert grid.valid.sum() > 50


def test_public_pcd_binary_compressed_lzf_matches_pcls_ascii_of_the_same_values():
    """milk.pcd's body (LZF with back-references, padded to a page) decodes to finite points in
    the box PCL's test of it states (a milk carton about 0.15 x 0.25 x 0.18 m)."""
    mesh = read_mesh(PUBLIC / "milk.pcd")
    assert np.isfinite(mesh.points).all()
    assert np.allclose(np.ptp(mesh.points, axis=0), [0.154, 0.252, 0.177], atol=0.005)


def test_public_organised_pcd_is_triangulated_along_its_lattice():
    """pypcd4's 4 x 2 organised binary_compressed cloud: its cells become triangles, none across
    its depth jumps, each facing the sensor at the origin."""
    mesh = read_mesh(PUBLIC / "binary_compressed_organized.pcd")
    assert len(mesh.points) == 8 and len(mesh.triangles) > 0


def depth_camera(rows=60, cols=80, holes=True):
    """An organised cloud as a depth camera sees it: pinhole rays from the origin (z forward)
    onto a ball 1 m away in front of a wall at 2 m, NaN where a ray meets neither."""
    v, u = np.mgrid[0:rows, 0:cols]
    rays = np.stack([(u - cols / 2) / cols, (v - rows / 2) / cols, np.ones((rows, cols))], axis=-1)
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    centre, radius = np.array([0.0, 0.0, 1.0]), 0.25
    b = rays @ centre
    disc = b * b - (centre @ centre - radius * radius)
    ball = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0)), np.inf)
    wall = 2.0 / rays[..., 2]
    distance = np.minimum(ball, wall)
    if holes:
        distance[:5, :5] = np.nan
    return (rays * distance[..., None]).astype(np.float32), disc >= 0


@pytest.mark.parametrize("body", ["ascii", "binary", "binary_compressed"])
def test_organised_depth_camera_cloud_meshes_by_its_lattice_without_bridging_jumps(body):
    points, on_ball = depth_camera()
    data = pcd(xyz_columns(points.reshape(-1, 3)), body, width=80, height=60)
    mesh = mesh_from_bytes(data, "kinect.pcd")
    assert len(mesh.points) == 60 * 80 - 25
    corners = mesh.points[mesh.triangles]
    # no triangle joins the ball (z < 1.5) to the wall (z = 2): the jump edges are dropped
    depth = corners[:, :, 2]
    assert not ((depth.min(axis=1) < 1.5) & (depth.max(axis=1) > 1.9)).any()
    # every triangle faces the sensor at the origin
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert (np.einsum("ij,ij->i", normal, corners.mean(axis=1)) < 0).all()
    # two triangles a cell wherever the lattice has no hole and no jump: most of them
    assert len(mesh.triangles) > 0.9 * 2 * 59 * 79
    grid = slice_surface(mesh, projection="planar")
    assert grid.valid.sum() > 0


def test_organised_cloud_seen_from_its_sensor_is_sliced_from_the_sensors_side():
    points, _ = depth_camera(holes=False)
    mesh = mesh_from_bytes(pcd(xyz_columns(points.reshape(-1, 3)), "binary", width=80, height=60), "k.pcd")
    grid = slice_surface(mesh, projection="planar")
    # the camera looks along +z from z = 0, so the grid looks from -z: the ball (nearer) is outermost
    assert grid.transform[2, 2] < 0


@pytest.mark.parametrize("edit, message, line", [
    (lambda d: d.replace(b"POINTS 4", b"POINTS 5"), "POINTS: 5 points, but WIDTH x HEIGHT is 4 x 1", 10),
    (lambda d: d.replace(b"SIZE 4 4 4", b"SIZE 4 4"), "SIZE: 2 values for 3 fields", 4),
    (lambda d: d.replace(b"TYPE F F F", b"TYPE F F X"), "TYPE: field 'z': type X of size 4", 5),
    (lambda d: d.replace(b"TYPE F F F", b"TYPE F F I").replace(b"SIZE 4 4 4", b"SIZE 4 4 3"), "size 3", 5),
    (lambda d: d.replace(b"FIELDS x y z", b"FIELDS x y w"), "FIELDS: no field 'z'", 3),
    (lambda d: d.replace(b"COUNT 1 1 1", b"COUNT 1 1 2"), "COUNT: field 'z' has 2 values a point", 6),
    (lambda d: d.replace(b"WIDTH 4", b"WIDTH four"), "WIDTH: 'four' is not a whole number", 7),
    (lambda d: d.replace(b"DATA ascii", b"DATA zip"), "DATA: 'zip' is not one of", 11),
    (lambda d: d.replace(b"VIEWPOINT 0 0 0 1 0 0 0", b"VIEWPOINT 0 0"), "VIEWPOINT: expected 7 numbers", 9),
    (lambda d: d.replace(b"VERSION 0.7\n", b"VERSION 0.7\nVERSION 0.7\n"), "VERSION: given twice", 3),
    (lambda d: d.replace(b"VERSION 0.7\n", b"COLOUR red\n"), "unknown header line 'COLOUR red'", 2),
    (lambda d: d[:d.index(b"DATA")], "the header ends without a DATA line", 11),
    (lambda d: d.replace(b"1.0 2.0 3.0\n", b"1.0 2.0\n"), "2 values on the line; the fields make 3", 13),
    (lambda d: d.replace(b"1.0 2.0 3.0\n", b"1.0 2.0 oops\n"), "point 2: z 'oops' is not a number", 13),
    (lambda d: d + b"7 8 9\n", "5 points, but the header declares 4", 16),
])
def test_bad_pcd_headers_and_ascii_bodies_are_one_line_naming_line_and_field(edit, message, line):
    good = pcd(xyz_columns(np.array([[0, 0, 0], [1, 2, 3], [2, 0, 1], [0, 3, 1]], dtype=float)))
    mesh_from_bytes(good, "ok.pcd")
    with pytest.raises(MzcError) as error:
        mesh_from_bytes(edit(good), "bad.pcd")
    assert message in str(error.value) and error.value.line == line, (str(error.value), error.value.line)


def test_hostile_binary_pcd_sizes_are_refused_before_allocating():
    points = np.random.default_rng(3).normal(size=(100, 3))
    binary = pcd(xyz_columns(points), "binary")
    with pytest.raises(MzcError, match="truncated: 100 points of 12 bytes need 1200 bytes"):
        mesh_from_bytes(binary[:-1], "cut.pcd")
    huge = binary.replace(b"WIDTH 100", b"WIDTH 100000000000").replace(b"POINTS 100", b"POINTS 100000000000")
    with pytest.raises(MzcError, match="truncated: 100000000000 points"):
        mesh_from_bytes(huge, "huge.pcd")
    compressed = pcd(xyz_columns(points), "binary_compressed")
    start = compressed.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n")
    packed, plain = struct.unpack_from("<II", compressed, start)

    def with_sizes(first, second, body=None):
        head = compressed[:start] + struct.pack("<II", first, second)
        return head + (compressed[start + 8:] if body is None else body)

    for data, message in [
        (compressed[:start + 5], "truncated: a binary_compressed body starts with 8 bytes"),
        (with_sizes(packed + 1, plain), f"truncated: the compressed data declares {packed + 1} bytes"),
        (with_sizes(packed, plain + 4), f"declares {plain + 4} bytes, but 100 points make 1200"),
        (with_sizes(packed, plain)[:-3], "truncated"),
        (with_sizes(20, plain, b"\x1f" + bytes(19)), "ends inside a run"),     # a 32-byte literal cut to 19
        (with_sizes(20, plain, b"\x20\x05" + bytes(18)), "refers back before its start"),
    ]:
        with pytest.raises(MzcError, match=message):
            mesh_from_bytes(data, "bad.pcd")
    tiny = pcd(xyz_columns(np.zeros((LZF_MAX_EXPANSION * 3 // 12 + 100, 3))), "binary_compressed")
    start = tiny.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n")
    _, plain = struct.unpack_from("<II", tiny, start)
    with pytest.raises(MzcError, match="more than 3 bytes of LZF can hold"):
        mesh_from_bytes(tiny[:start] + struct.pack("<II", 3, plain) + b"\x00\x00\x00", "bomb.pcd")


def test_bad_pcd_is_one_line_from_the_command(mzc, tmp_path):
    path = tmp_path / "bad.pcd"
    path.write_bytes(pcd(xyz_columns(np.ones((3, 3)))).replace(b"SIZE 4 4 4", b"SIZE 4 4"))
    assert_one_line_error(mzc("slice", path), "bad.pcd:4: SIZE: 2 values for 3 fields")


# --------------------------------------------------------------------------- LAS and LAZ


def test_public_las_and_laz_hold_the_same_scaled_points_and_classes():
    las, laz = read_mesh(PUBLIC / "simple.las"), read_mesh(PUBLIC / "simple.laz")
    assert len(las.points) == 1065 and np.array_equal(las.points, laz.points)
    assert np.array_equal(las.classification, laz.classification)
    assert sorted(set(las.classification.tolist())) == [1, 2]
    # scale 0.01 applied: the coordinates are the file's integers in hundredths (state plane feet)
    assert np.allclose(las.points.min(axis=0), [635619.85, 848899.70, 406.59])
    assert np.allclose(las.points * 100, np.round(las.points * 100), atol=1e-6)


def test_las_classes_keep_the_ground_alone(mzc, tmp_path):
    mesh = read_mesh(PUBLIC / "simple.laz")
    ground = mesh.with_classes([2])
    assert len(ground.points) == int((mesh.classification == 2).sum()) == 276
    out = tmp_path / "ground.zg"
    assert mzc("slice", PUBLIC / "simple.laz", "--classes", "2", "-o", out).returncode == 0
    assert_one_line_error(mzc("slice", PUBLIC / "simple.laz", "--classes", "6,9"),
                          "simple.laz: classes: no point has class 6, 9 (the cloud's classes: 1, 2)")
    assert_one_line_error(mzc("slice", PUBLIC / "bun0.pcd", "--classes", "2"),
                          "bun0.pcd: classes: the input has no point classes")
    result = mzc("slice", PUBLIC / "simple.laz", "--classes", "ground")
    assert result.returncode == 2 and "--classes" in result.stderr.decode()


@pytest.mark.parametrize("name, crs", [
    ("autzen_geo_proj.las", "EPSG:2994"),        # GeoTIFF keys
    ("1_4_w_evlr.laz", 'PROJCS["NAD83(HARN) / New Mexico Central (ftUS)"'),   # a WKT record
    ("simple.las", None),
])
def test_las_crs_is_kept_on_the_cloud(name, crs):
    found = read_mesh(PUBLIC / name).crs
    assert found == crs if crs is None or crs.startswith("EPSG") else found.startswith(crs)


def test_a_planar_grid_keeps_the_clouds_wkt_crs_through_its_file(tmp_path):
    import mzc

    mesh = read_mesh(PUBLIC / "1_4_w_evlr.laz")
    grid = mzc.slice(mesh, projection="planar")
    mzc.write(tmp_path / "g.zg", grid)
    assert grid.crs == mesh.crs and mzc.read(tmp_path / "g.zg").crs == mesh.crs


def test_a_clouds_epsg_code_is_spelled_out_as_wkt_in_the_grid(tmp_path, monkeypatch):
    import mzc

    rasterio = pytest.importorskip("rasterio")
    mesh = read_mesh(PUBLIC / "autzen_geo_proj.las")   # EPSG:2994 in its GeoTIFF keys
    grid = mzc.slice(mesh, projection="planar")
    assert grid.crs.startswith('PROJCS["NAD83(HARN) / Oregon GIC Lambert (ft)"')
    mzc.write(tmp_path / "g.tif", grid)
    with rasterio.open(tmp_path / "g.tif") as dataset:
        assert dataset.crs.to_epsg() == 2994
    monkeypatch.setitem(sys.modules, "rasterio.crs", None)   # as without the geo extra
    with pytest.warns(MzcWarning, match=r"CRS \(EPSG:2994\) is not kept in the grid: .*mzc\[geo\]"):
        assert mzc.slice(mesh, projection="planar").crs is None


GEOGRAPHIC_WKT = ('GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
                  'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]]')


def hills(lon, lat):
    """Terrain heights in metres at longitude and latitude near 105 W, 40 N: hills a few hundred
    metres across (0.003 degrees of longitude is 256 m there)."""
    return 1600 + 30 * np.sin((lon + 105) / 0.003) * np.cos((lat - 40) / 0.004) + 2000 * (lat - 40)


def lonlat_las(path, record, count=6000):
    """A LAS 1.4 cloud of ``count`` points scattered over 0.01 x 0.01 degrees at 105 W, 40 N on
    ``hills``, its CRS EPSG:4326 in a WKT record or in GeoTIFF keys (``record``)."""
    import laspy
    from laspy.vlrs.geotiff import GeoKeyEntryStruct
    from laspy.vlrs.known import GeoKeyDirectoryVlr, WktCoordinateSystemVlr

    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = [1e-7, 1e-7, 0.01], [-105, 40, 0]
    if record == "wkt":
        header.vlrs.append(WktCoordinateSystemVlr(GEOGRAPHIC_WKT))
    else:
        keys = GeoKeyDirectoryVlr()
        keys.geo_keys_header.number_of_keys = 2
        keys.geo_keys = [GeoKeyEntryStruct(1024, 0, 1, 2), GeoKeyEntryStruct(2048, 0, 1, 4326)]
        header.vlrs.append(keys)
    data = laspy.LasData(header)
    rng = np.random.default_rng(0)
    lon, lat = -105 + 0.01 * rng.random(count), 40 + 0.01 * rng.random(count)
    data.x, data.y, data.z = lon, lat, hills(lon, lat)
    data.classification = np.full(count, 2)
    data.write(path)
    return path


@pytest.mark.parametrize("record", ["wkt", "geokeys"])
def test_a_las_cloud_in_longitude_and_latitude_is_gridded_as_terrain_in_degrees(mzc, tmp_path, record):
    """Its CRS says x and y are degrees: the grid looks down z at the cloud's own point spacing in
    degrees (not its Delaunay edges over degrees and metres of height), keeps the geographic CRS,
    and holds the terrain's heights; the codec then takes a vertical RMSE in metres."""
    import mzc as api
    from mzc.georef import crs_kind, metres_per_unit

    if record == "geokeys":
        pytest.importorskip("rasterio")   # EPSG:4326 spelled out as WKT from GDAL's database
    path = lonlat_las(tmp_path / "degrees.las", record)
    assert crs_kind(read_mesh(path).crs) == "geographic"
    grid = api.slice(path)
    assert crs_kind(grid.crs) == "geographic" and grid.projection == "planar"
    east, north = metres_per_unit(grid.crs, 40.005)
    assert grid.d1 == grid.d2 and 0.00005 <= grid.d1 <= 0.0002   # 4-17 m: 6000 points over about 0.9 km^2
    assert min(grid.shape) >= 50 and grid.shape[0] * grid.shape[1] < 10 * 6000
    lon, lat = np.meshgrid(grid.xs(), grid.ys())
    valid = grid.valid
    assert valid.mean() > 0.9 and np.abs(grid.z - hills(lon, lat))[valid].max() < 0.5   # metres (0.13 measured)
    sliced, coded = tmp_path / "g.zg", tmp_path / "g.mzw2"
    mzc("slice", path, "-o", sliced, check=True)
    assert api.read(sliced).z.tobytes() == grid.z.tobytes()
    mzc("encode", "--dwt2d", "--rmse", "0.5", sliced, "-o", coded, check=True)
    back = api.read(coded)
    assert np.sqrt(np.mean((back.z - grid.z)[valid] ** 2)) < 0.5 * 1.05 and back.crs == grid.crs
    with pytest.raises(MzcError, match="longitude and latitude") as error:
        api.slice(path, projection="spherical")
    assert error.value.field == "projection"
    assert east * grid.d2 < 20 and north * grid.d1 < 20


@pytest.mark.parametrize("compressed", [False, True])
def test_generated_las_applies_scale_and_offset(tmp_path, compressed):
    import laspy

    points = np.column_stack([np.linspace(500000, 500100, 50), np.linspace(4e6, 4e6 + 30, 50),
                              np.linspace(100, 130, 50)])
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = [0.001, 0.001, 0.01], [500000, 4000000, 100]
    data = laspy.LasData(header)
    data.x, data.y, data.z = points.T
    data.classification = np.arange(50) % 3
    path = tmp_path / ("g.laz" if compressed else "g.las")
    data.write(path)
    mesh = read_mesh(path)
    assert np.allclose(mesh.points, points, atol=0.005) and np.array_equal(mesh.classification, np.arange(50) % 3)


@pytest.mark.parametrize("name", ["simple.las", "simple.laz"])
def test_truncated_las_is_refused_in_one_line(mzc, tmp_path, name):
    data = (PUBLIC / name).read_bytes()
    for cut in (len(data) - 10, 400, 50):
        path = tmp_path / name
        path.write_bytes(data[:cut])
        assert_one_line_error(mzc("slice", path), f"{name}: ")
        with pytest.raises(MzcError, match="truncated|not a readable LAS"):
            read_mesh(path)


def test_las_without_laspy_names_the_extra(tmp_path):
    script = ("import sys; sys.modules['laspy'] = None\n"
              "from mzc.meshes import read_mesh\n"
              f"read_mesh({str(PUBLIC / 'simple.laz')!r})\n")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert "pip install 'mzc[las]'" in result.stderr
    cli = subprocess.run([sys.executable, "-c", "import sys; sys.modules['laspy'] = None\n"
                          "from mzc.cli import main; sys.argv = ['mzc', 'slice', " + repr(str(PUBLIC / "simple.laz"))
                          + "]; main()"], capture_output=True, text=True)
    assert cli.stderr.strip() == "mzc: " + str(PUBLIC / "simple.laz") + \
        ": reading LAS/LAZ needs laspy and lazrs: pip install 'mzc[las]'"


# --------------------------------------------------------------------------- dense clouds: binning


def surface(x, y):
    return 0.3 * np.sin(x / 7.0) * np.cos(y / 11.0) * 10 + 0.01 * x * y / 10


def terrain_cloud(count, seed=0, noise=0.0):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 100, (count, 2))
    return np.column_stack([xy, surface(*xy.T) + rng.normal(0, noise, count) if noise else surface(*xy.T)])


def test_binning_reproduces_a_plane_exactly():
    xy = np.random.default_rng(4).uniform(0, 50, (20000, 2))
    cloud = Mesh(np.column_stack([xy, 0.3 * xy[:, 0] - 0.2 * xy[:, 1] + 5]))
    grid = slice_surface(cloud, d1=1.0, d2=1.0, view="+z", cloud="bin")
    x, y = np.meshgrid(grid.origin[0] + np.arange(grid.shape[1]), grid.origin[1] + np.arange(grid.shape[0]))
    assert grid.valid.mean() > 0.95
    assert np.allclose(grid.z[grid.valid], (0.3 * x - 0.2 * y + 5)[grid.valid], atol=1e-9)


def test_a_dense_cloud_is_binned_automatically_and_agrees_with_delaunay():
    cloud = Mesh(terrain_cloud(BIN_POINTS + 20000))
    binned = slice_surface(cloud, d1=0.5, d2=0.5, view="+z")
    delaunay = slice_surface(cloud, d1=0.5, d2=0.5, view="+z", cloud="delaunay")
    both = binned.valid & delaunay.valid
    assert both.sum() > 0.95 * delaunay.valid.sum()
    difference = binned.z[both] - delaunay.z[both]
    assert np.sqrt(np.mean(difference ** 2)) < 0.01 * np.ptp(cloud.points[:, 2])


def test_a_cloud_dense_enough_for_the_narrowest_window_is_binned_with_it():
    from mzc.ops.slicing import cloud_window

    cloud = terrain_cloud(BIN_POINTS + 20000)   # 120,000 points over 100 x 100: 12 a node at d = 1
    low, shape = cloud[:, :2].min(axis=0), (101, 101)
    assert binning.window_radius(12.0) == 0
    assert cloud_window(cloud, low, 1.0, 1.0, shape, "auto") == 0
    assert cloud_window(cloud, low, 1.0, 1.0, shape, "bin") == 0
    assert cloud_window(cloud, low, 0.05, 0.05, (2001, 2001), "bin") == binning.MAX_RADIUS   # sparse: the widest


def test_auto_keeps_delaunay_for_small_and_for_sparse_clouds(monkeypatch):
    calls = []
    monkeypatch.setattr(binning, "binned_values", lambda *a, **k: calls.append(1))
    small = Mesh(terrain_cloud(5000))
    slice_surface(small, view="+z")
    sparse = Mesh(terrain_cloud(BIN_POINTS + 1000))
    slice_surface(sparse, d1=0.05, d2=0.05, view="+z")     # 0.05 points a node: too sparse for a window
    assert not calls


def test_binning_leaves_holes_where_no_point_fell():
    points = terrain_cloud(BIN_POINTS + 20000)
    gap = (np.abs(points[:, 0] - 50) < 8) & (np.abs(points[:, 1] - 50) < 8)
    grid = slice_surface(Mesh(points[~gap]), d1=0.5, d2=0.5, view="+z")
    x = grid.origin[0] + 0.5 * np.arange(grid.shape[1])
    y = grid.origin[1] + 0.5 * np.arange(grid.shape[0])
    inside = (np.abs(y - 50)[:, None] < 7) & (np.abs(x - 50)[None, :] < 7)
    assert not grid.valid[inside].any() and grid.valid[~inside].mean() > 0.97


def test_binning_keeps_the_front_layer_behind_a_depth_jump():
    """A sheet 100 spacings above another over half the area: the nodes over both see the front
    one, as the outermost hit of the node lines would."""
    rng = np.random.default_rng(5)
    low = np.column_stack([rng.uniform(0, 100, (150000, 2)), np.zeros(150000)])
    high = np.column_stack([rng.uniform(0, 50, (40000, 2)), np.full(40000, 50.0)])
    grid = slice_surface(Mesh(np.vstack([low, high])), d1=0.5, d2=0.5, view="+z")
    x = grid.origin[0] + 0.5 * np.arange(grid.shape[1])
    y = grid.origin[1] + 0.5 * np.arange(grid.shape[0])
    covered = (x[None, :] < 48) & (y[:, None] < 48)
    assert np.allclose(grid.z[covered & grid.valid], 50.0) and grid.valid[covered].mean() > 0.97


def test_quantised_lidar_coordinates_are_no_lattice():
    """LAS stores coordinates as integers of 0.01: every x and y is a multiple of it, but the
    points fill a tiny share of that lattice, so they are a cloud, not a DEM."""
    xy = np.round(np.random.default_rng(6).uniform(0, 1000, (5000, 2)), 2)
    assert lattice_steps(xy) is None
    dem = np.stack(np.meshgrid(np.arange(30.0), np.arange(20.0)), axis=-1).reshape(-1, 2)
    assert lattice_steps(dem[np.random.default_rng(7).random(len(dem)) < 0.7]) == (1.0, 1.0)


def test_a_laz_cloud_slices_from_the_command_line(mzc, tmp_path):
    import laspy

    points = terrain_cloud(BIN_POINTS + 50000, noise=0.01)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = [0.001, 0.001, 0.001], [0, 0, 0]
    data = laspy.LasData(header)
    data.x, data.y, data.z = points.T
    data.classification = np.where(np.arange(len(points)) % 4 == 0, 5, 2)
    data.z = np.where(data.classification == 5, points[:, 2] + 20, points[:, 2])
    path, out = tmp_path / "terrain.laz", tmp_path / "ground.zg"
    data.write(path)
    assert mzc("slice", path, "--classes", "2", "-o", out).returncode == 0
    grid = mzc_read(out)
    nodes = grid.to_input_frame(grid.node_points()[grid.valid])
    error = nodes[:, 2] - surface(nodes[:, 0], nodes[:, 1])
    assert grid.valid.mean() > 0.95 and np.sqrt(np.mean(error ** 2)) < 0.02


# --------------------------------------------------------------------------- OBJ and PLY as exporters write them


EXPORTED_OBJ = (b"# Exported by a scanner suite\x00 with a NUL in its comment\r\n"
                b"mtllib scan.mtl\no scan\ng patch\ns 1\nusemtl skin\n"
                b"v 0 0 0\nv 1 0 0\nv 1 1 \\\n 0\nv 0 1 0\nv 2 0.5 0\nv 1.5 1.5 0\n"
                b"vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
                b"f 1/1/1 2/2/1 3/3/1 4/3/1\n"                 # a quad, v/vt/vn
                b"usemtl other\ng second\ns off\n"
                b"f -5//1 -2//1 -1//1 \\\r\n -4//1 -3//1\n"     # a pentagon, v//vn, negative, continued
                b"f 2/1 5/2 3/3\n")                            # v/vt
EXPORTED_TRIANGLES = [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2], [1, 2, 3], [1, 4, 2]]


def test_obj_as_exporters_write_it():
    mesh = mesh_from_bytes(EXPORTED_OBJ, "scan.obj")
    assert mesh.points.shape == (6, 3) and mesh.points[2].tolist() == [1, 1, 0]
    assert mesh.triangles.tolist() == EXPORTED_TRIANGLES


def test_obj_errors_name_the_files_line_after_continued_lines():
    bad = EXPORTED_OBJ + b"f 1 2 \\\n 9\n"
    with pytest.raises(MzcError) as error:
        mesh_from_bytes(bad, "scan.obj")
    assert error.value.line == 25 and "does not exist" in str(error.value)   # where the statement starts


def ply_cloud(faces_element, body="ascii"):
    rows = [(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 255, 0, 0), (1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0, 255, 0),
            (0.0, 1.0, 1.5, 0.0, 0.0, 1.0, 0, 0, 255), (1.0, 1.0, 1.2, 0.0, 0.0, -1.0, 9, 9, 9)]
    header = (f"ply\nformat {body} 1.0\ncomment exported with colours\nelement vertex 4\n"
              "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
              "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
              + ("element face 0\nproperty list uchar int vertex_indices\n" if faces_element else "")
              + "end_header\n").encode()
    if body == "ascii":
        return header + "".join(" ".join(str(v) for v in row) + "\n" for row in rows).encode()
    record = np.dtype([(c, "<f4") for c in ("x", "y", "z", "nx", "ny", "nz")] + [(c, "u1") for c in "rgb"])
    return header + np.array(rows, dtype=record).tobytes()


@pytest.mark.parametrize("faces_element", [False, True])
@pytest.mark.parametrize("body", ["ascii", "binary_little_endian"])
def test_ply_with_colours_normals_and_an_empty_face_element_is_a_cloud(faces_element, body):
    mesh = mesh_from_bytes(ply_cloud(faces_element, body), "scan.ply")
    assert mesh.is_point_cloud and mesh.points.shape == (4, 3)
    assert mesh.normals is not None and mesh.normals[:, 2].tolist() == [1, 1, 1, -1]
