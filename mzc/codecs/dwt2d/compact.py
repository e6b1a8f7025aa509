"""The container of ``mzc-dwt2d 7.0``, ``8.0``, ``9.0`` and ``10.0`` (spec/dwt2d.md, Version 7.0): the magic line,
then tagged sections, each with its own CRC-32, the first of them the header's fields in binary. 8.0 has one
more field, the source's vertex count (``source_vertices``), and codes its mask otherwise (Version 8.0).
9.0 (progressive, Version 9.0) splits 8.0's payload into a base section and one section per detail
level, coarsest first, each CRC-32 chained to the section before, so that a prefix of whole sections
decodes (``read_progressive``). 10.0 (Version 10.0) has no sections: its header fields (present ones
as bits, no count a field's keyword implies), its payload (short table records) and colour section in
one body under one CRC-32 (``tight_bytes``, ``read_tight``).

A 3.x header of a face file took about 215 bytes of text; the same fields take about 60 here. The
fields are the 3.x header lines (keyword and values), so one reader checks them all
(mzc.formats.header.Header and the codec's read_codec_fields): this module turns the lines into
bytes and back, and ``mzc info`` prints them as the text lines they stand for. A section's tag
says what it holds, so a later version adds a section (a colour layer) without changing these.
"""

import struct
import zlib
from decimal import Decimal
from typing import NamedTuple

from mzc.codecs.dwt2d.entropy import read_varint, varint
from mzc.errors import MzcError
from mzc.formats.header import CHECKSUM, Header, format_number, split_magic

MAGIC = b"mzc-dwt2d 7.0\n"
MAJORS = (7, 8, 9, 10)          # the majors in this container: 8.0 is 7.0 with source_vertices and the mask as flips,
                                # 9.0 is 8.0 in sections of levels, 10.0 is 8.0 in one body (``tight_bytes``)
PROGRESSIVE_MAJOR = 9
TIGHT_MAJOR = 10
HEADER, PAYLOAD, COLOUR = 1, 2, 3   # section tags, in the order they come (COLOUR only in a file with colours)
BASE, LEVEL = 4, 5              # 9.0: HEADER, BASE, one LEVEL a detail level (coarsest first), then COLOUR
CRC = struct.Struct("<I")
MAX_VARINT_BYTES = 10           # an unsigned 64-bit integer
MAX_DIGITS = 40                 # a decimal's mantissa (repr of a binary64 has at most 17 digits)
MAX_EXPONENT = 400
# field id -> (keyword, type): u unsigned integers, d decimal numbers, e one word of a list, t text (one string)
FIELDS = {
    1: ("rows", "u"), 2: ("cols", "u"), 3: ("d1", "d"), 4: ("d2", "d"), 5: ("origin", "d"),
    6: ("projection", "e"), 7: ("radius", "d"), 8: ("transform", "d"), 9: ("units", "t"), 10: ("nodata", "t"),
    11: ("crs", "t"), 12: ("raster", "t"), 13: ("chart_count", "u"), 14: ("wavelet", "e"), 15: ("levels", "u"),
    16: ("steps", "d"), 17: ("slope_limit", "d"), 18: ("correction", "d"), 19: ("rounding", "e"),
    20: ("max_error", "d"), 21: ("colour_psnr", "d"), 22: ("colour_max_error", "d"), 23: ("source_vertices", "u"),
    24: ("band_models", "u"),
}
COUNTED_MAJOR = 8               # the major whose header has source_vertices (field 23)
SINCE = {23: COUNTED_MAJOR, 24: 10}   # field id -> the major that added it (the others are 7.0's)
IDS = {keyword: (number, kind) for number, (keyword, kind) in FIELDS.items()}
# 10.0: the fields present as one bit each, in this order (the usual ones first, so the bits take 2 bytes), and
# no value count where a field has one count (d2 left out when it equals d1, a transform whose rotation is
# the identity given as its translation alone: TRANSLATION values)
TIGHT_ORDER = (1, 2, 3, 4, 5, 6, 7, 8, 16, 23, 9, 10, 11, 12, 13, 14, 15, 17, 18, 19, 20, 21, 22, 24)
TIGHT_PLACES = (23, 24)         # by minor: the places of TIGHT_ORDER a 10.0 file may use, and a 10.1 file (band_models)
FIXED_COUNTS = {"rows": 1, "cols": 1, "d1": 1, "d2": 1, "origin": 2, "radius": 1, "chart_count": 1, "levels": 1,
                "slope_limit": 1, "correction": 1, "max_error": 1, "colour_psnr": 1, "colour_max_error": 1,
                "source_vertices": 1, "band_models": 1}
