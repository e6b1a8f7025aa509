"""The validity mask as predicted flips through adaptive binary models (issue 33: small files small).

A row's *flips* are the columns c in 0..cols where validity changes between c-1 and c (outside
the row counts as invalid), 2 per span. Every row is coded from the row above:

- its span count, as the change from the row above's (0 above row 0);
- a row with as many spans as the row above (a *same* row) codes each flip's move from the same
  flip above minus that flip's move in the row above (0 when the row above was not a same row):
  a smooth boundary moves alike from row to row. The context is the flip's side (entering or
  leaving) and the signs of that flip's residual and move in the row above;
- any other row codes each flip from the first flip of the row above on the same side that lies
  right of the row's previous flip (the *reference*), or, when there is none, as a gap from it.

Each integer is binarised (nonzero, sign, the class k = bit length of |v| minus 1 in unary, the
top bit below the leading one, then k - 1 bits of probability 1/2) and every binary decision but
the last ones goes through an adaptive model: a pair of counts (n0, n1) giving P(1) = (2 n1 + 1)
/ (2 n + 2) in 24-bit fixed point, counts frozen once n = n0 + n1 reaches BIN_LIMIT. The bits
share the rANS coder of the payload (spec/dwt2d.md), so there are no tables to send and no raw
bits: measured on the 13 faces' masks (benchmarks/mask-coding-results.md) about 28% fewer bytes
than 7.0's span coding, and 10-30% fewer on whole objects' multi-chart grids.

The encoder computes every decision's probability up front (the counts before it within its
model: one stable sort), so the rows are visited once in Python and the bits never; the decoder
is the C loop ``_rows.decode_flips``.
"""

import numpy as np

from mzc.codecs.dwt2d import _rows

PRECISION = 24
BIN_LIMIT = 1 << 16          # a model's counts stop at n0 + n1 = 65536 (4096 cost the longest grid 5%)
HALF = -1                    # the model id of a decision of probability 1/2
PREFIX_BINS = 16             # unary class bits and top bits by class, capped at 15
BINS = 2 + 2 * PREFIX_BINS   # per context set: nonzero, sign, 16 prefix, 16 top-bit models
MAX_CLASS = 40               # a unary class longer than this is refused (flips are < 2**40)
COUNT_SET, SAME_SET, NEAR_SET, GAP_SET = 0, 1, 19, 21
SETS = 23


