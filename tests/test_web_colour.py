"""web/colour.mjs's decodeColour (spec/colour.md) against mzc.codecs.dwt2d.colour.decode_colour:
the same bytes on the fixtures of tests/fixtures/colour (the CDF 9/7 with a correction layer, the
lossless integer 5/3, and a version 2 section of colours twice finer than the nodes), the spec's
worked examples (versions 1, 2 and 3) and fresh sections of random images and masks (at colour
scales 1 to 3, and of version 3 on random multi-chart grids); damaged sections (cut, bytes added,
bytes changed under a right CRC-32, another mask) refused where mzc refuses them and decoded alike
otherwise; a section of the other kind of grid (version 3 without charts, version 2 with them)
refused by both in the same words. Whole files too: dwt2d files with colours finer than the nodes
(of one grid, and of a multi-chart grid) and a z-grid 6.0 of a multi-chart grid decode in web/'s
CLI to the z-grid bytes `mzc decode` writes. Skipped when node is not installed."""

import dataclasses
import random
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_colour_codec import FIXTURE_NAMES, fixture, spec_example
from test_fine_colour import spec_example_2, spec_example_3
from test_web_compact import node_json

from mzc.codecs.dwt2d import colour, encode_grid
from mzc.errors import MzcError
from mzc.formats import zgrid
from mzc.grid import Chart, ZGrid, fine_mask
from mzc.projections import PLANAR_VIEWS

from codec_contract import rechecksummed
from web_node import needs_node

pytestmark = needs_node

SCRIPT = """
import { readFileSync } from "node:fs";
import { decodeColour } from "./colour.mjs";
import { MzcError } from "./header.mjs";
const cases = JSON.parse(readFileSync(0, "utf8"));
process.stdout.write(JSON.stringify(cases.map(({ section, rows, cols, mask, charts }) => {
  try {
    const valid = Uint8Array.from(Buffer.from(mask, "hex"));
    const bytes = Uint8Array.from(Buffer.from(section, "hex"));
    return Buffer.from(decodeColour(bytes, { rows, cols, valid, charts })).toString("hex");
  } catch (error) {
    if (error instanceof MzcError) return { refused: error.message };
    throw error;
  }
})));
"""


def case_json(section, mask, charts=None):
    """One case of SCRIPT: the section and the node mask, and a multi-chart grid's ``charts`` (else null)."""
    return {"section": section.hex(), "rows": mask.shape[0], "cols": mask.shape[1],
            "mask": mask.astype(np.uint8).tobytes().hex(),
            "charts": None if charts is None else [dataclasses.asdict(chart) for chart in charts]}


def web_outcomes(cases):
    """decodeColour's image bytes (hex) for each (section, mask) or (section, mask, charts), or where
    it refuses it {"refused": its message}."""
    return node_json(SCRIPT, [case_json(*case) for case in cases])


def web_decoded(cases):
    """decodeColour's image bytes (hex) for each case of ``web_outcomes``, None where it refuses it."""
    return [got if isinstance(got, str) else None for got in web_outcomes(cases)]


def mzc_decoded(section, mask, charts=None):
    """decode_colour's image bytes (hex), None where it refuses the section."""
    try:
        return colour.decode_colour(section, mask, charts=charts).tobytes().hex()
    except MzcError:
        return None


def test_fixtures_and_the_worked_example_decode_as_mzc_decodes_them():
    section, samples, rgb = spec_example_2()
    cases = [fixture(name) for name in FIXTURE_NAMES]
    cases += [(*spec_example()[:2], None, spec_example()[2]), (section, samples[::2, ::2], None, rgb)]
    assert len(cases) == 6
    for (*_case, rgb), made in zip(cases, web_decoded([case[:3] for case in cases]), strict=True):
        assert made == rgb.astype(np.uint8).tobytes().hex()


def with_crc(section):
    """``section`` with its CRC-32 made right again (version 1: bytes 26..29, of bytes 0..25 and the
    payload; versions 2 and 3: a byte further)."""
    changed = bytearray(section)
    at = 26 if changed[4] == 1 else 27
    changed[at:at + 4] = zlib.crc32(changed[at + 4:], zlib.crc32(changed[:at])).to_bytes(4, "little")
    return bytes(changed)


