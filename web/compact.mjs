// The container of `mzc-dwt2d 7.0`, 8.0 and 9.0 (spec/dwt2d.md, Version 7.0): the magic line, then tagged
// sections each under its own CRC-32, the header's fields in binary turned back into the header
// lines they stand for, so that dwt2d.mjs reads them as it reads a 3.x file's lines. 9.0 (Version 9.0)
// has a base section and one section per detail level, each CRC-32 chained to the section before, and
// a prefix of whole sections decodes (`progressiveSections`). 10.0 (Version 10.0) has one body under one
// CRC-32, its fields as presence bits without implied counts (`tightParts`).

import { fail, crc32, formatNumber, words, parseMagic } from "./header.mjs";

const TEXT = new TextDecoder("utf-8", { fatal: true });
const MAX_VARINT_BYTES = 10;   // a header's varints: an unsigned 64-bit integer (as mzc reads them)
const MAX_DIGITS = 40;
const MAX_EXPONENT = 400;
/** Field id -> [keyword, type]: u unsigned integers, d decimals, e one word of WORDS, t text. */
const FIELDS = {
  1: ["rows", "u"], 2: ["cols", "u"], 3: ["d1", "d"], 4: ["d2", "d"], 5: ["origin", "d"], 6: ["projection", "e"],
  7: ["radius", "d"], 8: ["transform", "d"], 9: ["units", "t"], 10: ["nodata", "t"], 11: ["crs", "t"],
  12: ["raster", "t"], 13: ["chart_count", "u"], 14: ["wavelet", "e"], 15: ["levels", "u"], 16: ["steps", "d"],
  17: ["slope_limit", "d"], 18: ["correction", "d"], 19: ["rounding", "e"], 20: ["max_error", "d"],
  21: ["colour_psnr", "d"], 22: ["colour_max_error", "d"], 23: ["source_vertices", "u"], 24: ["band_models", "u"],
};
/** Field id -> the major that added it (8.0: the source's vertex count, 10.1: band_models); the others are 7.0's. */
const SINCE = { 23: 8, 24: 10 };
const WORDS = ["planar", "cylindrical", "spherical", "bior4.4", "bior2.2", "integer"];
const COMPACT = ["mzc-dwt2d 7.", "mzc-dwt2d 8.", "mzc-dwt2d 9.", "mzc-dwt2d 10."].map((text) => new TextEncoder().encode(text));

/** The magic of a binary file (`mzc-dwt2d 7.x` to `10.x`, its line within 16 bytes, a CR included) and
 * the end of that line; null for a file of text header lines. */
export function compactMagic(bytes) {
  if (!COMPACT.some((magic) => magic.every((b, i) => bytes[i] === b))) return null;
  const end = bytes.subarray(0, 16).indexOf(10) + 1;
  if (!end) fail(null, "not an mzc file (no `mzc-KIND MAJOR.MINOR` magic line)");
  const magic = parseMagic(new TextDecoder().decode(bytes.subarray(0, end - 1)).replace(/\r$/, ""));
  return { ...magic, end };
}

export const HEADER = 1;
export const PAYLOAD = 2;
export const COLOUR = 3;
export const BASE = 4;
export const LEVEL = 5;

/** A front-to-back reader of a byte range whose every failure is a one-line MzcError. */
class Cursor {
  constructor(bytes, at, end = bytes.length) {
    this.bytes = bytes;
    this.at = at;
    this.end = end;
  }

  /** An unsigned LEB128 integer of at most 10 bytes, as a BigInt (a decimal's digits need 64 bits). */
  varint() {
    let value = 0n;
    for (let i = 0; i < MAX_VARINT_BYTES; i++) {
      if (this.at >= this.end) fail("data", this.end === this.bytes.length ? "the file ends inside a number" : "a header field runs past its section");
      const b = this.bytes[this.at++];
      value |= BigInt(b & 0x7f) << BigInt(7 * i);
      if (!(b & 0x80)) return value;
    }
    return fail("data", `a number longer than ${MAX_VARINT_BYTES} bytes`);
  }
}

/** The body of the section `tag` at `cursor` (moved past it), its CRC-32 checked: that of `before`
 * (the magic line, for the first section; in 9.0 the CRC-32 bytes of the section before) and the
 * section's bytes up to its own CRC-32. */
