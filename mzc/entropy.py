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
    starts = np.concatenate([[0], np.cumsum(k)[:-1]])
    word = np.zeros(len(k), dtype=np.int64)
    for offset in range(int(k.max())):
        active = offset < k
        word[active] = (word[active] << 1) | bits[starts[active] + offset]
    sign = word >> (k - 1)
    magnitude = (np.int64(1) << (k - 1)) | (word & ((np.int64(1) << (k - 1)) - 1))
    values[nonzero] = np.where(sign == 1, -magnitude, magnitude)
    return values


# --------------------------------------------------------------------------- tables


def frequency_table(cls):
    """Frequencies (>= 1 each, sum 2**TABLE_BITS) for classes 0..max, from the class counts."""
    size = max(2, int(cls.max()) + 1 if len(cls) else 2)
    counts = np.bincount(cls, minlength=size).astype(np.float64)
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


def categorical(freq):
    """The constriction model of a table; exact because freq/2**TABLE_BITS is representable."""
    return constriction.stream.model.Categorical(freq / float(1 << TABLE_BITS), perfect=True)


# --------------------------------------------------------------------------- encoder


class Encoder:
    """Collects segments (model id, values) in decoding order, then writes one payload."""

    def __init__(self):
        self.segments = []

    def add(self, model, values):
        """Append ``values`` (ints) coded with context ``model`` (ids 0, 1, 2, ... in first-use order).

        ``model`` may also be an array with one model id per value: the same as adding each
        run of equal ids as its own segment, in order.
        """
        values = np.asarray(values, dtype=np.int64).ravel()
        model = np.asarray(model, dtype=np.int64)
        if model.ndim == 0:
            self.segments.append((int(model), values))
            return
        model = model.ravel()
        if len(model) != len(values):
            raise ValueError("one model id per value")
        starts = np.flatnonzero(np.diff(model, prepend=-1))
        ends = np.append(starts[1:], len(model))
        self.segments.extend((int(model[a]), values[a:b]) for a, b in zip(starts, ends))

    def finish(self, merge=True):
        """Payload bytes: tables, rANS words, raw bits (layout in spec/dwt2d.md section 'payload')."""
        seg_classes = [(m, classes(v)) for m, v in self.segments]
        count = max((m for m, _ in seg_classes), default=-1) + 1
        grouped = {}
        for m, c in seg_classes:
            grouped.setdefault(m, []).append(c)
        per_model = [np.concatenate(grouped.get(i, [np.zeros(0, np.int64)])) for i in range(count)]
        tables = choose_tables(per_model, merge)
        words = ans_encode([(tables[m], c) for m, c in seg_classes])
        values = np.concatenate([v for _, v in self.segments] or [np.zeros(0, np.int64)])
        bits = raw_bits(values, classes(values))
        table_bytes = b"".join(b"\x00" if shared else encode_table(f) for f, shared in table_records(tables))
        return (varint(count) + table_bytes + varint(len(words)) + words.astype("<u4").tobytes()
                + np.packbits(bits).tobytes())


def choose_tables(per_model, merge):
    """One frequency table per model; a model reuses the previous model's table when that is cheaper."""
    tables = []
    for cls in per_model:
        own = frequency_table(cls)
        if merge and tables:
            previous = tables[-1]
            counts = np.bincount(cls, minlength=len(own))
            if len(counts) <= len(previous) and (
                    table_cost_bits(previous, counts) - 8 <= table_cost_bits(own, counts)):
                tables.append(previous)
                continue
        tables.append(own)
    return tables


def table_records(tables):
    """(table, reuses previous) for each model, for writing."""
    return [(t, i > 0 and t is tables[i - 1]) for i, t in enumerate(tables)]


def ans_encode(segments):
    """rANS words of the class segments (encoded last-to-first so they decode first-to-last)."""
    coder = constriction.stream.stack.AnsCoder()
    models = {}
    for freq, cls in reversed(segments):
        if len(cls):
            model = models.setdefault(id(freq), categorical(freq))
            coder.encode_reverse(cls.astype(np.int32), model)
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
        self.models = [categorical(t) for t in self.tables]

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
        if model >= len(self.models):
            raise self.error(f"the payload has no model table {model}")
        if not count:
            return np.zeros(0, dtype=np.int64)
        try:
            cls = self.coder.decode(self.models[model], count).astype(np.int64)
        except Exception as exc:  # constriction raises its own types on a corrupt stream
            raise self.error(f"corrupt rANS stream ({exc})") from None
        need = int(cls.sum())
        if self.bit_position + need > len(self.bits):
            raise self.error("payload ends inside the raw bits")
        values = values_from_bits(cls, self.bits[self.bit_position:self.bit_position + need])
        self.bit_position += need
        return values
