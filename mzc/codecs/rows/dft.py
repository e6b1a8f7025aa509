"""The DFT codec format (``mzc-dft 1.1`` and 2.1, older 1.0 and 2.0 read; extension ``.mzf``): see spec/dft.md.

Each row's valid span is coded by the thesis's sine-cosine series (§6.2.2, Table 6.1):
``a0 aN L an(1..K) bn(1..K)`` with L = floor((m+1)/2) - 1 and K = floor(Q*L/100).
"""

import numpy as np

from mzc.codecs import rows
from mzc.codecs.rows.transforms import dft_forward, dft_inverse, dft_length, kept
from mzc.errors import MzcError

KIND = "dft"
VERSION, PROJECTED_VERSION, OLDEST_MAJOR, CHECKSUM_SINCE = (rows.VERSION, rows.PROJECTED_VERSION, rows.OLDEST_MAJOR,
                                                       rows.CHECKSUM_SINCE)
GEOREFERENCED_VERSION, GEOREF_SINCE = rows.GEOREFERENCED_VERSION, rows.GEOREF_SINCE


def encode(spans, firsts, d2, options):
    """Row tokens: a0 aN L, then the first K of an and the first K of bn."""
    a0, a_last, an, bn = dft_forward(spans)
    count = kept(options["quality"], an.shape[1])
    numbers = np.column_stack([a0, a_last, an[:, :count], bn[:, :count]])
    tokens = [rows.format_values(row, options["precision"]) for row in numbers]
    for row in tokens:
        row.insert(2, str(an.shape[1]))
    return tokens


def unpack(values, length, options):
    """[a0, aN, an (L, zero padded), bn (L, zero padded)] after checking L and the count."""
    if values.size < 3:
        raise rows.count_error("at least 3", values.size, "numbers (a0 aN L)")
    big_l = rows.integer_field(values[2], "L")
    if big_l != dft_length(length):
        raise MzcError(f"L is {big_l} but a span of {length} samples has L = {dft_length(length)}", field="L")
    count = kept(options["quality"], big_l)
    if values.size != 3 + 2 * count:
        raise rows.count_error(3 + 2 * count, values.size, f"numbers (a0 aN L and {count} an, {count} bn)")
    return pack(values[0], values[1], values[3:3 + count], values[3 + count:], big_l)


def pack(a0, a_last, an, bn, big_l):
    """The vector [a0, aN, an, bn] with an and bn zero padded to L each."""
    vector = np.zeros(2 + 2 * big_l)
    vector[:2] = a0, a_last
    vector[2:2 + len(an)] = an
    vector[2 + big_l:2 + big_l + len(bn)] = bn
    return vector


def decode(vectors, length, firsts, d2, options):
    """The inverse series evaluated at the span's true length."""
    big_l = dft_length(length)
    return dft_inverse(vectors[:, 0], vectors[:, 1], vectors[:, 2:2 + big_l], vectors[:, 2 + big_l:], length)


ROW_CODEC = rows.RowCodec(KIND, rows.common_options, rows.common_header_lines, encode, unpack, decode)
CODEC = rows.codec_of(ROW_CODEC, ".mzf", "Discrete Fourier transform per row (thesis Ch. 6)")
read, write = CODEC.decode, CODEC.encode
