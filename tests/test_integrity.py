"""Integrity: a compressed file whose bytes changed in any way is refused, never decoded.

Every compressed format's current version carries a ``crc32`` line over the whole file
(spec/zgrid.md, Checksum). These tests damage real files (a face coded with --dwt2d, and
every codec's file of a generated grid) by single-bit flips, cuts, appended bytes and
CRLF conversion, and check that each damaged file is refused with an MzcError, that the
command line says so on one line, and that the formats without a checksum (mzc-dwt2d 3.0
and 2.0) still refuse bytes after their payload and CRLF headers.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.codecs import BUILT_IN, get_codec
from mzc.errors import MzcError
from mzc.formats import read_any

from codec_contract import CHECKSUM_LINE, fixture_bytes, generated_grids
from conftest import run_mzc

FLIPS = 1000


@pytest.fixture(scope="module")
def face_file():
    """f18 sliced at 0.5 mm and coded with --dwt2d --rmse 0.05, as the README's pipeline does."""
    from conftest import face_path

    grid = mzc.slice(face_path("f18.ply"), d1=0.5, d2=0.5)
    return mzc.encode(grid, "dwt2d", rmse=0.05)


@pytest.fixture(scope="module")
def text_face_file():
    """The face of ``face_file`` in mzc-dwt2d 3.1, whose text header carries the ``crc32`` line (7.0's
    sections carry their CRC-32s in binary)."""
    from mzc.codecs.dwt2d import encode_whole

    from conftest import face_path

    grid = mzc.slice(face_path("f18.ply"), d1=0.5, d2=0.5)
    return encode_whole(grid, rmse=0.05, compact=False)[0]


def header_bytes(data):
    """The bytes of a file's header: through its ``data`` line, a dwt2d 7.0 or 8.0 file's magic line and
    header section, or a 10.0 file's magic line and header fields."""
    from mzc.codecs.dwt2d import compact

    if compact.major(data) == compact.TIGHT_MAJOR:
        reader = compact.Reader(data, "t")
        return reader.varint() + reader.position
    if compact.is_compact(data):
        reader = compact.Reader(data, "t")
        reader.header()
        return reader.position
    return data.index(b"\ndata\n") + 6


def codec_files():
    """(name, bytes) of every built-in codec's file of the generated grids (planar and central)."""
    files = []
    for index, grid in enumerate(generated_grids()):
        for name in BUILT_IN:
            codec = get_codec(name)
            files.append((f"{name}-{index}", codec.encode(grid, **codec.example)))
    return files


CODEC_FILES = codec_files()


