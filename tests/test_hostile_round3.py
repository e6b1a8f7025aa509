"""The hostile corpus of issue 29 (reliability, round 3) for the readers, the API, the Zarr
codec and diff: each case is refused in one line naming the file and the reason, or done
right, in bounded time and memory. The command-line cases run through tests/test_hostile.py's
in-process runner and its general promise (``kept_promises``)."""

import contextlib
import struct
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from mzc.errors import MzcError
from mzc.meshes import mesh_from_bytes

from test_hostile import kept_promises, run


def write_obj(path, points, faces=((1, 2, 3), (2, 4, 3))):
    """An OBJ file of ``points`` and 1-based ``faces``; returns its path."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(points, dtype=float).tolist()]
    path.write_text("\n".join(lines + [f"f {a} {b} {c}" for a, b, c in faces]) + "\n")
    return path


def square(z=0.0, size=1.0):
    """The corners of a flat square at height ``z``."""
    return [[0, 0, z], [size, 0, z], [0, size, z], [size, size, z]]


def lattice(tmp_path, count=300):
    """A z-grid of count x count nodes of a gentle slope, about 180,000 triangles as a mesh."""
    y, x = np.mgrid[0:count, 0:count] / count
    rows = "\n".join(" ".join(repr(v) for v in row) for row in (0.1 * x + 0.05 * y).tolist())
    path = tmp_path / "lattice.zg"
    path.write_text(f"mzc-zgrid 1.0\nrows {count}\ncols {count}\nd1 {1 / count!r}\nd2 {1 / count!r}\norigin 0 0\n"
                    f"data\n{rows}\n")
    return path


def bump_grid():
    """A small planar grid of the bump sample, with holes."""
    import mzc

    return mzc.slice(mzc.sample("bump"), 4.0, 4.0)


@contextlib.contextmanager
def traced():
    """Trace Python's allocations inside; yields a function giving their peak in bytes."""
    tracemalloc.start()
    try:
        yield lambda: tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


# --- 1. diff's nearest-triangle search: bounded work ---------------------------------------

@pytest.mark.parametrize("height", [1e10, 9e99])
def test_diff_of_a_surface_far_above_a_fine_one_ends_in_seconds(tmp_path, height):
    """Every triangle of the fine mesh lay within the search's slack of a sample that far away,
    so each of the samples measured all 180,000 of them (1e10: over 20 s for 10,000 samples,
    3e299: over 11 minutes)."""
    far = write_obj(tmp_path / "far.obj", square(height))
    for pair in ((far, lattice(tmp_path)), (lattice(tmp_path), far)):
        result = kept_promises(run("diff", *pair, "--surface", "--samples", "10000"))
        assert result.status == 0 and result.seconds < 10, result.stderr
        report = dict(line.split() for line in result.stdout.decode().splitlines())
        assert np.isclose(float(report["surface_hausdorff"]), height, rtol=1e-6)


@pytest.mark.parametrize("points", [square(3e299), [[0, 0, 0], [1, 0, 0], [0, 1, 1e250], [1, 1, 1]]],
                         ids=["heights 3e299", "one 1e250"])
def test_diff_refuses_coordinates_beyond_the_limit_naming_the_file(tmp_path, points):
    huge = write_obj(tmp_path / "huge.obj", points)
    small = write_obj(tmp_path / "small.obj", square())
    for pair in ((huge, small), (small, huge)):
        result = kept_promises(run("diff", *pair, "--surface"))
        assert result.status == 1 and "huge.obj: coordinates reach" in result.stderr[0]


def test_diff_samples_a_surface_whose_areas_overflow(tmp_path):
    """Coordinates of 9e99 (within the limit) square to past float64's range in a triangle's area:
    the draw by area was 'Probabilities contain NaN', an internal error."""
    wide = write_obj(tmp_path / "wide.obj", [[0, 0, 0], [9e99, 0, 0], [0, 9e99, 1], [9e99, 9e99, 0]])
    small = write_obj(tmp_path / "small.obj", square())
    result = kept_promises(run("diff", small, wide, "--surface"))
    assert result.status == 0, result.stderr


# --- 2. declared counts checked against the file before any work -----------------------------

LAS = Path(__file__).parent / "data" / "public"


@pytest.mark.parametrize("name, offset", [("simple.las", 100), ("autzen_geo_proj.las", 100),
                                          ("1_4_w_evlr.laz", 243)])
