"""The z-grid format: the spec's examples, round trips, and every rejection the spec names."""

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mzc.errors import MzcError
from mzc.formats import read_any, zgrid
from mzc.grid import ZGrid

SPEC = Path(__file__).resolve().parents[1] / "spec" / "zgrid.md"


def spec_examples(path):
    """(example bytes, expected array) pairs from a spec page's fenced blocks."""
    text = path.read_text()
    examples = re.findall(r"```mzc-example\n(.*?)```", text, re.S)
    expected = re.findall(r"```expected\n(.*?)```", text, re.S)
    assert examples and len(examples) == len(expected)
    return [(e.encode(), np.array([[float(v) for v in line.split()] for line in x.strip().splitlines()]))
            for e, x in zip(examples, expected)]


@pytest.mark.parametrize("example, expected", spec_examples(SPEC))
def test_spec_examples_decode_to_their_expected_values(example, expected):
    grid = read_any(example, "spec")
    np.testing.assert_array_equal(grid.z, expected)


def spec_points(path):
    """(example bytes, rows of 'row col x y z') of the examples followed by an expected-points block."""
    blocks = re.findall(r"```mzc-example\n([^`]*)```\s*```expected\n[^`]*```\s*```expected-points\n([^`]*)```",
                        path.read_text())
    assert len(blocks) == 3
    return [(e.encode(), np.array([[float(v) for v in line.split()] for line in p.strip().splitlines()]))
            for e, p in blocks]


@pytest.mark.parametrize("example, points", spec_points(SPEC))
def test_spec_projection_examples_place_their_nodes(example, points):
    grid = read_any(example, "spec")
    placed = grid.to_input_frame(grid.node_points())
    for row, col, *xyz in points:
        np.testing.assert_allclose(placed[int(row), int(col)], xyz, atol=1e-9)


def test_spec_transform_example_maps_grid_x_to_input_y():
    example, _ = spec_examples(SPEC)[1]
    grid = zgrid.read(example, "spec")
    np.testing.assert_allclose(grid.to_input_frame(np.array([1.0, 0, 0])), [5, 1, 100])
    assert grid.nodata == "-9999"


finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@st.composite
def grids(draw):
    shape = draw(st.tuples(st.integers(1, 12), st.integers(1, 12)))
    z = draw(arrays(float, shape, elements=finite))
    holes = draw(arrays(bool, shape))
    z[holes] = np.nan
    angle = draw(st.floats(-np.pi, np.pi))
    c, s = np.cos(angle), np.sin(angle)
    transform = np.array([[c, -s, 0, draw(finite)], [s, c, 0, draw(finite)], [0, 0, 1, draw(finite)]])
    return ZGrid(z, draw(st.floats(1e-3, 1e3)), draw(st.floats(1e-3, 1e3)),
                 origin=(draw(finite), draw(finite)), transform=transform,
                 units=draw(st.sampled_from([None, "mm", "m"])),
                 nodata=draw(st.sampled_from(["nan", "-9999", "NA"])))


@given(grids())
@settings(max_examples=150, deadline=None)
def test_round_trip_is_exact(grid):
    back = zgrid.read(zgrid.write(grid), "t")
    np.testing.assert_array_equal(back.z, grid.z)
    assert (back.d1, back.d2, back.origin, back.units, back.nodata) == (
        grid.d1, grid.d2, grid.origin, grid.units, grid.nodata)
    np.testing.assert_array_equal(back.transform, grid.transform)


@given(grids(), st.integers(0, 6))
@settings(max_examples=60, deadline=None)
def test_precision_rounds_to_the_given_decimals(grid, digits):
    back = zgrid.read(zgrid.write(grid, precision=digits), "t")
    np.testing.assert_array_equal(np.isnan(back.z), np.isnan(grid.z))
    assert np.nanmax(np.abs(back.z - grid.z), initial=0) <= 0.5 * 10.0**-digits * (1 + 1e-9) + 1e-9


@given(st.binary(max_size=300))
@settings(max_examples=300, deadline=None, derandomize=True)
def test_arbitrary_bytes_never_escape_as_anything_but_mzc_errors(data):
    try:
        zgrid.read(b"mzc-zgrid 1.0\n" + data, "fuzz")
    except MzcError:
        pass


GOOD = b"mzc-zgrid 1.0\nrows 2\ncols 2\nd1 1\nd2 1\ndata\n1 2\n3 4\n"