ROTATION = (0, 1, 2, 4, 5, 6, 8, 9, 10)   # the rotation's places among a transform's 12 values (row by row)
TRANSLATION = 3
COLOURED = ("colour_psnr", "colour_max_error")   # a 10.0 header with one of these has a colour section
SMALL_EXPONENTS, EXPONENT_BIAS = (-8, 6), 8   # a decimal exponent in this range shares the mantissa's varint
WORDS = ("planar", "cylindrical", "spherical", "bior4.4", "bior2.2", "integer")   # the words of ``e`` fields


# --------------------------------------------------------------------------- writing


def signed(magnitude, negative):
    """A signed integer as an unsigned one, 2|v| + 1 when negative: -0 (of -0.0) is 1, not 0."""
    return 2 * magnitude + int(negative)


def decimal_bytes(word):
    """A number written as ``word`` (the shortest text of a binary64) as its decimal digits m (signed,
    -0 kept) and exponent e: one varint 16 s(m) + e + 8 for e in -8..6, else 16 s(m) + 15 and a varint
    s(e), s being ``signed``. The text it reads back as is the number itself, on every machine; 0, 1
    and 0.5 take a byte (a face's transform is nine of them)."""
    sign, digits, exponent = Decimal(word).as_tuple()
    mantissa = signed(int("".join(map(str, digits)) or "0"), sign)
    if SMALL_EXPONENTS[0] <= exponent <= SMALL_EXPONENTS[1]:
        return varint(16 * mantissa + exponent + EXPONENT_BIAS)
    return varint(16 * mantissa + 15) + varint(signed(abs(exponent), exponent < 0))


def field_bytes(line):
    """One header line (``keyword values...``) as its field id, value count and values."""
    keyword, *words = line.split()
    number, kind = IDS[keyword]
    if kind == "t":
        text = " ".join(words).encode("utf-8")
        return varint(number) + varint(len(text)) + text
    if kind == "e":
        return varint(number) + varint(WORDS.index(words[0]))
    values = [varint(int(w)) for w in words] if kind == "u" else [decimal_bytes(w) for w in words]
    return varint(number) + varint(len(values)) + b"".join(values)


def tight_fields(lines):
    """10.0's header fields of the header ``lines``: a varint of one bit per field present (TIGHT_ORDER),
    then each field's values as 7.0 codes them, without the value count of a field in FIXED_COUNTS."""
    words = {line.split()[0]: line.split()[1:] for line in lines}
    if words.get("d2") == words["d1"]:
        words.pop("d2")
    rotation = [words["transform"][i] for i in ROTATION] if "transform" in words else None
    if rotation == "1 0 0 0 1 0 0 0 1".split():
        words["transform"] = words["transform"][TRANSLATION::4]
    present = [number for number in TIGHT_ORDER if FIELDS[number][0] in words]
    out = varint(sum(1 << TIGHT_ORDER.index(number) for number in present))
    for number in present:
        keyword = FIELDS[number][0]
        field = field_bytes(" ".join([keyword, *words[keyword]]))[len(varint(number)):]   # without the field id
        out += field[len(varint(len(words[keyword]))):] if keyword in FIXED_COUNTS else field
    return out


def tight_bytes(lines, payload, colour=None):
    """The 10.0 file of the header ``lines`` and payload (and colour section, for a grid with colours):
    the magic line, the varint length of the header fields (``tight_fields``), the fields, the varint
    length of the payload when a colour section follows it, the payload, the colour section, then one
    CRC-32 (little-endian) of every byte before it. A file with ``band_models`` is 10.1, the first minor
    that has the field (a 10.0 reader refuses it as newer)."""
    fields = tight_fields(lines)
    minor = int(any(line.split()[0] == "band_models" for line in lines))
    head = magic_line((TIGHT_MAJOR, minor)) + varint(len(fields)) + fields
    body = payload if colour is None else varint(len(payload)) + payload + colour
    return head + body + CRC.pack(zlib.crc32(head + body))