def test_a_las_file_declaring_4e9_records_is_refused_before_laspy_reads_them(name, offset):
    """laspy built records past the end of a 34 KB file: 68 s and 1.4 GB before running out."""
    pytest.importorskip("laspy")
    data = bytearray((LAS / name).read_bytes())
    struct.pack_into("<I", data, offset, 4_000_000_000)
    with traced() as peak:
        with pytest.raises(MzcError, match="truncated: the header declares 4000000000 (extended )?variable"):
            mesh_from_bytes(bytes(data), name)
    assert peak() < 10_000_000


@pytest.mark.parametrize("properties", [20_000, 100_000])
def test_a_ply_header_of_many_properties_is_read_in_linear_time(properties):
    """Each property's name was checked against all before it: 17 s for 20,000, over 90 s for 100,000."""
    extra = "".join(f"property float p{i}\n" for i in range(properties))
    data = ("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            f"{extra}end_header\n" + ("1 2 3" + " 0" * properties + "\n") * 3).encode()
    start = time.perf_counter()
    mesh = mesh_from_bytes(data, "wide.ply")
    assert time.perf_counter() - start < 5 and mesh.points.tolist() == [[1, 2, 3]] * 3
    twice = data.replace(b"property float p7\n", b"property float p6\n")
    with pytest.raises(MzcError, match="second property 'p6'"):
        mesh_from_bytes(twice, "twice.ply")


# --- 3. degenerate meshes: refused by name, not divided by zero ------------------------------

DEGENERATE = {"equal corners": "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n",
              "collinear corners": "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"}


@pytest.mark.parametrize("projection", ["auto", "planar", "cylindrical", "spherical"])
@pytest.mark.parametrize("name", DEGENERATE)
def test_a_mesh_without_area_is_refused_by_slice(tmp_path, name, projection):
    path = tmp_path / "flat.obj"
    path.write_text(DEGENERATE[name])
    result = kept_promises(run("slice", path, "--projection", projection))
    assert result.status == 1 and "flat.obj: the mesh has no area" in result.stderr[0], result.stderr


def test_an_organised_cloud_of_equal_points_is_refused_at_once(tmp_path):
    """A 640 x 480 depth image whose every pixel is one point: its lattice's triangles have no area."""
    path = tmp_path / "equal.pcd"
    path.write_bytes(b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 640\nHEIGHT 480\n"
                     b"POINTS 307200\nDATA binary\n" + np.ones((307200, 3), "<f4").tobytes())
    result = kept_promises(run("slice", path))
    assert result.status == 1 and "equal.pcd: the mesh has no area" in result.stderr[0], result.stderr
    assert result.seconds < 10


def test_diff_refuses_a_mesh_without_area(tmp_path):
    from mzc.measure.metrics import sample_surface

    with pytest.raises(ValueError, match="no area"):
        sample_surface(np.ones((3, 3)), np.array([[0, 1, 2]]), 10, np.random.default_rng(0))


# --- 4. the Zarr codec: a chunk lands only where it fits --------------------------------------

def zarr_chunk():
    """(the codec, a 32 x 128 chunk's bytes)."""
    pytest.importorskip("numcodecs")
    from mzc.zarr import Dwt2d

    codec = Dwt2d(max_error=0.1)
    return codec, codec.encode(np.linspace(0, 144, 32 * 128).reshape(32, 128))


@pytest.mark.parametrize("out", [np.empty((64, 64)), np.empty((128, 32)), np.empty((32, 128), np.float32),
                                 np.empty(4000), np.empty((32, 128), ">f4")],
                         ids=["64 x 64", "128 x 32", "float32", "too few", "big-endian float32"])
def test_a_chunk_is_not_decoded_into_an_out_of_another_shape_or_type(out):
    codec, data = zarr_chunk()
    with pytest.raises(MzcError, match="the chunk is 32 x 128 float64, not the"):
        codec.decode(data, out=out)


@pytest.mark.parametrize("out", [np.empty((32, 128)), np.empty(32 * 128), bytearray(32 * 128 * 8)],
                         ids=["its shape", "flat", "bytes"])
def test_a_chunk_is_decoded_into_an_out_that_fits(out):
    codec, data = zarr_chunk()
    codec.decode(data, out=out)
    values = np.frombuffer(out, dtype=float) if isinstance(out, bytearray) else out
    assert np.abs(values.reshape(32, 128) - np.linspace(0, 144, 32 * 128).reshape(32, 128)).max() <= 0.1


@pytest.mark.filterwarnings("ignore:Numcodecs codecs are not in the Zarr version 3")
@pytest.mark.parametrize("dtype", ["f8", "f4"])
def test_a_version_3_array_refuses_a_chunk_of_another_shape_or_type(dtype):
    """Off by 144 against a bound of 0.1: a 32 x 128 chunk read as 64 x 64."""
    zarr = pytest.importorskip("zarr")
    from zarr.core.buffer import default_buffer_prototype

    from mzc.zarr import Dwt2dV3

    _, data = zarr_chunk()
    store = {}
    array = zarr.create_array(store=store, shape=(64, 64), chunks=(64, 64), dtype=dtype, zarr_format=3,
                              serializer=Dwt2dV3(max_error=0.1), compressors=None, fill_value=np.nan)
    array[:] = np.ones((64, 64))
    key = next(key for key in store if key.startswith("c"))
    store[key] = default_buffer_prototype().buffer.from_bytes(data)
    with pytest.raises(MzcError, match="the chunk is 32 x 128 float64, not the 64 x 64"):
        array[:]


@pytest.mark.parametrize("config", [{}, {"max_error": None}, {"max_error": "x"}, {"max_error": "nan"},
                                    {"max_error": [1]}, {"max_error": 0.1, "level": "x"}])
def test_a_zarr_codec_config_without_a_valid_max_error_is_one_error(config):
    numcodecs = pytest.importorskip("numcodecs")
    with pytest.raises(MzcError):
        numcodecs.get_codec({"id": "mzc_dwt2d", **config})


# --- 5. the API: MzcError for bad input, checked before work ---------------------------------

def api_calls():
    """name -> a call of the public API with one hostile argument."""
    import mzc

    grid, mesh, pts = bump_grid(), mzc.Mesh(square(), [[0, 1, 2], [1, 3, 2]]), np.random.default_rng(0).random((9, 3))
    huge = np.broadcast_to(np.float64(1), (10001, 10001))   # no memory: a size refused before any work
    return {
        "encode 0 x 0": lambda: mzc.encode(np.zeros((0, 0))), "encode 0 x 5": lambda: mzc.encode(np.zeros((0, 5))),
        "encode 1000001 x 1": lambda: mzc.encode(np.zeros((1_000_001, 1)), max_error=0.1),
        "encode 10001 x 10001": lambda: mzc.encode(huge, max_error=0.1),
        "encode complex": lambda: mzc.encode(np.ones((4, 4)) * (1 + 1j), max_error=0.1),
        "encode objects": lambda: mzc.encode(np.array([[object()]])), "encode text": lambda: mzc.encode("abc"),
        "encode None": lambda: mzc.encode(None), "encode 3D": lambda: mzc.encode(np.zeros((2, 2, 2))),
        "encode ragged": lambda: mzc.encode([[1, 2], [3]]), "encode inf": lambda: mzc.encode(np.full((4, 4), np.inf)),
        "encode 1e200": lambda: mzc.encode(np.full((4, 4), 1e200), "dct"),
        "encode max_error nan": lambda: mzc.encode(grid, max_error=float("nan")),
        "encode quality text": lambda: mzc.encode(grid, "dct", quality="x"),
        "encode codec 3": lambda: mzc.encode(grid, 3),
        "decode text": lambda: mzc.decode("mzc-zgrid 1.0"), "decode None": lambda: mzc.decode(None),
        "decode int": lambda: mzc.decode(10**12), "decode empty": lambda: mzc.decode(b""),
        "decode legacy kind": lambda: mzc.decode(b"1 2 3", legacy="nope"),
        "densify n text": lambda: mzc.densify(grid, "x"), "densify n 1.5": lambda: mzc.densify(grid, 1.5),
        "densify n huge": lambda: mzc.densify(grid, 10**30), "densify None": lambda: mzc.densify(None, 1),
        "densify 10001 x 10001": lambda: mzc.densify(huge, 1),
        "densify tol text": lambda: mzc.densify(grid, 1, tol="x"),
        "densify tol nan": lambda: mzc.densify(grid, 1, tol=float("nan")),
        "densify iterations text": lambda: mzc.densify(grid, 1, method="thesis", iterations="x"),
        "densify jump_angle text": lambda: mzc.densify(grid, 1, jump_angle="x"),
        "triangulate None": lambda: mzc.triangulate(None),
        "triangulate jump inf": lambda: mzc.triangulate(grid, jump_angle=np.inf),
        "triangulate 1D": lambda: mzc.triangulate(np.ones(5)),
        "slice None": lambda: mzc.slice(None), "slice empty": lambda: mzc.slice(np.zeros((0, 3))),
        "slice NaN points": lambda: mzc.slice(np.full((5, 3), np.nan)),
        "slice complex points": lambda: mzc.slice(pts * 1j),
        "slice index 5 of 3": lambda: mzc.slice((pts[:3], [[0, 1, 5]])),
        "slice index 2.5": lambda: mzc.slice((pts[:3], [[0, 1, 2.5]])),
        "slice index 2^70": lambda: mzc.slice((pts[:3], [[0, 1, 2**70]])),
        "slice faces None": lambda: mzc.slice(type("M", (), {"vertices": pts, "faces": None})()),
        "slice d1 text": lambda: mzc.slice(mesh, d1="x"), "slice rows text": lambda: mzc.slice(mesh, rows="x"),
        "slice rows 2.5": lambda: mzc.slice(mesh, rows=2.5),
        "slice center of 2": lambda: mzc.slice(mesh, projection="spherical", center=(1, 2)),
        "slice center text": lambda: mzc.slice(mesh, projection="spherical", center="abc"),
        "slice axis text": lambda: mzc.slice(mesh, projection="cylindrical", axis="abc"),
        "slice classes 5": lambda: mzc.slice(mesh, classes=5), "slice path NUL": lambda: mzc.slice("a\0b.obj"),
        "compare None": lambda: mzc.compare(None, mesh),
        "compare samples text": lambda: mzc.compare(mesh, mesh, samples="x"),
        "compare samples 1000.5": lambda: mzc.compare(mesh, mesh, surface=True, samples=1000.5),
        "compare seed text": lambda: mzc.compare(mesh, mesh, surface=True, seed="x"),
        "compare seed -1": lambda: mzc.compare(mesh, mesh, surface=True, seed=-1),
        "compare d1 text": lambda: mzc.compare(mesh, mesh, d1="x"),
        "sample list": lambda: mzc.sample([1]), "read None": lambda: mzc.read(None), "read 5": lambda: mzc.read(5),
        "read NUL": lambda: mzc.read("a\0b"), "write None": lambda: mzc.write(None, grid),
        "write precision text": lambda: mzc.write("x.zg", grid, precision="x", plain=True),
        "write precision 10^6": lambda: mzc.write("x.zg", grid, precision=10**6, plain=True),
        "write 5": lambda: mzc.write("x.zg", 5),
        "ZGrid complex": lambda: mzc.ZGrid(np.ones((3, 3)) * 1j, 1, 1),
        "ZGrid d1 text": lambda: mzc.ZGrid(np.ones((3, 3)), "x", 1),
        "ZGrid origin 5": lambda: mzc.ZGrid(np.ones((3, 3)), 1, 1, origin=5),
        "ZGrid origin NaN": lambda: mzc.ZGrid(np.ones((3, 3)), 1, 1, origin=(np.nan, 0)),
        "ZGrid transform of 5": lambda: mzc.ZGrid(np.ones((3, 3)), 1, 1, transform=np.zeros(5)),
        "ZGrid radius text": lambda: mzc.ZGrid(np.ones((3, 3)), 1, 1, projection="cylindrical", radius="x"),
        "ZGrid raster text": lambda: mzc.ZGrid(np.ones((3, 3)), 1, 1, raster="x"),
        "Mesh text": lambda: mzc.Mesh("abc"), "Mesh triangles (2, 2)": lambda: mzc.Mesh(pts, np.ones((2, 2))),
        "Mesh normals (2, 3)": lambda: mzc.Mesh(pts, normals=np.ones((2, 3))),
        "batch_decode densify text": lambda: mzc.batch_decode([], "out", densify="x"),
        "batch_encode sources 5": lambda: mzc.batch_encode(5, "out", max_error=0.1),
        "batch_encode d1 text": lambda: mzc.batch_encode([], "out", slice_options={"d1": "x"}, max_error=0.1),
        "register_codec 5": lambda: mzc.register_codec(5),
    }


API_CALLS = api_calls()


@pytest.mark.parametrize("name", API_CALLS)
def test_the_api_refuses_hostile_arguments_with_an_mzc_error_before_work(name, tmp_path, monkeypatch):
    """Each raised IndexError, OverflowError, ZeroDivisionError, TypeError, AttributeError, a
    ComplexWarning (the imaginary part dropped) or a bare MemoryError after seconds, or returned
    bytes that mzc.decode refuses."""
    import warnings

    monkeypatch.chdir(tmp_path)
    start = time.perf_counter()
    with warnings.catch_warnings(), traced() as peak:
        warnings.simplefilter("error")
        with pytest.raises(MzcError):
            API_CALLS[name]()
    assert time.perf_counter() - start < 5 and peak() < 100_000_000
    assert not list(tmp_path.iterdir())


def test_arrays_are_grids_to_densify_and_triangulate():
    import mzc

    z = np.add.outer(np.arange(4.0), np.arange(5.0))
    assert mzc.densify(z, 1).shape == (7, 5)
    assert len(mzc.triangulate(z).triangles) == 2 * 3 * 4


# --- 6. the 1e100 limit kept on reading ------------------------------------------------------

def edited(data, pattern, replacement):
    """``data`` with the first match of ``pattern`` replaced, its checksum made right again."""
    import re

    from codec_contract import rechecksummed

    changed, found = re.subn(pattern, replacement, data, count=1)
    assert found
    return rechecksummed(changed)


def coefficient_set(data, value):
    """A row codec's file with the first coefficient of its first coded row set to ``value``."""
    head, body = data.split(b"\ndata\n", 1)
    lines = body.split(b"\n")
    row = next(i for i, line in enumerate(lines) if len(line.split()) > 3)
    tokens = lines[row].split()
    tokens[2] = value
    lines[row] = b" ".join(tokens)
    return edited(head + b"\ndata\n" + b"\n".join(lines), rb"\ndata\n", b"\ndata\n")


def compact_edited(data, keyword, words):
    """A dwt2d 7.0 or 8.0 file with the header field ``keyword`` set to ``words`` (added when absent),
    its sections' CRC-32s made right again."""
    from mzc.codecs.dwt2d import compact

    header, payload, _colour = compact.read(data, "t")
    fields = {name: values for name, (values, _line) in header.fields.items()} | {keyword: words}
    return compact.file_bytes([f"{name} {' '.join(values)}" for name, values in fields.items()], payload,
                              major=compact.major(data))


def beyond_the_limit():
    """CRC-valid files whose decoded heights or coordinates pass 1e100: name -> bytes."""
    import mzc
    from mzc.codecs.dwt2d import encode_whole
    from mzc.formats import zgrid

    grid = bump_grid()
    compact = mzc.encode(grid, max_error=0.1)   # 8.0: binary header fields
    dwt2d = encode_whole(grid, max_error=0.1, compact=False)[0]   # 3.1: text header lines
    dct = mzc.encode(grid, "dct", quality=50)
    raw = zgrid.write(grid, raw="float64")
    huge = np.full(grid.shape, 1e299).tobytes()
    return {
        "dwt2d correction 1e300": edited(dwt2d, rb"\ncorrection [^\n]*\n", b"\ncorrection 1e300\n"),
        "dwt2d steps 1e300": edited(dwt2d, rb"\nsteps [^\n]*\n", b"\nsteps 1e300 1e300\n"),
        "dwt2d origin 1e300": edited(dwt2d, rb"\norigin [^\n]*\n", b"\norigin 1e300 0\n"),
        "dwt2d 8.0 correction 1e300": compact_edited(compact, "correction", ["1e300"]),
        "dwt2d 8.0 steps 1e300": compact_edited(compact, "steps", ["1e300", "1e300"]),
        "dwt2d 8.0 origin 1e300": compact_edited(compact, "origin", ["1e300", "0"]),
        "dct coefficient 1e308": coefficient_set(dct, b"1e308"),
        "dct coefficient 1e200": coefficient_set(dct, b"1e200"),
        "dct transform shift 1e300": edited(dct, rb"\norigin [^\n]*\n", b"\norigin 0 0\ntransform 1 0 0 1e300 0 1 0 0 "
                                                                          b"0 0 1 0\n"),
        "raw heights 1e299": raw.split(b"\ndata\n")[0] + b"\ndata\n" + huge,
        "plain heights 1e299": b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\ndata\n1 1e299\n",
        "plain origin 1e300": b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\norigin 1e300 0\ndata\n1 2\n",
    }


BEYOND = beyond_the_limit()


@pytest.mark.parametrize("name", BEYOND)
def test_a_file_beyond_the_limit_is_refused_by_every_reader(name, tmp_path):
    data = BEYOND[name]
    if name.startswith("raw"):
        data = edited(data, rb"\ndata\n", b"\ndata\n")
    path = tmp_path / "big.mzc"
    path.write_bytes(data)
    for command in (["decode"], ["densify", "-n", "1"], ["triangulate"], ["diff", path], ["info", "--decode"]):
        result = kept_promises(run(*command, path))
        assert result.status == 1 and "big.mzc" in result.stderr[0] and " reach " in result.stderr[0], result.stderr
    import mzc

    with pytest.raises(mzc.MzcError, match="reach"):
        mzc.decode(data)
    with pytest.raises(mzc.MzcError, match="reach"):
        mzc.read(path)


def test_a_legacy_file_beyond_the_limit_is_refused():
    data = b"1 1 1 4 100\n1 4 1e200 0 0 0\n"
    result = kept_promises(run("decode", "--legacy", "dct", stdin=data))
    assert result.status == 1 and "heights reach" in result.stderr[0], result.stderr


@pytest.mark.parametrize("corner", ["xllcorner 1e300\nyllcorner 0", "xllcorner 0\nyllcorner -1e150"])
def test_a_raster_beyond_the_limit_is_refused(tmp_path, corner):
    path = tmp_path / "far.asc"
    path.write_text(f"ncols 2\nnrows 2\n{corner}\ncellsize 1\n1 2\n3 4\n")
    for command in (["slice", path], ["diff", path, path]):
        result = kept_promises(run(*command))
        assert result.status == 1 and "far.asc" in result.stderr[0] and "coordinates reach" in result.stderr[0]


@pytest.mark.parametrize("file_name", ["g.zg", "g.asc", "g.tif"])
def test_writers_refuse_what_no_reader_takes_back(tmp_path, file_name):
    import mzc

    grid = bump_grid()
    for bad in (grid.with_z(grid.z * 1e300), grid.with_z(grid.z, origin=(1e120, 0))):
        with pytest.raises(mzc.MzcError, match="reach"):
            mzc.write(tmp_path / file_name, bad)
    assert not list(tmp_path.iterdir())


def test_a_lossy_file_whose_decoded_heights_would_pass_the_limit_is_not_written():
    """Heights of 1e100 (the limit) coded by a DCT at quality 50 decode to 1.7e100: the encoder
    refuses the file that every reader would refuse, rather than write it."""
    import mzc

    z = np.random.default_rng(1).choice([-1e100, 1e100], size=(20, 50))
    with pytest.raises(mzc.MzcError, match="decoded heights reach"):
        mzc.encode(z, "dct", quality=50)
    back = mzc.decode(mzc.encode(z / 10, "dct", quality=100))
    assert np.abs(back.z).max() <= 1e100


# --- 7. text files padded with NUL bytes -----------------------------------------------------

def text_files():
    """name -> valid bytes of every text format mzc reads."""
    import mzc
    from mzc.formats import zgrid
    from mzc.meshes import mesh_to_bytes
    from mzc.rasters import asc

    mesh = mzc.Mesh([[0, 0, 0], [1, 0, 0.5], [0, 1, 1], [1, 1, 0.25]], [[0, 1, 2], [1, 3, 2]])
    grid = bump_grid()
    ply = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           b"element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0.5\n0 1 1\n"
           b"1 1 0.25\n3 0 1 2\n3 1 3 2\n")
    pcd = (b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\nPOINTS 4\n"
           b"DATA ascii\n0 0 0\n1 0 0.5\n0 1 1\n1 1 0.25\n")
    return {"m.obj": mesh_to_bytes(mesh, "obj"), "m.ply": ply, "m.xyz": b"0 0 0\n1 0 0.5\n0 1 1\n1 1 0.25\n",
            "m.pcd": pcd, "m.stl": mesh_to_bytes(mesh, "stl"), "m.off": mesh_to_bytes(mesh, "off"),
            "g.asc": asc.write(grid), "g.zg": zgrid.write(grid), "dct-1.0.mzd": (FIXTURES / "dct-1.0.mzd").read_bytes()}


