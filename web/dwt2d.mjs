// The 2D wavelet codec `mzc-dwt2d` 2.0, 3.0, 3.1, 3.2, 4.0, 5.0 (tiles), 5.1 (rounded tiles), 6.0 (rounding)
// and 7.0 (binary header and parametric tables, in the sections of compact.mjs), 8.0 (7.0, its mask in mask.mjs),
// 9.0 (8.0 in sections of levels, coarsest first: a prefix of whole sections decodes to a coarser surface),
// 10.0 (8.0 in one body under one CRC-32, its header fields tighter, its table records short), 10.1 (10.0 with
// band_models: each detail band its own contexts' models), 11.0 (tiles that are 10.x files with their block's
// colours, decoded by colour.mjs)
// (spec/dwt2d.md): header, payload (tables, rANS, raw bits), mask, relevance, bands, slope
// factors, inverse transform, correction layer, chart records, rounding and tiles.

import { fail, headerFields, fieldReader, gridFields, checkChecksum, checkCharts, VIEWS, crc32, splitHeader, parseMagic } from "./header.mjs";
import { cos } from "./elementary.mjs";
import { sections, progressiveSections, tightParts, headerLines, compactMagic, HEADER, PAYLOAD, COLOUR, TIGHT_PLACES } from "./compact.mjs";
import { inversePeriodized2d, relevantPeriodized2d } from "./pywt.mjs";
import { decodeFlips } from "./mask.mjs";

const WAVELETS_3 = ["bior4.4", "bior2.2"];
const WAVELETS_2 = ["bior4.4", "bior2.2", "bior3.3", "db2", "db4", "sym4", "coif1", "haar"];

/** Decodes a dwt2d file (bytes; its header lines; the payload's offset; its magic); `withColours`
 * (colour.mjs's, given by the caller: colour.mjs reads payloads with this module) decodes the colour
 * sections of an 11.0 file's tiles. */
export function decodeDwt2d(bytes, lines, body, magic, withColours) {
  if (magic.major === 5 || magic.major === 11) return decodeTiled(bytes, lines, body, magic, withColours);
  const fields = headerFields(lines, false);
  checkChecksum(bytes, lines, fields, magic.major >= 4 || (magic.major === 3 && magic.minor >= 1));
  return decodeWhole(fields, [bytes.subarray(body)], magic);
}

/** Decodes a 7.0 file (bytes; the end of its magic line; its magic): its sections, the header's
 * fields read as the lines they stand for, the payload with 7.0's table records; section 3, a
 * grid's colours (Colours of 7.0), comes back undecoded as `colourSection` (colour.mjs's
 * `withColours` decodes it over the grid's valid nodes and charts). A 10.0 file's CRC-32 is
 * checked before its minor version, as mzc does. */
export function decodeCompact(bytes, magicEnd, magic) {
  if (magic.major >= 10) return decodeTight(bytes, magicEnd, magic).grid;
  checkMinor(magic, 0);
  if (magic.major === 9) return decodeProgressive(bytes, magicEnd, magic);
  const bodies = sections(bytes, magicEnd, [HEADER, PAYLOAD], COLOUR);
  const grid = decodeWhole(headerLines(bodies[HEADER], magic.major), [bodies[PAYLOAD]], magic);
  return bodies[COLOUR] ? { ...grid, colourSection: bodies[COLOUR] } : grid;
}

/** A 10.x file's grid (its colour section undecoded as `colourSection`, as `decodeCompact` gives it) and
 * its header's fields (keyword -> words), its CRC-32 checked before its minor version, as mzc does. */
function decodeTight(bytes, magicEnd, magic) {
  const newest = TIGHT_PLACES.length - 1;
  const parts = tightParts(bytes, magicEnd, Math.min(magic.minor, newest));
  checkMinor(magic, newest);
  const grid = decodeWhole(parts.fields, [parts.payload], magic);
  return { grid: parts.colour ? { ...grid, colourSection: parts.colour } : grid, fields: parts.fields };
}

/** Refuses a binary file of a minor version newer than `newest`. */
function checkMinor(magic, newest) {
  if (magic.minor > newest) fail(null, `mzc-dwt2d version ${magic.major}.${magic.minor} is newer than this decoder reads (${magic.major}.${newest}); upgrade`);
}

/** Decodes a 9.0 file or a prefix of one (Version 9.0): its base section and each whole level section,
 * coarsest first, the finer bands zero; a file cut short comes back with `cut`, the line saying so. */
function decodeProgressive(bytes, magicEnd, magic) {
  const { header, bodies, colour, cut } = progressiveSections(bytes, magicEnd);
  const fields = headerLines(header, magic.major);
  const grid = decodeWhole(fields, bodies, magic);
  const coloured = fields.has("colour_psnr") || fields.has("colour_max_error");
  const complete = bodies.length - 1;
  if (complete < grid.levels || (coloured && !colour)) {
    grid.cut = complete < grid.levels
      ? `the file is cut short: decoded ${complete} of its ${grid.levels} detail levels, a coarser surface (without its finest levels${coloured ? " and colours" : ""})`
      : "the file is cut short in its colour section: the surface is whole, its colours are left out";
  }
  delete grid.levels;
  return colour ? { ...grid, colourSection: colour } : grid;
}

/** Decodes a grid coded whole from its header lines (keyword -> words) and its payload bodies: one
 * (before 9.0, every level's integers in it), or 9.0's base and level sections, each with its own tables
 * and rANS words (a level section may keep the base section's tables). */
function decodeWhole(fields, bodies, magic) {
  const h = fieldReader(fields);
  const georef = magic.major >= 6 || (magic.major === 3 && magic.minor >= 2);
  const grid = gridFields(h, { projected: magic.major >= 3, georef, counted: magic.major >= 8 });
  const p = codecFields(h, magic, grid);
  if (bodies.length > 1 + p.levels) fail("data", `${bodies.length - 1} level sections for ${p.levels} wavelet levels`);
  const payloads = [];
  const groups = sameSizeGroups(3 * p.levels, p.bandModels);
  for (const body of bodies) payloads.push(new Payload(body, magic.major >= 7, magic.major === 9 && payloads.length ? payloads[0].tables : null, magic.major >= 10, groups));
  const z = decodeGrid(payloads, grid, p);
  const charts = p.chartCount ? chartRecords(payloads[0], p.chartCount, grid, z) : undefined;
  for (const payload of payloads) payload.finish();
  if (p.rounding) roundToSamples(z, grid);
  return magic.major === 9 ? { ...grid, z, charts, levels: p.levels } : { ...grid, z, charts };
}

const SAMPLE_RANGES = { uint8: [0, 255], int8: [-128, 127], uint16: [0, 65535], int16: [-32768, 32767],
  uint32: [0, 4294967295], int32: [-2147483648, 2147483647] };