def section(tag, body, before=b""):
    """A section: its tag, the varint length of ``body``, ``body``, then the CRC-32 (little-endian) of
    ``before`` (the magic line, for the header section) and the section's bytes so far."""
    head = bytes([tag]) + varint(len(body)) + body
    return head + CRC.pack(zlib.crc32(head, zlib.crc32(before)))


def magic_line(version):
    """The magic line of ``version`` (major, minor)."""
    return f"mzc-dwt2d {version[0]}.{version[1]}\n".encode()


def file_bytes(lines, payload, colour=None, major=7):
    """The file of ``major`` (7, 8 or 9) of the header ``lines`` (3.x's, without the magic and ``data``
    lines; fields of that major's), the payload (9.0: the list of its base and level sections' bodies)
    and, for a grid with colours, its colour section (mzc.codecs.dwt2d.colour's bytes); 10.0's is ``tight_bytes``."""
    if major == TIGHT_MAJOR:
        return tight_bytes(lines, payload, colour)
    fields = b"".join(field_bytes(line) for line in sorted(lines, key=field_number))   # in the table's order
    magic = magic_line((major, 0))
    head = magic + section(HEADER, fields, magic)
    if major == PROGRESSIVE_MAJOR:
        tagged = [(BASE, payload[0]), *((LEVEL, body) for body in payload[1:])]
        return head + chained(tagged + ([] if colour is None else [(COLOUR, colour)]), head[-CRC.size:])
    coloured = b"" if colour is None else section(COLOUR, colour)
    return head + section(PAYLOAD, payload) + coloured


def chained(tagged, before):
    """The sections of (tag, body) pairs, each CRC-32 starting from the CRC-32 bytes of the section
    before it (``before``: the header's), so that a section moved, dropped or taken from another
    file does not check."""
    out = []
    for tag, body in tagged:
        out.append(section(tag, body, before))
        before = out[-1][-CRC.size:]
    return b"".join(out)


def field_number(line):
    """The field id of a header line."""
    return IDS[line.split()[0]][0]


# --------------------------------------------------------------------------- reading


class Cut(Exception):
    """A section's length runs to the end of the file (``Reader.ends_inside``)."""


