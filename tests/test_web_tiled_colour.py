"""web/dwt2d.mjs on tiled files with colours (``mzc-dwt2d 11.0``: 5.0's layout, every tile a 10.x file
with its block's colour section): fresh files of random grids with holes (tile sides 4 to 16, partial
tiles at the edges, a tile of no valid node, colour_max_error 0 and 3) decode, in web/'s CLI too, to the
z-grid bytes with colours that `mzc decode` writes; damaged files (a byte flipped in a tile under its own
CRC-32s, the index or the tiles cut) and files whose tiles break 11.0's rules (3.x tiles, 10.x tiles
without colours or with colours finer than the nodes, two tiles swapped) are refused by both. The
fixture dwt2d-11.0.mzw2 is checked with every fixture in tests/test_web.py. Skipped when node is not
installed."""

import dataclasses
import struct
import zlib

import numpy as np
import pytest
from test_web import assert_decodes_alike, node_decode_all, python_decode

import mzc
from mzc.codecs import dwt2d
from mzc.formats.header import with_checksum
from mzc.grid import ZGrid

from codec_contract import CHECKSUM_LINE
from web_node import needs_node

pytestmark = needs_node

MAX_ERROR = 0.1
# (rows, cols, tile side, colour_max_error, projection): partial tiles at the bottom and right edges
# (but for 32 x 48 in tiles of 16), one row or column of tiles, tiles of 4 to 16 nodes
CASES = [(40, 50, 16, 3, "planar"), (40, 50, 16, 0, "planar"), (32, 48, 16, 3, "planar"), (23, 17, 4, 3, "planar"),
         (9, 30, 8, 0, "planar"), (30, 9, 5, 3, "planar"), (21, 26, 7, 0, "cylindrical"), (13, 13, 12, 3, "planar")]
EMPTY_TILES = (13, 13)   # the shape whose nodes past a diagonal are invalid: three tiles of no valid node


def random_grid(rng, rows, cols, projection="planar"):
    """A rows x cols grid of a random walk down its columns with about 10% holes and random colours,
    off the origin; cylindrical about R = 40, under a full turn."""
    z = 50 + np.cumsum(rng.normal(size=(rows, cols)), axis=0)
    z[rng.random(z.shape) < 0.1] = np.nan
    radius = 40.0 if projection != "planar" else None
    return ZGrid(np.round(z, 3), d1=0.5, d2=0.75, origin=(-3.25, 12.5), units="mm", projection=projection,
                 radius=radius, colors=rng.integers(0, 256, (rows, cols, 3)))


def coded(grid, tile, colour_max_error):
    """The 11.0 file of ``grid`` in tiles of ``tile``, its colours within ``colour_max_error`` levels."""
    data = mzc.encode(grid, "dwt2d", max_error=MAX_ERROR, colour_max_error=colour_max_error, tile=tile)
    assert data.startswith(b"mzc-dwt2d 11.0\n")
    return data


def split(data):
    """(text header through its ``data`` line, [every tile's bytes]) of a tiled file."""
    head = data[:data.index(b"\ndata\n") + 6]
    rows, cols = (int(n) for n in head.split(b"\ntiles ")[1].split(b"\n")[0].split())
    lengths = struct.unpack(f"<{rows * cols}Q", data[len(head):len(head) + 8 * rows * cols])
    at = len(head) + 8 * len(lengths) + 4
    tiles = []
    for length in lengths:
        tiles.append(data[at:at + length])
        at += length
    return head, tiles


def joined(head, tiles):
    """The tiled file of ``head`` and ``tiles``: its index (their lengths) under its right CRC-32."""
    index = struct.pack(f"<{len(tiles)}Q", *(len(tile) for tile in tiles))
    return head + index + zlib.crc32(index).to_bytes(4, "little") + b"".join(tiles)


def retiled(data, change):
    """The file ``data`` with each tile's grid (as mzc reads it) changed by ``change`` and coded again
    whole as a 10.x file, within MAX_ERROR and its colours losslessly."""
    head, tiles = split(data)
    grids = [change(dwt2d.read(tile, "tile")) for tile in tiles]
    return joined(head, [dwt2d.encode_whole(grid, max_error=MAX_ERROR, colour_max_error=0)[0] for grid in grids])