FIXTURES = Path(__file__).parent / "fixtures"
TEXT_FILES = text_files()


@pytest.mark.parametrize("padding", [b"\0", b"\0" * 3, b"\n\0\0"], ids=["one NUL", "three", "newline and two"])
@pytest.mark.parametrize("name", TEXT_FILES)
def test_a_text_file_padded_with_nul_bytes_reads_as_without(tmp_path, name, padding):
    """LeePerrySmith.obj, a real head scan, ends with one NUL byte, and was refused."""
    import mzc

    plain, padded = tmp_path / name, tmp_path / f"padded-{name}"
    plain.write_bytes(TEXT_FILES[name])
    padded.write_bytes(TEXT_FILES[name] + padding)
    if name.endswith(".mzd"):
        plain_item, padded_item = (mzc.decode(path.read_bytes(), legacy=None) for path in (plain, padded))
    else:
        plain_item, padded_item = mzc.read(plain), mzc.read(padded)
    for field in ("points", "triangles", "z"):
        if hasattr(plain_item, field):
            np.testing.assert_array_equal(getattr(plain_item, field), getattr(padded_item, field))


def test_a_nul_inside_text_is_still_binary_data():
    data = TEXT_FILES["m.obj"]
    with pytest.raises(MzcError, match="NUL"):
        mesh_from_bytes(data[:20] + b"\0" + data[20:], "m.obj")