def row_flips(valid):
    """Per row, the flips (int64 columns in 0..cols where validity changes)."""
    padded = np.zeros((valid.shape[0], valid.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = valid
    flips = np.diff(padded, axis=1) != 0
    return [np.flatnonzero(row) for row in flips]


def integers(valid):
    """(values, context sets, signed) of the mask's integers in decoding order (the module's scheme)."""
    values, sets, signed = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=bool)]

    def put(v, s, sign=True):
        values.append(np.asarray(v, dtype=np.int64).ravel())
        sets.append(np.broadcast_to(np.asarray(s, dtype=np.int64), values[-1].shape))
        signed.append(np.full(values[-1].shape, sign))

    above = np.zeros(0, dtype=np.int64)
    moves = residuals = above
    for flips in row_flips(valid):
        put(len(flips) // 2 - len(above) // 2, COUNT_SET)
        if len(flips) and len(flips) == len(above):
            residual = flips - above - moves
            put(residual, same_sets(np.arange(len(flips)), residuals, moves))
            moves, residuals = flips - above, residual
        else:
            put(*new_row(flips, above))
            moves = residuals = np.zeros(len(flips), dtype=np.int64)
        above = flips
    return np.concatenate(values), np.concatenate(sets), np.concatenate(signed)


def same_sets(index, residuals, moves):
    """The context set of each flip of a same row: its side, the sign of its residual above and
    the sign of its move above (a jagged edge zigzags: the residual's sign tends to alternate)."""
    return SAME_SET + index % 2 + 2 * (np.sign(residuals) + 1) + 6 * (np.sign(moves) + 1)


def new_row(flips, above):
    """(values, sets, signed) of a row coded against its references in the row above (or as gaps)."""
    last = np.r_[-1, flips][:-1].astype(np.int64)
    side = np.arange(len(flips)) % 2
    reference = np.full(len(flips), -1, dtype=np.int64)
    for parity in (0, 1):
        candidates = above[parity::2]
        here = side == parity
        j = np.searchsorted(candidates, last[here], side="right")
        found = j < len(candidates)
        reference[np.flatnonzero(here)[found]] = candidates[j[found]]
    near = reference >= 0
    values = np.where(near, flips - reference, flips - last - 1)
    sets = np.where(near, NEAR_SET + side, GAP_SET + np.minimum(np.arange(len(flips)), 1))
    return values, sets, near


def binarised(values, sets, signed):
    """(bits, model ids) of the integers' binary decisions in order; model HALF: probability 1/2.

    Per integer: nonzero?; if so the sign (signed ones), k ones and a zero for the class k of |v|
    (bit length - 1), and the k bits of |v| below its leading one, the first with a model by k."""
    magnitude = np.abs(values)
    k = np.where(magnitude > 0, np.frexp(magnitude.astype(np.float64))[1] - 1, 0)
    nonzero = magnitude > 0
    sign = nonzero & signed
    lengths = 1 + sign + nonzero * (k + 1) + k
    owner = np.repeat(np.arange(len(values)), lengths)
    step = np.arange(int(lengths.sum())) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    o_k, o_sign, o_set = k[owner], sign[owner].astype(np.int64), sets[owner] * BINS
    prefix = step - 1 - o_sign           # 0..k: the unary bits
    low = prefix - (o_k + 1)             # 0..k-1: the bits below the leading one
    bits = np.select(
        [step == 0, (step == 1) & (o_sign == 1), prefix <= o_k],
        [nonzero[owner], values[owner] < 0, prefix < o_k],
        (magnitude[owner] >> np.maximum(o_k - 1 - low, 0)) & 1).astype(np.int64)
    models = np.select(
        [step == 0, (step == 1) & (o_sign == 1), prefix <= o_k, low == 0],
        [o_set, o_set + 1, o_set + 2 + np.minimum(prefix, PREFIX_BINS - 1),
         o_set + 2 + PREFIX_BINS + np.minimum(o_k, PREFIX_BINS - 1)], HALF)
    return bits, models


def probabilities(bits, models):
    """P(1) of each decision in PRECISION-bit fixed point, from its model's counts before it
    (frozen at BIN_LIMIT): floor((2 n1 + 1) 2**24 / (2 n + 2)), 2**23 for model HALF."""
    order = np.argsort(models, kind="stable")
    m, b = models[order], bits[order]
    start = np.flatnonzero(np.r_[True, m[1:] != m[:-1]]) if len(m) else np.zeros(0, dtype=np.int64)
    group = np.cumsum(np.r_[True, m[1:] != m[:-1]]) - 1 if len(m) else np.zeros(0, dtype=np.int64)
    seen = np.minimum(np.arange(len(m)) - start[group], BIN_LIMIT)   # n, frozen
    ones = np.concatenate([[0], np.cumsum(b)])                        # ones before each sorted place
    n1 = ones[start[group] + seen] - ones[start[group]]
    f1 = ((2 * n1 + 1) << PRECISION) // (2 * seen + 2)
    out = np.empty(len(m), dtype=np.int64)
    out[order] = np.where(m == HALF, 1 << (PRECISION - 1), f1)
    return out


def ideal_bits(valid):
    """Bits the mask costs in the rANS stream (-log2 of each decision's probability)."""
    bits, models = binarised(*integers(valid))
    f1 = probabilities(bits, models) / (1 << PRECISION)
    return float(-np.log2(np.where(bits == 1, f1, 1 - f1)).sum())


def decisions(valid):
    """(bits, weights) of the mask's decisions, as ``push`` takes them: made once for a payload that
    10.1 writes with each of two sets of models."""
    bits, models = binarised(*integers(valid))
    f1 = probabilities(bits, models)
    # Categorical(perfect=False) gives class s the probability (w_s + 1) / 2**24 when the weights sum
    # to 2**24 - 2: F - 1 per class reproduces F0 = 2**24 - F1 and F1 exactly (entropy.family_weights)
    return bits.astype(np.int32), np.stack([(1 << PRECISION) - f1 - 1, f1 - 1], axis=1).astype(np.float64)


def push(coder, decided):
    """Push the mask's ``decided`` (``decisions``) onto constriction's AnsCoder ``coder`` (last to
    first, so they decode first to last): call it after everything the payload decodes after the mask."""
    import constriction  # the encoder only

    bits, weights = decided
    coder.encode_reverse(bits, constriction.stream.model.Categorical(perfect=False), weights)


def alone(valid):
    """A payload holding the mask alone (no tables, its rANS words, no raw bits): its real size,
    and what the benchmarks and tests decode."""
    import constriction

    from mzc.codecs.dwt2d.entropy import varint

    coder = constriction.stream.stack.AnsCoder()
    push(coder, decisions(valid))
    words = coder.get_compressed()
    return varint(0) + varint(len(words)) + words.astype("<u4").tobytes()


def decode(decoder, rows, cols):
    """The validity mask (rows x cols) from the payload of ``decoder`` (entropy.Decoder) at its
    position; refuses span counts, classes and flips that no mask has."""
    valid = np.zeros((rows, cols), dtype=bool)
    bad = _rows.decode_flips(*decoder.stream, rows, cols, valid)
    if bad >= 0:
        raise decoder.error(f"mask row {bad + 1} has spans outside the row, out of order or too many")
    return valid