/** 6.0's `rounding integer` (Rounding): each valid value to the nearest integer, ties to even,
 * then held to the range of the `raster` line's integer sample type. */
function roundToSamples(z, grid) {
  const range = grid.raster && SAMPLE_RANGES[grid.raster[2]];
  if (!range) fail("rounding", "rounding integer needs a raster line of an integer sample type");
  for (let i = 0; i < z.length; i++) {
    if (Number.isNaN(z[i])) continue;
    const r = Math.abs(z[i] % 1) === 0.5 ? 2 * Math.round(z[i] / 2) : Math.round(z[i]);
    z[i] = Math.min(Math.max(r, range[0]), range[1]);
  }
}

// ---------------------------------------------------------------------------------------
// Tiled files (5.0): a header, an index of the tiles' lengths, and tiles that are 3.x files
// (5.1 with `rounding integer`: 6.0 files rounded to the header's raster type; 11.0: 10.x files,
// each with its block's colours)

/** Decodes a 5.x or 11.0 file: checks its header's checksum and lines, the index and its CRC-32,
 * then decodes every tile as a 3.x file (6.0 in a rounded 5.1 file, 10.x with its nodes' colours in
 * an 11.0 file) and puts its values, and its colours, in their place. */
function decodeTiled(bytes, lines, body, magic, withColours) {
  const fields = headerFields(lines, false);
  const h = fieldReader(fields);
  checkChecksum(bytes, lines, fields, true, body);
  const grid = gridFields(h, { projected: true, georef: true });
  const rounded = magic.major === 5 && magic.minor >= 1 && h.word("rounding", ["integer"], false) === "integer";
  if (rounded && !(grid.raster && SAMPLE_RANGES[grid.raster[2]])) {
    fail("rounding", "rounding integer needs a raster line of an integer sample type");
  }
  const T = h.integer("tile", 4, 4096);
  const [NR, NC] = h.words("tiles", 2).map((w) => (/^\d+$/.test(w) ? Number(w) : fail("tiles", `not an integer: ${w}`)));
  if (NR !== Math.ceil(grid.rows / T) || NC !== Math.ceil(grid.cols / T) || NR * NC > 4194304) {
    fail("tiles", `${NR} ${NC} is not ceil(rows / ${T}) and ceil(cols / ${T}), at most 4,194,304 tiles`);
  }
  const lengths = tileIndex(bytes, body, NR * NC);
  const major = rounded ? 6 : magic.major === 11 ? 10 : 3;
  const z = new Float64Array(grid.rows * grid.cols);
  const colors = major === 10 ? new Uint8Array(grid.rows * grid.cols * 3) : undefined;
  let at = body + 8 * NR * NC + 4;
  for (let i = 0; i < NR; i++) {
    for (let j = 0; j < NC; j++) {
      const tile = decodeTile(bytes.subarray(at, at + lengths[i * NC + j]), grid, T, i, j, major, withColours);
      place(z, tile.z, 1, tile, grid.cols, i * T, j * T);
      if (colors) place(colors, tile.colors, 3, tile, grid.cols, i * T, j * T);
      at += lengths[i * NC + j];
    }
  }
  return colors ? { ...grid, z, colors } : { ...grid, z };
}

/** Copies a tile's `values` (`width` of them a node, row by row) into the grid's array `into` (`cols`
 * nodes a row) at node (`top`, `left`). */
function place(into, values, width, tile, cols, top, left) {
  const w = tile.cols * width;
  for (let r = 0; r < tile.rows; r++) into.set(values.subarray(r * w, (r + 1) * w), ((top + r) * cols + left) * width);
}

/** The index's n lengths (u64 little-endian), its CRC-32 checked, each at least 1 and all
 * adding up to exactly the bytes after the index. */
function tileIndex(bytes, body, n) {
  const end = body + 8 * n + 4;
  if (end > bytes.length) fail("data", "the file ends inside the tile index");
  const view = new DataView(bytes.buffer, bytes.byteOffset + body, 8 * n + 4);
  if (crc32(bytes.subarray(body, end - 4)) !== view.getUint32(8 * n, true)) fail("data", "the tile index's checksum does not match");
  const lengths = Array.from({ length: n }, (_, k) => view.getUint32(8 * k + 4, true) * 4294967296 + view.getUint32(8 * k, true));
  if (lengths.some((l) => l < 1)) fail("data", "a tile of no bytes");
  if (lengths.reduce((a, b) => a + b, 0) !== bytes.length - end) fail("data", "the tiles' lengths do not add up to the bytes after the index");
  return lengths;
}

/** Tile (i, j): a whole mzc-dwt2d file of its block, of `major` (3: 3.x; 6: 6.0 of a rounded file,
 * with the header's raster line, its values integers; 10: 10.x of an 11.0 file, with its nodes'
 * colours), its lines those the header implies. */
function decodeTile(bytes, grid, T, i, j, major, withColours) {
  const name = `tile ${i + 1}, ${j + 1}`;
  const { tile, fields } = major === 10 ? colouredTile(bytes, name, withColours) : textTile(bytes, name, major);
  const rounded = major === 6;
  const origin = [grid.origin[0] + j * T * grid.d2, grid.origin[1] + i * T * grid.d1];
  const ok = tile.rows === Math.min((i + 1) * T, grid.rows) - i * T && tile.cols === Math.min((j + 1) * T, grid.cols) - j * T
    && tile.d1 === grid.d1 && tile.d2 === grid.d2 && tile.projection === grid.projection && tile.radius === grid.radius
    && tile.origin[0] === origin[0] && tile.origin[1] === origin[1]
    && !["transform", "units", "nodata", "crs", ...(rounded ? [] : ["raster"])].some((key) => fields.has(key))
    && (!rounded || (String(tile.raster) === String(grid.raster) && tile.z.every((v) => Number.isNaN(v) || Number.isInteger(v))));
  if (!ok) fail("data", `${name}: its lines do not say the block the header gives it`);
  return tile;
}

/** A tile of text header lines, which must be an mzc-dwt2d `major`.x file: its grid and its lines
 * (keyword -> words). */
function textTile(bytes, name, major) {
  const { lines, body } = splitHeader(bytes);
  const magic = parseMagic(lines[0]);
  if (magic.kind !== "dwt2d" || magic.major !== major) fail("data", `${name} is not an mzc-dwt2d ${major}.x file`);
  return { tile: decodeDwt2d(bytes, lines, body, magic), fields: headerFields(lines, false) };
}

/** A tile of an 11.0 file, which must be an mzc-dwt2d 10.x file with a colour section of its nodes'
 * colours (version 1: finer colours are not tiled): its grid with those colours, decoded as a whole
 * 10.x file's are (`withColours`), and its fields as header lines. */
