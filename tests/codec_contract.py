"""The contract every codec keeps, as checks that take a ``mzc.codecs.base.Codec``.

``tests/test_codec_contract.py`` runs them over every registered codec; a codec written
elsewhere (``tests/test_toy_codec.py``) runs the same checks on itself. They cover a round
trip on generated surfaces with the codec's example options, the worked examples of its
spec page, hostile input (truncated, flipped, padded, empty files) and its stored fixtures.
"""

import re
from pathlib import Path

import numpy as np

from mzc.errors import MzcError
from mzc.formats import read_any
from mzc.formats.header import with_checksum
from mzc.grid import ZGrid

REPO = Path(__file__).resolve().parents[1]
SPEC = REPO / "spec"
FIXTURES = REPO / "tests" / "fixtures"
EXPECTED = ".expected.zg"
# a fixture: KIND-MAJOR.MINOR[-VARIANT].EXT, a variant being a second file of one version (a 7.0 file with colours)
FIXTURE_NAME = re.compile(r"^(?P<kind>[a-z0-9]+)-(?P<major>\d+)\.(?P<minor>\d+)(?P<variant>-[a-z]+)?"
                          r"(?P<ext>\.[a-z0-9]+)$")
# a worked example: the file as text (or as its header then the payload in hex), then, after any
# prose, the values it decodes to
EXAMPLE_BLOCK = re.compile(r"```mzc-example(-hex)?\n(.*?)```.*?```expected\n(.*?)```", re.S)

CHECKSUM_LINE = re.compile(rb"(?m)^crc32 [0-9a-f]{8}\n")


def generated_grids():
    """Surfaces the contract codes: a smooth planar patch with a hole and ragged edges, and a
    cylindrical grid (values are distances along rays)."""
    y, x = np.mgrid[0:48, 0:64] / 8.0
    z = 10 + 2 * np.sin(x) * np.cos(y / 2) + 0.1 * x
    z[20:24, 30:36] = np.nan
    z[:6, :5] = np.nan
    z[-3:, -7:] = np.nan
    planar = ZGrid(z=z, d1=0.5, d2=0.25, origin=(-3.0, 1.5), units="mm")
    radial = 50 + 0.5 * np.cos(np.linspace(0, 2 * np.pi, 64))[None, :] + np.linspace(0, 1, 40)[:, None]
    central = ZGrid(z=radial, d1=1.0, d2=2 * np.pi * 50 / 128, projection="cylindrical", radius=50.0)
    return [planar, central]


def check_round_trip(codec, grid):
    """Encoding with the example options and decoding keeps the frame and the valid nodes, and
    the values come back close (within a max_error the example states, else 1% of their range)."""
    data = codec.encode(grid, **codec.example)
    assert isinstance(data, bytes) and data.startswith(f"mzc-{codec.kind} ".encode())
    for back in (codec.decode(data, "contract"), read_any(data, "contract")):
        assert back.shape == grid.shape and np.array_equal(back.valid, grid.valid)
        assert (back.d1, back.d2, back.origin, back.projection, back.radius, back.units) == \
            (grid.d1, grid.d2, grid.origin, grid.projection, grid.radius, grid.units)
        assert np.array_equal(back.transform, grid.transform)
        error = np.abs(back.z - grid.z)[grid.valid].max()
        bound = codec.example.get("max_error", 0.01 * np.ptp(grid.z[grid.valid]))
        assert error <= bound, f"{codec.name}: error {error:g} above {bound:g}"
    return data


def check_decoded_heights(codec, grid):
    """``encode_with_decoded`` gives the bytes ``encode`` gives and, bit for bit, the heights
    their decoder gets (what mzc batch reports errors from)."""
    data, heights = codec.encode_with_decoded(grid, **codec.example)
    assert data == codec.encode(grid, **codec.example)
    np.testing.assert_array_equal(heights, codec.decode(data, "contract").z)


def spec_examples(kind=None):
    """(file bytes, expected heights, id) of every worked example in spec/*.md (of one kind)."""
    cases = []
    for path in sorted(SPEC.glob("*.md")):
        for index, (hex_payload, text, expected) in enumerate(EXAMPLE_BLOCK.findall(path.read_text())):
            if kind is None or text.startswith(f"mzc-{kind} "):
                values = np.array([[float(v) for v in line.split()] for line in expected.strip().splitlines()])
                cases.append((example_bytes(text, bool(hex_payload)), values, f"{path.stem}-{index + 1}"))
    return cases


def example_bytes(text, hex_payload):
    """The file of a worked example: its text, or its header lines then its payload given in hex, or
    (a binary header, dwt2d 7.0: no ``data`` line) its magic line then the rest of the file in hex."""
    if not hex_payload:
        return text.encode()
    if "data\n" not in text:
        magic, rest = text.split("\n", 1)
        return (magic + "\n").encode() + bytes.fromhex(rest)
    header, payload = text.split("data\n")
    return (header + "data\n").encode() + bytes.fromhex(payload)


def header_fields(data):
    """{keyword: value words} of a compressed file's header: its text lines, or a dwt2d 7.0 file's
    binary fields (the lines they stand for)."""
    from mzc.codecs.dwt2d import compact

    if compact.is_compact(data):
        return {keyword: values for keyword, (values, _line) in compact.read(data, "t")[0].fields.items()}
    lines = data.split(b"\ndata\n")[0].decode().splitlines()[1:]
    return {line.split()[0]: line.split()[1:] for line in lines if line.strip()}


