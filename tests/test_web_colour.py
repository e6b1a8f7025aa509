"""web/colour.mjs's decodeColour (spec/colour.md) against mzc.codecs.dwt2d.colour.decode_colour:
the same bytes on the fixtures of tests/fixtures/colour (the CDF 9/7 with a correction layer, the
lossless integer 5/3, and a version 2 section of colours twice finer than the nodes), the spec's
worked examples and fresh sections of random images and masks (at colour scales 1 to 3); damaged
sections (cut, bytes added, bytes changed under a right CRC-32, another mask) refused where mzc
refuses them and decoded alike otherwise. Skipped when node is not installed."""

import random
import zlib

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_colour_codec import spec_example
from test_fine_colour import spec_example_2
from test_web_compact import node_json

from mzc.codecs.dwt2d import colour
from mzc.errors import MzcError

from codec_contract import FIXTURES
from web_node import needs_node

COLOUR_FIXTURES = FIXTURES / "colour"

pytestmark = needs_node

SCRIPT = """
import { readFileSync } from "node:fs";
import { decodeColour } from "./colour.mjs";
import { MzcError } from "./header.mjs";
const cases = JSON.parse(readFileSync(0, "utf8"));
process.stdout.write(JSON.stringify(cases.map(({ section, rows, cols, mask }) => {
  try {
    const valid = Uint8Array.from(Buffer.from(mask, "hex"));
    const bytes = Uint8Array.from(Buffer.from(section, "hex"));
    return Buffer.from(decodeColour(bytes, { rows, cols, valid })).toString("hex");
  } catch (error) {
    if (error instanceof MzcError) return null;
    throw error;
  }
})));
"""


def web_decoded(cases):
    """decodeColour's image bytes (hex) for each (section, mask), None where it refuses it."""
    return node_json(SCRIPT, [{"section": section.hex(), "rows": mask.shape[0], "cols": mask.shape[1],
                               "mask": mask.astype(np.uint8).tobytes().hex()} for section, mask in cases])


def mzc_decoded(section, mask):
    """decode_colour's image bytes (hex), None where it refuses the section."""
    try:
        return colour.decode_colour(section, mask).tobytes().hex()
    except MzcError:
        return None


def fixtures():
    """(section bytes, mask, image) of each colour fixture."""
    for path in sorted(COLOUR_FIXTURES.glob("*.bin")):
        expected = np.load(path.with_name(path.stem + ".expected.npz"))
        yield path.read_bytes(), expected["mask"], expected["rgb"]


def test_fixtures_and_the_worked_example_decode_as_mzc_decodes_them():
    section, samples, rgb = spec_example_2()
    cases = [*fixtures(), spec_example(), (section, samples[::2, ::2], rgb)]
    assert len(cases) == 5
    for (_section, _mask, rgb), made in zip(cases, web_decoded([case[:2] for case in cases]), strict=True):
        assert made == rgb.astype(np.uint8).tobytes().hex()


def with_crc(section):
    """``section`` with its CRC-32 made right again (version 1: bytes 26..29, of bytes 0..25 and the
    payload; version 2: a byte further)."""
    changed = bytearray(section)
    at = 27 if changed[4] == 2 else 26
    changed[at:at + 4] = zlib.crc32(changed[at + 4:], zlib.crc32(changed[:at])).to_bytes(4, "little")
    return bytes(changed)


def damaged(section, mask, seed):
    """Variants of a section: cut, bytes added, another mask, and 60 with 1 to 3 bytes changed under
    a right CRC-32 (its header fields among them)."""
    rng = random.Random(seed)
    yield section[:-1], mask
    yield section[:20], mask
    yield section + b"\0", mask
    yield section, mask[:-1]
    yield section, ~mask
    for _ in range(60):
        changed = bytearray(section)
        for _ in range(rng.choice((1, 1, 2, 3))):
            at = rng.randrange(30 if rng.random() < 0.8 else 0, len(section))
            changed[at] = rng.randrange(256) if rng.random() < 0.5 else changed[at] ^ (1 << rng.randrange(8))
        yield with_crc(changed), mask


def test_damaged_sections_are_refused_or_decoded_as_mzc_decodes_them():
    cases = [case for number, (section, mask, _rgb) in enumerate(fixtures()) for case in damaged(section, mask, number)]
    made = web_decoded(cases)
    for (section, mask), got in zip(cases, made, strict=True):
        assert got == mzc_decoded(section, mask), section.hex()
    assert 0 < sum(got is None for got in made) < len(made)   # some refused, some decoded


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2 ** 32 - 1))
def test_random_images_decode_as_mzc_decodes_them(seed):
    """Sections of random images (noise or smooth ramps) under random masks, at max errors 0 (the
    integer 5/3, lossless) to 20 and at several levels: the same image bytes."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(6):
        rows, cols = (int(n) for n in rng.integers(1, 24, 2))
        ramp = np.add.outer(np.arange(rows) * rng.uniform(0, 9), np.arange(cols) * rng.uniform(0, 9))
        rgb = (ramp[..., None] + rng.normal(0, rng.choice([0, 3, 60]), (rows, cols, 3))) % 256
        mask = rng.random((rows, cols)) < rng.choice([0.5, 0.9, 1.0])
        levels, scale = int(rng.integers(0, 4)), int(rng.integers(1, 4))
        nodes = mask[::scale, ::scale]   # at scale K the image is the colours K times finer than these nodes
        rgb = rgb[:(nodes.shape[0] - 1) * scale + 1, :(nodes.shape[1] - 1) * scale + 1]
        cases.append((colour.encode_colour(rgb.astype(np.uint8), nodes, max_error=int(rng.choice([0, 1, 3, 20])),
                                           levels=levels, scale=scale), nodes))
    for (section, mask), got in zip(cases, web_decoded(cases), strict=True):
        assert got is not None and got == mzc_decoded(section, mask)


def test_a_dwt2d_file_with_fine_colours_decodes_to_the_zgrid_6_mzc_writes(tmp_path):
    """web/'s decode of a whole dwt2d file whose colour section is of version 2 (colours twice finer
    than the nodes, a hole in the grid): the same z-grid 6.0 bytes as `mzc decode`."""
    from test_web import mzc_decode, node_decode

    from mzc.codecs.dwt2d import encode_grid
    from mzc.grid import ZGrid

    rng = np.random.default_rng(5)
    z = rng.normal(0, 1, (9, 12))
    z[3:5, 4:7] = np.nan
    grid = ZGrid(z, 0.5, 0.5, units="mm", fine_colors=rng.integers(0, 256, (17, 23, 3)))
    (tmp_path / "fine.mzw2").write_bytes(encode_grid(grid, max_error=0.01, colour_max_error=2))
    result = node_decode(tmp_path / "fine.mzw2")
    assert result.returncode == 0, result.stderr.decode()
    assert result.stdout.startswith(b"mzc-zgrid 6.0\n") and result.stdout == mzc_decode(tmp_path / "fine.mzw2")
