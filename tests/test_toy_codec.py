"""A codec written outside mzc joins it by registering itself: this file touches no other.

The toy codec stores a grid's heights as zlib-compressed float64 behind the shared header
lines. Once registered it gets ``mzc encode --toy``, ``mzc decode``, ``mzc info``,
``mzc.encode(grid, "toy")`` and the codec contract, with no change anywhere else.
"""

import zlib

import numpy as np
import pytest

import mzc
from mzc.codecs.base import Codec, Option
from mzc.errors import MzcError
from mzc.formats import zgrid
from mzc.formats.header import grid_header_lines, magic_line, read_grid_fields, read_header
from mzc.grid import ZGrid

from codec_contract import check_codec, generated_grids
from golden import run


def write_toy(grid, level):
    """Header lines, ``data``, then the heights as zlib-compressed little-endian float64."""
    lines = [magic_line("toy", (1, 0)), f"level {level}", *grid_header_lines(grid), "data"]
    return ("\n".join(lines) + "\n").encode() + zlib.compress(grid.z.astype("<f8").tobytes(), level)


def read_toy(data, source):
    """A toy file back to its grid; the declared size bounds the decompression."""
    header, body, line = read_header(data, source, "toy", 1, projected_major=1)
    fields, rows, cols = read_grid_fields(header)
    expected = rows * cols * 8
    try:
        stream = zlib.decompressobj()
        values = stream.decompress(body, expected)
        complete = len(values) == expected and stream.eof and not stream.unconsumed_tail and not stream.unused_data
    except zlib.error as error:
        raise MzcError(f"corrupt heights: {error}", source=source, line=line) from None
    if not complete:
        raise MzcError(f"the heights are not {rows} x {cols} float64 values", source=source, line=line)
    return ZGrid(z=np.frombuffer(values, "<f8").reshape(rows, cols), **fields)


TOY = Codec("toy", write_toy, read_toy, version=(1, 0), extension=".mzt", summary="Toy: zlib of the heights",
            options=(Option("level", int, 6, 0, 9, metavar="L", help="zlib level."),))


@pytest.fixture
def toy():
    mzc.register_codec(TOY)
    yield TOY
    from mzc.codecs import unregister_codec

    unregister_codec("toy")


def test_the_toy_keeps_the_codec_contract(toy):
    check_codec(toy)


def test_the_command_line_takes_the_toy_once_it_is_registered(toy):
    grid = generated_grids()[0]
    text = zgrid.write(grid)
    coded = run(["encode", "--toy", "--level", "9"], text)
    assert coded.startswith(b"mzc-toy 1.0\nlevel 9\n")
    assert run(["decode", "--plain"], coded) == text
    assert run(["decode"], coded) == zgrid.write(grid, raw="float64")
    assert b"format    mzc-toy 1.0" in run(["info"], coded)
    assert mzc.encode(grid, "toy", level=9) == coded
    assert "toy" in mzc.codec_names()


def test_the_toy_is_gone_once_unregistered(toy):
    from mzc.codecs import unregister_codec

    coded = mzc.encode(generated_grids()[0], "toy")
    unregister_codec("toy")
    with pytest.raises(MzcError, match="unknown mzc format 'mzc-toy'"):
        mzc.decode(coded)
    with pytest.raises(MzcError, match="unknown codec"):
        mzc.encode(np.zeros((2, 2)), "toy")
