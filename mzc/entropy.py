"""Entropy coding of signed integers: magnitude classes through rANS, the rest as raw bits.

A value v maps to a class k (0 for v = 0, else the bit length of |v|) and, for k >= 1, k
raw bits: the sign (1 = negative) then the k-1 bits of |v| below its leading one. Classes
go through a static categorical model per context whose frequency table (summing to
2**TABLE_BITS) is sent in the payload; raw bits go to a separate bit buffer. The
classes are coded with the rANS coder of ``constriction`` (AnsCoder: 32-bit words,
64-bit state, 24-bit probabilities); spec/dwt2d.md gives the exact arithmetic, so a
decoder needs no constriction. Everything is vectorised per segment of symbols that
share one model, which keeps a 150 000-node grid well under a tenth of a second.
"""

import constriction
import numpy as np

from mzc.errors import MzcError

TABLE_BITS = 14
MAX_CLASSES = 48          # |v| < 2**47: far beyond any quantised height
ANS_PRECISION = 24


# --------------------------------------------------------------------------- classes


def classes(values):
    """Magnitude class of each int64 value: 0 for zero, else the bit length of |v|."""
    return np.frexp(np.abs(values).astype(np.float64))[1].astype(np.int64)


def raw_bits(values, cls):
    """The raw bits of each value (sign, then |v| below its leading one), concatenated MSB first."""
    nonzero = cls > 0
    values, cls = values[nonzero], cls[nonzero]
    if not len(values):
        return np.zeros(0, dtype=np.uint8)
    # word = sign bit followed by the k-1 low bits: k bits in all, written MSB first
    low = np.abs(values) - (np.int64(1) << (cls - 1))
    word = ((values < 0).astype(np.int64) << (cls - 1)) | low
    position = np.arange(int(cls.max()))[None, :]
    bits = (word[:, None] >> (cls[:, None] - 1 - position).clip(0)) & 1
    return bits[position < cls[:, None]].astype(np.uint8)


def values_from_bits(cls, bits):
    """Inverse of raw_bits: the values whose classes are ``cls`` from their raw ``bits``."""
    values = np.zeros(len(cls), dtype=np.int64)
    nonzero = np.flatnonzero(cls > 0)
    if not len(nonzero):
        return values
    k = cls[nonzero]
    ends = np.cumsum(k)
    # each bit weighs 2**(bits of its word after it); the words are sums over their bits
    weight = np.repeat(ends, k) - 1 - np.arange(int(ends[-1]))
    word = np.add.reduceat(bits[: ends[-1]].astype(np.int64) << weight, ends - k)
    sign = word >> (k - 1)
    magnitude = (np.int64(1) << (k - 1)) | (word & ((np.int64(1) << (k - 1)) - 1))
    values[nonzero] = np.where(sign == 1, -magnitude, magnitude)
    return values


# --------------------------------------------------------------------------- tables


def frequency_table(counts):
    """Frequencies (>= 1 each, sum 2**TABLE_BITS), one per class, from the class counts."""
    size = len(counts)
    counts = np.asarray(counts, dtype=np.float64)
    total = 1 << TABLE_BITS
    freq = np.maximum(1, np.round(counts * (total - size) / max(counts.sum(), 1))).astype(np.int64)
    freq[np.argmax(freq)] += total - freq.sum()
    return freq


def table_cost_bits(freq, counts):
    """Bits to code ``counts`` symbols per class with table ``freq``, plus the table itself."""
    ideal = -(counts * np.log2(freq[: len(counts)] / (1 << TABLE_BITS))).sum()
    return ideal + 8 * len(encode_table(freq))


def encode_table(freq):
    """Table bytes: class count C, then C-1 frequencies as varints (the last is implied)."""
    return bytes([len(freq)]) + b"".join(varint(int(f)) for f in freq[:-1])


def varint(value):
    """LEB128: 7 bits per byte, low group first, high bit set on all but the last byte."""
    out = bytearray()
    while True:
        out.append((value & 0x7F) | (0x80 if value > 0x7F else 0))
        value >>= 7
        if not value:
            return bytes(out)


def family_weights(freq):
    """A table as weights for constriction's per-symbol categorical model: F - 1 per class.

    That model gives class s the probability (weight + 1) / 2**ANS_PRECISION when the
    weights sum to 2**ANS_PRECISION minus the class count, so F - 1 (F = freq scaled to
    ANS_PRECISION bits) reproduces the table exactly: the stream spec/dwt2d.md describes.
    """
    return (np.asarray(freq, dtype=np.float64) * (1 << (ANS_PRECISION - TABLE_BITS))) - 1.0


FAMILY = constriction.stream.model.Categorical(perfect=False)


def weights_by_size(tables):
    """{class count: one row of family weights per table}, zeros for tables of another count:
    rows indexed by model id feed one coder call for a run of symbols of that count."""
    return {size: np.array([family_weights(t) if len(t) == size else np.zeros(size) for t in tables])
            for size in {len(t) for t in tables}}


# --------------------------------------------------------------------------- encoder