@pytest.mark.parametrize("data, message, line", [
    (b"rows 2\n", "missing magic", 1),
    (b"", "missing magic", 1),
    (GOOD.replace(b"mzc-zgrid 1.0", b"mzc-zgrid 3.0"), "newer than this mzc reads", 1),
    (GOOD.replace(b"mzc-zgrid 1.0", b"mzc-zgrid one"), "bad version", 1),
    (GOOD.replace(b"mzc-zgrid", b"mzc-other"), "expected an mzc-zgrid file", 1),
    (GOOD.replace(b"d2 1\n", b""), "required header line missing", None),
    (GOOD.replace(b"rows 2", b"rows 3"), "header says rows 3", 9),
    (GOOD.replace(b"rows 2", b"rows 1"), "header says rows 1", 8),
    (GOOD.replace(b"3 4", b"3 4 5"), "header says cols 2", 8),
    (GOOD.replace(b"3 4", b"3"), "header says cols 2", 8),
    (GOOD.replace(b"3 4", b"3 x4"), "value 2 is not a number", 8),
    (GOOD.replace(b"3 4", b"3 inf"), "value 2 is infinite", 8),
    (GOOD.replace(b"d1 1", b"d1 -1"), "must be > 0", 4),
    (GOOD.replace(b"d1 1", b"d1 nan"), "must be finite", 4),
    (GOOD.replace(b"rows 2", b"rows two"), "not an integer", 2),
    (GOOD.replace(b"rows 2\ncols 2", b"rows 100000\ncols 100000"), "too large", 3),
    (GOOD.replace(b"rows 2", b"rows 99999999999"), "outside", 2),
    (GOOD.replace(b"d2 1\n", b"d2 1\nd2 1\n"), "given twice", 6),
    (GOOD.replace(b"d2 1\n", b"d2 1\ntransform 2 0 0 0 0 1 0 0 0 0 1 0\n"), "not a rotation", 6),
    (GOOD.replace(b"d2 1\n", b"d2 1\ntransform 1 0 0\n"), "expected 12 value", 6),
    (GOOD.replace(b"data\n", b""), "without a 'data' line", None),
    (GOOD.replace(b"1 2", b"1 \xff"), "not UTF-8", 7),
])
def test_bad_files_are_rejected_with_line_and_reason(data, message, line):
    with pytest.raises(MzcError) as caught:
        zgrid.read(data, "bad.zg")
    assert message in str(caught.value)
    assert str(caught.value).startswith("bad.zg")
    if line is not None:
        assert caught.value.line == line


def test_declared_size_is_refused_before_allocating(monkeypatch):
    allocations = []
    real_empty = np.empty
    monkeypatch.setattr(np, "empty", lambda *a, **k: allocations.append(a) or real_empty(*a, **k))
    with pytest.raises(MzcError):
        zgrid.read(GOOD.replace(b"rows 2\ncols 2", b"rows 1000000\ncols 1000000"), "big")
    assert allocations == []


def test_unknown_header_lines_and_comments_are_ignored():
    data = GOOD.replace(b"d1 1\n", b"d1 1\n# a comment\nfuture-field 1 2 3\n\n")
    np.testing.assert_array_equal(zgrid.read(data, "t").z, [[1, 2], [3, 4]])


def test_crlf_line_ends_are_read():
    np.testing.assert_array_equal(zgrid.read(GOOD.replace(b"\n", b"\r\n"), "t").z, [[1, 2], [3, 4]])


def test_writer_numbers_are_compact():
    text = zgrid.write(ZGrid(np.array([[1.0, 2.5, np.nan]]), 3.0, 0.25)).decode()
    assert "d1 3\n" in text and text.endswith("data\n1 2.5 nan\n")


@pytest.mark.parametrize("version", [b"+1.0", b"0_1.0", b"1", b"1.0.0", b"1.x"])
def test_a_version_that_is_not_major_dot_minor_is_refused(version):
    with pytest.raises(MzcError, match="bad version") as error:
        zgrid.read(b"mzc-zgrid " + version + b"\nrows 1\ncols 1\nd1 1\nd2 1\ndata\n1\n", "v.zg")
    assert error.value.line == 1


def test_a_central_grid_that_cannot_exist_is_refused_when_built():
    with pytest.raises(ValueError, match="full turn"):
        ZGrid(np.zeros((2, 10)), 1.0, 1.0, projection="cylindrical", radius=1.0)
    with pytest.raises(ValueError, match="poles"):
        ZGrid(np.zeros((3, 2)), 1.0, 0.1, origin=(0, 1.0), projection="spherical", radius=1.0)