function readSection(bytes, cursor, tag, before) {
  const start = cursor.at;
  if (start >= bytes.length) fail("data", `the file ends before its section ${tag}`);
  if (bytes[start] !== tag) fail("data", `section tag ${bytes[start]} where section ${tag} belongs`);
  cursor.at++;
  const length = cursor.varint();
  const end = cursor.at + Number(length);
  if (end + 4 > bytes.length) fail("data", `the file ends inside section ${tag} (cut short?)`);
  const stated = new DataView(bytes.buffer, bytes.byteOffset + end, 4).getUint32(0, true);
  if (crc32(before, bytes.subarray(start, end)) !== stated) fail("crc32", `checksum mismatch: section ${tag} of the file is corrupt`);
  const body = bytes.subarray(cursor.at, end);
  cursor.at = end + 4;
  return body;
}

/** 10.x's field ids in the order of its presence bits, and the fields of one count (Version 10.0). */
const TIGHT_ORDER = [1, 2, 3, 4, 5, 6, 7, 8, 16, 23, 9, 10, 11, 12, 13, 14, 15, 17, 18, 19, 20, 21, 22, 24];
/** By minor: how many of TIGHT_ORDER's places a file may use (10.1 adds band_models). */
export const TIGHT_PLACES = [23, 24];
const FIXED_COUNTS = { rows: 1, cols: 1, d1: 1, d2: 1, origin: 2, radius: 1, chart_count: 1, levels: 1, slope_limit: 1,
  correction: 1, max_error: 1, colour_psnr: 1, colour_max_error: 1, source_vertices: 1, band_models: 1 };

/** The parts of a 10.x file (`magicEnd`: the end of its magic line; `minor`: its minor version, one this
 * decoder reads): {fields (keyword -> words, d2 and a translation-only transform filled in), payload,
 * colour (null without)}, its CRC-32 checked first. */
export function tightParts(bytes, magicEnd, minor) {
  checkBinary(bytes, magicEnd);
  const last = bytes.length - 4;
  if (last < magicEnd || crc32(bytes.subarray(0, last)) !== new DataView(bytes.buffer, bytes.byteOffset + last, 4).getUint32(0, true)) {
    fail("crc32", "checksum mismatch: the file is corrupt (damaged, cut short or added to)");
  }
  const outer = new Cursor(bytes, magicEnd, last);
  const length = Number(outer.varint());
  const end = outer.at + length;
  if (end > last) fail("data", "the header fields run past the end of the file");
  const cursor = new Cursor(bytes, outer.at, end);
  const present = cursor.varint();
  if (present >> BigInt(TIGHT_PLACES[minor])) fail("data", `unknown header field (bits 0x${present.toString(16)})`);
  const fields = new Map();
  TIGHT_ORDER.forEach((id, place) => {
    if (!((present >> BigInt(place)) & 1n)) return;
    const [keyword, type] = FIELDS[id];
    fields.set(keyword, values(cursor, type, FIXED_COUNTS[keyword]));
  });
  if (cursor.at !== end) fail("data", "the header fields end before their length says");
  if (fields.has("d1") && !fields.has("d2")) fields.set("d2", fields.get("d1"));
  const transform = fields.get("transform");
  if (transform?.length === 3) fields.set("transform", ["1", "0", "0", transform[0], "0", "1", "0", transform[1], "0", "0", "1", transform[2]]);
  if (!fields.has("colour_psnr") && !fields.has("colour_max_error")) return { fields, payload: bytes.subarray(end, last), colour: null };
  const rest = new Cursor(bytes, end, last);
  const payloadLength = Number(rest.varint());
  const split = rest.at + payloadLength;
  if (split > last) fail("data", "the payload runs past the end of the file");
  return { fields, payload: bytes.subarray(rest.at, split), colour: bytes.subarray(split, last) };
}

/** Refuses a file whose magic line ends in CRLF (copied as text). */
function checkBinary(bytes, magicEnd) {
  if (bytes[magicEnd - 2] === 13) fail("crc32", "the magic line ends in CRLF: the file was copied as text; copy mzc files as binary");
}

/** Refuses bytes after the last section (added to the file, which no CRC-32 covers). */
function checkEnd(bytes, cursor) {
  if (cursor.at !== bytes.length) fail("crc32", `checksum mismatch: ${bytes.length - cursor.at} byte(s) after the last section (added to the file)`);
}

/** The sections of a container file after its magic line (`magicEnd` bytes, which the first
 * section's CRC-32 covers): each tag in `tags` in order, its body checked, then the `optional`
 * tag when bytes remain (a grid's colours, Colours of 7.0), and nothing after them. Returns the
 * bodies by tag. */
export function sections(bytes, magicEnd, tags, optional) {
  checkBinary(bytes, magicEnd);
  const cursor = new Cursor(bytes, magicEnd);
  const bodies = {};
  const all = optional === undefined ? tags : [...tags, optional];
  all.forEach((tag, i) => {
    if (i >= tags.length && cursor.at === bytes.length) return;   // no optional section
    bodies[tag] = readSection(bytes, cursor, tag, i ? new Uint8Array(0) : bytes.subarray(0, magicEnd));
  });
  checkEnd(bytes, cursor);
  return bodies;
}

