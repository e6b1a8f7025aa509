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
from mzc.limits import MAX_MAGNITUDE

from codec_contract import CHECKSUM_LINE, rechecksummed
from codec_contract import spec_examples as contract_examples

SPEC = Path(__file__).resolve().parents[1] / "spec" / "zgrid.md"


def spec_examples(_path):
    """(example bytes, expected array) pairs of the spec page's worked z-grid examples, plain
    and raw (codec_contract.spec_examples reads both kinds of block)."""
    examples = contract_examples("zgrid")
    assert len(examples) == 12
    return [(data, expected) for data, expected, _id in examples]


@pytest.mark.parametrize("example, expected", spec_examples(SPEC))
def test_spec_examples_decode_to_their_expected_values(example, expected):
    grid = read_any(example, "spec")
    np.testing.assert_array_equal(grid.z, expected)


def test_spec_colour_example_decodes_to_its_expected_colours():
    """The 5.0 example's colours are the bytes after its heights, three a node, row by row."""
    import codec_contract

    text = SPEC.read_text()
    found = re.findall(r"```mzc-example-hex\n([^`]*)```\s*```expected\n[^`]*```\s*```expected-colours\n([^`]*)```",
                       text)
    assert len(found) == 1
    example, colours = found[0]
    grid = read_any(codec_contract.example_bytes(example, True), "spec")
    expected = np.array([[int(v) for v in line.split()] for line in colours.strip().splitlines()])
    assert grid.colors.tolist() == expected.reshape(*grid.shape, 3).tolist()
    assert zgrid.write(grid, raw="float64") == codec_contract.example_bytes(example, True)   # byte for byte


def test_spec_fine_colour_example_decodes_to_its_expected_samples():
    """The 6.0 example's colour samples are the bytes after its heights, (rows - 1) 2 + 1 rows of
    (cols - 1) 2 + 1; the nodes' colours are every second sample, those of the 5.0 example."""
    import codec_contract

    found = re.findall(r"```mzc-example-hex\n([^`]*)```\s*```expected\n[^`]*```\s*```expected-fine-colours\n([^`]*)```",
                       SPEC.read_text())
    assert len(found) == 1
    example, colours = found[0]
    data = codec_contract.example_bytes(example, True)
    grid = read_any(data, "spec")
    expected = np.array([[int(v) for v in line.split()] for line in colours.strip().splitlines()])
    assert grid.colour_scale == 2 and grid.fine_colors.tolist() == expected.reshape(3, 5, 3).tolist()
    assert grid.colors.tolist() == [[[255, 0, 0], [0, 255, 0], [0, 0, 255]], [[128, 128, 128], [0, 0, 0], [255] * 3]]
    assert zgrid.write(grid, raw="float64") == data   # byte for byte


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
    z = draw(arrays(float, shape, elements=finite.filter(lambda v: v != -9999)))   # a valid value is never the marker
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
    (GOOD.replace(b"mzc-zgrid 1.0", b"mzc-zgrid 7.0"), "newer than this mzc reads", 1),
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


# --- the raw body (mzc-zgrid 3.0) ---------------------------------------------------------

any_float = st.floats(-MAX_MAGNITUDE, MAX_MAGNITUDE)   # ±0, subnormals, up to mzc.limits' ±1e100


@st.composite
def raw_grids(draw, elements=any_float):
    """Grids of any finite values (holes as NaN), any projection fields as grids() draws them."""
    grid = draw(grids())
    grid.z = draw(arrays(float, grid.shape, elements=elements))
    grid.z[draw(arrays(bool, grid.shape))] = np.nan
    return grid


def same_bits(a, b):
    """Equal arrays bit for bit, NaN where NaN (so -0 differs from 0, as a raw body keeps it)."""
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    assert a[~np.isnan(a)].tobytes() == b[~np.isnan(b)].tobytes()


@given(raw_grids())
@settings(max_examples=150, deadline=None)
def test_raw_round_trip_is_exact_bit_for_bit(grid):
    data = zgrid.write(grid, raw="float64")
    assert data.startswith(b"mzc-zgrid 3.0\n")
    back = zgrid.read(data, "t")
    same_bits(back.z, grid.z)
    assert (back.d1, back.d2, back.origin, back.units, back.nodata) == (
        grid.d1, grid.d2, grid.origin, grid.units, grid.nodata)
    np.testing.assert_array_equal(back.transform, grid.transform)
    assert len(data.split(b"\ndata\n", 1)[1]) == 8 * grid.z.size


@given(raw_grids(st.floats(-3e38, 3e38, allow_nan=False)))
@settings(max_examples=100, deadline=None)
def test_raw_float32_holds_each_value_rounded_to_the_nearest_float32(grid):
    data = zgrid.write(grid, raw="float32")
    assert len(data.split(b"\ndata\n", 1)[1]) == 4 * grid.z.size
    same_bits(zgrid.read(data, "t").z, grid.z.astype(np.float32).astype(np.float64))


def test_raw_float32_refuses_a_value_it_cannot_hold():
    with pytest.raises(MzcError, match="row 1, column 2, 1e\\+39, does not fit float32") as error:
        zgrid.write(ZGrid(np.array([[1.0, 1e39]]), 1.0, 1.0), raw="float32")
    assert error.value.field == "raw"


