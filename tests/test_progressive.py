"""Progressive files (mzc-dwt2d 9.0, issue 33): levels in sections coarsest first, each with its own
CRC-32 and entropy stream, so that a prefix of whole sections (a cut download, ``decode --levels K``)
decodes to the coarser surface of its whole levels; opt-in, the default staying 8.0."""

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mzc import api
from mzc.codecs import dwt2d
from mzc.codecs.dwt2d import compact
from mzc.errors import MzcError, MzcWarning
from mzc.grid import ZGrid

from codec_contract import fixture_bytes
from conftest import face_path


def surface(rows=40, cols=56, seed=0, holes=True):
    """A smooth planar patch with noise, ragged corners and a hole."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:rows, 0:cols] / 6.0
    z = 10 + 2 * np.sin(x) * np.cos(y / 2) + 0.1 * x + rng.normal(0, 0.02, (rows, cols))
    if holes:
        z[rows // 2:rows // 2 + 3, cols // 3:cols // 3 + 4] = np.nan
        z[:3, :4] = np.nan
    return ZGrid(z=z, d1=0.5, d2=0.5, origin=(-3.0, 1.5), units="mm")


def decoded_quietly(data, **options):
    """The grid of ``data`` and the messages of the warnings its decoding gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        grid = dwt2d.read(data, "p.mzw2", **options)
    return grid, [str(w.message) for w in caught if issubclass(w.category, MzcWarning)]


@pytest.mark.parametrize("target", [{"max_error": 0.05}, {"rmse": 0.02}, {"size": 1200}])
def test_a_progressive_file_decodes_as_its_8_0_file_would_and_meets_the_target(target):
    grid = surface()
    data, heights = dwt2d.CODEC.encode_with_decoded(grid, progressive=True, **target)
    assert data.startswith(b"mzc-dwt2d 9.0\n")
    back = dwt2d.read(data)
    np.testing.assert_array_equal(back.z, heights)
    if "max_error" in target:
        assert np.nanmax(np.abs(back.z - grid.z)) <= target["max_error"]
    if "size" in target:
        assert len(data) <= target["size"]
    whole = dwt2d.read(dwt2d.write(grid, **target))
    assert np.array_equal(whole.valid, back.valid)


def test_the_default_stays_whole_and_progressive_false_is_the_default():
    grid = surface()
    data = dwt2d.write(grid, rmse=0.02)
    assert data.startswith(b"mzc-dwt2d 10.0\n") and dwt2d.write(grid, rmse=0.02, progressive=False) == data


def test_levels_decode_band_0_and_the_coarsest_levels_the_rest_zero():
    grid = surface()
    data = dwt2d.write(grid, rmse=0.02, progressive=True)
    levels = int(compact.read(data, "p")[0].integer("levels", required=False, default=dwt2d.w2.default_levels(
        grid.shape, dwt2d.w2.TRANSFORMS[9].coarsest)))
    whole = dwt2d.read(data).z
    errors = [np.sqrt(np.nanmean((dwt2d.read(data, wanted=k).z - whole) ** 2)) for k in range(levels + 2)]
    assert errors[levels] == errors[levels + 1] == 0
    assert all(a >= b for a, b in zip(errors, errors[1:])) and errors[0] > 0


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rows=st.integers(9, 40), cols=st.integers(9, 40), seed=st.integers(0, 1000),
       target=st.sampled_from([{"max_error": 0.05}, {"rmse": 0.01}]), coloured=st.booleans())
