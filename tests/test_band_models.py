"""mzc-dwt2d 10.1 (spec/dwt2d.md, Version 10.1): each detail band's own models where that makes the file
smaller (a large DEM's), the same integers and heights as the 10.0 file of the grid, 10.0 kept byte for byte
where the shared models win (a face at an RMS target), and the new header field read strictly."""

import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_dwt2d import spec_examples
from test_dwt2d_compact import face_grid, small_grids

import mzc
from mzc.codecs import dwt2d
from mzc.codecs.dwt2d import compact
from mzc.codecs.dwt2d.entropy import read_varint, varint
from mzc.errors import MzcError
from mzc.grid import ZGrid

from codec_contract import fixture_bytes
from conftest import run_mzc


def with_band_models(grid, choice, **options):
    """The file ``dwt2d.write`` makes of ``grid`` when its encoder takes band models or not (``choice``)."""
    original = dwt2d.Prepared.payload
    dwt2d.Prepared.payload = lambda self, *args: original(self, *args[:4], band_models=choice)
    try:
        return dwt2d.write(grid, **options)
    finally:
        dwt2d.Prepared.payload = original


def header_span(data):
    """(start, end) of a 10.x file's header fields (after the varint of their length)."""
    start = len(compact.magic_line((10, 0)))
    length, position = read_varint(data, start, len(data), 5, ValueError)
    return position, position + length


def rechecked(body):
    """``body`` (a 10.x file without its CRC-32) with its CRC-32."""
    return body + compact.CRC.pack(zlib.crc32(body))


def test_the_spec_examples_of_10_0_and_10_1_are_one_grid_at_one_step_in_each_layout(harmonic_fill):
    """The 3.0 example's input on its sphere, coded at the 10.0 example's steps (by the encoder of the
    examples' day, ``harmonic_fill``): the shared layout is the 10.0 example byte for byte, band models
    the 10.1 example, and both decode to the same heights."""
    *_older, (tight, heights), (band_models, same_heights) = spec_examples()
    z = np.array([[10, 10.5, 11, 11.2, 11.1, 10.8], [10.2, 10.9, 11.6, 11.9, 11.7, 11],
                  [10.1, 10.8, np.nan, 12.1, 11.8, 11.1], [9.8, 10.3, 10.9, 11.3, 11.2, 10.7]])
    grid = ZGrid(z=z, d1=0.5, d2=0.5, origin=(-1.25, -0.75), projection="spherical", radius=10.0, units="mm",
                 source_vertices=30204)
    prepared = dwt2d.Prepared(grid, "bior4.4", 1, 2.0)
    assert prepared.encode(0.16, max_error=0.05)[0] == tight   # left to choose: 10.0
    assert prepared.encode(0.16, max_error=0.05, band_models=True)[0] == band_models
    np.testing.assert_array_equal(heights, same_heights)
    np.testing.assert_array_equal(dwt2d.read(tight).z, dwt2d.read(band_models).z)


@pytest.fixture(scope="module")
def jacksboro():
    return mzc.slice(mzc.sample("jacksboro"))


def test_a_large_dem_is_smaller_with_band_models_and_decodes_to_the_same_heights(jacksboro):
    """Measured: 49,473 bytes where 10.0 takes 52,042 (4.9% smaller) at rmse 1 m, the same heights."""
    data = dwt2d.write(jacksboro, rmse=1.0)
    shared = with_band_models(jacksboro, False, rmse=1.0)
    assert data.startswith(b"mzc-dwt2d 10.1\n") and shared.startswith(b"mzc-dwt2d 10.0\n")
    assert len(data) <= 0.97 * len(shared)
    np.testing.assert_array_equal(dwt2d.read(data).z, dwt2d.read(shared).z)   # the search's step alike


@pytest.mark.parametrize("name", ["f18.ply", "m56.ply"])
def test_faces_at_an_rms_target_keep_their_10_0_file_byte_for_byte(name):
    grid = face_grid(name)
    for rmse in (0.05, 0.2):
        data = dwt2d.write(grid, rmse=rmse)
        assert data.startswith(b"mzc-dwt2d 10.0\n")
        assert data == with_band_models(grid, False, rmse=rmse)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_grids(), st.sampled_from([0.01, 0.2, 3.0]), st.sampled_from([None, 0.05]), st.sampled_from([1, 2]))
def test_at_a_step_the_encoder_writes_the_cheaper_layout_of_the_same_integers(grid, step, max_error, level):
    """The choice (estimated from the class counts, then held to the shared models' bytes) is one of the
    two files and never larger than the 10.0 file of the same integers, which decode alike."""
    prepared = dwt2d.Prepared(grid, "bior4.4", level, 2.0)
    chosen = prepared.encode(step, max_error=max_error)[0]
    shared, own = (prepared.encode(step, max_error=max_error, band_models=choice)[0] for choice in (False, True))
    assert shared.startswith(b"mzc-dwt2d 10.0\n") and own.startswith(b"mzc-dwt2d 10.1\n")
    assert chosen == shared or chosen == own and len(own) < len(shared)
    np.testing.assert_array_equal(dwt2d.read(shared).z, dwt2d.read(own).z)


def with_band_models_field(minor, value):
    """The 10.0 fixture with the field band_models ``value`` added to its header fields, as version 10.``minor``."""
    body = fixture_bytes("dwt2d-10.0.mzw2")[:-compact.CRC.size]
    start, end = header_span(body)
    present, after = read_varint(body, start, end, 10, ValueError)
    fields = varint(present | 1 << 23) + body[after:end] + varint(value)
    return rechecked(compact.magic_line((10, minor)) + varint(len(fields)) + fields + body[end:])


def test_a_10_0_file_with_the_band_models_bit_is_refused():
    """Place 23 of the presence bits is 10.1's: a 10.0 file that sets it is refused, not misread."""
    with pytest.raises(MzcError, match="unknown header field"):
        dwt2d.read(with_band_models_field(0, 1), "t")


@pytest.mark.parametrize("value", [0, 2, 127])
def test_a_band_models_value_other_than_1_is_refused(value):
    body = bytearray(fixture_bytes("dwt2d-10.1.mzw2")[:-compact.CRC.size])
    _start, end = header_span(bytes(body))
    assert body[end - 1] == 1   # band_models, the last field
    body[end - 1] = value
    with pytest.raises(MzcError, match="band_models"):
        dwt2d.read(rechecked(bytes(body)), "t")
    with pytest.raises(MzcError, match="band_models"):
        dwt2d.read(with_band_models_field(1, value), "t")


def test_the_fixture_shows_its_band_models_in_info(tmp_path):
    path = tmp_path / "a.mzw2"
    path.write_bytes(fixture_bytes("dwt2d-10.1.mzw2"))
    lines = run_mzc("info", path, check=True).stdout.decode().splitlines()
    assert "format    mzc-dwt2d 10.1" in lines and "  band_models 1" in lines and "  levels 2" in lines


def test_an_older_container_refuses_the_band_models_field():
    """Field 24 is 10.1's: the sectioned header of a 7.0-9.0 file that holds it is refused."""
    lines = ["rows 2", "cols 2", "d1 1", "steps 1", "band_models 1"]
    header = compact.section(compact.HEADER, b"".join(compact.field_bytes(line) for line in lines),
                             compact.magic_line((8, 0)))
    with pytest.raises(MzcError, match="unknown header field 24"):
        compact.Reader(compact.magic_line((8, 0)) + header, "t").header()