def assert_refused_by_both(files, tmp_path, words=None):
    """mzc refuses every one of ``files`` (name -> bytes), and web/ with an MzcError (one of whose
    messages holds ``words``, when given)."""
    paths = [tmp_path / f"{name}.mzw2" for name in files]
    for path, data in zip(paths, files.values()):
        path.write_bytes(data)
    results = node_decode_all(paths)
    for path, data, result in zip(paths, files.values(), results):
        assert python_decode(data, path.name) is None, path.name
        assert "refused" in result, (path.name, result)
    if words is not None:
        assert any(words in result["refused"] for result in results), results


def test_random_grids_in_tiles_with_colours_decode_as_mzc_decodes_them(tmp_path):
    rng = np.random.default_rng(1100)
    paths, expected = [], []
    for rows, cols, tile, colour_max_error, projection in CASES:
        grid = random_grid(rng, rows, cols, projection)
        if (rows, cols) == EMPTY_TILES:
            inside = np.add.outer(np.arange(rows), np.arange(cols)) < 12
            grid = dataclasses.replace(grid, z=np.where(inside, grid.z, np.nan))
        paths.append(tmp_path / f"{rows}x{cols}-{tile}-{colour_max_error}-{projection}.mzw2")
        paths[-1].write_bytes(coded(grid, tile, colour_max_error))
        expected.append(python_decode(paths[-1].read_bytes(), paths[-1].name))
    for path, want, result in zip(paths, expected, node_decode_all(paths)):
        assert want is not None and b"\ncolours rgb8\n" in want, path.name
        assert "zgrid" in result, (path.name, result)
        assert bytes.fromhex(result["zgrid"]) == want, path.name
    assert_decodes_alike(paths[0])   # and the CLIs, web/'s and mzc's


@pytest.fixture(scope="module")
def tiled():
    """An 11.0 file of 3 x 4 tiles of 16 (the last row and column partial)."""
    return coded(random_grid(np.random.default_rng(11), 40, 50), 16, 3)


def test_a_byte_flipped_in_a_tile_or_the_index_cut_is_refused_by_both(tiled, tmp_path):
    head, tiles = split(tiled)
    starts = np.cumsum([len(head) + 8 * len(tiles) + 4, *(len(tile) for tile in tiles)])[:-1]
    files = {f"flipped-{k}-{at}": tiled[:start + at] + bytes([tiled[start + at] ^ 0x10]) + tiled[start + at + 1:]
             for k, start in enumerate(starts) for at in (20, len(tiles[k]) // 2, len(tiles[k]) - 1)}
    files.update({f"cut-{n}": tiled[:len(head) + n] for n in (0, 1, 8 * len(tiles) // 2, 8 * len(tiles) + 3)})
    files.update({f"cut-tiles-{n}": tiled[:n] for n in (starts[1], len(tiled) - 1)})
    assert_refused_by_both(files, tmp_path)


def test_tiles_that_break_the_rules_of_11_0_are_refused_by_both(tiled, tmp_path):
    """3.x tiles (an 11.0 header over a 5.0 file's tiles), 10.x tiles without colours or with colours
    twice finer than the nodes, and two tiles swapped (each then at another's block)."""
    head, tiles = split(tiled)
    grid = random_grid(np.random.default_rng(11), 40, 50)
    plain = mzc.encode(dataclasses.replace(grid, colors=None), "dwt2d", max_error=MAX_ERROR, tile=16)
    plain_head, plain_tiles = split(plain)
    header = with_checksum(CHECKSUM_LINE.sub(b"", plain_head.replace(b"mzc-dwt2d 5.0", b"mzc-dwt2d 11.0"), count=1))
    assert_refused_by_both({"3.x tiles": joined(header, plain_tiles)}, tmp_path, "is not an mzc-dwt2d 10.x file")
    assert_refused_by_both({"no colours": retiled(tiled, lambda tile: dataclasses.replace(tile, colors=None))},
                           tmp_path, "has no colour section of its nodes' colours")
    finer = retiled(tiled, lambda tile: dataclasses.replace(tile, colors=None, fine_colors=np.repeat(
        np.repeat(tile.colors, 2, axis=0), 2, axis=1)[:2 * tile.shape[0] - 1, :2 * tile.shape[1] - 1]))
    assert_refused_by_both({"finer colours": finer}, tmp_path, "has no colour section of its nodes' colours")
    assert_refused_by_both({"swapped": joined(head, [tiles[1], tiles[0], *tiles[2:]])}, tmp_path,
                           "its lines do not say the block the header gives it")