def test_a_prefix_of_whole_sections_decodes_as_levels_k(rows, cols, seed, target, coloured):
    grid = surface(rows, cols, seed)
    if coloured:
        grid = ZGrid(z=grid.z, d1=grid.d1, d2=grid.d2, origin=grid.origin, units=grid.units,
                     colors=np.random.default_rng(seed).integers(0, 256, (rows, cols, 3), dtype=np.uint8))
    data = dwt2d.write(grid, progressive=True, **target)
    sections = compact.read_progressive(data, "p")
    levels = len(sections.ends) - 1
    for k, end in enumerate(sections.ends):
        prefix, messages = decoded_quietly(data[:end])
        wanted = dwt2d.read(data, wanted=k)
        np.testing.assert_array_equal(prefix.z, wanted.z)
        complete = k == levels and not coloured
        assert len(messages) == (0 if complete else 1)
        if not complete:
            assert f"of its {levels} detail levels" in messages[0] or "colour section" in messages[0]
        assert prefix.colors is None   # the colour section comes after the levels
    assert (dwt2d.read(data).colors is None) != coloured


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 1000))
def test_a_file_cut_anywhere_is_refused_in_one_line_or_decodes_coarser(seed):
    grid = surface(24, 30, seed)
    data = dwt2d.write(grid, max_error=0.05, progressive=True)
    base_end = compact.read_progressive(data, "p").ends[0]
    for n in range(len(data)):
        try:
            back, messages = decoded_quietly(data[:n])
        except MzcError as error:
            assert n < base_end and "\n" not in str(error)
            continue
        assert n >= base_end and len(messages) == 1 and np.array_equal(back.valid, grid.valid)


def test_a_damaged_complete_section_is_refused_not_dropped():
    data = dwt2d.write(surface(), rmse=0.02, progressive=True)
    ends = compact.read_progressive(data, "p").ends
    for position in (ends[0] + 3, ends[1] - 1, len(data) - 10):
        bad = data[:position] + bytes([data[position] ^ 0x20]) + data[position + 1:]
        with pytest.raises(MzcError, match="checksum mismatch"):
            dwt2d.read(bad)


def test_sections_swapped_or_spliced_from_another_file_are_refused():
    """Each level section's CRC-32 starts from the one before it: the right tags in another order fail."""
    data = dwt2d.write(surface(), rmse=0.02, progressive=True)
    ends = compact.read_progressive(data, "p").ends
    first, second = data[ends[0]:ends[1]], data[ends[1]:ends[2]]
    swapped = data[:ends[0]] + second + first + data[ends[2]:]
    with pytest.raises(MzcError, match="checksum mismatch"):
        dwt2d.read(swapped)


def test_levels_on_a_file_that_is_not_progressive_is_one_clear_error():
    data = dwt2d.write(surface(), rmse=0.02)
    with pytest.raises(MzcError, match="takes a progressive file"):
        dwt2d.read(data, wanted=1)
    with pytest.raises(MzcError, match="takes a progressive file"):
        api.decode(data, levels=1)
    with pytest.raises(MzcError, match="must be a whole number"):
        api.decode(dwt2d.write(surface(), rmse=0.02, progressive=True), levels=1.5)


def test_progressive_refuses_tiles_and_takes_only_true_or_false():
    with pytest.raises(MzcError, match="codes the grid whole"):
        dwt2d.write(surface(), rmse=0.02, progressive=True, tile=16)
    with pytest.raises(MzcError, match="True or False"):
        dwt2d.write(surface(), rmse=0.02, progressive=1)


def test_the_cut_fixture_is_the_whole_fixture_decoded_to_its_first_level():
    whole, cut = fixture_bytes("dwt2d-9.0.mzw2"), fixture_bytes("dwt2d-9.0-cut.mzw2")
    assert whole.startswith(cut[:-5])
    coarse, messages = decoded_quietly(cut)
    assert messages == ["p.mzw2: the file is cut short: decoded 1 of its 2 detail levels, a coarser surface "
                        "(without its finest levels and colours)"]
    np.testing.assert_array_equal(coarse.z, dwt2d.read(whole, wanted=1).z)


