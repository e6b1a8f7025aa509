"""web/'s reading of `mzc-dwt2d 7.0`'s parts against mzc's (spec/dwt2d.md, Version 7.0): the
parametric tables of every class count, z and t; the header section's fields, decimals of any
binary64 included, and header sections of random bytes, refused where mzc refuses them and read
as the same lines otherwise. Skipped when node is not installed."""


from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.codecs.dwt2d import compact
from mzc.codecs.dwt2d.entropy import parametric_table
from mzc.errors import MzcError
from mzc.formats.header import format_number

from web_node import needs_node, node_json

pytestmark = needs_node

TABLES_SCRIPT = """
import { readFileSync } from "node:fs";
import { frequencyTable, parametricWeights } from "./dwt2d.mjs";
const cases = JSON.parse(readFileSync(0, "utf8"));
process.stdout.write(JSON.stringify(cases.map(([s, z, t]) => frequencyTable(parametricWeights(s, z, t)).freq)));
"""

HEADER_SCRIPT = """
import { readFileSync } from "node:fs";
import { headerLines } from "./compact.mjs";
import { MzcError } from "./header.mjs";
const bodies = JSON.parse(readFileSync(0, "utf8"));
process.stdout.write(JSON.stringify(bodies.map((hex) => {
  try {
    return Object.fromEntries(headerLines(Uint8Array.from(Buffer.from(hex, "hex")), 8));
  } catch (error) {
    if (error instanceof MzcError) return null;
    throw error;
  }
})));
"""


def test_parametric_tables_are_mzcs():
    """Every ratio code t, zero shares from none to all but one 256th, class counts 2..48."""
    cases = [[s, z, t] for s in (2, 3, 4, 7, 12, 20, 33, 47, 48) for z in (0, 1, 64, 200, 255) for t in range(256)]
    made = node_json(TABLES_SCRIPT, cases)
    for (s, z, t), freq in zip(cases, made, strict=True):
        assert freq == parametric_table(s, z, t).tolist(), (s, z, t)
        assert sum(freq) == 16384


def mzc_lines(body):
    """{keyword: words} of an 8.0 file's header section body (every field) as mzc reads it, or None where
    it refuses it."""
    magic = b"mzc-dwt2d 8.0\n"
    data = magic + compact.section(compact.HEADER, body, magic)
    try:
        header = compact.Reader(data, "t").header()
    except MzcError:
        return None
    return {keyword: list(values) for keyword, (values, _line) in header.fields.items()}


FINITE = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=15, deadline=None)
@given(st.lists(st.tuples(FINITE, FINITE), min_size=1, max_size=40), st.integers(0, 2 ** 64 - 1))
def test_header_fields_read_as_mzc_reads_them(origins, count):
    """Fields of any binary64 (their shortest decimals, small and large exponents, -0) and of any
    unsigned 64-bit integer give the words mzc's reader gives."""
    bodies = [compact.field_bytes(f"origin {format_number(x)} {format_number(y)}")
              + compact.field_bytes(f"levels {count}") + compact.field_bytes("units mm") for x, y in origins]
    made = node_json(HEADER_SCRIPT, [body.hex() for body in bodies])
    for body, lines in zip(bodies, made, strict=True):
        assert lines == mzc_lines(body)


@settings(max_examples=15, deadline=None)
@given(st.lists(st.binary(max_size=24), min_size=1, max_size=60))
def test_header_sections_of_random_bytes_are_refused_or_read_as_mzc_does(bodies):
    made = node_json(HEADER_SCRIPT, [body.hex() for body in bodies])
    for body, lines in zip(bodies, made, strict=True):
        assert lines == mzc_lines(body), body.hex()