function colouredTile(bytes, name, withColours) {
  const magic = compactMagic(bytes);
  if (magic?.major !== 10) fail("data", `${name} is not an mzc-dwt2d 10.x file`);
  const { grid, fields } = decodeTight(bytes, magic.end, magic);
  const tile = withColours(grid);
  if (!tile.colors || tile.fineColors) fail("colour", `${name} has no colour section of its nodes' colours`);
  return { tile, fields };
}

/** The codec's header lines (spec/dwt2d.md, Header lines) and the steps of every band. */
function codecFields(h, magic, grid) {
  const v3 = magic.major >= 3;
  const wavelet = h.word("wavelet", v3 ? WAVELETS_3 : WAVELETS_2, false) ?? "bior4.4";
  const small = Math.min(grid.rows, grid.cols);
  const byDefault = Math.min(12, Math.max(0, Math.floor(Math.log2(small / (v3 ? 8 : 16)))));
  const levels = h.integer("levels", 0, 12, false) ?? byDefault;
  const written = h.floats("steps");
  if (written.some((s) => !(s > 0))) fail("steps", "every step must be > 0");
  const slopeLimit = h.float("slope_limit", false, 1) ?? 2;
  const correction = h.float("correction", false, 0) ?? 0;
  if (!v3) h.word("coder", ["rans-signs-2"]);
  const chartCount = magic.major >= 4 ? h.integer("chart_count", 1, 65536, false) : undefined;
  const rounding = magic.major >= 6 && h.word("rounding", ["integer"], false) === "integer";
  const flips = magic.major >= 8;   // 8.0's mask: predicted flips (mask.mjs)
  const bandModels = magic.major >= 10 && h.integer("band_models", 1, 1, false) === 1;   // 10.1
  return { v3, wavelet, levels, steps: bandSteps(written, levels), slopeLimit, correction, chartCount, rounding, flips, bandModels };
}

/** The step of each of the 1 + 3L bands from the `steps` line's 1, 2 or 1 + 3L values. */
function bandSteps(written, levels) {
  const n = 1 + 3 * levels;
  if (written.length === n) return written;
  if (written.length === 1) return new Array(n).fill(written[0]);
  if (written.length !== 2 || levels < 1) fail("steps", `expected 1, 2 or ${n} values, found ${written.length}`);
  const detail = [];   // level 1 .. L
  for (let l = 1, d = written[1]; l <= levels; l++, d *= 0.9) detail.push(d);
  const steps = [written[0]];
  for (let l = levels; l >= 1; l--) steps.push(detail[l - 1], detail[l - 1], detail[l - 1]);
  return steps;
}

// ---------------------------------------------------------------------------------------
// Payload: model tables, rANS words, raw bits (spec/dwt2d.md, Payload)

const WEIGHT_MANTISSA = [16, 19, 23, 27];
const TOTAL = 16384;
const range = (from, to) => Array.from({ length: to - from + 1 }, (_, i) => from + i);
const SAME_SIZE = [range(4, 14), range(15, 22), range(23, 26)];   // detail, sign and correction tables
const BAND_MODELS = 34;   // 10.1's band_models: detail band b >= 2's context 0, after the chart models (27..33)

/** The model of context 0 of detail band b: band 1's (4) for every band, but with `bandModels` (10.1). */
function detailModel(b, bandModels) {
  return bandModels && b >= 2 ? BAND_MODELS + 11 * (b - 2) : 4;
}

/** SAME_SIZE, and with `bandModels` the group of each of the `bands` detail bands' own models. */
function sameSizeGroups(bands, bandModels) {
  if (!bandModels) return SAME_SIZE;
  return [...SAME_SIZE, ...range(2, bands).map((b) => range(detailModel(b, true), detailModel(b, true) + 10))];
}

/** 10.0's one-byte tables: P(0) in 65536ths and ratio codes (Tables of 10.0). */
const SHORT_ZEROS = [1179, 2903, 6881, 15004, 28118, 42952, 54263, 60565, 63477, 64707, 65206, 65405, 65484, 65516, 65528];
const SHORT_RATIOS = [0, 4, 8, 12, 16, 20, 24, 30, 36, 44, 52, 62, 74, 88, 104, 124];

/** `tables`, refused when the tables of one of `groups` (mixed in one row) have different class counts. */
function sameSizes(tables, groups) {
  for (const group of groups) {
    const sizes = new Set(group.filter((m) => m < tables.length).map((m) => tables[m].freq.length));
    if (sizes.size > 1) fail("tables", "tables mixed in one row have different class counts");
  }
  return tables;
}

/** A reader of the payload: its tables, its rANS state and its raw-bit cursor. */
export class Payload {
  /** `parametric`: 7.0's table records (Tables of 7.0), else 3.x's; `prior`: a 9.0 level section's, the
   * base section's tables (Tables of 9.0); `short`: 10.0's records (Tables of 10.0); `groups`: the models
   * whose tables must have one class count. */
  constructor(bytes, parametric, prior = null, short = false, groups = SAME_SIZE) {
    this.bytes = bytes;
    this.at = 0;
    this.groups = groups;
    this.tables = short ? this.readShortTables() : this.readTables(parametric, prior);
    this.startRans();
    this.bitAt = this.at * 8;
  }

  /** An unsigned LEB128 varint of at most 5 bytes. */
  varint(field) {
    let value = 0;
    for (let i = 0; i < 5; i++) {
      if (this.at >= this.bytes.length) fail(field, "the payload is cut short");
      const b = this.bytes[this.at++];
      value += (b & 0x7f) * 2 ** (7 * i);
      if (!(b & 0x80)) return value;
    }
    return fail(field, "a varint longer than 5 bytes");
  }

  /** The M model tables, each a lookup from a 14-bit slot to its class; with `prior` (9.0's level
   * sections), M = 0 keeps every table of the base section and a record 1 that section's table of
   * its model. */
  readTables(parametric, prior) {
    const m = this.varint("tables");
    if (m === 0 && prior) return prior;
    if (m > 4096) fail("tables", `${m} tables (at most 4096)`);
    const tables = [];
    for (let t = 0; t < m; t++) {
      let s = this.varint("tables");
      if (s === 0) {
        if (!t) fail("tables", "the first table repeats none");
        tables.push(tables[t - 1]);
        continue;
      }
      if (s === 1 && prior) {
        if (t >= prior.length) fail("tables", `model table ${t} keeps the base section's, which has none`);
        tables.push(prior[t]);
        continue;
      }
      const kind = parametric ? s % 2 : 0;
      if (parametric) s = Math.floor(s / 2);
      if (s < 2 || s > 48) fail("tables", `a table of ${s} classes (2..48)`);
      tables.push(frequencyTable(kind ? this.parametricRecord(s) : this.codeWeights(s)));
    }
    return sameSizes(tables, this.groups);
  }