def assert_heights(z, expected):
    """Decoded heights equal to a spec's expectation (NaN where it has nan, values to 1e-3)."""
    np.testing.assert_array_equal(np.isnan(z), np.isnan(expected))
    np.testing.assert_allclose(z[~np.isnan(z)], expected[~np.isnan(expected)], atol=1e-3)


def check_spec_examples(codec):
    """Every worked example of the codec's kind on its spec page decodes to what the page says."""
    examples = spec_examples(codec.kind)
    assert examples, f"{codec.spec} has no worked example of mzc-{codec.kind}"
    for data, expected, _id in examples:
        assert_heights(codec.decode(data, codec.spec).z, expected)


def damaged(data):
    """Hostile variants of a good file: truncated at many lengths, one byte flipped in the
    header and in the body, garbage appended, nothing at all."""
    header_end = data.find(b"\ndata\n") + 6
    lengths = sorted({*range(0, min(len(data), 64)), *np.linspace(0, len(data) - 1, 40).astype(int).tolist()})
    yield from (data[:n] for n in lengths)
    for position in sorted({3, header_end // 2, header_end - 2, header_end + 1, (header_end + len(data)) // 2,
                            len(data) - 1}):
        if 0 <= position < len(data):
            yield data[:position] + bytes([data[position] ^ 0x5A]) + data[position + 1:]
    yield data + b"\x00garbage\n"
    yield b""


def check_hostile_input(codec, data):
    """Every damaged variant of ``data`` decodes to a grid or raises MzcError, nothing else; a
    file that carries a checksum (mzc.formats.header) is never decoded once damaged."""
    checksummed = CHECKSUM_LINE.search(data.split(b"\ndata\n")[0]) is not None
    for variant in damaged(data):
        try:
            grid = codec.decode(variant, "hostile")
        except MzcError:
            continue
        assert not checksummed, f"a damaged file decoded: {variant[:60]!r}..."
        assert isinstance(grid, ZGrid)


def rechecksummed(data):
    """``data``, edited on purpose, with its crc32 line made right again (none if it had none):
    tests of the readers' other checks use it to get past the checksum."""
    stripped, found = CHECKSUM_LINE.subn(b"", data, count=1)
    return with_checksum(stripped) if found else data


def fixture_names(kind=None):
    """The stored fixture files (of one kind), not their expectations."""
    return sorted(p.name for p in FIXTURES.iterdir() if p.is_file() and not p.name.endswith(EXPECTED)
                  and FIXTURE_NAME.match(p.name) and (kind is None or p.name.startswith(f"{kind}-")))


def fixture_bytes(name):
    """The bytes of a stored fixture."""
    return (FIXTURES / name).read_bytes()


def expected_grid(name):
    """The z-grid a stored fixture decodes to."""
    return read_any((FIXTURES / (name + EXPECTED)).read_bytes(), name + EXPECTED)


def bits(value):
    """The binary64 bytes of a float (so -0.0 and 0.0 differ), or None."""
    return None if value is None else np.float64(value).tobytes()


def assert_same_grid(got, want):
    """Equal in every field, values to 1e-12, NaN exactly where the expectation has it."""
    assert got.shape == want.shape
    got_nan, want_nan = np.isnan(got.z), np.isnan(want.z)
    assert np.array_equal(got_nan, want_nan), (
        f"invalid nodes differ at {np.argwhere(got_nan != want_nan).tolist()}")
    # The decoders' transforms run in numpy and PyWavelets, whose last bits may change with
    # their versions or the CPU: the promise is the surface, to one part in 10^12.
    np.testing.assert_allclose(got.z[~got_nan], want.z[~want_nan], rtol=1e-12, atol=0)
    assert (bits(got.d1), bits(got.d2)) == (bits(want.d1), bits(want.d2))
    assert [bits(v) for v in got.origin] == [bits(v) for v in want.origin]
    assert got.transform.shape == want.transform.shape == (3, 4)
    assert got.transform.tobytes() == want.transform.tobytes()
    assert (got.projection, bits(got.radius)) == (want.projection, bits(want.radius))
    assert (got.units, got.nodata) == (want.units, want.nodata)
    assert (got.crs, got.raster) == (want.crs, want.raster)
    assert got.charts == want.charts
    assert (got.colors is None) == (want.colors is None)
    assert got.colors is None or got.colors.tobytes() == want.colors.tobytes()
    assert got.colour_scale == want.colour_scale
    assert got.fine_colors is None or got.fine_colors.tobytes() == want.fine_colors.tobytes()
    assert got.source_vertices == want.source_vertices


def check_fixtures(codec):
    """Every stored fixture of the codec's kind decodes to its expected grid."""
    for name in fixture_names(codec.kind):
        assert_same_grid(codec.decode(fixture_bytes(name), name), expected_grid(name))


def check_codec(codec):
    """The whole contract: round trips, spec examples (when it has a page), hostile input, fixtures."""
    for grid in generated_grids():
        data = check_round_trip(codec, grid)
        check_decoded_heights(codec, grid)
    check_hostile_input(codec, data)
    if codec.spec:
        check_spec_examples(codec)
    check_fixtures(codec)
