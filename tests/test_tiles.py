"""Tiled dwt2d files (mzc-dwt2d 5.0): a grid of any size as independent tiles behind a header and an
index. Round trips and windows (hypothesis, small tiles), the bound per tile and so over the grid,
the spec's worked example and the fixture, lying headers refused before any allocation, and the
command line: a GeoTIFF encoded window by window and decoded tile by tile into a GeoTIFF.
"""

import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.codecs.dwt2d import tiles
from mzc.codecs.dwt2d.tiles import Bytes, TiledFile
from mzc.errors import MzcError
from mzc.grid import ZGrid

from codec_contract import assert_heights, spec_examples
from conftest import run_mzc


def terrain(rows, cols, seed=0, holes=True):
    """A smooth field plus noise, a few invalid nodes: a DEM's kind of values."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:rows, 0:cols].astype(float)
    z = 20 * np.sin(c / 7.0) * np.cos(r / 5.0) + 0.3 * c + rng.normal(0, 0.05, (rows, cols))
    if holes:
        z[rng.random((rows, cols)) < 0.05] = np.nan
    return z


def grid_of(z, **fields):
    return ZGrid(z=z, d1=2.0, d2=1.5, origin=(100.0, -50.0), units="m", **fields)


@settings(max_examples=25, deadline=None)
@given(rows=st.integers(1, 40), cols=st.integers(1, 40), tile=st.integers(4, 16), seed=st.integers(0, 99),
       data=st.data())
def test_tiles_round_trip_within_the_bound_and_any_window_is_the_whole_decode_cut(rows, cols, tile, seed, data):
    z = terrain(rows, cols, seed)
    grid = grid_of(z)
    encoded = mzc.encode(grid, "dwt2d", max_error=0.05, tile=tile)
    assert encoded.startswith(b"mzc-dwt2d 5.0\n")
    whole = mzc.decode(encoded)
    assert whole.shape == (rows, cols) and (whole.d1, whole.d2, whole.origin, whole.units) == (2.0, 1.5,
                                                                                                (100.0, -50.0), "m")
    assert np.array_equal(np.isnan(whole.z), np.isnan(z))
    assert np.nanmax(np.abs(whole.z - z), initial=0) <= 0.05
    row, col = data.draw(st.integers(0, rows - 1)), data.draw(st.integers(0, cols - 1))
    window = (row, col, data.draw(st.integers(1, rows - row)), data.draw(st.integers(1, cols - col)))
    cut = mzc.decode(encoded, window=window)
    assert np.array_equal(cut.z, whole.z[row:row + window[2], col:col + window[3]], equal_nan=True)
    assert cut.origin == (100.0 + col * 1.5, -50.0 + row * 2.0)


def test_a_window_reads_only_the_tiles_it_touches():
    encoded = mzc.encode(grid_of(terrain(40, 40)), "dwt2d", max_error=0.05, tile=8)
    reads = []

    class Counting(Bytes):
        def read(self, offset, length):
            reads.append((offset, length))
            return super().read(offset, length)

    tiled = TiledFile(Counting(encoded), "counted")
    first_tile = int(tiled.offsets[0])
    reads.clear()
    tiled.window(9, 17, 6, 5)   # rows 9..14, columns 17..21: tile (1, 2) alone
    assert [(o, n) for o, n in reads if o >= first_tile] == [(int(tiled.offsets[7]), int(np.diff(tiled.offsets)[7]))]


def test_the_same_rms_target_per_tile_bounds_the_grid_and_size_is_refused():
    grid = grid_of(terrain(48, 40, holes=False))
    tiled = mzc.decode(mzc.encode(grid, "dwt2d", rmse=0.05, tile=16))
    flat_error = np.sqrt(np.mean((tiled.z - grid.z) ** 2))
    assert 0 < flat_error < 0.2   # the surface estimate weighs each value's error by cos(lean) <= 1
    with pytest.raises(MzcError, match="--size aims at one file's bytes"):
        mzc.encode(grid, "dwt2d", size=3000, tile=16)


def test_grids_up_to_one_tile_keep_their_bytes_and_larger_ones_are_tiled(monkeypatch):
    monkeypatch.setattr(tiles, "DEFAULT_TILE", 8)
    small, large = grid_of(terrain(8, 8)), grid_of(terrain(9, 8))
    assert mzc.encode(small, "dwt2d", max_error=0.05) == mzc.encode(small, "dwt2d", max_error=0.05, tile=0)
    assert mzc.encode(small, "dwt2d", max_error=0.05).startswith(b"mzc-dwt2d 10.0\n")   # coded whole: 10.0
    assert mzc.encode(large, "dwt2d", max_error=0.05) == mzc.encode(large, "dwt2d", max_error=0.05, tile=8)
    assert mzc.encode(large, "dwt2d", max_error=0.05, tile=0).startswith(b"mzc-dwt2d 10.0\n")


def test_the_worked_example_decodes_as_the_spec_says():
    examples = [case for case in spec_examples("dwt2d") if case[0].startswith(b"mzc-dwt2d 5.0")]
    assert examples
    for data, expected, _id in examples:
        assert_heights(mzc.decode(data).z, expected)
        tiled = TiledFile(Bytes(data), "example")
        assert (tiled.tile, tiled.counts) == (4, (1, 2))


# --- lying and damaged files --------------------------------------------------------------------


def made(rows=10, cols=9, tile=4):
    return mzc.encode(grid_of(terrain(rows, cols)), "dwt2d", max_error=0.05, tile=tile)


def with_header(data, *changes):
    """``data`` with header text changed (``changes``: pairs of old and new bytes) and its crc32 made
    right again: a file that lies."""
    head_end = data.index(b"\ndata\n") + 6
    head = data[:head_end]
    for old, new in changes:
        head = head.replace(old, new)
    head = b"".join(line for line in head.splitlines(keepends=True) if not line.startswith(b"crc32 "))
    at = head.index(b"\ndata\n") + 1
    head = head[:at] + b"crc32 %08x\n" % zlib.crc32(head) + head[at:]
    return head + data[head_end:]


@pytest.mark.parametrize(("changes", "message"), [
    ([(b"tiles 3 3", b"tiles 3 4")], "make 3 x 3 tiles, not 3 x 4"),
    ([(b"tile 4\n", b"tile 2\n")], "tile: 2 is outside 4..4096"),
    ([(b"rows 10", b"rows 1000000"), (b"tiles 3 3", b"tiles 250000 3")], "ends inside its index of 750000 tiles"),
    ([(b"rows 10", b"rows 1000000"), (b"cols 9", b"cols 1000000"), (b"tiles 3 3", b"tiles 250000 250000")],
     "at most 4194304"),
    ([(b"cols 9", b"cols 1000001")], "cols: 1000001 is outside"),
])
def test_a_lying_header_is_refused_before_anything_is_allocated(changes, message):
    with pytest.raises(MzcError, match=message):
        mzc.decode(with_header(made(), *changes))


def test_damage_anywhere_is_refused_in_one_line():
    data = made()
    tiled = TiledFile(Bytes(data), "good")
    index_at, first_tile = data.index(b"\ndata\n") + 6, int(tiled.offsets[0])
    for position, message in [(20, "checksum"), (index_at + 3, "index's checksum"), (first_tile + 40, "checksum"),
                              (len(data) - 1, "checksum")]:
        bad = data[:position] + bytes([data[position] ^ 0x21]) + data[position + 1:]
        with pytest.raises(MzcError, match=message):
            mzc.decode(bad)
    for bad in (data[:-1], data + b"\0", data[:index_at + 10]):
        with pytest.raises(MzcError, match="cut short|added to"):
            mzc.decode(bad)


def test_tiles_in_the_wrong_place_are_refused():
    data = made()
    tiled = TiledFile(Bytes(data), "good")
    lengths = np.diff(tiled.offsets)
    first, second = tiled.tile_bytes(0, 0), tiled.tile_bytes(0, 1)
    swapped_lengths = [int(lengths[1]), int(lengths[0]), *map(int, lengths[2:])]
    index = b"".join(struct.pack("<Q", n) for n in swapped_lengths)
    head_end = data.index(b"\ndata\n") + 6
    bad = (data[:head_end] + index + struct.pack("<I", zlib.crc32(index)) + second + first
           + data[int(tiled.offsets[2]):])
    with pytest.raises(MzcError, match="is not the block the header places there"):
        mzc.decode(bad)


def test_a_grid_too_large_to_hold_is_refused_with_the_ways_round_it():
    with pytest.raises(MzcError, match=r"decode --window.*--format tif"):
        tiles.check_window((12_000, 12_000), (0, 0, 12_000, 12_000))


# --- the command line: GeoTIFFs by windows ------------------------------------------------------


@pytest.fixture
def dem(tmp_path):
    """A 70 x 90 float32 GeoTIFF in UTM 11N with a no-data block."""
    rasterio = pytest.importorskip("rasterio")
    from rasterio.transform import from_origin

    z = terrain(70, 90, holes=False).astype(np.float32)
    z[5:9, 10:30] = -9999
    path = tmp_path / "dem.tif"
    with rasterio.open(path, "w", driver="GTiff", width=90, height=70, count=1, dtype="float32", crs="EPSG:32611",
                       transform=from_origin(440000, 3750000, 2, 2), nodata=-9999) as dataset:
        dataset.write(z, 1)
    return path


def test_a_geotiff_is_coded_by_windows_and_decoded_by_tiles_to_a_geotiff(dem, tmp_path):
    rasterio = pytest.importorskip("rasterio")
    coded, back = tmp_path / "dem.mzw2", tmp_path / "back.tif"
    run_mzc("encode", "--dwt2d", "--max-error", "0.05", "--tile", "32", dem, "-o", coded, check=True)
    whole = mzc.read(dem)
    assert coded.read_bytes() == mzc.encode(whole, "dwt2d", max_error=0.05, tile=32)
    info = run_mzc("info", coded, check=True).stdout.decode()
    assert "mzc-dwt2d 5.0 (tiled)" in info and "tiles     3 x 3 of 32 x 32 nodes" in info
    run_mzc("decode", coded, "-o", back, check=True)
    with rasterio.open(dem) as a, rasterio.open(back) as b:
        original, decoded = a.read(1).astype(float), b.read(1)
        assert (a.transform, a.crs, b.nodata) == (b.transform, b.crs, -9999)
    valid = original != -9999
    assert np.array_equal(decoded == -9999, ~valid) and np.abs(decoded - original)[valid].max() <= 0.05
    window = run_mzc("decode", coded, "--window", 3, 4, 10, 12, check=True).stdout
    cut = mzc.decode(window)
    assert np.array_equal(cut.z, mzc.decode(coded.read_bytes()).z[3:13, 4:16], equal_nan=True)
    assert np.array_equal(mzc.read(coded, window=(3, 4, 10, 12)).z, cut.z, equal_nan=True)
    assert cut.crs == whole.crs and cut.raster == whole.raster
    untiled = tmp_path / "untiled.mzw2"
    mzc.write(untiled, mzc.encode(whole, "dwt2d", max_error=0.05))
    from_whole = mzc.decode(run_mzc("decode", untiled, "--window", 3, 4, 10, 12, check=True).stdout)
    assert np.array_equal(from_whole.z, mzc.decode(untiled.read_bytes()).z[3:13, 4:16], equal_nan=True)
    assert from_whole.origin == cut.origin
    refused = run_mzc("encode", "--dwt2d", "--size", "3000", "--tile", "32", dem, "-o", tmp_path / "x.mzw2")
    assert refused.returncode == 1 and refused.stderr.decode().count("\n") == 1
    assert not (tmp_path / "x.mzw2").exists()


def test_the_tiles_of_a_geotiff_are_coded_as_dask_tasks_into_the_same_bytes(dem, tmp_path):
    pytest.importorskip("distributed")
    from distributed import LocalCluster

    here, there = tmp_path / "here.mzw2", tmp_path / "there.mzw2"
    run_mzc("encode", "--dwt2d", "--rmse", "0.05", "--tile", "32", dem, "-o", here, check=True)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None,
                      silence_logs=50) as cluster:
        run_mzc("encode", "--dwt2d", "--rmse", "0.05", "--tile", "32", dem, "-o", there, "--scheduler",
                cluster.scheduler_address, check=True)
    assert there.read_bytes() == here.read_bytes()
    refused = run_mzc("encode", "--dwt2d", "--rmse", "0.05", dem, "-o", there, "--scheduler", "tcp://127.0.0.1:1")
    assert refused.returncode == 2 and "--scheduler codes the tiles" in refused.stderr.decode()


def test_a_multi_chart_grid_is_coded_whole_unless_told_to_tile(monkeypatch):
    from mzc.grid import Chart

    monkeypatch.setattr(tiles, "DEFAULT_TILE", 4)
    z = terrain(6, 9, holes=False)
    z[:, 4] = np.nan
    charted = ZGrid(z=z, d1=1.0, d2=1.0, charts=(Chart("+z", 0, 0, 6, 4, 0, 0), Chart("-x", 0, 5, 6, 4, 0, 0)))
    data = mzc.encode(charted, "dwt2d", max_error=0.05)
    assert data.startswith(b"mzc-dwt2d 10.0\n") and mzc.decode(data).charts == charted.charts
    with pytest.raises(MzcError, match="multi-chart grid is coded whole"):
        mzc.encode(charted, "dwt2d", max_error=0.05, tile=4)


def test_a_z_grid_too_large_to_hold_is_refused_in_one_line_before_any_tile_is_decoded(tmp_path):
    from mzc.codecs.dwt2d.tiles import Frame, header_bytes

    frame = Frame(12_000, 12_000, {"d1": 1.0, "d2": 1.0})
    path = tmp_path / "huge.mzw2"
    path.write_bytes(header_bytes(frame, 4096, [1] * 9, {}) + b"\0" * 9)   # tiles of one byte: never read
    result = run_mzc("decode", path)
    error = result.stderr.decode()
    assert result.returncode == 1 and error.count("\n") == 1 and not result.stdout
    assert "12000 x 12000 nodes is too large" in error and "--window" in error and "--format tif" in error
    assert "tiles     3 x 3 of 4096 x 4096 nodes" in run_mzc("info", path, check=True).stdout.decode()


# --- tiles with colours (11.0) ------------------------------------------------------------------


def coloured(z, seed=0):
    """``grid_of(z)`` with a colour at every node: ramps along the rows and columns, blue random."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:z.shape[0], 0:z.shape[1]]
    return grid_of(z, colors=np.stack([c * 7 % 256, r * 5 % 256, rng.integers(0, 256, z.shape)], axis=-1))