  /** 10.0's M model tables: one record a model, of the class count S (2 at first) of the table before,
   * unless RESIZED (243) gives it (Tables of 10.0). */
  readShortTables() {
    const m = this.varint("tables");
    if (m > 4096) fail("tables", `${m} tables (at most 4096)`);
    const tables = [];
    let s = 2;
    for (let t = 0; t < m; t++) {
      let r = this.byte();
      if (r === 243) {
        s = this.varint("tables");
        if (s < 2 || s > 48) fail("tables", `a table of ${s} classes (2..48)`);
        r = this.byte();
        if (r === 0 || r === 243) fail("tables", "a resized model table record must give its table");
      }
      if (r === 0) {
        if (!t) fail("tables", "the first table repeats none");
        tables.push(tables[t - 1]);
      } else if (r <= 240) {
        tables.push(frequencyTable(parametricWeights(s, SHORT_ZEROS[(r - 1) >> 4], SHORT_RATIOS[(r - 1) % 16], 65536)));
      } else if (r === 241) {
        tables.push(frequencyTable(this.parametricRecord(s)));
      } else if (r === 242) {
        tables.push(frequencyTable(this.codeWeights(s)));
      } else {
        fail("tables", `model table record ${r} is not 0..243`);
      }
      s = tables[t].freq.length;
    }
    return sameSizes(tables, this.groups);
  }

  /** The byte at the cursor (of a table record). */
  byte() {
    if (this.at >= this.bytes.length) fail("tables", "the payload is cut short");
    return this.bytes[this.at++];
  }

  /** The weights of S 6-bit weight codes, most significant bit first (Tables). */
  codeWeights(s) {
    const nbytes = Math.ceil((6 * s) / 8);
    if (this.at + nbytes > this.bytes.length) fail("tables", "the payload is cut short");
    const weights = [];
    for (let i = 0; i < s; i++) {
      const bit = i * 6;
      const word = (this.bytes[this.at + (bit >> 3)] << 8) | (this.bytes[this.at + (bit >> 3) + 1] ?? 0);
      const e = (word >> (10 - (bit & 7))) & 63;
      weights.push(e === 0 ? 0n : BigInt(WEIGHT_MANTISSA[e % 4]) << BigInt(e >> 2));
    }
    this.at += nbytes;
    return weights;
  }

  /** A parametric table's weights (S classes) from its bytes z and t. */
  parametricRecord(s) {
    if (this.at + 2 > this.bytes.length) fail("tables", "the payload is cut short");
    this.at += 2;
    return parametricWeights(s, this.bytes[this.at - 2], this.bytes[this.at - 1]);
  }

  /** Reads the W words and sets the 64-bit state (hi, lo) from the last ones popped. */
  startRans() {
    const w = this.varint("words");
    if (this.at + 4 * w > this.bytes.length) fail("words", `${w} rANS words do not fit in the payload`);
    const view = new DataView(this.bytes.buffer, this.bytes.byteOffset + this.at, 4 * w);
    this.words = Array.from({ length: w }, (_, i) => view.getUint32(4 * i, true));
    this.at += 4 * w;
    this.hi = 0;
    this.lo = 0;
    if (w) {
      this.lo = this.words.pop();
      if (this.lo === 0) fail("words", "the last rANS word is 0");
      if (this.words.length) {
        this.hi = this.lo;
        this.lo = this.words.pop();
      }
    }
  }

  /** Decodes one class with model `model`'s table (constriction's AnsCoder, 24-bit
   * precision, 32-bit words), in exact double arithmetic on the state's two halves. */
  symbol(model) {
    const table = this.tables[model];
    if (!table) fail("tables", `model ${model} has no table`);
    const m = this.lo & 0xffffff;
    const s = table.slot[m >>> 10];
    const f = table.freq[s];
    // x' = f 2^10 (x >> 24) + m - B = (f hi) 2^18 + f (lo >> 24) 2^10 + m - B, each part exact
    const a = f * this.hi;
    const top = Math.floor(a / 16384);
    this.settle(top, (a - top * 16384) * 262144 + f * (this.lo >>> 24) * 1024 + m - table.cum[s] * 1024);
    return s;
  }

  /** The state after a decode step, x' = top 2^32 + low (low < 2^53), as its two 32-bit halves,
   * then x' = (x' << 32) | the next word when x' < 2^32 and words remain (the symbols' and the 8.0
   * mask's decisions alike). */
  settle(top, low) {
    const carry = Math.floor(low / 4294967296);
    this.hi = top + carry;
    this.lo = low - carry * 4294967296;
    if (this.hi === 0 && this.words.length) {
      this.hi = this.lo;
      this.lo = this.words.pop();
    }
  }

  /** n raw bits, most significant first. */
  bits(n) {
    if (this.bitAt + n > this.bytes.length * 8) fail("data", "more raw bits than the payload holds");
    let v = 0;
    for (let i = 0; i < n; i++, this.bitAt++) v = v * 2 + ((this.bytes[this.bitAt >> 3] >> (7 - (this.bitAt & 7))) & 1);
    return v;
  }

  /** A signed integer: its class, then the sign bit and the bits below the leading 1. */
  signed(model) {
    const k = this.symbol(model);
    if (k === 0) return 0;
    const negative = this.bits(1);
    const v = 2 ** (k - 1) + this.bits(k - 1);
    return negative ? -v : v;
  }

  /** An unsigned integer: its class, then the k-1 bits below the leading 1. */
  unsigned(model) {
    const k = this.symbol(model);
    return k === 0 ? 0 : 2 ** (k - 1) + this.bits(k - 1);
  }

  /** Refuses a payload with data left once everything it declares is decoded: bytes after
   * the last one the raw bits need, or rANS words not consumed (the state is then not 0;
   * spec/dwt2d.md does not say so, mzc refuses them). */
  finish() {
    if (Math.ceil(this.bitAt / 8) < this.bytes.length) fail("data", "bytes after the end of the payload");
    if (this.hi || this.lo || this.words.length) fail("data", "rANS words left over after the last symbol");
  }
}

/** A table's frequencies (summing to 16384) from its integer weights (BigInts: a parametric
 * table's sum to 2^48, their products 2^62), with the lookup of a 14-bit slot to its class and
 * the cumulative frequencies. */
export function frequencyTable(weights) {
  const s = weights.length;
  const total = weights.reduce((a, b) => a + b, 0n);
  const spare = BigInt(TOTAL - s);
  const freq = weights.map((w) => (total === 0n ? 1 : 1 + Number((w * spare) / total)));
  let largest = 0;
  weights.forEach((w, i) => {
    if (w > weights[largest]) largest = i;
  });
  freq[largest] += TOTAL - freq.reduce((a, b) => a + b, 0);
  const cum = [];
  const slot = new Uint8Array(TOTAL);
  for (let i = 0, c = 0; i < s; c += freq[i], i++) {
    cum.push(c);
    slot.fill(i, c, c + freq[i]);
  }
  return { freq, cum, slot };
}