def damaged(section, mask, charts, seed):
    """Variants of a section (of a multi-chart grid's ``charts``, else None): cut, bytes added,
    another mask, and 60 with 1 to 3 bytes changed under a right CRC-32 (its header fields among them)."""
    rng = random.Random(seed)
    yield section[:-1], mask, charts
    yield section[:20], mask, charts
    yield section + b"\0", mask, charts
    yield section, mask[:-1], charts
    yield section, ~mask, charts
    for _ in range(60):
        changed = bytearray(section)
        for _ in range(rng.choice((1, 1, 2, 3))):
            at = rng.randrange(30 if rng.random() < 0.8 else 0, len(section))
            changed[at] = rng.randrange(256) if rng.random() < 0.5 else changed[at] ^ (1 << rng.randrange(8))
        yield with_crc(changed), mask, charts


def test_damaged_sections_are_refused_or_decoded_as_mzc_decodes_them():
    cases = [case for number, name in enumerate(FIXTURE_NAMES) for case in damaged(*fixture(name)[:3], number)]
    made = web_decoded(cases)
    for case, got in zip(cases, made, strict=True):
        assert got == mzc_decoded(*case), case[0].hex()
    assert 0 < sum(got is None for got in made) < len(made)   # some refused, some decoded


def random_section(rng, nodes, scale, charts=None):
    """A fresh section of a random image (noise or smooth ramps) of colours ``scale`` times finer than
    the ``nodes`` (of a multi-chart grid with ``charts``), at a max error of 0 (the integer 5/3,
    lossless) to 20 and at 0 to 3 levels."""
    rows, cols = ((n - 1) * scale + 1 for n in nodes.shape)
    ramp = np.add.outer(np.arange(rows) * rng.uniform(0, 9), np.arange(cols) * rng.uniform(0, 9))
    rgb = (ramp[..., None] + rng.normal(0, rng.choice([0, 3, 60]), (rows, cols, 3))) % 256
    return colour.encode_colour(rgb.astype(np.uint8), nodes, max_error=int(rng.choice([0, 1, 3, 20])),
                                levels=int(rng.integers(0, 4)), scale=scale, charts=charts)


def side_by_side_charts(rng, rows, cols):
    """2 or 3 charts of random views side by side over a rows x cols grid (cols >= 3), its columns
    cut at random places."""
    cuts = sorted(int(c) for c in rng.choice(np.arange(1, cols), int(rng.integers(1, 3)), replace=False))
    return tuple(Chart(str(rng.choice(sorted(PLANAR_VIEWS))), 0, col0, rows, col1 - col0, 0, 0)
                 for col0, col1 in zip([0, *cuts], [*cuts, cols], strict=True))


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2 ** 32 - 1))
def test_random_images_decode_as_mzc_decodes_them(seed):
    """Sections of random images under random masks at colour scales 1 to 3: the same image bytes."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(6):
        scale = int(rng.integers(1, 4))
        nodes = rng.random(tuple(int(n) // scale + 1 for n in rng.integers(0, 23, 2))) < rng.choice([0.5, 0.9, 1.0])
        cases.append((random_section(rng, nodes, scale), nodes))
    for case, got in zip(cases, web_decoded(cases), strict=True):
        assert got is not None and got == mzc_decoded(*case)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2 ** 32 - 1))
def test_random_version_3_sections_decode_as_mzc_decodes_them(seed):
    """Version 3 sections of random images on random multi-chart grids (2 or 3 charts side by side,
    random node masks, colour scales 2 and 3): the same image bytes."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(6):
        rows, cols, scale = int(rng.integers(1, 10)), int(rng.integers(3, 12)), int(rng.integers(2, 4))
        nodes, charts = rng.random((rows, cols)) < rng.choice([0.6, 0.9, 1.0]), side_by_side_charts(rng, rows, cols)
        cases.append((random_section(rng, nodes, scale, charts), nodes, charts))
    for case, got in zip(cases, web_decoded(cases), strict=True):
        assert case[0][4] == 3 and got is not None and got == mzc_decoded(*case)


def test_the_version_3_worked_example_decodes_as_mzc_decodes_it():
    """spec/colour.md's version 3 section on its 2 x 4 grid of two charts: the image it shows, the
    samples of column 3 (between the charts) 0, in web/ and mzc alike."""
    section, nodes, charts, rgb = spec_example_3()
    assert len(charts) == 2 and nodes.shape == (2, 4)
    assert web_decoded([(section, nodes, charts)]) == [rgb.astype(np.uint8).tobytes().hex()]
    assert mzc_decoded(section, nodes, charts) == rgb.astype(np.uint8).tobytes().hex()


