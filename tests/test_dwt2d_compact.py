"""mzc-dwt2d 7.0 (spec/dwt2d.md, Version 7.0): binary header fields, tagged sections under CRC-32s and
parametric model tables decode to exactly what 3.x decodes from the same integers, cost less on
the faces, and every damaged file is refused in one line."""

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mzc.codecs import dwt2d
from mzc.codecs.dwt2d import compact
from mzc.codecs.dwt2d import entropy as en
from mzc.codecs.dwt2d.anatomy import parts
from mzc.errors import MzcError
from mzc.formats.header import format_number
from mzc.grid import ZGrid

from codec_contract import fixture_bytes
from conftest import run_mzc

FACES = Path(__file__).resolve().parents[2] / "shared" / "data" / "faces"


def both_versions(grid, step, max_error=None, levels=None, wavelet="bior4.4", slope_limit=2.0):
    """(7.0 bytes, the 3.x/4.0/6.0 bytes) of ``grid`` coded at one step: the same integers."""
    prepared = dwt2d.Prepared(grid, wavelet, levels, slope_limit, compact=dwt2d.COMPACT_VERSION)
    new = prepared.encode(step, max_error=max_error)[0]
    prepared.compact = False
    return new, prepared.encode(step, max_error=max_error)[0]


def face_grid(name):
    if not (FACES / name).exists():
        pytest.skip("shared faces absent")
    import mzc

    return mzc.slice(str(FACES / name))


@pytest.mark.parametrize("name", ["f18.ply", "m56.ply"])
def test_faces_decode_to_the_same_values_in_7_0_and_3_1_and_cost_less(name):
    grid = face_grid(name)
    for step in (0.3, 1.5, 7.0):
        new, old = both_versions(grid, step)
        assert new.startswith(b"mzc-dwt2d 7.0\n") and old.startswith(b"mzc-dwt2d 3.1\n")
        a, b = dwt2d.read(new), dwt2d.read(old)
        assert a.source_vertices is None is b.source_vertices   # a field of 8.0's, which neither has
        np.testing.assert_array_equal(a.z, b.z)
        np.testing.assert_array_equal(a.transform, b.transform)
        assert (a.d1, a.d2, a.origin, a.projection, a.radius) == (b.d1, b.d2, b.origin, b.projection, b.radius)
        split_new, split_old = parts(new), parts(old)
        assert sum(split_new.values()) == len(new) and sum(split_old.values()) == len(old)
        assert split_new["header"] <= split_old["header"] / 1.9   # measured: 108 against 215 on f18
        assert split_new["tables"] < split_old["tables"]
        assert len(new) < len(old)


@st.composite
def small_grids(draw):
    rows, cols = draw(st.integers(1, 20)), draw(st.integers(1, 20))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    z = 50 + rng.normal(scale=draw(st.sampled_from([0.01, 1.0, 10.0])), size=(rows, cols)).cumsum(axis=0)
    z[rng.random((rows, cols)) < draw(st.floats(0, 0.6))] = np.nan
    central = draw(st.sampled_from([None, "cylindrical", "spherical"]))
    fields = {"projection": central, "radius": 60.0} if central else {}
    if central == "spherical":
        fields["origin"] = (0.0, -0.5 * rows * 0.25)
    return ZGrid(z=z, d1=0.25, d2=draw(st.sampled_from([0.25, 1 / 3])), units=draw(st.sampled_from([None, "mm"])),
                 **fields)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_grids(), st.sampled_from([0.01, 0.2, 3.0]), st.sampled_from([None, 0.05]),
       st.sampled_from([None, 0, 1, 2]), st.sampled_from(["bior4.4", "bior2.2"]))
def test_random_grids_decode_alike_in_7_0_and_the_text_versions(grid, step, max_error, levels, wavelet):
    new, old = both_versions(grid, step, max_error, levels, wavelet)
    a, b = dwt2d.read(new), dwt2d.read(old)
    np.testing.assert_array_equal(a.z, b.z)
    text_keywords = {line.split()[0] for line in old.split(b"\ndata\n")[0].decode().splitlines()[1:]}
    assert set(compact.read(new, "t")[0].fields) == text_keywords - {"crc32"}


finite = st.floats(allow_nan=False, allow_infinity=False)


@given(finite)
def test_decimals_read_back_as_the_same_binary64(value):
    word = format_number(value)
    reader = compact.Reader(b"m\n" + compact.decimal_bytes(word), "t")
    assert reader.decimal(len(reader.data)) == word and reader.position == len(reader.data)
    assert float(word) == value or (value == 0 and float(word) == 0)


@given(st.integers(2, en.MAX_CLASSES), st.integers(0, 255), st.integers(0, 255))
def test_parametric_tables_are_tables(size, zero, ratio):
    freq = en.parametric_table(size, zero, ratio)
    assert len(freq) == size and freq.min() >= 1 and int(freq.sum()) == 1 << en.TABLE_BITS


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 30), st.lists(st.integers(-300, 300), min_size=1, max_size=40)),
                min_size=1, max_size=10))