const ONE = 1n << 32n;
/** R[i] = floor(2^(32 - i/16)) (Tables of 7.0). */
const ROOTS = [4294967296n, 4112874773n, 3938502375n, 3771522796n, 3611622602n, 3458501653n, 3311872529n,
  3171459999n, 3037000499n, 2908241642n, 2784941737n, 2666869344n, 2553802833n, 2445529971n, 2341847523n, 2242560871n];

/** The BigInt weights of a parametric table of S classes with bytes z and t (Tables of 7.0):
 * class 0 z/`zeros` of the mass (256ths; 10.0's one-byte tables 65536ths), class k >= 1 the |v| in
 * 2^(k-1) .. 2^k - 1 of a |v| - 1 geometric of ratio theta / 2^32, the last class the whole tail. */
export function parametricWeights(s, z, t, zeros = 256) {
  const theta = ONE - (ROOTS[t % 16] >> BigInt(t >> 4));
  const tails = [];
  for (let k = 1; k < s; k++) tails.push(power(theta, 2 ** (k - 1) - 1));
  tails.push(0n);
  return [BigInt(z) << 32n, ...tails.slice(0, -1).map((tail, k) => BigInt(zeros - z) * (tail - tails[k + 1]))];
}

/** theta^n in 32-bit fixed point by squaring, every product floored (exact integers). */
function power(theta, n) {
  let result = ONE;
  let base = theta;
  for (; n; n = Math.floor(n / 2)) {
    if (n % 2) result = (result * base) >> 32n;
    base = (base * base) >> 32n;
  }
  return result;
}

// ---------------------------------------------------------------------------------------
// The grid: mask, bands, slope factors, transform, correction (spec/dwt2d.md)

/** The decoded values (NaN at invalid nodes), row-major rows x cols, from the payload of each level of
 * bands (`payloads`: one for them all, or 9.0's sections, the bands of the levels beyond them zero). */
function decodeGrid(payloads, grid, p) {
  const { rows, cols } = grid;
  const payload = payloads[0];
  const level = (b) => (payloads.length === 1 ? 0 : Math.floor((b + 2) / 3));
  const mask = (p.flips ? decodeFlips : decodeMask)(payload, rows, cols);
  const periodic = isPeriodic(grid);
  const shapes = bandShapes(rows, cols, p);
  const relevant = p.v3 ? relevance3(mask, rows, cols, p, periodic) : relevantPeriodized2d(mask, rows, cols, p.wavelet, p.levels);
  const q = [decodeBand0(payload, shapes[0])];
  for (let b = 1; b < shapes.length; b++) {
    const zero = () => new Float64Array(shapes[b].rows * shapes[b].cols);
    q.push(level(b) < payloads.length ? decodeDetail(payloads[level(b)], q, b, shapes, relevant, p) : zero());
  }
  const bands = dequantise(q, shapes, grid, p, periodic);
  const w = p.v3 ? inverse3(bands, shapes, rows, cols, p, periodic) : inversePeriodized2d(bands, shapes, rows, cols, p.wavelet, p.levels);
  const whole = payloads.length === 1 || payloads.length === 1 + p.levels;   // the corrections: the last section's
  const k = p.correction > 0 && whole ? decodeCorrection(payloads.at(-1), mask, rows, cols) : null;
  const z = new Float64Array(rows * cols);
  for (let i = 0; i < z.length; i++) {
    if (!mask[i]) z[i] = NaN;
    else {
      z[i] = k ? w[i] + p.correction * k[i] : w[i];
      if (!Number.isFinite(z[i])) fail("data", "a decoded height is not finite");
    }
  }
  return z;
}

/** A central grid whose columns make exactly one turn (within one part in 10^9). */
function isPeriodic(grid) {
  if (grid.projection === "planar") return false;
  const turn = 2 * Math.PI * grid.radius;
  return Math.abs(grid.cols * grid.d2 - turn) <= 1e-9 * turn;
}

/** The mask of valid nodes from its span counts and flips (Order of the integers, 1-3). */
function decodeMask(payload, rows, cols) {
  const spans = [];
  for (let r = 0, above = 0; r < rows; r++) {
    const n = above + payload.signed(0);
    if (n < 0 || n > Math.ceil(cols / 2)) fail("data", `row ${r}: ${n} spans (0..${Math.ceil(cols / 2)})`);
    spans.push(n);
    above = n;
  }
  const same = (r) => spans[r] === (r ? spans[r - 1] : 0);
  const deltas = spans.map((n, r) => (same(r) ? Array.from({ length: 2 * n }, () => payload.signed(1)) : null));
  const flips = spans.map((n, r) => {
    if (same(r)) return null;
    const f = [];
    for (let i = 0, prev = -1; i < 2 * n; i++) prev = f[i] = prev + 1 + payload.signed(2);
    return f;
  });
  for (let r = 0; r < rows; r++) if (deltas[r]) flips[r] = deltas[r].map((d, i) => (r ? flips[r - 1][i] : 0) + d);
  const mask = new Uint8Array(rows * cols);
  flips.forEach((f, r) => {
    for (let i = 0; i < f.length; i++) {
      if (f[i] < 0 || f[i] > cols || (i && f[i] <= f[i - 1])) fail("data", `row ${r}: flips out of range`);
    }
    for (let i = 0; i < f.length; i += 2) mask.fill(1, r * cols + f[i], r * cols + f[i + 1]);
  });
  return mask;
}

/** The bands' shapes in band order, each {rows, cols, level, orient (0 band 0, 1 H, 2 V, 3 D)}:
 * in 3.0 ceil/floor halves of each level, in 2.0 (periodization) ceil halves. */
export function bandShapes(rows, cols, p) {
  const levels = [];
  let r = rows;
  let c = cols;
  for (let l = 1; l <= p.levels; l++) {
    const lowR = Math.ceil(r / 2);
    const lowC = Math.ceil(c / 2);
    const highR = p.v3 ? Math.floor(r / 2) : lowR;
    const highC = p.v3 ? Math.floor(c / 2) : lowC;
    levels.push({ r, c, lowR, lowC, highR, highC });
    r = lowR;
    c = lowC;
  }
  const shapes = [{ rows: r, cols: c, level: p.levels, orient: 0 }];
  for (let l = p.levels; l >= 1; l--) {
    const s = levels[l - 1];
    shapes.push({ rows: s.highR, cols: s.lowC, level: l, orient: 1, input: s },
      { rows: s.lowR, cols: s.highC, level: l, orient: 2, input: s },
      { rows: s.highR, cols: s.highC, level: l, orient: 3, input: s });
  }
  return shapes;
}

/** Band 0's integers from their planar residuals: cumulative sums down the columns, then
 * along the rows (Order of the integers, 4). */