class Reader:
    """Reads the bytes of one 7.0 file front to back; every failure is a one-line MzcError."""

    def __init__(self, data, source):
        self.data, self.source = memoryview(data), source
        self.position = bytes(self.data[:len(magic_line((MAJORS[-1], 0))) + 1]).find(b"\n") + 1   # after the magic line
        if self.data[self.position - 2:self.position] == b"\r\n":
            raise self.error("the magic line ends in CRLF: the file was copied as text, which changes its binary "
                             "bytes; copy mzc files as binary", CHECKSUM)

    def error(self, message, field="data"):
        return MzcError(message, source=self.source, field=field)

    def varint(self, end=None):
        """One unsigned LEB128 integer (at most MAX_VARINT_BYTES bytes) that ends before ``end``."""
        end = len(self.data) if end is None else end

        def fault(kind):
            if kind == "long":
                return self.error(f"a number longer than {MAX_VARINT_BYTES} bytes")
            return self.error("the file ends inside a number" if end == len(self.data)
                              else "a header field runs past its section")

        value, self.position = read_varint(self.data, self.position, end, MAX_VARINT_BYTES, fault)
        return value

    def section(self, tag, before=b"", cut=False):
        """The body of the next section, which must be ``tag``'s, its CRC-32 checked; with ``cut``, None
        when the file ends before the section does (a prefix of a 9.0 file), which is else refused."""
        start = self.position
        if cut and self.ends_inside(start):
            return None
        if start >= len(self.data):
            raise self.error(f"the file ends before its section {tag}")
        if self.data[start] != tag:
            raise self.error(f"section tag {self.data[start]} where section {tag} belongs")
        self.position += 1
        length = self.varint()
        end = self.position + length
        if end + CRC.size > len(self.data):
            raise self.error(f"the file ends inside section {tag} (cut short?)")
        stated = CRC.unpack_from(self.data, end)[0]
        if zlib.crc32(self.data[start:end], zlib.crc32(before)) != stated:
            raise self.error(f"checksum mismatch: section {tag} of the file is corrupt (damaged, or bytes changed)",
                             CHECKSUM)
        body, self.position = bytes(self.data[self.position:end]), end + CRC.size
        return body

    def ends_inside(self, start):
        """True when the section at ``start`` does not end within the file (its tag, length, body or CRC-32 cut)."""
        def fault(kind):
            return Cut() if kind == "cut" else self.error(f"a number longer than {MAX_VARINT_BYTES} bytes")

        try:
            length, after = read_varint(self.data, start + 1, len(self.data), MAX_VARINT_BYTES, fault)
        except Cut:
            return True
        return after + length + CRC.size > len(self.data)

    def decimal(self, end):
        """A number of ``decimal_bytes`` as the text 3.x writes for it."""
        head = self.varint(end)
        mantissa, low = head >> 4, head & 15
        exponent = unsigned(self.varint(end)) if low == 15 else low - EXPONENT_BIAS
        if mantissa >= 2 * 10 ** MAX_DIGITS or abs(exponent) > MAX_EXPONENT:
            raise self.error("a header number has too many digits")
        return format_number(float(f"{'-' if mantissa % 2 else ''}{mantissa // 2}e{exponent}"))

    def header(self):
        """The Header of the header section (keywords and their value words, as a 3.x header's lines)
        of a 7.0 or 8.0 file (a later minor is refused: its fields are not known here)."""
        magic = bytes(self.data[:self.position])
        _kind, major, minor = split_magic(magic, self.source)
        if minor:
            raise MzcError(f"mzc-dwt2d version {major}.{minor} is newer than this mzc reads ({major}.0); upgrade mzc",
                           source=self.source, line=1)
        body = self.section(HEADER, magic)
        fields = Reader(magic + body, self.source)
        header = Header(self.source, major, projected=True, georeferenced=True, charted=True,
                        counted=major >= COUNTED_MAJOR)
        end = len(fields.data)
        while fields.position < end:
            number = fields.varint(end)
            if number not in FIELDS or SINCE.get(number, 7) > major:
                raise self.error(f"unknown header field {number}")
            keyword, kind = FIELDS[number]
            if header.has(keyword):
                raise self.error(f"header field {keyword} given twice")
            header.add(keyword, fields.words(kind, end), None)
        return header

    def words(self, kind, end, count=None):
        """The value words of one field of ``kind`` (FIELDS) ending before ``end``; ``count`` values
        when given (10.0's FIXED_COUNTS), else as many as the varint before them says."""
        if kind == "e":
            index = self.varint(end)
            if index >= len(WORDS):
                raise self.error(f"word number {index} of a header field is not 0..{len(WORDS) - 1}")
            return [WORDS[index]]
        count = self.varint(end) if count is None else count
        if kind == "t":
            if self.position + count > end:
                raise self.error("a header field runs past its section")
            text, self.position = bytes(self.data[self.position:self.position + count]), self.position + count
            try:
                return text.decode("utf-8").split()
            except UnicodeDecodeError:
                raise self.error("a header text is not UTF-8") from None
        if count > end - self.position:
            raise self.error("a header field runs past its section")
        return [str(self.varint(end)) if kind == "u" else self.decimal(end) for _ in range(count)]

    def last_crc(self):
        """The CRC-32 bytes of the section just read, where the next one's CRC-32 starts in 9.0 (``chained``)."""
        return bytes(self.data[self.position - CRC.size:self.position])

    def check_end(self):
        """Refuse bytes after the last section (added to the file, which its sections' CRC-32s do not cover)."""
        if self.position != len(self.data):
            raise self.error(f"checksum mismatch: {len(self.data) - self.position} byte(s) after the last section "
                             "(added to the file)", CHECKSUM)