@settings(max_examples=20, deadline=None)
@given(rows=st.integers(1, 40), cols=st.integers(1, 40), tile=st.integers(4, 16), seed=st.integers(0, 99),
       colour_error=st.sampled_from([0, 3]), data=st.data())
def test_coloured_tiles_keep_every_nodes_colour_and_a_window_its_own(rows, cols, tile, seed, colour_error, data):
    """A grid with colours in tiles is 11.0: every valid node's colour within the colour bound,
    0 at the invalid ones, its heights as 5.0 holds them, and a window's colours the whole's, cut."""
    grid = coloured(terrain(rows, cols, seed), seed)
    encoded = mzc.encode(grid, "dwt2d", max_error=0.05, colour_max_error=colour_error, tile=tile)
    assert encoded.startswith(b"mzc-dwt2d 11.0\n") and tiles.is_tiled(encoded)
    whole = mzc.decode(encoded)
    assert np.array_equal(whole.valid, grid.valid) and np.nanmax(np.abs(whole.z - grid.z), initial=0) <= 0.05
    assert np.abs(whole.colors.astype(int) - grid.colors)[grid.valid].max(initial=0) <= colour_error
    assert not whole.colors[~grid.valid].any()
    row, col = data.draw(st.integers(0, rows - 1)), data.draw(st.integers(0, cols - 1))
    window = (row, col, data.draw(st.integers(1, rows - row)), data.draw(st.integers(1, cols - col)))
    cut = mzc.decode(encoded, window=window)
    assert cut.colors.tobytes() == whole.colors[row:row + window[2], col:col + window[3]].tobytes()