export function decodeBand0(payload, shape) {
  const { rows, cols } = shape;
  const q = new Float64Array(rows * cols);
  for (let i = 0; i < q.length; i++) q[i] = payload.signed(3);
  for (let r = 1; r < rows; r++) for (let c = 0; c < cols; c++) q[r * cols + c] += q[(r - 1) * cols + c];
  for (let r = 0; r < rows; r++) for (let c = 1; c < cols; c++) q[r * cols + c] += q[r * cols + c - 1];
  return q;
}

const THRESHOLDS = [0.5, 1, 1.5, 3, 5, 8, 14, 24, 40, 70];
const SIGN_WEIGHTS = { 1: [-2, 1, 2], 2: [2, 1, -2], 3: [-1, 0, 0] };

/** |q| at (r, c) of a band, 0 outside it. */
const at = (q, shape, r, c) => (r >= 0 && c >= 0 && r < shape.rows && c < shape.cols ? Math.abs(q[r * shape.cols + c]) : 0);

/** The context (0..10) of a magnitude whose neighbourhood sums to a: the thresholds it reaches. */
function magnitudeContext(a) {
  let n = 0;
  while (n < 10 && THRESHOLDS[n] <= a) n++;
  return n;
}

/** The integers of detail band b, row by row in even and odd passes: magnitudes grouped by
 * context (in context order, each context's columns left to right), then the signs of the
 * nonzero ones (Order of the integers, 5). */
export function decodeDetail(payload, q, b, shapes, relevant, p) {
  const shape = shapes[b];
  const { rows, cols } = shape;
  const out = new Float64Array(rows * cols);
  const parentIndex = shape.level < p.levels ? b - 3 : -1;
  const parent = parentIndex > 0 && shapes[parentIndex].rows * shapes[parentIndex].cols ? parentIndex : -1;
  const ratio = parent > 0 ? p.steps[parent] / p.steps[b] : 0;
  const ps = parent > 0 ? shapes[parent] : null;
  const parentCol = Int32Array.from({ length: cols }, (_, c) => (ps ? Math.min(c >> 1, ps.cols - 1) : 0));
  const parentBand = parent > 0 ? q[parent] : null;
  const earlier = Array.from({ length: shape.orient - 1 }, (_, i) => b - shape.orient + 1 + i);
  const earlierBands = earlier.map((e) => q[e]);
  const earlierRows = earlier.map((e) => shapes[e].rows);
  const earlierCols = earlier.map((e) => shapes[e].cols);
  const [wa, wp, wt] = SIGN_WEIGHTS[shape.orient];
  const mask = relevant[b];
  const context = new Int8Array(cols);   // each column's context in the pass
  const order = new Int32Array(cols);    // the pass's coded columns by context, then column
  const starts = new Int32Array(12);
  const first = detailModel(b, p.bandModels);
  for (let r = 0; r < rows; r++) {
    const row = r * cols;
    const parentRow = ps ? Math.min(r >> 1, ps.rows - 1) * ps.cols : 0;   // (r >> 1, c >> 1), held to the parent band
    for (let odd = 0; odd < 2; odd++) {
      starts.fill(0);
      for (let c = odd; c < cols; c += 2) {
        if (!mask[row + c]) continue;
        let a = parent > 0 ? Math.abs(parentBand[parentRow + parentCol[c]]) * ratio : 0;
        for (let e = 0; e < earlier.length; e++) {
          if (r < earlierRows[e] && c < earlierCols[e]) a += Math.abs(earlierBands[e][r * earlierCols[e] + c]);
        }
        const up = r > 0 ? Math.abs(out[row - cols + c]) : 0;
        const upLeft = r > 0 && c > 0 ? Math.abs(out[row - cols + c - 1]) : 0;
        const upRight = r > 0 && c + 1 < cols ? Math.abs(out[row - cols + c + 1]) : 0;
        const upUp = r > 1 ? Math.abs(out[row - 2 * cols + c]) : 0;
        a += up + (upLeft + upRight + upUp) / 2;
        if (odd) a += (c > 0 ? Math.abs(out[row + c - 1]) : 0) + (c + 1 < cols ? Math.abs(out[row + c + 1]) : 0);
        const n = magnitudeContext(a);
        context[c] = n;
        starts[n + 1]++;
      }
      for (let n = 1; n < 12; n++) starts[n] += starts[n - 1];
      const coded = starts[11];
      for (let c = odd; c < cols; c += 2) if (mask[row + c]) order[starts[context[c]]++] = c;
      for (let i = 0; i < coded; i++) {
        const c = order[i];
        out[row + c] = payload.unsigned(first + context[c]);
      }
      for (let c = odd; c < cols; c += 2) {
        const i = row + c;
        if (!out[i]) continue;
        const above = r ? Math.sign(out[i - cols]) : 0;
        const par = parent > 0 ? Math.sign(parentBand[parentRow + parentCol[c]]) : 0;
        const t = odd ? (c > 0 ? Math.sign(out[i - 1]) : 0) + (c + 1 < cols ? Math.sign(out[i + 1]) : 0) : 0;
        const score = wa * above + wp * par + wt * t;
        const flip = payload.symbol(15 + (odd ? 4 : 0) + Math.min(Math.abs(score), 3));
        if (flip > 1) fail("data", "a sign symbol other than 0 or 1");
        const predicted = score < 0 ? -1 : 1;
        out[i] *= flip ? -predicted : predicted;
      }
    }
  }
  return out;
}

/** The correction integers k at the valid nodes, row by row in two passes, by context
 * (Order of the integers, 6). */
export function decodeCorrection(payload, mask, rows, cols) {
  const k = new Float64Array(rows * cols);
  const shape = { rows, cols };
  for (let r = 0; r < rows; r++) {
    for (const odd of [0, 1]) {
      const byContext = [[], [], [], []];
      for (let c = odd; c < cols; c += 2) {
        if (!mask[r * cols + c]) continue;
        let a = at(k, shape, r - 1, c) + (at(k, shape, r - 1, c - 1) + at(k, shape, r - 1, c + 1) + at(k, shape, r - 2, c)) / 2;
        if (odd) a += at(k, shape, r, c - 1) + at(k, shape, r, c + 1);
        byContext[(a >= 0.25) + (a >= 1) + (a >= 2)].push(c);
      }
      byContext.forEach((list, context) => {
        for (const c of list) k[r * cols + c] = payload.signed(23 + context);
      });
    }
  }
  return k;
}

/** The K chart records (Order of the integers, 7), checked against the array and mask. */
function chartRecords(payload, count, grid, z) {
  const fields = [];
  for (let f = 0; f < 7; f++) fields.push(Array.from({ length: count }, () => payload.signed(27 + f)));
  for (const f of [1, 2]) for (let i = 1; i < count; i++) fields[f][i] += fields[f][i - 1];
  const charts = fields[0].map((view, i) => {
    if (!(view >= 0 && view < 6)) fail("charts", `view number ${view} (0..5)`);
    return { view: VIEWS[view], row0: fields[1][i], col0: fields[2][i], rows: fields[3][i], cols: fields[4][i], i0: fields[5][i], j0: fields[6][i] };
  });
  checkCharts(charts, grid, z);
  return charts;
}