def flipped(data, bit):
    """``data`` with bit number ``bit`` (0 = the first byte's lowest) inverted."""
    damaged = bytearray(data)
    damaged[bit // 8] ^= 1 << (bit % 8)
    return bytes(damaged)


def refused(data, source="damaged"):
    """The MzcError reading ``data`` raises (the test fails if it decodes)."""
    with pytest.raises(MzcError) as error:
        read_any(data, source)
    return error.value


def test_a_thousand_single_bit_flips_of_a_face_file_are_all_refused(face_file):
    """The issue's promise: 1,000 random single-bit flips of a .mzw2 face, none decodes."""
    rng = np.random.default_rng(13)
    bits = rng.choice(len(face_file) * 8, size=min(FLIPS, len(face_file) * 8), replace=False)
    assert read_any(face_file, "f18.mzw2").valid.sum() > 100_000
    messages = {refused(flipped(face_file, int(bit))).message.split(":")[0] for bit in bits}
    assert "checksum mismatch" in messages


@pytest.mark.parametrize("name, data", CODEC_FILES, ids=[n for n, _ in CODEC_FILES])
def test_every_bit_of_every_codec_file_is_guarded(name, data):
    """Bits of every codec's file (planar and central grids; every bit of the header and up to
    3,000 in all): flipped, each is refused."""
    assert CHECKSUM_LINE.search(data) or data.startswith(b"mzc-dwt2d 10.0\n"), f"{name} carries no crc32 line"
    header_bits = 8 * header_bytes(data)
    rng = np.random.default_rng(len(data))
    body_bits = rng.choice(np.arange(header_bits, len(data) * 8), size=min(3000, len(data) * 8 - header_bits),
                           replace=False)
    for bit in [*range(header_bits), *body_bits.tolist()]:
        with pytest.raises(MzcError):
            read_any(flipped(data, bit), name)


@pytest.mark.parametrize("name, data", CODEC_FILES[:len(BUILT_IN)], ids=[n for n, _ in CODEC_FILES[:len(BUILT_IN)]])
def test_cut_appended_and_crlf_files_are_refused(name, data):
    """A file cut at any length, with bytes appended, or converted to CRLF line ends is refused."""
    for length in range(len(data)):
        with pytest.raises(MzcError):
            read_any(data[:length], name)
    for tail in (b"\n", b"\x00", b"garbage\n", data):
        assert "checksum mismatch" in refused(data + tail).message
    crlf = refused(data.replace(b"\n", b"\r\n"))
    assert "CRLF" in crlf.message and crlf.field == "crc32"
    assert "CRLF" in refused(data.replace(b"\n", b"\r\n", 1)).message   # the magic line alone


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_any_edit_of_a_checksummed_file_is_refused(data):
    """Hypothesis: replace, insert or delete any run of bytes anywhere; the file is refused."""
    name, original = data.draw(st.sampled_from(CODEC_FILES))
    start = data.draw(st.integers(0, len(original)))
    end = data.draw(st.integers(start, min(len(original), start + 16)))
    insert = data.draw(st.binary(max_size=16))
    edited = original[:start] + insert + original[end:]
    if edited != original:
        with pytest.raises(MzcError):
            read_any(edited, name)


def test_a_current_version_without_its_checksum_is_refused(text_face_file):
    """Taking the crc32 line out does not turn the check off: 3.1 requires it."""
    error = refused(CHECKSUM_LINE.sub(b"", text_face_file, count=1))
    assert error.field == "crc32" and "missing" in error.message


@pytest.mark.parametrize("value", ["0", "XYZXYZXY", "1234567890", "DEADBEEF"])
def test_a_malformed_checksum_is_refused(text_face_file, value):
    error = refused(CHECKSUM_LINE.sub(f"crc32 {value}\n".encode(), text_face_file, count=1))
    assert error.field == "crc32" and "hexadecimal" in error.message


def test_the_checksum_covers_the_version_so_an_older_version_number_does_not_hide_a_flip(text_face_file,
                                                                                          face_file):
    """3.1 -> 3.0 on the magic line (3.0 needs no checksum): the crc32 line is still checked; 8.0 -> 7.0
    (whose mask reads otherwise): the header section's CRC-32 covers the magic line; 10.0 -> 10.1: the
    file's one CRC-32 covers it, and is checked before the version is judged."""
    assert "checksum mismatch" in refused(text_face_file.replace(b"mzc-dwt2d 3.1\n", b"mzc-dwt2d 3.0\n", 1)).message
    eight = fixture_bytes("dwt2d-8.0.mzw2")
    assert "checksum mismatch" in refused(eight.replace(b"mzc-dwt2d 8.0\n", b"mzc-dwt2d 7.0\n", 1)).message
    assert face_file.startswith(b"mzc-dwt2d 10.0\n")
    assert "checksum mismatch" in refused(face_file.replace(b"mzc-dwt2d 10.0\n", b"mzc-dwt2d 10.1\n", 1)).message


@pytest.mark.parametrize("name", ["dwt2d-3.0.mzw2", "dwt2d-2.0.mzw2"])
def test_older_dwt2d_files_refuse_bytes_after_the_payload_and_crlf(name):
    """The versions without a checksum still end at their payload and refuse text-mode copies."""
    data = fixture_bytes(name)
    for tail in (b"\x00", b"xx", b"\n" * 9):
        assert "after the end of the payload" in refused(data + tail, name).message
    header, payload = data.split(b"\ndata\n", 1)
    assert "CRLF" in refused(header.replace(b"\n", b"\r\n") + b"\r\ndata\r\n" + payload, name).message


def test_the_command_line_refuses_a_flipped_file_in_one_line(face_file, tmp_path):
    """decode and info: one stderr line naming the file and the crc32 line, exit 1, no output."""
    path = tmp_path / "f18.mzw2"
    path.write_bytes(flipped(face_file, 8 * (len(face_file) // 2)))
    for command in ("decode", "info"):
        result = run_mzc(command, path)
        lines = result.stderr.decode().splitlines()
        assert result.returncode == 1 and result.stdout == b""
        assert len(lines) == 1 and lines[0].startswith(f"mzc: {path}:") and "crc32: checksum mismatch" in lines[0]