/** The sections of a 9.0 file or a prefix of one (`magicEnd`: the end of its magic line): {header,
 * bodies: [base, level 1 (coarsest), ...], colour, cut}. Each section's CRC-32 starts from the CRC-32
 * bytes of the section before (the header's from the magic line); a file that ends inside or before a
 * level or colour section is `cut` there (a cut in the header or base section is refused). */
export function progressiveSections(bytes, magicEnd) {
  checkBinary(bytes, magicEnd);
  const cursor = new Cursor(bytes, magicEnd);
  let before = bytes.subarray(0, magicEnd);
  const read = (tag, cut) => {
    if (cut && endsInside(bytes, cursor.at)) return null;
    const body = readSection(bytes, cursor, tag, before);
    before = bytes.subarray(cursor.at - 4, cursor.at);   // this section's CRC-32: where the next one's starts
    return body;
  };
  const header = read(HEADER, false);
  const bodies = [read(BASE, false)];
  while (cursor.at < bytes.length && bytes[cursor.at] === LEVEL) {
    const body = read(LEVEL, true);
    if (!body) return { header, bodies, colour: null, cut: true };
    bodies.push(body);
  }
  let colour = null;
  if (cursor.at < bytes.length) {
    colour = read(COLOUR, true);
    if (!colour) return { header, bodies, colour, cut: true };
  }
  checkEnd(bytes, cursor);
  return { header, bodies, colour, cut: false };
}

/** True when the section at `start` does not end within the file (its tag, length, body or CRC-32 cut). */
function endsInside(bytes, start) {
  let length = 0;
  let at = start + 1;
  for (let i = 0; ; i++) {
    if (at >= bytes.length) return true;
    if (i >= MAX_VARINT_BYTES) fail("data", `a number longer than ${MAX_VARINT_BYTES} bytes`);
    const b = bytes[at++];
    length += (b & 0x7f) * 2 ** (7 * i);
    if (!(b & 0x80)) break;
  }
  return at + length + 4 > bytes.length;
}

/** The header section's fields of a file of `major` (7 or 8) as the map of header lines (keyword ->
 * value words) they stand for. */
export function headerLines(body, major) {
  const cursor = new Cursor(body, 0);
  const fields = new Map();
  while (cursor.at < body.length) {
    const id = cursor.varint();
    const field = id <= 24n && (SINCE[Number(id)] ?? 7) <= major ? FIELDS[Number(id)] : undefined;
    if (!field) fail("data", `unknown header field ${id}`);
    const [keyword, type] = field;
    if (fields.has(keyword)) fail("data", `header field ${keyword} given twice`);
    fields.set(keyword, values(cursor, type));
  }
  return fields;
}

/** The value words of one field of `type`: `fixed` of them when given (10.0's fields of one count), else
 * as many as the count before them says. */
function values(cursor, type, fixed) {
  if (type === "e") {
    const index = cursor.varint();
    if (index >= BigInt(WORDS.length)) fail("data", `word number ${index} of a header field is not 0..${WORDS.length - 1}`);
    return [WORDS[Number(index)]];
  }
  const count = fixed === undefined ? cursor.varint() : BigInt(fixed);
  if (count > BigInt(cursor.end - cursor.at)) fail("data", "a header field runs past its section");
  const n = Number(count);
  if (type === "t") {
    const text = cursor.bytes.subarray(cursor.at, cursor.at + n);
    cursor.at += n;
    try {
      return words(TEXT.decode(text));
    } catch {
      return fail("data", "a header text is not UTF-8");
    }
  }
  return Array.from({ length: n }, () => (type === "u" ? String(cursor.varint()) : decimal(cursor)));
}

/** The signed integer of 2|v| + (1 when negative). */
const unsigned = (s) => (s & 1n ? -(s >> 1n) : s >> 1n);

/** A decimal (Decimals): digits m and exponent e, as the text of the binary64 nearest m x 10^e
 * (JavaScript's Number() of a decimal text rounds correctly, as Python's float() does). */
function decimal(cursor) {
  const head = cursor.varint();
  const mantissa = head >> 4n;
  const low = head & 15n;
  const exponent = low === 15n ? unsigned(cursor.varint()) : low - 8n;
  if (mantissa >= 2n * 10n ** BigInt(MAX_DIGITS) || (exponent < 0n ? -exponent : exponent) > BigInt(MAX_EXPONENT)) {
    fail("data", "a header number has too many digits");
  }
  return formatNumber(Number(`${mantissa & 1n ? "-" : ""}${mantissa >> 1n}e${exponent}`));
}