// ---------------------------------------------------------------------------------------
// Relevance, slope factors and the lifting transform of 3.0

const LIFTING = {
  "bior4.4": { steps: [-1.586134342059924, -0.052980118572961, 0.882911075530934, 0.443506852043971], k: 1.230174104914001, reach: [3, 4] },
  "bior2.2": { steps: [-0.5, 0.25], k: 1, reach: [1, 2] },
};

/** Marks along every row of an r x c array of 0/1: the low coefficients within reach[0]
 * of a valid sample, the high ones within reach[1] (samples outside the row ignored, or
 * wrapping round when `wrap`): the row-low (r x ceil(c/2)) and row-high (r x floor(c/2)) marks.
 * Each run of valid samples marks the coefficients within reach of it. */
function markRows(a, r, c, reach, wrap) {
  const lc = (c + 1) >> 1;
  const hc = c >> 1;
  const low = new Uint8Array(r * lc);
  const high = new Uint8Array(r * hc);
  for (let i = 0; i < r; i++) {
    for (let j = 0; j < c; j++) {
      if (!a[i * c + j]) continue;
      const start = j;
      while (j + 1 < c && a[i * c + j + 1]) j++;
      markWithin(low.subarray(i * lc, (i + 1) * lc), 0, start - reach[0], j + reach[0], c, wrap);
      markWithin(high.subarray(i * hc, (i + 1) * hc), 1, start - reach[1], j + reach[1], c, wrap);
    }
  }
  return [low, high];
}

/** Marks the coefficients k of a row of c samples (k at sample 2k + parity) whose sample is
 * from..to, taken round the row when `wrap` (else the part within the row; from > -c and
 * to < 2c - 1: a reach is less than a wrapping row's width). */
function markWithin(marks, parity, from, to, c, wrap) {
  if (wrap && from < 0) {
    markWithin(marks, parity, from + c, c - 1, c, false);
    markWithin(marks, parity, 0, to, c, false);
  } else if (wrap && to >= c) {
    markWithin(marks, parity, 0, to - c, c, false);
    markWithin(marks, parity, from, c - 1, c, false);
  } else {
    const first = Math.max(0, Math.ceil((from - parity) / 2));
    marks.fill(1, first, Math.max(first, Math.floor((to - parity) / 2) + 1));
  }
}

/** The c x r transpose of an r x c array. */
function transpose(a, r, c) {
  const out = new a.constructor(r * c);
  for (let i = 0; i < r; i++) for (let j = 0; j < c; j++) out[j * r + i] = a[i * c + j];
  return out;
}

/** The relevant coefficients of every band (3.0): each level's marks along the rows, then
 * down the columns of both halves; band 0's marks are the next level's mask. */
export function relevance3(mask, rows, cols, p, periodic) {
  const reach = LIFTING[p.wavelet].reach;
  const detail = [];
  let current = mask;
  let r = rows;
  let c = cols;
  for (let l = 1; l <= p.levels; l++) {
    const [rowLow, rowHigh] = markRows(current, r, c, reach, periodic && c % 2 === 0 && c > 2);
    const down = (x, w) => markRows(transpose(x, r, w), w, r, reach, false).map((m, i) => transpose(m, w, i ? r >> 1 : (r + 1) >> 1));
    const [ll, h] = down(rowLow, (c + 1) >> 1);
    const [v, d] = down(rowHigh, c >> 1);
    detail.unshift([h, v, d]);
    current = ll;
    r = (r + 1) >> 1;
    c = (c + 1) >> 1;
  }
  return [current, ...detail.flat()];
}

/** The dequantised bands: q times its band's step, detail steps scaled by the slope factors
 * when F > 1 and L >= 1. */
function dequantise(q, shapes, grid, p, periodic) {
  const factors = p.slopeLimit > 1 && p.levels >= 1 ? slopeFactors(q[0], shapes[0], grid, p, periodic) : null;
  return q.map((band, b) => {
    const shape = shapes[b];
    const step = p.steps[b];
    const out = new Float64Array(band.length);
    if (!factors || b === 0) {
      for (let i = 0; i < band.length; i++) out[i] = band[i] * step;
      return out;
    }
    const g = resample(factors, shapes[0].rows, shapes[0].cols, shape.rows, shape.cols);
    for (let i = 0; i < band.length; i++) out[i] = band[i] * (step * g[i]);
    return out;
  });
}

/** The slope factor of every approximation node (Slope factors, 1-4). */
function slopeFactors(q0, shape, grid, p, periodic) {
  const { rows: R, cols: C } = shape;
  const scale = 2 ** p.levels;
  const A = q0.map((v) => (v * p.steps[0]) / scale);
  const gy = gradient(A, 0, R, C, scale * grid.d1, false);
  const gx = gradient(A, 1, R, C, scale * grid.d2, periodic && C > 2);
  const F = p.slopeLimit;
  const g = new Float64Array(R * C);
  for (let i = 0; i < R; i++) {
    for (let j = 0; j < C; j++) {
      const n = i * C + j;
      const [hu, hv] = metric(A[n], i, grid, scale);
      const y = gy[n] / hv;
      const x = gx[n] / hu;
      const value = Math.sqrt(Math.sqrt(1 + y * y + x * x) / (hu * hv));
      g[n] = Number.isFinite(value) ? Math.min(F, value) : F;
    }
  }
  return g;
}

/** numpy.gradient of the R x C array A down its columns (axis 0) or along its rows (axis 1)
 * with spacing h; 0 along an axis of one node, central everywhere when `wrap`. */
function gradient(A, axis, R, C, h, wrap) {
  const out = new Float64Array(R * C);
  const n = axis === 0 ? R : C;
  const stride = axis === 0 ? C : 1;
  const lines = axis === 0 ? C : R;
  const lineStride = axis === 0 ? 1 : C;
  if (n < 2) return out;
  for (let o = 0; o < lines; o++) {
    const base = o * lineStride;
    const v = (i) => A[base + i * stride];
    for (let i = 0; i < n; i++) {
      let d;
      if (wrap) d = (v((i + 1) % n) - v((i - 1 + n) % n)) / (2 * h);
      else if (i === 0) d = (v(1) - v(0)) / h;
      else if (i === n - 1) d = (v(n - 1) - v(n - 2)) / h;
      else d = (v(i + 1) - v(i - 1)) / (2 * h);
      out[base + i * stride] = d;
    }
  }
  return out;
}