# --- 8. what the fuzz found (tests/test_fuzz_readers.py, tests/fuzz/) -------------------------

def test_a_laz_chunk_table_declaring_more_chunks_than_bytes_is_refused_not_aborted(tmp_path, mzc):
    """lazrs reserved room for 1.7e9 chunks (28 GB) of an 18 KB file and aborted the process
    with a Rust backtrace of 125 lines."""
    pytest.importorskip("laspy")
    data = bytearray((LAS / "simple.laz").read_bytes())
    table = struct.unpack_from("<q", data, struct.unpack_from("<I", data, 96)[0])[0]
    struct.pack_into("<I", data, table + 4, 1_748_356_570)
    path = tmp_path / "chunks.laz"
    path.write_bytes(bytes(data))
    result = mzc("slice", path)
    assert result.returncode == 1 and result.stderr.decode().count("\n") == 1, result.stderr[-300:]
    assert b"chunks.laz: the LAZ chunk table declares 1748356570 chunks" in result.stderr


@pytest.mark.parametrize("name, data", [
    ("m.off", b"OFF\n100000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
    ("m.off", b"OFF\n# a comment\n3 100000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
    ("m.vtk", b"# vtk DataFile Version 5.1\nm\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000 double\n"
              b"0 0 0 1 0 0 0 1 1\nCELLS 2 3\nOFFSETS vtktypeint64\n0\n3\nCONNECTIVITY vtktypeint64\n0\n1\n2\n"
              b"CELL_TYPES 1\n5\n")], ids=["OFF vertices", "OFF faces", "VTK points"])
def test_an_off_or_vtk_header_declaring_more_than_its_file_holds_is_refused_before_meshio(name, data):
    """meshio allocated what the header declared first: 2.3 GB for a 50-byte file."""
    with traced() as peak:
        with pytest.raises(MzcError, match="header declares .* values, more than the file's .* bytes hold"):
            mesh_from_bytes(data, name)
    assert peak() < 10_000_000


def test_a_geotiff_without_a_geotransform_reads_without_a_warning():
    """rasterio warned (NotGeoreferencedWarning) as the dataset opened, before the reader's filter."""
    pytest.importorskip("rasterio")
    import warnings

    from mzc.formats import read

    data = bytearray((LAS / "rasterio_float.tif").read_bytes())
    data[142] ^= 1   # the tag of the geotransform's pixel scale becomes another
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        grid = read(bytes(data), "plain.tif")
    assert grid.shape == (2, 3) and (grid.d1, grid.d2) == (1.0, 1.0)


def test_a_signalling_nan_in_a_float32_cloud_is_a_point_dropped_without_a_warning():
    import warnings

    header = (b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\nPOINTS 4\n"
              b"DATA binary\n")
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [9, 9, 9]], "<f4")
    points.view("<u4")[3, 0] = 0x7FA00000   # a signalling NaN
    ply = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
           b"property float z\nend_header\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(mesh_from_bytes(header + points.tobytes(), "m.pcd").points) == 3
        with pytest.raises(MzcError, match="vertex 4 has a NaN"):
            mesh_from_bytes(ply + points.tobytes(), "m.ply")