def test_cli_on_a_real_face_encodes_progressive_decodes_levels_and_a_cut_file(mzc, tmp_path):
    face = face_path("f18.ply")
    grid_path, coded = tmp_path / "f18.zg", tmp_path / "f18.mzw2"
    mzc("slice", str(face), "-o", str(grid_path), check=True)
    mzc("encode", "--progressive", "--rmse", "0.1", str(grid_path), "-o", str(coded), check=True)
    data = coded.read_bytes()
    sections = compact.read_progressive(data, "f18")
    info = mzc("info", str(coded), check=True).stdout.decode()
    assert "mzc-dwt2d 9.0" in info and f"the first {sections.ends[2]} bytes decode to here" in info
    mzc("decode", "--levels", "2", str(coded), "-o", str(tmp_path / "l2.zg"), check=True)
    cut = tmp_path / "cut.mzw2"
    cut.write_bytes(data[:sections.ends[2] + 7])
    result = mzc("decode", str(cut), "-o", str(tmp_path / "cut.zg"))
    assert result.returncode == 0 and result.stderr.count(b"\n") == 1
    assert f"decoded 2 of its {len(sections.ends) - 1} detail levels" in result.stderr.decode()
    cut_info = mzc("info", str(cut), check=True).stdout.decode()
    assert f"it holds 2 of its {len(sections.ends) - 1} detail levels whole" in cut_info
    levels = api.decode((tmp_path / "l2.zg").read_bytes()).z
    np.testing.assert_array_equal(levels, api.decode((tmp_path / "cut.zg").read_bytes()).z)
    refused = mzc("decode", "--levels", "1", str(grid_path))
    assert refused.returncode != 0 and refused.stderr.count(b"\n") == 1 and b"Traceback" not in refused.stderr


def test_the_spec_worked_example_is_the_whole_file_and_its_cut_prefix():
    """spec/dwt2d.md's 9.0 example: its second file is its first one's header and base sections,
    which decode (with the one warning) to band 0 alone, as levels 0 of the whole file does."""
    from codec_contract import spec_examples

    (whole, heights, _), (prefix, coarse, _) = [example for example in spec_examples("dwt2d")
                                                if example[0].startswith(b"mzc-dwt2d 9.0\n")]
    assert whole.startswith(prefix) and compact.read_progressive(whole, "spec").ends[0] == len(prefix)
    cut, messages = decoded_quietly(prefix)
    assert messages == ["p.mzw2: the file is cut short: decoded 0 of its 1 detail levels, a coarser surface "
                        "(without its finest levels)"]
    np.testing.assert_array_equal(cut.z, dwt2d.read(whole, wanted=0).z)
    np.testing.assert_allclose(cut.z, coarse, atol=1e-7)
    np.testing.assert_allclose(dwt2d.read(whole).z, heights, atol=1e-7)


def test_more_level_sections_than_levels_or_another_tag_are_refused_in_one_line():
    data = dwt2d.write(surface(), rmse=0.02, progressive=True)
    sections = compact.read_progressive(data, "p")
    last = data[sections.ends[-2]:sections.ends[-1]]
    extra = compact.chained([(compact.LEVEL, sections.bodies[-1])], last[-4:])   # one level section too many
    with pytest.raises(MzcError, match="level sections for"):
        dwt2d.read(data + extra)
    payload = compact.chained([(compact.PAYLOAD, sections.bodies[1])], data[sections.ends[0] - 4:sections.ends[0]])
    with pytest.raises(MzcError, match="section tag 2 where section 3 belongs"):
        dwt2d.read(data[:sections.ends[0]] + payload)


def test_levels_beyond_the_files_decode_all_of_it_and_a_level_count_is_checked():
    data = dwt2d.write(surface(), max_error=0.05, progressive=True)
    np.testing.assert_array_equal(dwt2d.read(data, wanted=99).z, dwt2d.read(data).z)
    np.testing.assert_array_equal(api.decode(data, levels=99).z, dwt2d.read(data).z)
    with pytest.raises(MzcError, match="legacy"):
        api.decode(data, legacy="dwt", levels=1)
