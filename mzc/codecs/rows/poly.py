"""The polynomial codec format (``mzc-poly 1.1`` and 2.1, older 1.0 and 2.0 read; extension ``.mzp``): see spec/poly.md.

Each row's valid span is fitted by a polynomial (thesis Ch. 5, §5.3.1) of degree
min(n, m-1); the row line holds its coefficients and the degree follows from their count.
There is no quality factor: the degree is the knob. The ``chebyshev`` basis (default) is
stable at any degree; ``power`` is the thesis's polyfit on raw x and is unstable past ~40.
"""

from mzc.codecs import rows
from mzc.codecs.base import Option
from mzc.codecs.rows.transforms import BASES, poly_degree, poly_forward, poly_inverse
from mzc.errors import MzcError

KIND = "poly"
VERSION, PROJECTED_VERSION, OLDEST_MAJOR, CHECKSUM_SINCE = (rows.VERSION, rows.PROJECTED_VERSION, rows.OLDEST_MAJOR,
                                                       rows.CHECKSUM_SINCE)
GEOREFERENCED_VERSION, GEOREF_SINCE = rows.GEOREFERENCED_VERSION, rows.GEOREF_SINCE
MAX_DEGREE = 10_000


def read_options(header):
    """The required ``basis`` and ``degree`` lines, and ``precision`` (informative)."""
    return {"basis": header.word("basis", BASES),
            "degree": header.integer("degree", 0, MAX_DEGREE),
            "precision": header.integer("precision", 0, rows.MAX_PRECISION, required=False)}


def header_lines(options):
    lines = [f"basis {options['basis']}", f"degree {options['degree']}"]
    if options["basis"] == "chebyshev":
        lines.append(f"precision {options['precision']}")
    return lines


def encode(spans, firsts, d2, options):
    """Row tokens: the coefficients (power basis: exact, since rounding x^n terms ruins the fit)."""
    coefficients = poly_forward(spans, options["degree"], options["basis"], firsts, d2)
    precision = options["precision"] if options["basis"] == "chebyshev" else None
    return [rows.format_values(row, precision) for row in coefficients]


def unpack(values, length, options):
    """The coefficients; a span of m samples holds min(degree, m-1)+1 of them."""
    expected = poly_degree(options["degree"], length) + 1
    if values.size != expected:
        raise rows.count_error(expected, values.size, f"coefficients (span {length}, degree {options['degree']})")
    return values


def decode(vectors, length, firsts, d2, options):
    """The polynomials evaluated at the span's columns."""
    return poly_inverse(vectors, length, options["basis"], firsts, d2)


def check_options(options):
    """The degree is required: it is the codec's one knob."""
    if options["degree"] is None:
        raise MzcError("the polynomial codec needs a degree", field="degree")


ROW_CODEC = rows.RowCodec(KIND, read_options, header_lines, encode, unpack, decode)
DEGREE = Option("degree", int, None, 0, MAX_DEGREE, metavar="DEGREE", help="Polynomial degree per row.")
BASIS = Option("basis", BASES, "chebyshev",
               help="Polynomial basis: chebyshev (stable) or power (the thesis's polyfit).")
CODEC = rows.codec_of(ROW_CODEC, ".mzp", "Polynomial of DEGREE per row (thesis Ch. 5)", (DEGREE, BASIS, rows.PRECISION),
                      selector="degree", check_options=check_options, example={"degree": 20})
read = CODEC.decode


def write(grid, degree, **options):
    """Encode ``grid`` with polynomials of ``degree`` (the basis and precision as options)."""
    return CODEC.encode(grid, degree=degree, **options)