def test_a_transform_of_huge_entries_is_refused_without_an_overflow_warning():
    import warnings

    import mzc

    data = (b"mzc-zgrid 1.0\nrows 1\ncols 2\nd1 1\nd2 1\ntransform 1e308 0 0 0 0 1e308 0 0 0 0 1 0\ndata\n1 2\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(MzcError, match="not a rotation"):
            mzc.decode(data)


def test_a_geotiff_whose_crs_is_not_utf8_is_refused_in_one_line():
    """rasterio raised a UnicodeDecodeError as it opened the file: an internal error."""
    pytest.importorskip("rasterio")
    from mzc.formats import read

    data = (LAS / "rasterio_float_nodata.tif").read_bytes()
    at = data.index(b"unknown|")   # the GeoTIFF's citation of its CRS
    with pytest.raises(MzcError, match="crs.tif: not a readable GeoTIFF: 'utf-8' codec"):
        read(data[:at] + b"\xff" + data[at + 1:], "crs.tif")


def test_a_geotiff_of_a_signalling_nan_reads_it_as_no_data_without_a_warning():
    pytest.importorskip("rasterio")
    import warnings

    from affine import Affine
    from rasterio.io import MemoryFile

    from mzc.formats import read

    values = np.ones((1, 2, 3), "float32")
    values.view("<u4")[0, 0, 0] = 0x7FA00000
    with MemoryFile() as memory:
        with memory.open(driver="GTiff", width=3, height=2, count=1, dtype="float32",
                         transform=Affine(1, 0, 0, 0, -1, 2)) as dataset:
            dataset.write(values)
        data = memory.read()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read(data, "snan.tif").valid.sum() == 5


@pytest.mark.parametrize("scale", [1e80, 1e99])
def test_an_organised_cloud_far_out_is_triangulated_without_an_overflow(scale):
    """The lattice's depth-jump test takes fourth powers of the coordinates: past 1e77 they
    overflowed (a RuntimeWarning, and every edge a jump)."""
    import warnings

    y, x = np.mgrid[0:3, 0:4].astype(float)
    points = np.stack([x, y, np.full_like(x, 5.0)], axis=-1) * scale
    header = (b"VERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 3\nPOINTS 12\n"
              b"DATA binary\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(mesh_from_bytes(header + points.astype("<f8").tobytes(), "far.pcd").triangles) == 12
        with pytest.raises(MzcError, match="far.pcd:8: VIEWPOINT: coordinates reach 1e"):
            mesh_from_bytes(header.replace(b"POINTS", b"VIEWPOINT 0 1e308 0 1 0 0 0\nPOINTS")
                            + points.astype("<f8").tobytes(), "far.pcd")


def test_a_geotiff_whose_crs_gdal_cannot_parse_is_refused_in_one_line():
    """rasterio's CRSError (a ValueError, not a RasterioError) was an internal error."""
    pytest.importorskip("rasterio")
    from mzc.formats import read

    data = (LAS / "rasterio_float_nodata.tif").read_bytes()
    data = (data[:502] + b"\xff" * 8 + data[510:]).replace(b"GRS80", b"GRS-1")   # a NaN in the CRS's numbers
    with pytest.raises(MzcError, match="crs.tif: not a readable GeoTIFF: OGR Error"):
        read(data, "crs.tif")


def test_a_laz_extended_record_of_2_to_the_63_bytes_is_refused_in_one_line():
    """laspy asked its stream for 2^63 bytes: an OverflowError."""
    pytest.importorskip("laspy")
    data = bytearray((LAS / "1_4_w_evlr.laz").read_bytes())
    struct.pack_into("<Q", data, struct.unpack_from("<Q", data, 235)[0] + 20, 2**63)
    with pytest.raises(MzcError, match="evlr.laz: not a readable LAS/LAZ file"):
        mesh_from_bytes(bytes(data), "evlr.laz")


def test_a_blank_line_where_the_holes_section_starts_is_refused_in_one_line():
    """A line of spaces after a row codec's rows was a ValueError (nothing to unpack)."""
    import mzc

    from codec_contract import rechecksummed

    data = mzc.encode(np.arange(12.0).reshape(3, 4), "dft", quality=50)
    with pytest.raises(MzcError, match="expected 'holes COUNT'"):
        mzc.decode(rechecksummed(data + b"   \nholes 0\n"))


def test_a_laz_whose_chunk_table_makes_lazrs_panic_is_refused_in_one_line(tmp_path, mzc):
    """One byte of the chunk table's coded entries changed: lazrs panicked in Rust (capacity
    overflow), printed its message and backtrace on stderr, and the PanicException, a
    BaseException, came out as a Python traceback."""
    pytest.importorskip("laspy")
    data = bytearray((LAS / "1_4_w_evlr.laz").read_bytes())
    table = struct.unpack_from("<q", data, struct.unpack_from("<I", data, 96)[0])[0]
    data[table + 8] = 243
    path = tmp_path / "panic.laz"
    path.write_bytes(bytes(data))
    result = mzc("slice", path)
    assert result.returncode == 1 and result.stderr.decode().count("\n") == 1, result.stderr[-500:]
    assert b"panic.laz: truncated or damaged point data" in result.stderr