def test_a_grid_without_colours_keeps_5_0_and_finer_colours_leave_their_nodes_in_tiles():
    """Colours change nothing of an uncoloured grid's tiles (5.0, byte for byte its heights'); a
    grid with colours finer than its nodes keeps the nodes' in tiles, and says it drops the rest."""
    from mzc.errors import MzcWarning

    z = terrain(12, 10)
    plain = mzc.encode(grid_of(z), "dwt2d", max_error=0.05, tile=4)
    assert plain.startswith(b"mzc-dwt2d 5.0\n")
    fine = grid_of(z, fine_colors=np.random.default_rng(2).integers(0, 256, (23, 19, 3)))
    with pytest.warns(MzcWarning, match="the colours 2 times finer than the nodes .* keeps the nodes' colours"):
        encoded = mzc.encode(fine, "dwt2d", max_error=0.05, colour_max_error=0, tile=4)
    back = mzc.decode(encoded)
    assert back.colour_scale == 1 and back.colors[fine.valid].tolist() == fine.colors[fine.valid].tolist()
    assert mzc.decode(mzc.encode(fine, "dwt2d", max_error=0.05, tile=0)).colour_scale == 2


def test_an_11_0_tile_without_its_colours_or_of_another_version_is_refused():
    """In an 11.0 file a tile must be a 10.x file with a colour section at the nodes: a 3.x tile
    (5.0's) or a 10.x tile without colours in its place is refused in one line."""
    from mzc.codecs.dwt2d import encode_whole

    grid = coloured(terrain(10, 9))
    data = mzc.encode(grid, "dwt2d", max_error=0.05, tile=4)
    tiled = TiledFile(Bytes(data), "good")
    block = ZGrid(z=grid.z[:4, :4], **tiled.frame.block_fields(0, 0))
    others = b"".join(tiled.tile_bytes(i, j) for i in range(3) for j in range(3))[len(tiled.tile_bytes(0, 0)):]
    head = data[:data.index(b"\ndata\n") + 6]
    for tile, message in ((encode_whole(block, max_error=0.05, compact=False)[0], "is a dwt2d 10.x stream"),
                          (encode_whole(block, max_error=0.05)[0], "has no colour section")):
        lengths = [len(tile), *map(int, np.diff(tiled.offsets)[1:])]
        index = b"".join(struct.pack("<Q", n) for n in lengths)
        with pytest.raises(MzcError, match=message) as error:
            mzc.decode(head + index + struct.pack("<I", zlib.crc32(index)) + tile + others)
        assert "\n" not in str(error.value)


