"""The source's vertex count (issue 31): a sliced grid records how many vertices its mesh or cloud had,
the z-grid (1.2, 2.1, 3.2, 4.1, 5.2) and mzc-dwt2d 8.0 keep it, and the default rebuild comes back
near it, so a round trip gives back a mesh of the size that went in (spec/zgrid.md, Header lines)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mzc
from mzc.codecs import dwt2d
from mzc.codecs.dwt2d import compact
from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.grid import MAX_SOURCE_VERTICES, ZGrid

from conftest import face_path, run_mzc


@st.composite
def counted_grids(draw):
    rows, cols = draw(st.integers(2, 12)), draw(st.integers(2, 12))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    z = 20 + rng.normal(size=(rows, cols)).cumsum(axis=1)
    z[rng.random((rows, cols)) < 0.3] = np.nan
    z[0, 0] = 20.0
    central = draw(st.booleans())
    fields = {"projection": "cylindrical", "radius": 30.0} if central else {}
    count = draw(st.one_of(st.none(), st.integers(1, MAX_SOURCE_VERTICES)))
    return ZGrid(z, d1=0.5, d2=0.5, source_vertices=count, **fields)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(counted_grids(), st.sampled_from([None, "float64", "float32"]))
def test_the_count_survives_the_z_grid_and_leaves_other_grids_their_versions(grid, raw):
    data = zgrid.write(grid, raw=raw)
    major, minor = map(int, data.split(b"\n", 1)[0].split()[1].split(b"."))
    if grid.source_vertices is None:
        assert minor == 0   # byte for byte the version before the count
    else:
        assert (major, minor) in zgrid.COUNTED_SINCE.items()
    assert read_any(data, "t.zg").source_vertices == grid.source_vertices


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(counted_grids())
def test_the_count_survives_dwt2d_and_costs_its_field_alone(grid):
    data = mzc.encode(grid, "dwt2d", max_error=0.1)
    decoded = dwt2d.read(data)
    assert data.startswith(b"mzc-dwt2d 10.0\n") and decoded.source_vertices == grid.source_vertices
    if grid.source_vertices is not None:   # at one step: the encoder's choice among steps weighs whole files
        def coded(g):
            return dwt2d.Prepared(g, dwt2d.DEFAULT_WAVELET, None, 1.0).encode(0.32, max_error=0.1)[0]

        counted, without = coded(grid), coded(grid.with_z(grid.z, source_vertices=None))
        assert len(counted) - len(without) <= 1 + 1 + 8   # the field's id, its count and a varint
        np.testing.assert_array_equal(dwt2d.read(counted).z, dwt2d.read(without).z)


def test_a_7_0_file_with_the_count_field_and_a_newer_minor_are_refused():
    data = dwt2d.encode_whole(ZGrid(np.arange(12.0).reshape(3, 4), 1.0, 1.0, source_vertices=99), max_error=0.1,
                              compact=dwt2d.FLIPS_VERSION)[0]   # 8.0's header section
    reader = compact.Reader(data, "t")
    reader.position += 1
    length = reader.varint()
    body, rest = data[reader.position:reader.position + length], data[reader.position + length + 4:]
    for magic, message in ((b"mzc-dwt2d 7.0\n", "unknown header field 23"), (b"mzc-dwt2d 8.1\n", "newer than")):
        with pytest.raises(MzcError, match=message):
            dwt2d.read(magic + compact.section(compact.HEADER, body, magic) + rest, "t")


@pytest.mark.parametrize("value", ["0", "-3", "9007199254740993", "1.5", "many"])
def test_a_bad_count_is_refused_naming_its_line(value):
    text = f"mzc-zgrid 1.2\nrows 1\ncols 2\nd1 1\nd2 1\nsource_vertices {value}\ndata\n1 2\n".encode()
    with pytest.raises(MzcError) as error:
        read_any(text, "hand.zg")
    assert error.value.field == "source_vertices" and error.value.line == 6
    older = read_any(text.replace(b"1.2", b"1.0", 1), "hand.zg")   # a 1.0 reader ignores the line
    assert older.source_vertices is None


def test_slicing_records_the_count_and_densify_and_windows_drop_it():
    mesh = mzc.sample("blob")
    grid = mzc.slice(mesh)
    assert grid.source_vertices == len(mesh.points) == 10242
    assert mzc.densify(grid, 1).source_vertices is None   # a denser rebuild was asked for
    assert mzc.decode(mzc.encode(grid), window=(0, 0, 10, 10)).source_vertices is None
    cloud = mzc.slice(np.asarray(mesh.points))
    assert cloud.source_vertices == len(mesh.points)


def test_the_row_codecs_leave_the_count_out():
    grid = mzc.slice(mzc.sample("blob"))
    assert mzc.decode(mzc.encode(grid, "dct", quality=50)).source_vertices is None


def test_a_round_trip_comes_back_near_the_size_that_went_in(tmp_path):
    """The README's pipeline without densify: the rebuild has about the sample's 10,242 vertices
    (not the grid's 180,000), at a whole-surface RMS within 1.2 times the full grid's."""
    blob, packed, rebuilt, full = (tmp_path / name for name in ("blob.obj", "blob.mzw2", "r.ply", "full.ply"))
    run_mzc("sample", "blob", "-o", blob, check=True)
    data = run_mzc("slice", blob, check=True).stdout
    run_mzc("encode", "--dwt2d", "--rmse", "0.05", "-o", packed, input=data, check=True)
    info = run_mzc("info", packed, check=True).stdout.decode()
    assert "format    mzc-dwt2d 10.0" in info and "source    10,242 vertices" in info
    grid = run_mzc("decode", packed, check=True).stdout
    done = run_mzc("triangulate", "-o", rebuilt, input=grid, check=True)
    assert done.stderr == b""
    run_mzc("triangulate", "--vertices", "all", "-o", full, input=grid, check=True)
    source, mesh, every = mzc.read(blob), mzc.read(rebuilt), mzc.read(full)
    assert abs(len(mesh.points) / len(source.points) - 1) < 0.2 and len(every.points) > 10 * len(source.points)
    assert mzc.compare(source, mesh)["surface_rms"] <= 1.2 * mzc.compare(source, every)["surface_rms"]


def test_a_face_comes_back_at_its_scans_size():
    """f18 (30,260 vertices; its grid has 81,319 valid nodes) through dwt2d at 0.05 mm."""
    original = mzc.read(face_path("f18.ply"))
    decoded = mzc.decode(mzc.encode(mzc.slice(original), rmse=0.05))
    rebuilt, every = mzc.triangulate(decoded), mzc.triangulate(decoded, vertices="all")
    assert decoded.source_vertices == len(original.points)
    assert abs(len(rebuilt.points) / len(original.points) - 1) < 0.2 < len(every.points) / len(original.points) - 1
    assert mzc.compare(original, rebuilt)["surface_rms"] <= 1.2 * mzc.compare(original, every)["surface_rms"]


def test_the_api_refuses_a_count_that_is_not_one():
    grid = mzc.slice(mzc.sample("blob"))
    with pytest.raises(MzcError, match="vertices"):
        mzc.triangulate(grid, vertices="most")
    with pytest.raises(MzcError, match="source_vertices"):
        ZGrid(np.zeros((2, 2)), 1.0, 1.0, source_vertices=0)


def test_the_worked_example_of_8_0_holds_its_count():
    from codec_contract import spec_examples

    (data, values, _name), = [case for case in spec_examples("dwt2d") if case[0].startswith(b"mzc-dwt2d 8.0\n")]
    grid = dwt2d.read(data)
    assert grid.source_vertices == 30204 and grid.shape == values.shape


def test_the_worked_example_of_a_z_grid_1_2_holds_its_count():
    from codec_contract import spec_examples

    (data, values, _name), = [case for case in spec_examples("zgrid") if case[0].startswith(b"mzc-zgrid 1.2\n")]
    grid = read_any(data, "spec")
    assert grid.source_vertices == 12 and grid.shape == values.shape
    assert read_any(data.replace(b"mzc-zgrid 1.2", b"mzc-zgrid 1.0", 1), "spec").source_vertices is None