/** The projection's metric (h_u, h_v) at approximation node row i with value w. */
function metric(w, i, grid, scale) {
  if (grid.projection === "planar") return [1, 1];
  const ratio = w / grid.radius;
  if (grid.projection === "cylindrical") return [ratio, 1];
  const p = Math.min(Math.max((i + 0.5) * scale - 0.5, 0), grid.rows - 1);
  const v = grid.origin[1] + p * grid.d1;
  return [ratio * cos(v / grid.radius), ratio];
}

/** g (n1 x n2) resampled linearly to m1 x m2: first along the columns, then the rows. */
function resample(g, n1, n2, m1, m2) {
  const down = linear(n1, m1);
  const tmp = new Float64Array(m1 * n2);
  for (let i = 0; i < m1; i++) {
    const from = down.at[i] * n2;
    const w = down.weight[i];
    for (let j = 0; j < n2; j++) tmp[i * n2 + j] = n1 === 1 ? g[j] : (1 - w) * g[from + j] + w * g[from + n2 + j];
  }
  const along = linear(n2, m2);
  const out = new Float64Array(m1 * m2);
  for (let i = 0; i < m1; i++) {
    for (let j = 0; j < m2; j++) {
      const from = i * n2 + along.at[j];
      const w = along.weight[j];
      out[i * m2 + j] = n2 === 1 ? tmp[i * n2] : (1 - w) * tmp[from] + w * tmp[from + 1];
    }
  }
  return out;
}

/** One axis of the resampling, n input nodes to m output cells: each cell's node j (`at`) and
 * the weight w of node j + 1 (`weight`), the cell (1 - w) x_j + w x_(j+1); with n = 1, x_0. */
function linear(n, m) {
  const at = new Int32Array(m);
  const weight = new Float64Array(m);
  if (n === 1) return { at, weight };
  for (let i = 0; i < m; i++) {
    const u = Math.min(Math.max(((i + 0.5) * n) / m - 0.5, 0), n - 1);
    at[i] = Math.min(Math.floor(u), n - 2);
    weight[i] = u - at[i];
  }
  return { at, weight };
}

/** The inverse 3.0 transform of the dequantised bands: coarsest level first, each level
 * columns before rows. `merge(s, d, n, w, wrap)` is one inverse level, in place, of w signals
 * of n samples side by side: their ceil(n/2) low rows s and floor(n/2) high rows d, each w
 * wide (interleaved afterwards); by default the lifting of p.wavelet (the colour section's
 * integer 5/3 gives its own). */
export function inverse3(bands, shapes, rows, cols, p, periodic, merge = liftingMerge(LIFTING[p.wavelet])) {
  let low = bands[0];
  for (let l = p.levels; l >= 1; l--) {
    const b = 1 + 3 * (p.levels - l);
    const { r, c } = shapes[b].input;
    const lc = Math.ceil(c / 2);
    const hc = c - lc;
    const rowLow = mergeColumns(low, bands[b], r, lc, merge);
    const rowHigh = mergeColumns(bands[b + 1], bands[b + 2], r, hc, merge);
    low = mergeRows(rowLow, rowHigh, r, c, merge, periodic && c % 2 === 0 && c > 2);
  }
  return low;
}

/** Columns of a low (ceil(r/2) x w) and a high (floor(r/2) x w) half merged into r x w: the
 * halves' rows are the merge's s and d rows as they lie. */
function mergeColumns(lo, hi, r, w, merge) {
  const s = Float64Array.from(lo);
  const d = Float64Array.from(hi);
  merge(s, d, r, w, false);
  return interleave(s, d, r, w);
}

/** The rows of r x ceil(c/2) low and r x floor(c/2) high halves merged into r x c, one row at a
 * time: each row's halves merged where they lie (lo and hi are scratch, changed), then interleaved. */
function mergeRows(lo, hi, r, c, merge, wrap) {
  const lc = (c + 1) >> 1;
  const hc = c >> 1;
  const out = new Float64Array(r * c);
  for (let i = 0; i < r; i++) {
    merge(lo.subarray(i * lc, (i + 1) * lc), hi.subarray(i * hc, (i + 1) * hc), c, 1, wrap);
    for (let k = 0; k < lc; k++) out[i * c + 2 * k] = lo[i * lc + k];
    for (let k = 0; k < hc; k++) out[i * c + 2 * k + 1] = hi[i * hc + k];
  }
  return out;
}

/** The n x w signal whose even rows are s's rows and odd rows d's. */
function interleave(s, d, n, w) {
  const out = new Float64Array(n * w);
  for (let k = 0; 2 * k < n; k++) out.set(s.subarray(k * w, (k + 1) * w), 2 * k * w);
  for (let k = 0; 2 * k + 1 < n; k++) out.set(d.subarray(k * w, (k + 1) * w), (2 * k + 1) * w);
  return out;
}

/** The inverse level of a wavelet's lifting steps, as a merge of inverse3. */
const liftingMerge = (lift) => (s, d, n, w, wrap) => inverseLevel(s, d, n, w, lift, wrap);

/** One inverse level, in place, of w n-sample signals from their low rows s and high rows d:
 * undo the scales, then the lifting steps from the last to the first (a d step reads only s
 * and an s step only d, so each updates in place as if all k at once). */
function inverseLevel(s, d, n, w, lift, wrap) {
  if (n === 1) {
    for (let j = 0; j < w; j++) s[j] /= Math.SQRT2;
    return;
  }
  const lowScale = Math.SQRT2 / lift.k;
  const highScale = -lift.k / Math.SQRT2;
  const ns = (n + 1) >> 1;
  const nd = n >> 1;
  for (let i = 0; i < ns * w; i++) s[i] /= lowScale;
  for (let i = 0; i < nd * w; i++) d[i] /= highScale;
  const dBefore = (wrap ? nd - 1 : 0) * w;   // where d_(-1) is
  const sLast = (wrap ? 0 : ns - 1) * w;      // where s_(ns) is
  for (let step = lift.steps.length - 1; step >= 0; step--) {
    const a = lift.steps[step];
    if (step % 2 === 0) {   // d_k -= a (s_k + s_(k+1)); one flat loop up to the d without s_(k+1)
      const inner = Math.min(nd, ns - 1) * w;
      for (let i = 0; i < inner; i++) d[i] -= a * (s[i] + s[i + w]);
      for (let i = inner; i < nd * w; i++) d[i] -= a * (s[i] + s[sLast + i - inner]);
    } else {                // s_k -= a (d_(k-1) + d_k): s_0 with d_(-1), then flat, then s_(nd) with d_(nd-1) twice
      for (let j = 0; j < w; j++) s[j] -= a * (d[dBefore + j] + d[j]);
      for (let i = w; i < nd * w; i++) s[i] -= a * (d[i - w] + d[i]);
      for (let i = nd * w; i < ns * w; i++) s[i] -= a * (d[i - w] + d[i - w]);
    }
  }
}
