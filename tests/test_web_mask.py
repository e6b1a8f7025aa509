"""web/mask.mjs, the browser's decoder of the 8.0 mask (spec/dwt2d.md, Version 8.0), against mzc's:
the same mask from the same payload on the faces', an object's and any random mask, and a refusal
of the same damaged payloads. Skipped when node is not installed."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import mzc
from mzc.codecs.dwt2d import entropy as en
from mzc.codecs.dwt2d import flips
from mzc.errors import MzcError

from conftest import REPO, face_path
from web_node import needs_node, node_json

pytestmark = needs_node

SCRIPT = """
import { readFileSync } from "node:fs";
import { Payload } from "./dwt2d.mjs";
import { decodeFlips } from "./mask.mjs";
import { MzcError } from "./header.mjs";
const cases = JSON.parse(readFileSync(0, "utf8"));
process.stdout.write(JSON.stringify(cases.map(([hex, rows, cols]) => {
  try {
    const payload = new Payload(Uint8Array.from(Buffer.from(hex, "hex")), true);
    const mask = decodeFlips(payload, rows, cols);
    payload.finish();
    return Buffer.from(mask).toString("hex");
  } catch (error) {
    if (error instanceof MzcError) return null;
    throw error;
  }
})));
"""


def mzc_mask(payload, rows, cols):
    """mzc's mask of a payload as web's hex of one byte a node, or None where mzc refuses it."""
    try:
        decoder = en.Decoder(payload, "<test>")
        valid = flips.decode(decoder, rows, cols)
        decoder.check_end()
    except MzcError:
        return None
    return valid.astype(np.uint8).tobytes().hex()


def web_masks(cases):
    """web's masks of (payload, rows, cols) cases (None where it refuses one)."""
    return node_json(SCRIPT, [[p.hex(), r, c] for p, r, c in cases])


def test_real_masks_decode_as_mzc_decodes_them():
    """Three faces and, when there, a multi-chart object (its rows come and go)."""
    grids = [mzc.slice(str(face_path(name))).valid for name in ("f18.ply", "m66.ply", "example.obj")]
    dragon = REPO.parent / "shared" / "data" / "objects" / "dragon.ply"
    if dragon.is_file():
        grids.append(mzc.slice(str(dragon)).valid)
    cases = [(flips.alone(valid), *valid.shape) for valid in grids]
    for valid, made in zip(grids, web_masks(cases), strict=True):
        assert made == valid.astype(np.uint8).tobytes().hex()


masks = st.tuples(st.integers(0, 16), st.integers(0, 16), st.integers(0, 2 ** 32 - 1), st.floats(0, 1)).map(
    lambda t: np.random.default_rng(t[2]).random((t[0], t[1])) < t[3])


@settings(max_examples=20, deadline=None)
@given(st.lists(masks, min_size=1, max_size=30))
def test_random_masks_decode_as_mzc_decodes_them(valids):
    cases = [(flips.alone(valid), *valid.shape) for valid in valids]
    assert web_masks(cases) == [valid.astype(np.uint8).tobytes().hex() for valid in valids]


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10), st.integers(0, 10), st.lists(st.lists(st.integers(0, 2 ** 32 - 1), max_size=10),
                                                         min_size=1, max_size=30))
def test_any_words_give_the_mask_or_the_refusal_mzc_gives(rows, cols, word_lists):
    """Arbitrary rANS words: web and mzc decode the same mask, or both refuse."""
    cases = [(en.varint(0) + en.varint(len(w)) + np.array(w, dtype="<u4").tobytes(), rows, cols) for w in word_lists]
    assert web_masks(cases) == [mzc_mask(*case) for case in cases]