def test_parametric_payloads_decode_exactly(runs):
    """Integers of many models through 7.0's table records (parametric, weight codes or repeats)."""
    encoder = en.Encoder(parametric=True)
    for model, values in runs:
        encoder.add(model, values)
    decoder = en.Decoder(encoder.finish(), "t", parametric=True)
    assert [decoder.read(model, len(values)).tolist() for model, values in runs] == [values for _, values in runs]
    decoder.check_end()


def test_the_fixture_shows_its_fields_as_text_lines_in_info(tmp_path):
    path = tmp_path / "a.mzw2"
    path.write_bytes(fixture_bytes("dwt2d-7.0.mzw2"))
    lines = run_mzc("info", path, check=True).stdout.decode().splitlines()
    assert "format    mzc-dwt2d 7.0" in lines
    for line in ("  raster area down int16", "  rounding integer", "  nodata -32768", "  max_error 2",
                 "  slope_limit 1", "  levels 1"):
        assert line in lines
    assert any(line.startswith('  crs GEOGCS["WGS 84"') for line in lines)


def damaged_variants(data):
    """Cuts at every length, every byte changed, bytes added."""
    yield from (data[:n] for n in range(len(data)))
    for at in range(len(data)):
        yield data[:at] + bytes([data[at] ^ 0x5A]) + data[at + 1:]
    yield data + b"\0"
    yield data + data


def test_every_damaged_7_0_file_is_refused():
    data = fixture_bytes("dwt2d-7.0.mzw2")
    for variant in damaged_variants(data):
        with pytest.raises(MzcError):
            dwt2d.read(variant, "bad.mzw2")


@pytest.mark.parametrize("cut", [14, 40, 200, -1])
def test_the_command_line_refuses_a_damaged_file_in_one_line(tmp_path, cut):
    data = fixture_bytes("dwt2d-7.0.mzw2")
    bad = tmp_path / "bad.mzw2"
    bad.write_bytes(data[:cut] if cut > 0 else data[:100] + bytes([data[100] ^ 1]) + data[101:])
    out = tmp_path / "out.zg"
    run = run_mzc("decode", bad, "-o", out)
    stderr = run.stderr.decode()
    assert run.returncode == 1 and not out.exists()
    assert len(stderr.splitlines()) == 1 and "bad.mzw2" in stderr and "Traceback" not in stderr


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.data())
def test_damaged_headers_with_matching_checksums_raise_only_mzc_errors(data):
    """Header sections with bytes changed and their CRC-32 recomputed reach the field reader: a grid
    or an MzcError, never another exception."""
    original = fixture_bytes("dwt2d-7.0.mzw2")
    reader = compact.Reader(original, "t")
    reader.position += 1   # the header section's tag
    length = reader.varint()
    body = bytearray(original[reader.position:reader.position + length])
    rest = original[reader.position + length + compact.CRC.size:]
    for _ in range(data.draw(st.integers(1, 4))):
        body[data.draw(st.integers(0, len(body) - 1))] = data.draw(st.integers(0, 255))
    if data.draw(st.booleans()):
        body = body[: data.draw(st.integers(0, len(body)))]
    head = compact.section(compact.HEADER, bytes(body), compact.MAGIC)
    try:
        decoded = dwt2d.read(compact.MAGIC + head + rest, "t")
    except MzcError:
        return
    assert np.isfinite(decoded.z[decoded.valid]).all() and math.isfinite(decoded.d1)


def test_spec_colour_example_decodes_to_its_expected_colours():
    """The worked example of 7.0 with colours: its heights are checked with every example
    (codec_contract.spec_examples); its colours are the expected-colours block, node by node, within
    its colour_max_error of the colours the spec states it coded."""
    import re

    from mzc.formats import read_any

    from codec_contract import REPO, example_bytes

    found = re.findall(r"```mzc-example-hex\n([^`]*)```\s*```expected\n[^`]*```\s*```expected-colours\n([^`]*)```",
                       (REPO / "spec" / "dwt2d.md").read_text())
    assert len(found) == 1
    example, colours = found[0]
    data = example_bytes(example, True)
    grid = read_any(data, "spec")
    expected = np.array([[int(v) for v in line.split()] for line in colours.strip().splitlines()])
    assert grid.colors.tolist() == expected.reshape(*grid.shape, 3).tolist()
    row, col = np.mgrid[0:4, 0:6]
    coded = np.stack([20 + 40 * col, 30 + 60 * row, 200 - 10 * col - 20 * row], axis=-1)
    assert np.abs(grid.colors.astype(int) - coded)[grid.valid].max() <= 2
    header, _payload, colour = compact.read(data, "spec")
    assert header.tokens("colour_max_error") == ["2"] and len(colour) == 118