def test_a_section_of_the_other_kind_of_grid_is_refused_by_both_in_the_same_words():
    """Version 3 on a grid without charts, version 2 on a grid with them (its sample mask would read
    the samples between the charts as valid): refused by mzc and web/ alike, word for word."""
    rng = np.random.default_rng(3)
    nodes = rng.random((5, 7)) < 0.9
    charts = side_by_side_charts(rng, 5, 7)
    cases = [(random_section(rng, nodes, 2, charts), nodes, None), (random_section(rng, nodes, 2), nodes, charts)]
    for (section, mask, grid_charts), got in zip(cases, web_outcomes(cases), strict=True):
        with pytest.raises(MzcError, match=f"version {section[4]} belongs") as error:
            colour.decode_colour(section, mask, None, grid_charts)
        assert got == {"refused": str(error.value)}   # no source: "colour: ..." as web/ says it


def charted_grid(rng):
    """A 7 x 11 multi-chart grid, two charts side by side (columns 0-4 looking along +z, 5-10 along
    -x), a hole in the first, with random colours twice finer than its nodes."""
    z = rng.normal(0, 1, (7, 11))
    z[2:4, 1:3] = np.nan
    charts = (Chart("+z", 0, 0, 7, 5, 0, 0), Chart("-x", 0, 5, 7, 6, 3, -2))
    return ZGrid(z, 0.5, 0.5, units="mm", charts=charts, fine_colors=rng.integers(0, 256, (13, 21, 3)))


def assert_web_decodes_as_mzc(path):
    """`node web/cli.mjs decode` of the file at ``path`` writes the z-grid 6.0 bytes `mzc decode`
    writes; they are returned."""
    from test_web import mzc_decode, node_decode

    result = node_decode(path)
    assert result.returncode == 0, result.stderr.decode()
    assert result.stdout.startswith(b"mzc-zgrid 6.0\n") and result.stdout == mzc_decode(path)
    return result.stdout


def test_a_dwt2d_file_with_fine_colours_decodes_to_the_zgrid_6_mzc_writes(tmp_path):
    """web/'s decode of a whole dwt2d file whose colour section is of version 2 (colours twice finer
    than the nodes, a hole in the grid): the same z-grid 6.0 bytes as `mzc decode`."""
    rng = np.random.default_rng(5)
    z = rng.normal(0, 1, (9, 12))
    z[3:5, 4:7] = np.nan
    grid = ZGrid(z, 0.5, 0.5, units="mm", fine_colors=rng.integers(0, 256, (17, 23, 3)))
    (tmp_path / "fine.mzw2").write_bytes(encode_grid(grid, max_error=0.01, colour_max_error=2))
    assert_web_decodes_as_mzc(tmp_path / "fine.mzw2")


def test_a_dwt2d_file_of_a_multi_chart_grid_with_fine_colours_decodes_to_the_zgrid_6_mzc_writes(tmp_path):
    """web/'s decode of a whole dwt2d file of a multi-chart grid whose colour section is of version 3
    (the charts from the payload's chart records reach the colours' sample mask): the same z-grid
    6.0 bytes, its charts line among them, as `mzc decode`."""
    data = encode_grid(charted_grid(np.random.default_rng(7)), max_error=0.01, colour_max_error=2)
    assert b"mzcC\x03" in data   # the colour section's magic and version 3
    (tmp_path / "charted.mzw2").write_bytes(data)
    assert b"\ncharts +z 0 0 7 5 0 0 -x 0 5 7 6 3 -2\n" in assert_web_decodes_as_mzc(tmp_path / "charted.mzw2")


def test_a_zgrid_6_of_a_multi_chart_grid_decodes_as_mzc_decodes_it(tmp_path):
    """A z-grid 6.0 with charts whose every colour sample has random bytes (those between the charts
    and of invalid nodes too): web/ and mzc make the same samples 0, those the chart-aware sample
    mask leaves out, and write the same bytes."""
    grid = charted_grid(np.random.default_rng(11))
    noise = np.random.default_rng(12).integers(1, 256, grid.fine_colors.shape, dtype=np.uint8)
    data = zgrid.write(grid, raw="float64")
    (tmp_path / "charted.zg").write_bytes(rechecksummed(data[:-noise.size] + noise.tobytes()))
    written = assert_web_decodes_as_mzc(tmp_path / "charted.zg")
    expected = noise * fine_mask(grid.valid, 2, grid.charts)[..., None]
    assert written.endswith(expected.tobytes()) and not expected[:, 9].any()   # sample column 9: between the charts
