"""Entropy coding of integers: magnitude classes through rANS, the rest as raw bits.

A value v maps to a class k (0 for v = 0, else the bit length of |v|) and, for k >= 1, raw
bits: the sign (1 = negative; none for values added as unsigned) then the k-1 bits of |v|
below its leading one. Classes go through a static categorical model per context whose
frequency table (summing to 2**TABLE_BITS) is sent in the payload as one 6-bit log-scale
weight per class; raw bits go to a separate bit buffer. The classes are coded with the
rANS coder of ``constriction`` (AnsCoder: 32-bit words, 64-bit state, 24-bit
probabilities), vectorised per run of symbols whose tables have one class count.
spec/dwt2d.md gives the exact arithmetic, and the decoder does it itself: its integers are
decoded by the C loops of mzc.codecs.dwt2d._rows (a row's contexts depend on the row decoded
just before). So a decode does not load constriction.
"""

import functools
import math

import numpy as np

from mzc import elementary
from mzc.codecs.dwt2d import _rows
from mzc.errors import MzcError

TABLE_BITS = 14
KEPT = b"\x01"            # 9.0's level sections: a table record keeping the base section's table of its model
MAX_CLASSES = 48          # |v| < 2**47: far beyond any quantised height
ANS_PRECISION = 24


# --------------------------------------------------------------------------- classes


def classes(values):
    """Magnitude class of each int64 value: 0 for zero, else the bit length of |v|."""
    return np.frexp(np.abs(values).astype(np.float64))[1].astype(np.int64)


def raw_bits(values, cls, signed):
    """The raw bits of each value, concatenated MSB first: the sign (1 = negative) where
    ``signed`` (per value), then the bits of |v| below its leading one."""
    nonzero = cls > 0
    values, cls, signed = values[nonzero], cls[nonzero], signed[nonzero]
    if not len(values):
        return np.zeros(0, dtype=np.uint8)
    width = cls - 1 + signed
    low = np.abs(values) - (np.int64(1) << (cls - 1))
    word = ((values < 0).astype(np.int64) << (cls - 1)) * signed | low
    # bit j of the output belongs to word ``owner`` and sits ``shift`` places from its end: work in
    # proportion to the bits, most values having one or none (a values x widest-word matrix was not)
    ends = np.cumsum(width)
    owner = np.repeat(np.arange(len(width)), width)
    shift = ends[owner] - 1 - np.arange(int(ends[-1]))
    return ((word[owner] >> shift) & 1).astype(np.uint8)


# --------------------------------------------------------------------------- tables