def unsigned(value):
    """The integer of ``signed`` (-0 as 0)."""
    return -(value // 2) if value % 2 else value // 2


def major(data):
    """The major version of a file of this container (its magic line's), else None."""
    return next((m for m in MAJORS if bytes(data[:len(magic_line((m, 0))) - 2]) == magic_line((m, 0))[:-2]), None)


def is_compact(data):
    """True when ``data`` starts as a 7.x or 8.x file."""
    return major(data) is not None


def read(data, source):
    """(Header, payload bytes, colour section bytes or None) of a 7.0 or 8.0 file; of a 9.0 file the payload
    is the list of its base and level sections' bodies (``read_progressive``)."""
    if major(data) == PROGRESSIVE_MAJOR:
        return read_progressive(data, source)[:3]
    if major(data) == TIGHT_MAJOR:
        return read_tight(data, source)
    reader = Reader(data, source)
    header = reader.header()
    payload = reader.section(PAYLOAD)
    colour = reader.section(COLOUR) if bytes(reader.data[reader.position:reader.position + 1]) == bytes([COLOUR]) \
        else None
    reader.check_end()
    return header, payload, colour


def read_tight(data, source):
    """(Header, payload bytes, colour section bytes or None) of a 10.0 file (``tight_bytes``), its CRC-32 checked
    first; the header's lines are the ones its fields stand for (d2 and a transform's rotation filled in)."""
    reader = Reader(data, source)
    last = len(reader.data) - CRC.size
    if last < reader.position or zlib.crc32(reader.data[:last]) != CRC.unpack_from(reader.data, last)[0]:
        raise reader.error("checksum mismatch: the file is corrupt (damaged, cut short or added to)", CHECKSUM)
    _kind, file_major, minor = split_magic(bytes(reader.data[:reader.position]), source)
    if minor >= len(TIGHT_PLACES):
        raise MzcError(f"mzc-dwt2d version {file_major}.{minor} is newer than this mzc reads "
                       f"({file_major}.{len(TIGHT_PLACES) - 1}); upgrade mzc", source=source, line=1)
    end = reader.varint(last)
    end += reader.position
    if end > last:
        raise reader.error("the header fields run past the end of the file")
    header = Header(source, file_major, projected=True, georeferenced=True, charted=True, counted=True)
    present = reader.varint(end)
    if present >> TIGHT_PLACES[minor]:
        raise reader.error(f"unknown header field (bits {present:#x})")
    for place, number in enumerate(TIGHT_ORDER):
        if present >> place & 1:
            keyword, kind = FIELDS[number]
            header.add(keyword, reader.words(kind, end, FIXED_COUNTS.get(keyword)), None)
    if reader.position != end:
        raise reader.error("the header fields end before their length says")
    filled(header)
    if not any(header.has(keyword) for keyword in COLOURED):
        return header, bytes(reader.data[reader.position:last]), None
    length = reader.varint(last)
    if reader.position + length > last:
        raise reader.error("the payload runs past the end of the file")
    split = reader.position + length
    return header, bytes(reader.data[reader.position:split]), bytes(reader.data[split:last])


def filled(header):
    """Give a 10.0 Header the fields its writer left out (``tight_fields``), d2 as d1 and a transform of
    TRANSLATION values with the identity rotation, and put its fields in the table's order (``mzc info``'s)."""
    if header.has("d1") and not header.has("d2"):
        header.add("d2", header.fields["d1"][0], None)
    if header.has("transform") and len(header.fields["transform"][0]) == TRANSLATION:
        values = ["1", "0", "0", "0", "1", "0", "0", "0", "1"]
        for place, value in zip(range(TRANSLATION, 12, 4), header.fields["transform"][0]):
            values.insert(place, value)
        header.fields["transform"] = (values, None)
    header.fields = dict(sorted(header.fields.items(), key=lambda item: IDS[item[0]][0]))


class Sections(NamedTuple):
    """What ``read_progressive`` reads of a 9.0 file: its Header, the bodies of its base section and
    level sections (coarsest first), its colour section's body or None, whether the file is ``cut``
    short, and ``ends``, the file's length up to the end of each base and level section read."""

    header: Header
    bodies: list
    colour: bytes | None
    cut: bool
    ends: list


def read_progressive(data, source):
    """The Sections of a 9.0 file or a prefix of one: ``cut`` when the file ends inside or before a
    level or colour section, which is then left out (a cut in the header or base section is refused)."""
    reader = Reader(data, source)
    header = reader.header()
    bodies = [reader.section(BASE, reader.last_crc())]
    ends = [reader.position]
    while reader.position < len(reader.data) and reader.data[reader.position] == LEVEL:
        body = reader.section(LEVEL, reader.last_crc(), cut=True)
        if body is None:
            return Sections(header, bodies, None, True, ends)
        bodies.append(body)
        ends.append(reader.position)
    colour = None
    if reader.position < len(reader.data):
        colour = reader.section(COLOUR, reader.last_crc(), cut=True)
        if colour is None:
            return Sections(header, bodies, None, True, ends)
    reader.check_end()
    return Sections(header, bodies, colour, False, ends)