class Encoder:
    """Collects integers with their model ids in decoding order, then writes one payload.

    ``same_size`` lists groups of model ids whose tables must have one class count, so a
    decoder can mix them symbol by symbol (Decoder.read_mixed).
    """

    def __init__(self, same_size=()):
        self.models, self.values = [], []
        self.same_size = [list(group) for group in same_size]

    def add(self, model, values):
        """Append ``values`` (ints) coded with context ``model``: one id, or one id per value."""
        values = np.asarray(values, dtype=np.int64).ravel()
        model = np.broadcast_to(np.asarray(model, dtype=np.int64), values.shape)
        self.models.append(model)
        self.values.append(values)

    def finish(self, merge=True):
        """Payload bytes: tables, rANS words, raw bits (layout in spec/dwt2d.md section 'payload')."""
        models = np.concatenate(self.models or [np.zeros(0, np.int64)])
        values = np.concatenate(self.values or [np.zeros(0, np.int64)])
        cls = classes(values)
        count = int(models.max()) + 1 if len(models) else 0
        counts = np.bincount(models * MAX_CLASSES + cls, minlength=count * MAX_CLASSES).reshape(count, MAX_CLASSES)
        tables = choose_tables(counts, self.table_sizes(counts), merge)
        words = ans_encode(tables, models, cls)
        table_bytes = b"".join(b"\x00" if shared else encode_table(f) for f, shared in table_records(tables))
        return (varint(count) + table_bytes + varint(len(words)) + words.astype("<u4").tobytes()
                + np.packbits(raw_bits(values, cls)).tobytes())

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


def choose_tables(counts, sizes, merge):
    """One frequency table per model, from its class counts; a model reuses the previous
    model's table when that has as many classes and is cheaper."""
    tables = []
    for model_counts, size in zip(counts, sizes):
        model_counts = model_counts[:size]
        own = frequency_table(model_counts)
        if merge and tables:
            previous = tables[-1]
            if len(previous) == len(own) and (
                    table_cost_bits(previous, model_counts) - 8 <= table_cost_bits(own, model_counts)):
                tables.append(previous)
                continue
        tables.append(own)
    return tables


def table_records(tables):
    """(table, reuses previous) for each model, for writing."""
    return [(t, i > 0 and t is tables[i - 1]) for i, t in enumerate(tables)]


def ans_encode(tables, models, cls):
    """rANS words of the classes, model by model (encoded last-to-first so they decode first-to-last).

    Each run of symbols whose tables have one class count goes to the coder in one call,
    with one row of weights per symbol.
    """
    coder = constriction.stream.stack.AnsCoder()
    weights = weights_by_size(tables)
    sizes = np.array([len(t) for t in tables], dtype=np.int64)[models]
    starts = np.flatnonzero(np.diff(sizes, prepend=-1))
    ends = np.append(starts[1:], len(sizes))
    for start, end in zip(starts[::-1], ends[::-1]):
        rows = weights[int(sizes[start])][models[start:end]]
        coder.encode_reverse(cls[start:end].astype(np.int32), FAMILY, rows)
    return coder.get_compressed()


# --------------------------------------------------------------------------- decoder


class Decoder:
    """Reads a payload written by Encoder.finish; every failure is an MzcError."""

    def __init__(self, payload, source):
        self.source = source
        self.data = memoryview(payload)
        self.position = 0
        self.tables = self.read_tables()
        word_count = self.read_varint()
        end = self.position + 4 * word_count
        if end > len(self.data):
            raise self.error("payload ends inside the rANS words")
        words = np.frombuffer(self.data[self.position:end], dtype="<u4").astype(np.uint32)
        if word_count and words[-1] == 0:
            raise self.error("the last rANS word is zero")
        self.coder = constriction.stream.stack.AnsCoder(words) if word_count else constriction.stream.stack.AnsCoder()
        self.bits = np.unpackbits(np.frombuffer(self.data[end:], dtype=np.uint8))
        self.bit_position = 0
        self.sizes = np.array([len(t) for t in self.tables], dtype=np.int64)
        self.weights = weights_by_size(self.tables)

    def error(self, message):
        return MzcError(message, source=self.source, field="data")

    def read_varint(self):
        """One LEB128 integer (at most 5 bytes)."""
        value = 0
        for shift in range(0, 35, 7):
            if self.position >= len(self.data):
                raise self.error("payload ends inside a varint")
            byte = self.data[self.position]
            self.position += 1
            value |= (byte & 0x7F) << shift
            if not byte & 0x80:
                return value
        raise self.error("varint longer than 5 bytes")

    def read_tables(self):
        """The model tables; a 0 class count repeats the previous table."""
        count = self.read_varint()
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
            if not 2 <= size <= MAX_CLASSES:
                raise self.error(f"model table with {size} classes (allowed 2..{MAX_CLASSES})")
            freq = [self.read_varint() for _ in range(size - 1)]
            freq.append((1 << TABLE_BITS) - sum(freq))
            if min(freq) < 1:
                raise self.error(f"model table frequencies must be >= 1 and sum to {1 << TABLE_BITS}")
            tables.append(np.array(freq, dtype=np.int64))
        return tables

    def read(self, model, count):
        """``count`` values coded with context ``model``."""
        return self.read_mixed(np.full(count, model, dtype=np.int64))

    def read_mixed(self, models):
        """One value per entry of ``models`` (model ids whose tables have one class count)."""
        models = np.asarray(models, dtype=np.int64)
        if not len(models):
            return np.zeros(0, dtype=np.int64)
        if models.max() >= len(self.tables):
            raise self.error(f"the payload has no model table {int(models.max())}")
        sizes = self.sizes[models]
        if (sizes != sizes[0]).any():
            raise self.error("tables mixed in one row have different class counts")
        try:
            cls = self.coder.decode(FAMILY, self.weights[int(sizes[0])][models]).astype(np.int64)
        except Exception as exc:  # constriction raises its own types on a corrupt stream
            raise self.error(f"corrupt rANS stream ({exc})") from None
        need = int(cls.sum())
        if self.bit_position + need > len(self.bits):
            raise self.error("payload ends inside the raw bits")
        values = values_from_bits(cls, self.bits[self.bit_position:self.bit_position + need])
        self.bit_position += need
        return values