CODE_BITS = 6                       # a table codes each class's weight in 6 bits...
CODE_MANTISSAS = (16, 19, 23, 27)   # ...on a log scale: weight(e) = M[e mod 4] * 2**(e div 4), 0 for e = 0
CODE_WEIGHTS = np.array([0] + [CODE_MANTISSAS[e % 4] << (e // 4) for e in range(1, 1 << CODE_BITS)], dtype=np.int64)


def frequencies(codes):
    """The table (frequencies >= 1 summing to 2**TABLE_BITS) that weight codes stand for (normalised)."""
    return normalised(CODE_WEIGHTS[np.asarray(codes, dtype=np.int64)])


def normalised(weights):
    """The table (frequencies >= 1 summing to 2**TABLE_BITS) of integer ``weights`` (or one per row of them).

    Each class gets 1 plus its share of the rest in proportion to its weight (floored); what
    the flooring leaves goes to the first class of largest weight. Integer arithmetic only,
    so every decoder builds the same table.
    """
    weights = np.asarray(weights, dtype=np.int64)   # summing to at most 2**48 (parametric), so w * 2**14 fits
    total = 1 << TABLE_BITS
    freq = 1 + (weights * (total - weights.shape[-1])) // np.maximum(weights.sum(axis=-1, keepdims=True), 1)
    first_top = np.arange(weights.shape[-1]) == np.argmax(weights, axis=-1)[..., None]
    return freq + first_top * (total - freq.sum(axis=-1, keepdims=True))


# 7.0's parametric tables: P(0) = z/256, and a nonzero |v| - 1 geometric of ratio theta, 1 - theta =
# 2**(-t/16) for a code t (0..255), its powers in 32-bit fixed point (floored products), so that a
# table is three bytes (S, z, t) instead of 1 + 6S/8, and every decoder builds it alike
PARAMETRIC_BITS = 32
ROOTS = tuple(math.isqrt(math.isqrt(math.isqrt(math.isqrt(1 << (16 * PARAMETRIC_BITS - i)))))   # floor(2**(32 - i/16))
              for i in range(16))
RATIO_CODES = 256
ZERO_CODES = 256


def power(theta, n):
    """theta**n in PARAMETRIC_BITS fixed point, by squaring, each product floored: exact integers."""
    result, base, one = 1 << PARAMETRIC_BITS, theta, PARAMETRIC_BITS
    while n:
        if n & 1:
            result = (result * base) >> one
        base = (base * base) >> one
        n >>= 1
    return result


def parametric_weights(size, zero, ratio, zeros=ZERO_CODES):
    """Integer weights of ``size`` classes: class 0 ``zero``/``zeros`` of the mass (``zeros``: 256 in 7.0's
    records, SHORT_ZERO_CODES in 10.0's one-byte records); class k >= 1 holds |v| in
    2**(k-1) .. 2**k - 1, whose share of the rest is its step (parametric_steps)."""
    return scaled_steps(zero, parametric_steps(size, ratio), zeros)


@functools.cache
def parametric_steps(size, ratio):
    """Unscaled weights of classes 1..size-1 of the ratio code ``ratio`` (int64, read-only: cached, as a
    decoder meets a few codes many times): theta**(2**(k-1) - 1) - theta**(2**k - 1) for class k, the
    last class taking the whole tail theta**(2**(size-2) - 1) (exact integers below 2**33)."""
    theta = (1 << PARAMETRIC_BITS) - (ROOTS[ratio % 16] >> (ratio // 16))
    tails = [power(theta, (1 << (k - 1)) - 1) for k in range(1, size)] + [0]
    steps = np.array([tails[k] - tails[k + 1] for k in range(size - 1)], dtype=np.int64)
    steps.flags.writeable = False
    return steps


@functools.cache
def ratio_steps(size):
    """parametric_steps of ``size`` classes for every ratio code, a row each (int64): the encoder's, which fits
    them all."""
    return np.array([parametric_steps(size, ratio) for ratio in range(RATIO_CODES)], dtype=np.int64)


def scaled_steps(zero, steps, zeros):
    """Integer weights (int64, below 2**48) of a zero code and the steps of classes 1..: ``zero`` << PARAMETRIC_BITS,
    then (``zeros`` - ``zero``) times each step; or one row per zero code and row of steps."""
    zero = np.asarray(zero, dtype=np.int64)[..., None]
    return np.concatenate([zero << PARAMETRIC_BITS, (zeros - zero) * steps], axis=-1)


def parametric_table(size, zero, ratio):
    """The frequencies of a parametric table (normalised)."""
    return normalised(parametric_weights(size, zero, ratio))


def fit_parametric(counts):
    """(zero code, ratio code) (int64 arrays) of the parametric table nearest ``counts`` (per class; or
    a pair of arrays for rows of them): z from the share of zeros, t the best of all 256 by the ideal
    cost of the nonzero classes."""
    counts = np.asarray(counts, dtype=np.float64)
    total = counts.sum(axis=-1)   # whole numbers: exact in any order
    zero = np.clip(np.rint(ZERO_CODES * counts[..., 0] / np.maximum(total, 1)), 1, ZERO_CODES - 1).astype(np.int64)
    cost = -(ratio_logs(counts.shape[-1]) * counts[..., None, 1:]).sum(axis=-1)
    return zero, np.argmin(cost, axis=-1)


# 10.0's short table records (spec/dwt2d.md, Version 10.0): one byte per model in the common case. A
# record byte is REPEAT (the previous model's table), 1 + c for the parametric table of P(0) =
# SHORT_ZEROS[c // 16] / 65536 and ratio code SHORT_RATIOS[c % 16] (7.0's t), PARAMETRIC (7.0's z and t
# bytes follow), CODED (weight codes follow) or RESIZED (a varint class count S follows, then the model's
# record of S classes); a record has the previous table's class count (2 for the first) unless RESIZED.
# Measured on the 13 faces at 3 RMS targets: 28 B a file fewer than 7.0's records (tables and symbols)
SHORT_ZERO_CODES = 1 << 16
SHORT_ZEROS = (1179, 2903, 6881, 15004, 28118, 42952, 54263, 60565, 63477, 64707, 65206, 65405, 65484, 65516,
               65528)   # 65536 / (1 + e**-x), x = -4 + 13 i / 14 (rounded), P(0) of 0.018 to 0.99988
SHORT_RATIOS = (0, 4, 8, 12, 16, 20, 24, 30, 36, 44, 52, 62, 74, 88, 104, 124)
REPEAT, PARAMETRIC, CODED, RESIZED = 0, 241, 242, 243
SHORT_CODES = len(SHORT_ZEROS) * len(SHORT_RATIOS)   # 240: record bytes 1..240
RECORD_WIDTH = 3 + (MAX_CLASSES * CODE_BITS + 7) // 8   # the longest record: RESIZED, S, CODED, the weight codes


def short_table(size, code):
    """The frequencies of the one-byte table ``code`` (0..SHORT_CODES-1) of ``size`` classes."""
    return normalised(parametric_weights(size, SHORT_ZEROS[code // len(SHORT_RATIOS)],
                                         SHORT_RATIOS[code % len(SHORT_RATIOS)], SHORT_ZERO_CODES))


@functools.cache
def short_tables(size):
    """(frequencies, log2 probabilities) of the SHORT_CODES one-byte tables of ``size`` classes, a row each
    (the encoder's: it tries them all)."""
    freq = np.array([short_table(size, code) for code in range(SHORT_CODES)], dtype=np.int64)
    return freq, elementary.log2(freq / (1 << TABLE_BITS))


def short_table_bits(counts):
    """(bits, class count) of the class ``counts`` (a row per model) under each model's best one-byte table
    of one class count, the largest class used + 1 (a group's, Encoder.table_sizes): what 10.0 mostly writes."""
    used = counts[counts.any(axis=1)]
    if not len(used):
        return 0.0, 2
    size = max(2, int(np.flatnonzero(used.any(axis=0))[-1]) + 1)
    return float((-(used[:, :size] @ short_tables(size)[1].T)).min(axis=1).sum()), size


def table_codes(counts):
    """Weight codes for class counts (or for rows of them): the code nearest each count on the log
    scale, with the largest count at the top code (codes step by 2**(1/4), so frequencies are within
    about 9% of the counts' proportions; measured: 0.1-0.3% more bits than exact tables); all 0 for
    no counts."""
    counts = np.asarray(counts, dtype=np.float64)
    top = counts.max(axis=-1, keepdims=True)
    target = elementary.log2(np.maximum(counts, 1e-300) * (CODE_WEIGHTS[-1] / np.where(top > 0, top, 1)))
    distance = np.abs(target[..., None] - elementary.log2(CODE_WEIGHTS[1:]))
    return np.where(counts > 0, 1 + np.argmin(distance, axis=-1), 0)


@functools.cache
def ratio_logs(size):
    """For every ratio code, the log2 shares of classes 1..size-1 among the nonzero values (float: to fit only)."""
    shares = (ZERO_CODES * ratio_steps(size)).astype(np.float64)
    shares /= np.maximum(shares.sum(axis=1, keepdims=True), 1)
    return np.log2(np.maximum(shares, 1e-300))


def table_cost_bits(codes, counts):
    """Bits to code ``counts`` symbols per class with the table of ``codes``, plus the table itself."""
    freq = frequencies(codes)
    ideal = -(counts * elementary.log2(freq[: len(counts)] / (1 << TABLE_BITS))).sum()
    return ideal + 8 * len(encode_table(codes))


def encode_table(codes):
    """Table bytes: class count C, then the C weight codes (packed_codes)."""
    return bytes([len(codes)]) + packed_codes(codes).tobytes()


def packed_codes(codes):
    """Weight codes as bytes (uint8): CODE_BITS each, MSB first, zero-padded; a row of bytes per row of codes."""
    bits = (np.asarray(codes, dtype=np.int64)[..., None] >> np.arange(CODE_BITS - 1, -1, -1)) & 1
    return np.packbits(bits.reshape(*bits.shape[:-2], -1).astype(np.uint8), axis=-1)


def varint(value):
    """LEB128: 7 bits per byte, low group first, high bit set on all but the last byte."""
    out = bytearray()
    while True:
        out.append((value & 0x7F) | (0x80 if value > 0x7F else 0))
        value >>= 7
        if not value:
            return bytes(out)


def read_varint(data, position, end, max_bytes, fault):
    """(value, the position after it) of the LEB128 integer at ``position`` of ``data``, of at most
    ``max_bytes`` bytes before ``end``: the one reader of the payload's varints (5 bytes) and 7.0's
    header fields (10). ``fault("cut")`` or ``fault("long")`` is the exception raised when it runs
    to ``end`` or past ``max_bytes``, each caller naming where."""
    value = 0
    for shift in range(0, 7 * max_bytes, 7):
        if position >= end:
            raise fault("cut")
        byte = data[position]
        position += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, position
    raise fault("long")


def family_weights(freq):
    """A table as weights for constriction's per-symbol categorical model: F - 1 per class.

    That model gives class s the probability (weight + 1) / 2**ANS_PRECISION when the
    weights sum to 2**ANS_PRECISION minus the class count, so F - 1 (F = freq scaled to
    ANS_PRECISION bits) reproduces the table exactly: the stream spec/dwt2d.md describes.
    """
    return (np.asarray(freq, dtype=np.float64) * (1 << (ANS_PRECISION - TABLE_BITS))) - 1.0


def weights_by_size(tables):
    """{class count: one row of family weights per table}, zeros for tables of another count:
    rows indexed by model id feed one coder call for a run of symbols of that count."""
    return {size: np.array([family_weights(t) if len(t) == size else np.zeros(size) for t in tables])
            for size in {len(t) for t in tables}}


# --------------------------------------------------------------------------- encoder


def model_class_counts(models, cls, count=0):
    """The count of each magnitude class ``cls`` under each model id ``models`` (a row per model id,
    at least ``count`` rows)."""
    count = max(count, int(models.max()) + 1 if len(models) else 0)
    return np.bincount(models * MAX_CLASSES + cls, minlength=count * MAX_CLASSES).reshape(count, MAX_CLASSES)


class Encoder:
    """Collects integers with their model ids in decoding order, then writes one payload.

    ``same_size`` lists groups of model ids whose tables must have one class count, so a
    decoder can mix them symbol by symbol (Decoder.read_rows).
    """

    def __init__(self, same_size=(), parametric=False, short=False):
        self.models, self.values, self.signed = [], [], []
        self.same_size = [list(group) for group in same_size]
        self.parametric = parametric   # 7.0's table records (parametric or weight codes), else 3.x's
        self.short = short             # 10.0's short table records (choose_short_records)
        self.leading = None            # 8.0: pushes the mask's binary decisions onto the coder, to decode first
        self.prior = None              # 9.0's level sections: the base section's tables, which ``01`` keeps
        self.tables = None             # the tables written, once finished
        self.value_cache = []          # value_data once computed; one list with the relabelled copies

    def add(self, model, values, signed=True):
        """Append ``values`` (ints) coded with context ``model``: one id, or one id per value.
        Unsigned values (``signed=False``, all >= 0) spend no raw bit on a sign."""
        values = np.asarray(values, dtype=np.int64).ravel()
        model = np.broadcast_to(np.asarray(model, dtype=np.int64), values.shape)
        self.models.append(model)
        self.values.append(values)
        self.signed.append(np.full(values.shape, int(signed), dtype=np.int64))
        self.value_cache.clear()

    def value_data(self):
        """(values, magnitude classes, raw-bit bytes) of everything added, in order: computed once for this
        encoder and its relabelled copies (10.1 makes a payload with each of two sets of models)."""
        if not self.value_cache:
            values = np.concatenate(self.values or [np.zeros(0, np.int64)])
            cls = classes(values)
            signed = np.concatenate(self.signed or [np.zeros(0, np.int64)])
            self.value_cache.append((values, cls, np.packbits(raw_bits(values, cls, signed)).tobytes()))
        return self.value_cache[0]

    def symbols(self):
        """(model ids, values, magnitude classes) of everything added, in order."""
        values, cls, _bits = self.value_data()
        return np.concatenate(self.models or [np.zeros(0, np.int64)]), values, cls

    def relabelled(self, function):
        """A copy of this encoder whose symbols have the model ids ``function`` maps theirs to (an array of
        ids to one), the same values."""
        copy = Encoder(self.same_size, self.parametric, self.short)
        copy.values, copy.signed, copy.leading, copy.prior = self.values, self.signed, self.leading, self.prior
        copy.value_cache = self.value_cache
        copy.models = [function(models) for models in self.models]
        return copy

    def class_counts(self, count=0):
        """The count of each class under each model (a row per model id, at least ``count`` rows)."""
        models, _values, cls = self.symbols()
        return model_class_counts(models, cls, count)

    def finish(self, shared=None):
        """Payload bytes: tables, rANS words, raw bits (layout in spec/dwt2d.md section 'payload').
        ``shared``: the class counts to choose the tables by instead of the payload's own (9.0's base
        section: the whole file's, so that its level sections can keep them, ``keeps_all``)."""
        models, _values, cls = self.symbols()
        counts = model_class_counts(models, cls, 0 if shared is None else len(shared))
        chosen = counts if shared is None else shared
        sizes = self.table_sizes(chosen)
        if self.short:
            tables, table_bytes = choose_short_records(chosen, sizes)
        elif self.parametric:
            tables, table_bytes = choose_records(chosen, sizes, self.prior)
        else:
            codes = choose_tables(chosen, sizes)
            tables = [frequencies(c) for c in codes]
            table_bytes = b"".join(b"\x00" if shared else encode_table(c) for c, shared in table_records(codes))
        head = varint(len(tables)) + table_bytes
        if self.prior is not None and keeps_all(self.prior, counts, tables, len(head)):
            tables, head = self.prior, varint(0)
        self.tables = tables
        words = ans_encode(tables, models, cls, self.leading)
        return head + varint(len(words)) + words.astype("<u4").tobytes() + self.value_data()[2]

    def table_sizes(self, counts):
        """Class count of each model's table: its largest class + 1, or its group's (at least 2)."""
        used = counts > 0
        top = np.where(used.any(axis=1), MAX_CLASSES - 1 - np.argmax(used[:, ::-1], axis=1), 1)
        sizes = np.maximum(2, top + 1)
        for group in self.same_size:
            group = [m for m in group if m < len(sizes)]
            if group:
                sizes[group] = sizes[group].max()
        return sizes


def choose_tables(counts, sizes):
    """Weight codes of one table per model, from its class counts; a model reuses the
    previous model's table when that has as many classes and is cheaper."""
    tables = []
    for model_counts, size in zip(counts, sizes):
        model_counts = model_counts[:size]
        own = table_codes(model_counts)
        if tables:
            previous = tables[-1]
            if len(previous) == len(own) and (
                    table_cost_bits(previous, model_counts) - 8 <= table_cost_bits(own, model_counts)):
                tables.append(previous)
                continue
        tables.append(own)
    return tables


def choose_records(counts, sizes, prior=None):
    """(frequencies, bytes) of 7.0's table records, one per model: each the cheapest, by the ideal bits
    of its symbols plus the record's own, of a repeat of the previous model's table (``00``), a
    parametric table (varint 2S + 1, then z and t, a byte each) and a table of weight codes (varint 2S,
    then the codes as in 3.x); with ``prior`` (9.0's level sections: the base section's tables), also
    that section's table of the same model (``01``), where it has as many classes."""
    tables, out = [], []
    for model, (model_counts, size) in enumerate(zip(counts, sizes)):
        model_counts = model_counts[:size]
        codes = table_codes(model_counts)
        zero, ratio = map(int, fit_parametric(model_counts))
        options = [(parametric_table(size, zero, ratio), varint(2 * size + 1) + bytes([zero, ratio])),
                   (frequencies(codes), varint(2 * size) + encode_table(codes)[1:])]
        if tables and len(tables[-1]) == size:
            options.append((tables[-1], b"\x00"))
        if prior is not None and model < len(prior) and len(prior[model]) == size:
            options.append((prior[model], KEPT))
        freq, record = min(options, key=lambda option: ideal_bits(option[0], model_counts) + 8 * len(option[1]))
        tables.append(freq)
        out.append(record)
    return tables, b"".join(out)


def choose_short_records(counts, sizes):
    """(frequencies, bytes) of 10.0's short table records, one per model: each the cheapest, by the ideal
    bits of its symbols plus the record's own, of REPEAT (the previous table, of as many classes), the
    best one-byte parametric table, 7.0's parametric table and a table of weight codes, each but REPEAT
    led by RESIZED and its class count where that is not the previous table's (a tie goes to the first of
    the last three in that order; REPEAT must cost less).

    Every model's own options are costed at once, a class count at a time (short_options); then the
    REPEATs are settled (short_repeats), and the records are cut from one matrix of their bytes: no loop
    over the models but building the list of tables (a loop over them was the hot spot of 10.1's encoder).
    The floating-point sums are those of a model at a time (each row summed as alone): the same choices,
    bytes and tables.
    """
    sizes = np.asarray(sizes, dtype=np.int64)
    count = len(sizes)
    resized = sizes != np.concatenate([[2], sizes[:-1]])
    may_repeat = ~resized & (np.arange(count) > 0)
    own = np.zeros((count, MAX_CLASSES), dtype=np.int64)     # each model's own table, in its first classes
    source = np.arange(count)                                # the model whose own table each one takes
    rows = np.zeros((count, RECORD_WIDTH), dtype=np.uint8)   # each model's record: RESIZED, S, then its body
    kept = np.zeros(rows.shape, dtype=bool)                  # ...of which these bytes
    for size in np.unique(sizes).tolist():
        group = np.flatnonzero(sizes == size)
        model_counts = counts[group, :size]
        tables, cost, body, length = short_options(model_counts, resized[group])
        own[group, :size] = tables
        source[group] = group[short_repeats(model_counts, tables, cost, may_repeat[group])]
        rows[group, :2] = RESIZED, size
        rows[group, 2:2 + body.shape[1]] = body
        kept[group, :2] = resized[group, None]
        kept[group, 2:] = np.arange(RECORD_WIDTH - 2) < length[:, None]
    repeated = source != np.arange(count)
    rows[repeated], kept[repeated] = REPEAT, np.arange(RECORD_WIDTH) == 2
    return [own[model, :size] for model, size in zip(source.tolist(), sizes[source].tolist())], rows[kept].tobytes()


def short_options(counts, resized):
    """The cheapest own record of each model of one class count (``counts``: a row per model; ``resized``:
    whether its record is led by RESIZED and the count, two bytes): (its table, its bits with the record's,
    its body bytes (the record byte and what follows it; a row per model), the body's length)."""
    size = counts.shape[1]
    freq, logs = short_tables(size)
    best = np.argmin(-(logs * counts[:, None, :]).sum(axis=-1), axis=-1)
    zero, ratio = fit_parametric(counts)
    codes = table_codes(counts)
    options = np.stack([freq[best], normalised(scaled_steps(zero, ratio_steps(size)[ratio], ZERO_CODES)),
                        frequencies(codes)], axis=1)
    packed = packed_codes(codes)
    lengths = np.array([1, 3, 1 + packed.shape[1]])
    cost = ideal_bits(options, counts[:, None, :]) + 8 * (2 * resized[:, None] + lengths)
    choice = np.argmin(cost, axis=1)
    bodies = np.zeros((len(counts), 3, 1 + packed.shape[1]), dtype=np.uint8)
    bodies[:, 0, 0] = 1 + best
    bodies[:, 1, :3] = np.stack([np.full_like(zero, PARAMETRIC), zero, ratio], axis=1)
    bodies[:, 2, 0], bodies[:, 2, 1:] = CODED, packed
    chosen = np.arange(len(counts)), choice
    return options[chosen], cost[chosen], bodies[chosen], lengths[choice]


def short_repeats(counts, tables, cost, may_repeat):
    """Which model's own table (``tables``, ``cost``: short_options') each model of one class count takes,
    as an index: its own, or where ``may_repeat`` (the previous model has this class count) and the
    previous model's table with a REPEAT byte costs fewer bits than its own record, the table the
    previous one took. That depends on the previous model's outcome, so it is a fixed point, found a
    pass over all the models at a time: each pass settles at least the next model in order."""
    own = np.arange(len(counts))
    source = own
    while True:
        previous = np.roll(source, 1)   # where may_repeat, the source of the model before
        taken = np.where(may_repeat & (ideal_bits(tables[previous], counts) + 8 < cost), previous, own)
        if np.array_equal(taken, source):
            return source
        source = taken


def keeps_all(prior, counts, own, own_bytes):
    """True when a 9.0 level section had better keep every table of the base section (``prior``; its
    table count 0) than write its ``own`` (``own_bytes`` of count and records): ``prior`` has a table
    of enough classes for every model it uses, and its symbols cost fewer bits with them."""
    used = np.flatnonzero(counts.any(axis=1))
    if any(m >= len(prior) or counts[m, len(prior[m]):].any() for m in used):
        return False
    kept = sum(ideal_bits(prior[m], counts[m, :len(prior[m])]) for m in used)
    return kept + 8 <= sum(ideal_bits(own[m], counts[m, :len(own[m])]) for m in used) + 8 * own_bytes


def ideal_bits(freq, counts):
    """Bits of ``counts`` symbols per class under the table ``freq``; or an array of them, one per row
    of both (broadcast), each summed as alone."""
    bits = -(counts * elementary.log2(freq[..., :np.shape(counts)[-1]] / (1 << TABLE_BITS))).sum(axis=-1)
    return bits if np.ndim(bits) else float(bits)


def table_records(tables):
    """(weight codes, reuses previous) for each model, for writing."""
    return [(t, i > 0 and t is tables[i - 1]) for i, t in enumerate(tables)]


def ans_encode(tables, models, cls, leading=None):
    """rANS words of the classes, model by model (encoded last-to-first so they decode first-to-last),
    then what ``leading`` (a function of the coder, or None) pushes, to be decoded before them.

    Each run of symbols whose tables have one class count goes to the coder in one call,
    with one row of weights per symbol (a face has about 3,000 runs: what can be taken
    out of the loop is).
    """
    import constriction  # here, not at the top: only the encoder uses it

    coder = constriction.stream.stack.AnsCoder()
    family = constriction.stream.model.Categorical(perfect=False)
    weights = weights_by_size(tables)
    sizes = np.array([len(t) for t in tables], dtype=np.int64)[models]
    symbols = cls.astype(np.int32)
    starts = np.flatnonzero(np.diff(sizes, prepend=-1))
    ends = np.append(starts[1:], len(sizes))
    runs = list(zip(starts.tolist(), ends.tolist(), [weights[size] for size in sizes[starts].tolist()]))
    for start, end, rows in reversed(runs):
        coder.encode_reverse(symbols[start:end], family, rows[models[start:end]])
    if leading is not None:
        leading(coder)
    return coder.get_compressed()


# --------------------------------------------------------------------------- decoder


class Decoder:
    """Reads a payload written by Encoder.finish; every failure is an MzcError.

    Python parses the tables; the integers are decoded by the C loops of mzc.codecs.dwt2d._rows,
    which read the words and raw bits where they lie in the payload and update the rANS state x
    (``state``, uint64) and the ``cursor`` (words left, next raw bit, an error detail) in place.
    """

    def __init__(self, payload, source, same_size=(), parametric=False, prior=None, short=False):
        self.source = source
        self.data = memoryview(payload)
        self.position = 0
        self.tables = self.read_short_tables() if short else self.read_tables(parametric, prior)
        word_count = self.read_varint()
        end = self.position + 4 * word_count
        if end > len(self.data):
            raise self.error("payload ends inside the rANS words")
        self.words = np.frombuffer(self.data[self.position:end], dtype="<u4")
        if word_count and self.words[-1] == 0:
            raise self.error("the last rANS word is zero")
        self.bits = self.data[end:]   # the raw bits, 8 a byte
        sizes = np.array([len(t) for t in self.tables], dtype=np.int64)
        for group in same_size:
            present = sizes[[m for m in group if m < len(sizes)]]
            if (present != present[:1]).any():
                raise self.error("tables mixed in one row have different class counts")
        # one row per table: the cumulative probabilities B(s) in ANS_PRECISION bits, 2**ANS_PRECISION
        # from its last class on
        cumulative = np.full((len(self.tables), MAX_CLASSES + 1), 1 << ANS_PRECISION, dtype=np.int64)
        for index, table in enumerate(self.tables):
            cumulative[index, 1:len(table) + 1] = np.cumsum(table) << (ANS_PRECISION - TABLE_BITS)
            cumulative[index, 0] = 0
        self.state, self.cursor = np.zeros(1, dtype=np.uint64), np.zeros(3, dtype=np.int64)
        self.stream = (self.state, self.cursor, self.words, self.bits, cumulative, MAX_CLASSES + 1)
        self.start()

    def start(self):
        """The initial state x: the last word, and the one before it while x < 2**32 (the spec's 'Start')."""
        left, x = len(self.words), 0
        if left:
            left -= 1
            x = int(self.words[left])
            if x < 1 << 32 and left:
                left -= 1
                x = (x << 32) | int(self.words[left])
        self.state[0], self.cursor[_rows.WORDS_LEFT] = x, left

    def error(self, message):
        return MzcError(message, source=self.source, field="data")

    def check(self, code):
        """Raise the MzcError that a kernel's error code stands for."""
        if code == _rows.NO_TABLE:
            raise self.error(f"the payload has no model table {int(self.cursor[_rows.DETAIL])}")
        if code == _rows.RAW_BITS_END:
            raise self.error("payload ends inside the raw bits")
        if code == _rows.NOT_A_SIGN:
            raise self.error("a sign symbol is not 0 or 1")

    def check_end(self):
        """Refuse a payload with data left once everything it declares is decoded: rANS words
        not consumed (x is 0 exactly when they are), or a byte or more of raw bits past the last one read."""
        extra = (8 * len(self.bits) - int(self.cursor[_rows.BIT_POSITION])) // 8
        if extra or self.state[0] != 0:
            raise self.error(f"{extra} byte(s) after the end of the payload" if extra
                             else "rANS words left over after the last symbol")

    def read_varint(self):
        """One LEB128 integer (at most 5 bytes)."""
        value, self.position = read_varint(self.data, self.position, len(self.data), 5, lambda kind: self.error(
            "payload ends inside a varint" if kind == "cut" else "varint longer than 5 bytes"))
        return value

    def read_tables(self, parametric=False, prior=None):
        """The model tables; a 0 class count repeats the previous table. ``parametric`` (7.0): a record's
        varint is 2S + 1 for a parametric table (z and t follow) or 2S for weight codes; with ``prior``
        (9.0's level sections: the base section's tables), 1 keeps that section's table of the model."""
        count = self.read_varint()
        if count == 0 and prior is not None:   # 9.0's level section keeping every table of the base section
            return list(prior)
        if count > 4096:
            raise self.error(f"{count} model tables is more than 4096")
        tables = []
        for _ in range(count):
            size = self.read_varint()
            if size == 0:
                if not tables:
                    raise self.error("the first model table cannot repeat a previous one")
                tables.append(tables[-1])
                continue
            if size == KEPT[0] and prior is not None:
                if len(tables) >= len(prior):
                    raise self.error(f"model table {len(tables)} keeps the base section's, which has none")
                tables.append(prior[len(tables)])
                continue
            if parametric:
                size, kind = divmod(size, 2)
                if kind and 2 <= size <= MAX_CLASSES:
                    if self.position + 2 > len(self.data):
                        raise self.error("payload ends inside a model table")
                    tables.append(parametric_table(size, self.data[self.position], self.data[self.position + 1]))
                    self.position += 2
                    continue
            if not 2 <= size <= MAX_CLASSES:
                raise self.error(f"model table with {size} classes (allowed 2..{MAX_CLASSES})")
            tables.append(self.coded_table(size))
        return tables

    def coded_table(self, size):
        """The table of ``size`` weight codes (CODE_BITS each, MSB first, zero-padded) at the position."""
        end = self.position + (size * CODE_BITS + 7) // 8
        if end > len(self.data):
            raise self.error("payload ends inside a model table")
        bits = np.unpackbits(np.frombuffer(self.data[self.position:end], dtype=np.uint8))
        self.position = end
        place_values = 1 << np.arange(CODE_BITS - 1, -1, -1)
        return frequencies(bits[: size * CODE_BITS].reshape(size, CODE_BITS).astype(np.int64) @ place_values)

    def read_short_tables(self):
        """10.0's model tables: a varint count, then one short record per model (choose_short_records)."""
        count = self.read_varint()
        if count > 4096:
            raise self.error(f"{count} model tables is more than 4096")
        tables, size = [], 2
        for _ in range(count):
            record = self.byte()
            if record == RESIZED:
                size = self.read_varint()
                if not 2 <= size <= MAX_CLASSES:
                    raise self.error(f"model table with {size} classes (allowed 2..{MAX_CLASSES})")
                record = self.byte()
                if record in (REPEAT, RESIZED):
                    raise self.error("a resized model table record must give its table")
            if record == REPEAT:
                if not tables:
                    raise self.error("the first model table cannot repeat a previous one")
                tables.append(tables[-1])
            elif record <= SHORT_CODES:
                tables.append(short_table(size, record - 1))
            elif record == PARAMETRIC:
                tables.append(parametric_table(size, self.byte(), self.byte()))
            elif record == CODED:
                tables.append(self.coded_table(size))
            else:
                raise self.error(f"model table record {record} is not 0..{RESIZED}")
            size = len(tables[-1])
        return tables

    def byte(self):
        """The byte at the position."""
        if self.position >= len(self.data):
            raise self.error("payload ends inside a model table")
        self.position += 1
        return self.data[self.position - 1]

    def read(self, model, count):
        """``count`` (signed) values coded with context ``model``."""
        out = np.zeros(count, dtype=np.int64)
        self.check(_rows.read_values(*self.stream, model, count, out))
        return out

    def read_rows(self, where, active, thresholds, first_model, signs=None):
        """A grid of integers coded row by row, each row in two passes by context (its even
        columns, then its odd ones; see decode_rows in _rows.c), 0 outside ``where``. ``active``
        is each cell's activity from outside its band, ``first_model`` the model of context 0.
        With ``signs`` = (parent map, the three sign weights, model of sign context 0, sign
        contexts per column parity), as for detail bands, each pass's values are magnitudes
        followed by the signs of the nonzero ones; without, each value carries its sign in the raw bits."""
        out = np.zeros(where.shape, dtype=np.int64)
        parent, weights, first_sign_model, sign_contexts = signs or (np.zeros(0, np.int64), (0, 0, 0), -1, 1)
        self.check(_rows.decode_rows(
            *self.stream, *where.shape, np.ascontiguousarray(where, dtype=bool),
            np.ascontiguousarray(active, dtype=np.float64), np.asarray(thresholds, dtype=np.float64), first_model,
            np.ascontiguousarray(parent, dtype=np.int64), tuple(weights), first_sign_model, sign_contexts, out))
        return out
