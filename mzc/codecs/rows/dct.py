"""The DCT codec format (``mzc-dct 1.1`` and 2.1, older 1.0 and 2.0 read; extension ``.mzd``): see spec/dct.md.

Each row's valid span is coded by its orthonormal DCT-II (thesis §7.2.2, Table 7.1);
quality Q keeps the first floor(Q*m/100) coefficients of a span of m samples.
"""

from mzc.codecs import rows
from mzc.codecs.rows.transforms import dct_forward, dct_inverse, kept

KIND = "dct"
VERSION, PROJECTED_VERSION, OLDEST_MAJOR, CHECKSUM_SINCE = (rows.VERSION, rows.PROJECTED_VERSION, rows.OLDEST_MAJOR,
                                                       rows.CHECKSUM_SINCE)
GEOREFERENCED_VERSION, GEOREF_SINCE = rows.GEOREFERENCED_VERSION, rows.GEOREF_SINCE


def encode(spans, firsts, d2, options):
    """Row tokens: the first floor(Q*m/100) DCT coefficients B."""
    coefficients = dct_forward(spans)[:, :kept(options["quality"], spans.shape[1])]
    return [rows.format_values(row, options["precision"]) for row in coefficients]


def unpack(values, length, options):
    """B as given; its count must be floor(Q*m/100)."""
    expected = kept(options["quality"], length)
    if values.size != expected:
        raise rows.count_error(expected, values.size, f"DCT coefficients (span {length}, quality {options['quality']})")
    return values


def decode(vectors, length, firsts, d2, options):
    """Inverse DCT, the dropped coefficients being zeros."""
    return dct_inverse(vectors, length)


ROW_CODEC = rows.RowCodec(KIND, rows.common_options, rows.common_header_lines, encode, unpack, decode)
CODEC = rows.codec_of(ROW_CODEC, ".mzd", "Discrete cosine transform per row (thesis §7.2.2)")
read, write = CODEC.decode, CODEC.encode