def test_info_says_the_tiles_carry_colours(tmp_path):
    (tmp_path / "c.mzw2").write_bytes(mzc.encode(coloured(terrain(10, 9)), "dwt2d", max_error=0.05, tile=4))
    shown = run_mzc("info", tmp_path / "c.mzw2", check=True).stdout.decode()
    assert "mzc-dwt2d 11.0 (tiled)" in shown and "each a dwt2d file with its nodes' colours" in shown


def test_a_tile_with_lines_only_the_header_may_have_is_refused():
    """A tile's own transform, units, nodata or crs would say something the file's header says
    for the whole grid (spec/dwt2d.md, Tiles): such a tile is refused, as web/ refuses it."""
    from mzc.codecs.dwt2d import encode_whole

    data = made()
    tiled = TiledFile(Bytes(data), "good")
    fields = tiled.frame.block_fields(0, 0)
    head, rest = data[:data.index(b"\ndata\n") + 6], data[int(tiled.offsets[1]):]
    z = mzc.decode(data).z[:4, :4]
    for extra in ({"units": "mm"}, {"nodata": "-9999"}, {"transform": np.hstack([np.eye(3), [[1.0], [0], [0]]])}):
        tile = encode_whole(ZGrid(z=z, **fields, **extra), max_error=0.05, compact=False)[0]
        lengths = [len(tile), *map(int, np.diff(tiled.offsets)[1:])]
        index = b"".join(struct.pack("<Q", n) for n in lengths)
        with pytest.raises(MzcError, match="lines of its own"):
            mzc.decode(head + index + struct.pack("<I", zlib.crc32(index)) + tile + rest)
