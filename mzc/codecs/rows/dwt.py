"""The DWT codec format (``mzc-dwt 1.1`` and 2.1, older 1.0 and 2.0 read; extension ``.mzw``): see spec/dwt.md.

Each row's valid span is decomposed by pywt.wavedec (thesis §7.2.3, Table 7.2) into
C = [A_J D_J ... D_1]; the row line holds the lengths vector L_1..L_(J+2) then the first
L_1 + floor(Q*D/100) entries of C (D = the detail count), which drops the finest details
first (D_1, then D_2, ...) and never the approximation.
"""

import numpy as np

from mzc.codecs import rows
from mzc.codecs.base import Option
from mzc.codecs.rows.transforms import DEFAULT_LEVEL, DEFAULT_WAVELET, dwt_forward, dwt_inverse, dwt_lengths, kept
from mzc.errors import MzcError

KIND = "dwt"
VERSION, PROJECTED_VERSION, OLDEST_MAJOR, CHECKSUM_SINCE = (rows.VERSION, rows.PROJECTED_VERSION, rows.OLDEST_MAJOR,
                                                       rows.CHECKSUM_SINCE)
GEOREFERENCED_VERSION, GEOREF_SINCE = rows.GEOREFERENCED_VERSION, rows.GEOREF_SINCE
MAX_LEVEL = 32


def wavelet_names():
    """The discrete wavelets pywt knows (db1, db2, sym4, coif1, bior2.2, ...)."""
    import pywt

    return pywt.wavelist(kind="discrete")


def check_wavelet(name):
    """Refuse a wavelet pywt does not have as a discrete wavelet."""
    if name not in wavelet_names():
        raise MzcError(f"unknown discrete wavelet {name!r} (e.g. db1, db2, db4, sym4, coif1)", field="wavelet")
    return name


def read_options(header):
    """quality, precision, and the required ``wavelet`` and ``level`` lines."""
    options = rows.common_options(header)
    wavelet = header.word("wavelet")
    try:
        options["wavelet"] = check_wavelet(wavelet)
    except MzcError as error:
        raise header.error("wavelet", error.message) from None
    options["level"] = header.integer("level", 1, MAX_LEVEL)
    return options


def header_lines(options):
    return [*rows.common_header_lines(options), f"wavelet {options['wavelet']}", f"level {options['level']}"]


def kept_count(lengths, quality):
    """Entries of C a row keeps: all of A_J plus floor(Q*D/100) details."""
    return lengths[0] + kept(quality, sum(lengths[1:-1]))


def encode(spans, firsts, d2, options):
    """Row tokens: the lengths vector, then the kept prefix of C."""
    lengths = dwt_lengths(spans.shape[1], options["wavelet"], options["level"])
    coefficients = dwt_forward(spans, options["wavelet"], options["level"])
    count = kept_count(lengths, options["quality"])
    prefix = [str(n) for n in lengths]
    return [prefix + rows.format_values(row[:count], options["precision"]) for row in coefficients]


def unpack(values, length, options):
    """C zero padded to its full length, after checking the lengths vector and the count."""
    expected = dwt_lengths(length, options["wavelet"], options["level"])
    if values.size < len(expected):
        raise rows.count_error(f"at least {len(expected)}", values.size, "numbers (the lengths vector)")
    found = [rows.integer_field(v, "lengths") for v in values[:len(expected)]]
    if found != expected:
        raise MzcError(f"lengths vector {' '.join(map(str, found))} does not add up for a span of {length} "
                       f"({options['wavelet']}, level {options['level']}: {' '.join(map(str, expected))})",
                       field="lengths")
    count = kept_count(expected, options["quality"])
    if values.size != len(expected) + count:
        raise rows.count_error(count, values.size - len(expected), "coefficients C")
    vector = np.zeros(sum(expected[:-1]))
    vector[:count] = values[len(expected):]
    return vector


def decode(vectors, length, firsts, d2, options):
    """Inverse DWT, the dropped details being zeros."""
    return dwt_inverse(vectors, dwt_lengths(length, options["wavelet"], options["level"]), options["wavelet"])


def check_options(options):
    """The wavelet must be one pywt has."""
    check_wavelet(options["wavelet"])


ROW_CODEC = rows.RowCodec(KIND, read_options, header_lines, encode, unpack, decode)
WAVELET = Option("wavelet", str, DEFAULT_WAVELET, metavar="NAME", help="Wavelet, e.g. db1, db2, sym4.")
LEVEL = Option("level", int, DEFAULT_LEVEL, 1, MAX_LEVEL, metavar="N", help="Wavelet levels.")
CODEC = rows.codec_of(ROW_CODEC, ".mzw", "Discrete wavelet transform per row (thesis §7.2.3)",
                      (rows.QUALITY, WAVELET, LEVEL, rows.PRECISION), check_options=check_options)
read, write = CODEC.decode, CODEC.encode