def test_raw_refuses_a_precision():
    with pytest.raises(MzcError, match="plain body") as error:
        zgrid.write(ZGrid(np.ones((1, 2)), 1.0, 1.0), precision=3, raw="float64")
    assert error.value.field == "precision"


def test_raw_writes_one_nan_and_reads_any_nan_as_invalid():
    data = zgrid.write(ZGrid(np.array([[np.nan, -np.nan, 1.0]]), 1.0, 1.0), raw="float64")
    header, body = data.split(b"\ndata\n", 1)
    assert body[:16] == bytes.fromhex("000000000000f87f") * 2
    odd_nans = bytes.fromhex("010000000000f07f") + bytes.fromhex("000000000000f8ff")   # signalling, negative
    back = zgrid.read(rechecksummed(header + b"\ndata\n" + odd_nans + body[16:]), "t")
    np.testing.assert_array_equal(np.isnan(back.z), [[True, True, False]])


RAW = zgrid.write(ZGrid(np.array([[1.0, 2.0, np.nan], [0.1, -0.0, 5e-324]]), 1.0, 1.0, units="mm"), raw="float64")


def test_raw_body_refuses_an_infinite_value():
    data = rechecksummed(RAW.replace(np.float64(2.0).tobytes(), np.float64(np.inf).tobytes()))
    with pytest.raises(MzcError, match="row 1, column 2 is infinite") as error:
        zgrid.read(data, "inf.zg")
    assert (error.value.source, error.value.field) == ("inf.zg", "data")


def damaged_raw():
    """RAW cut at every length past its header, padded, one byte flipped anywhere, its line ends
    converted to CRLF, and its crc32 line removed: (variant, what is wrong)."""
    start = RAW.index(b"\ndata\n") + 6
    yield from ((RAW[:n], f"cut to {n}") for n in range(start, len(RAW)))
    yield RAW + b"\n", "padded with a newline"
    yield RAW + b"\x00" * 8, "padded with a value"
    yield from ((RAW[:i] + bytes([RAW[i] ^ 1]) + RAW[i + 1:], f"bit flipped at {i}") for i in range(len(RAW)))
    yield RAW.replace(b"\n", b"\r\n"), "CRLF"
    yield CHECKSUM_LINE.sub(b"", RAW), "without crc32"


@pytest.mark.parametrize("data, what", list(damaged_raw()), ids=lambda v: v if isinstance(v, str) else "")
def test_a_damaged_raw_body_is_a_one_line_error_naming_file_and_field_or_line(data, what):
    with pytest.raises(MzcError) as error:
        zgrid.read(data, "raw.zg")
    assert error.value.source == "raw.zg" and (error.value.field or error.value.line), what
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("body, cause", [(b"", "cut short"), (RAW.split(b"data\n", 1)[1] * 2, "with bytes added")],
                         ids=["cut", "padded"])
def test_the_body_length_is_checked_against_the_declared_sizes(body, cause):
    """Past a right checksum (a file made so on purpose), the length check still stands."""
    head = RAW.split(b"data\n", 1)[0] + b"data\n"
    with pytest.raises(MzcError, match=f"has {len(body)} bytes, but rows 2 x cols 3 of float64 take 48 \\({cause}") \
            as error:
        zgrid.read(rechecksummed(head + body), "len.zg")
    assert error.value.field == "data"


def test_a_huge_declared_raw_grid_is_refused_before_allocating(monkeypatch):
    allocations = []
    for name in ("empty", "frombuffer", "zeros"):
        real = getattr(np, name)
        monkeypatch.setattr(np, name, lambda *a, real=real, **k: allocations.append(a) or real(*a, **k))
    forged = rechecksummed(RAW.replace(b"rows 2\ncols 3", b"rows 10000\ncols 10000"))
    with pytest.raises(MzcError, match="take 800000000"):
        zgrid.read(forged, "big.zg")
    assert allocations == []


def test_a_raw_body_labelled_as_a_text_version_is_refused_not_misread():
    """An older reader ignores the raw line; this reader, reading the file as 2.0 does, refuses
    the binary rows (3.0 exists so that a 2.0 reader refuses it by its version instead)."""
    with pytest.raises(MzcError):
        zgrid.read(rechecksummed(RAW.replace(b"mzc-zgrid 3.0", b"mzc-zgrid 2.0")), "old.zg")


def test_a_raw_body_without_its_raw_line_or_with_an_unknown_type_is_refused():
    for line, message in [(b"", "required header line missing"), (b"raw float16\n", "'float16' is not one of")]:
        with pytest.raises(MzcError, match=message) as error:
            zgrid.read(rechecksummed(RAW.replace(b"raw float64\n", line)), "t.zg")
        assert error.value.field == "raw"


def test_plain_writing_is_unchanged_by_the_raw_body():
    """The plain writer is the default of the format module, byte for byte as 1.0 and 2.0 were."""
    assert zgrid.write(zgrid.read(RAW, "t")) == (
        b"mzc-zgrid 1.0\nrows 2\ncols 3\nd1 1\nd2 1\norigin 0 0\nunits mm\nnodata nan\ndata\n"
        b"1 2 nan\n0.1 -0 5e-324\n")
