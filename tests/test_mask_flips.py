"""The mask as predicted flips (mzc.codecs.dwt2d.flips, _rows.decode_flips): exact round trips on the
faces', an object's and generated masks, its size against 7.0's span coding, hostile payloads."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.codecs.dwt2d import _rows, encode_mask, flips
from mzc.codecs.dwt2d import entropy as en
from mzc.errors import MzcError
from tests.conftest import REPO, face_path


def decoded(payload, rows, cols):
    """The mask a payload decodes to, after checking nothing is left over."""
    decoder = en.Decoder(payload, "<test>")
    valid = flips.decode(decoder, rows, cols)
    decoder.check_end()
    return valid


def spans_7_bytes(valid):
    """7.0's mask alone in a payload of its own (its three table records, rANS words and raw bits)."""
    encoder = en.Encoder(parametric=True)
    encode_mask(encoder, valid)
    return len(encoder.finish())


@pytest.mark.parametrize("name", ["f18.ply", "m56.ply", "f66.ply"])
def test_a_face_mask_round_trips_in_under_four_fifths_of_7_0s_bytes(name):
    valid = mzc.slice(str(face_path(name))).valid
    payload = flips.alone(valid)
    assert np.array_equal(decoded(payload, *valid.shape), valid)
    assert len(payload) <= 0.8 * spans_7_bytes(valid)


def test_an_objects_multi_chart_mask_round_trips_and_is_smaller():
    path = REPO.parent / "shared" / "data" / "objects" / "dragon.ply"
    if not path.is_file():
        pytest.skip(f"shared object data not available ({path})")
    grid = mzc.slice(str(path))
    assert len(grid.charts) > 1
    payload = flips.alone(grid.valid)
    assert np.array_equal(decoded(payload, *grid.valid.shape), grid.valid)
    assert len(payload) < spans_7_bytes(grid.valid)


def blob(rows, cols, seed):
    """A smooth blob with a wobbly edge and a hole: a face's mask in miniature."""
    rng = np.random.default_rng(seed)
    r, c = np.mgrid[0:rows, 0:cols]
    angle = np.arctan2(r - rows / 2, c - cols / 2)
    radius = 0.4 * min(rows, cols) * (1 + 0.1 * np.sin(3 * angle + rng.uniform(0, 6)))
    inside = np.hypot(r - rows / 2, c - cols / 2) < radius
    inside[rows // 3:rows // 3 + 3, cols // 3:cols // 3 + 2] = False
    return inside


@pytest.mark.parametrize("shape", [(1, 1), (1, 40), (40, 1), (60, 90), (257, 31)])
def test_generated_blobs_round_trip_and_an_all_valid_grid_costs_a_few_bytes(shape):
    valid = blob(*shape, seed=sum(shape))
    assert np.array_equal(decoded(flips.alone(valid), *shape), valid)
    full = np.ones(shape, dtype=bool)
    assert np.array_equal(decoded(flips.alone(full), *shape), full)
    assert len(flips.alone(full)) <= 12


masks = st.tuples(st.integers(0, 14), st.integers(0, 14), st.integers(0, 2 ** 32 - 1), st.floats(0, 1)).map(
    lambda t: np.random.default_rng(t[2]).random((t[0], t[1])) < t[3])


@settings(max_examples=300, deadline=None)
@given(masks)
def test_any_mask_round_trips_and_its_ideal_cost_is_its_size(valid):
    payload = flips.alone(valid)
    assert np.array_equal(decoded(payload, *valid.shape), valid)
    words = len(payload) - 2
    assert flips.ideal_bits(valid) / 8 <= words + 1 and words <= flips.ideal_bits(valid) / 8 + 8


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 12), st.integers(0, 12), st.lists(st.integers(0, 2 ** 32 - 1), max_size=12))
def test_any_words_decode_to_a_mask_or_one_error(rows, cols, words):
    """Arbitrary rANS words: a mask whose every row has its spans inside the grid, or an MzcError
    naming the data; never a crash or a hang."""
    payload = en.varint(0) + en.varint(len(words)) + np.array(words, dtype="<u4").tobytes()
    try:
        decoder = en.Decoder(payload, "<words>")
        valid = flips.decode(decoder, rows, cols)
    except MzcError as error:
        assert "data" in str(error) or "mask row" in str(error) or "rANS" in str(error)
        return
    assert valid.shape == (rows, cols)


def test_a_corrupted_mask_is_refused_with_the_row_named():
    valid = blob(60, 90, seed=1)
    payload = bytearray(flips.alone(valid))
    refused = 0
    for index in range(2, len(payload)):
        damaged = bytearray(payload)
        damaged[index] ^= 0xFF
        try:
            out = decoded(bytes(damaged), *valid.shape)
        except MzcError as error:
            refused += 1
            assert str(error).count("\n") == 0
            continue
        assert not np.array_equal(out, valid)
    assert refused > 0


def test_the_c_decoder_refuses_a_mask_buffer_of_the_wrong_size():
    decoder = en.Decoder(flips.alone(np.ones((3, 4), dtype=bool)), "<test>")
    with pytest.raises(ValueError):
        _rows.decode_flips(*decoder.stream, 3, 4, np.zeros(11, dtype=bool))


def test_the_spec_example_of_8_0_is_7_0s_grid_and_its_mask_rows_are_as_stated():
    """spec/dwt2d.md, Worked example of version 8.0: the 7.0 example's values, its rows' flips and
    the first decisions' probabilities as the text reads them."""
    from codec_contract import spec_examples

    examples = [data for data, _values, _id in spec_examples("dwt2d")]
    seven, eight = (mzc.decode(next(d for d in examples if d.startswith(f"mzc-dwt2d {v}\n".encode())))
                    for v in ("7.0", "8.0"))   # the first 7.0 example: the one without colours
    np.testing.assert_array_equal(eight.z, seven.z)
    assert [f.tolist() for f in flips.row_flips(eight.valid)] == [[0, 6], [0, 6], [0, 2, 3, 6], [0, 6]]
    values, sets, signed = flips.integers(eight.valid)
    assert values.tolist() == [1, 0, 5, 0, 0, 0, 1, 0, -4, 0, 0, -1, 0, 4]
    assert sets.tolist() == [0, 21, 22, 0, 9, 10, 0, 19, 20, 22, 20, 0, 19, 20]
    bits, models = flips.binarised(values, sets, signed)
    assert flips.probabilities(bits, models)[10] == 12582912   # row 1's count change: set 0's Z at (0, 1)


def test_a_sliced_face_is_written_as_8_0_with_its_vertex_count():
    """8.0 has every 7.0 field and source_vertices: a sliced face's count comes back; its 7.0 file (the
    same integers but the mask, without the count) decodes to the same values and is larger."""
    from mzc.codecs import dwt2d

    grid = mzc.slice(str(face_path("f18.ply")))
    assert grid.source_vertices
    prepared = dwt2d.Prepared(grid, "bior4.4", None, 2.0, compact=dwt2d.FLIPS_VERSION)
    new = prepared.encode(0.3)[0]
    prepared.compact = dwt2d.COMPACT_VERSION
    old = prepared.encode(0.3)[0]
    assert new.startswith(b"mzc-dwt2d 8.0\n") and old.startswith(b"mzc-dwt2d 7.0\n")
    a, b = mzc.decode(new), mzc.decode(old)
    assert (a.source_vertices, b.source_vertices) == (grid.source_vertices, None)
    np.testing.assert_array_equal(a.z, b.z)
    assert len(new) < len(old) - 50
