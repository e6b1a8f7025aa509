// The 2D wavelet codec `mzc-dwt2d` 2.0, 3.0, 3.1, 3.2, 4.0, 5.0 (tiles), 5.1 (rounded tiles), 6.0 (rounding)
// and 7.0 (binary header and parametric tables, in the sections of compact.mjs), 8.0 (7.0, its mask in mask.mjs)
// (spec/dwt2d.md): header, payload (tables, rANS, raw bits), mask, relevance, bands, slope
// factors, inverse transform, correction layer, chart records, rounding and tiles.

import { fail, headerFields, fieldReader, gridFields, checkChecksum, checkCharts, VIEWS, crc32, splitHeader, parseMagic } from "./header.mjs";
import { cos } from "./elementary.mjs";
import { sections, headerLines, HEADER, PAYLOAD, COLOUR } from "./compact.mjs";
import { inversePeriodized2d, relevantPeriodized2d } from "./pywt.mjs";
import { decodeFlips } from "./mask.mjs";

const WAVELETS_3 = ["bior4.4", "bior2.2"];
const WAVELETS_2 = ["bior4.4", "bior2.2", "bior3.3", "db2", "db4", "sym4", "coif1", "haar"];

/** Decodes a dwt2d file (bytes; its header lines; the payload's offset; its magic). */
export function decodeDwt2d(bytes, lines, body, magic) {
  if (magic.major === 5) return decodeTiled(bytes, lines, body, magic);
  const fields = headerFields(lines, false);
  checkChecksum(bytes, lines, fields, magic.major >= 4 || (magic.major === 3 && magic.minor >= 1));
  return decodeWhole(fields, bytes.subarray(body), magic);
}

/** Decodes a 7.0 file (bytes; the end of its magic line; its magic): its sections, the header's
 * fields read as the lines they stand for, the payload with 7.0's table records; section 3, a
 * grid's colours (Colours of 7.0), comes back undecoded as `colourSection` (colour.mjs's
 * `withColours` decodes it over the grid's valid nodes). */
export function decodeCompact(bytes, magicEnd, magic) {
  const bodies = sections(bytes, magicEnd, [HEADER, PAYLOAD], COLOUR);
  const grid = decodeWhole(headerLines(bodies[HEADER]), bodies[PAYLOAD], magic);
  return bodies[COLOUR] ? { ...grid, colourSection: bodies[COLOUR] } : grid;
}

/** Decodes a grid coded whole from its header lines (keyword -> words) and its payload. */
function decodeWhole(fields, bytes, magic) {
  const h = fieldReader(fields);
  const georef = magic.major >= 6 || (magic.major === 3 && magic.minor >= 2);
  const grid = gridFields(h, { projected: magic.major >= 3, georef });
  const p = codecFields(h, magic, grid);
  const payload = new Payload(bytes, magic.major >= 7);
  const z = decodeGrid(payload, grid, p);
  const charts = p.chartCount ? chartRecords(payload, p.chartCount, grid, z) : undefined;
  payload.finish();
  if (p.rounding) roundToSamples(z, grid);
  return { ...grid, z, charts };
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
// (5.1 with `rounding integer`: 6.0 files rounded to the header's raster type)

/** Decodes a 5.x file: checks its header's checksum and lines, the index and its CRC-32, then
 * decodes every tile as a 3.x file (6.0 in a rounded 5.1 file) and puts its values in their place. */
function decodeTiled(bytes, lines, body, magic) {
  const fields = headerFields(lines, false);
  const h = fieldReader(fields);
  checkChecksum(bytes, lines, fields, true, body);
  const grid = gridFields(h, { projected: true, georef: true });
  const rounded = magic.minor >= 1 && h.word("rounding", ["integer"], false) === "integer";
  if (rounded && !(grid.raster && SAMPLE_RANGES[grid.raster[2]])) {
    fail("rounding", "rounding integer needs a raster line of an integer sample type");
  }
  const T = h.integer("tile", 4, 4096);
  const [NR, NC] = h.words("tiles", 2).map((w) => (/^\d+$/.test(w) ? Number(w) : fail("tiles", `not an integer: ${w}`)));
  if (NR !== Math.ceil(grid.rows / T) || NC !== Math.ceil(grid.cols / T) || NR * NC > 4194304) {
    fail("tiles", `${NR} ${NC} is not ceil(rows / ${T}) and ceil(cols / ${T}), at most 4,194,304 tiles`);
  }
  const lengths = tileIndex(bytes, body, NR * NC);
  const z = new Float64Array(grid.rows * grid.cols);
  let at = body + 8 * NR * NC + 4;
  for (let i = 0; i < NR; i++) {
    for (let j = 0; j < NC; j++) {
      const tile = decodeTile(bytes.subarray(at, at + lengths[i * NC + j]), grid, T, i, j, rounded);
      for (let r = 0; r < tile.rows; r++) z.set(tile.z.subarray(r * tile.cols, (r + 1) * tile.cols), (i * T + r) * grid.cols + j * T);
      at += lengths[i * NC + j];
    }
  }
  return { ...grid, z };
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

/** Tile (i, j): a whole mzc-dwt2d 3.x file of its block (``rounded``: 6.0, with the header's raster
 * line, its values integers), its lines those the header implies. */
function decodeTile(bytes, grid, T, i, j, rounded) {
  const { lines, body } = splitHeader(bytes);
  const magic = parseMagic(lines[0]);
  const major = rounded ? 6 : 3;
  if (magic.kind !== "dwt2d" || magic.major !== major) fail("data", `tile ${i + 1}, ${j + 1} is not an mzc-dwt2d ${major}.x file`);
  const tile = decodeDwt2d(bytes, lines, body, magic);
  const fields = headerFields(lines, false);
  const origin = [grid.origin[0] + j * T * grid.d2, grid.origin[1] + i * T * grid.d1];
  const ok = tile.rows === Math.min((i + 1) * T, grid.rows) - i * T && tile.cols === Math.min((j + 1) * T, grid.cols) - j * T
    && tile.d1 === grid.d1 && tile.d2 === grid.d2 && tile.projection === grid.projection && tile.radius === grid.radius
    && tile.origin[0] === origin[0] && tile.origin[1] === origin[1]
    && !["transform", "units", "nodata", "crs", ...(rounded ? [] : ["raster"])].some((key) => fields.has(key))
    && (!rounded || (String(tile.raster) === String(grid.raster) && tile.z.every((v) => Number.isNaN(v) || Number.isInteger(v))));
  if (!ok) fail("data", `tile ${i + 1}, ${j + 1}: its lines do not say the block the header gives it`);
  return tile;
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
  return { v3, wavelet, levels, steps: bandSteps(written, levels), slopeLimit, correction, chartCount, rounding, flips };
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

/** A reader of the payload: its tables, its rANS state and its raw-bit cursor. */
export class Payload {
  /** `parametric`: 7.0's table records (Tables of 7.0), else 3.x's. */
  constructor(bytes, parametric) {
    this.bytes = bytes;
    this.at = 0;
    this.tables = this.readTables(parametric);
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

  /** The M model tables, each a lookup from a 14-bit slot to its class. */
  readTables(parametric) {
    const m = this.varint("tables");
    if (m > 4096) fail("tables", `${m} tables (at most 4096)`);
    const tables = [];
    for (let t = 0; t < m; t++) {
      let s = this.varint("tables");
      if (s === 0) {
        if (!t) fail("tables", "the first table repeats none");
        tables.push(tables[t - 1]);
        continue;
      }
      const kind = parametric ? s % 2 : 0;
      if (parametric) s = Math.floor(s / 2);
      if (s < 2 || s > 48) fail("tables", `a table of ${s} classes (2..48)`);
      tables.push(frequencyTable(kind ? this.parametricRecord(s) : this.codeWeights(s)));
    }
    for (const group of SAME_SIZE) {
      const sizes = new Set(group.filter((m) => m < tables.length).map((m) => tables[m].freq.length));
      if (sizes.size > 1) fail("tables", "tables mixed in one row have different class counts");
    }
    return tables;
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
    const low = (a - top * 16384) * 262144 + f * (this.lo >>> 24) * 1024 + m - table.cum[s] * 1024;
    const carry = Math.floor(low / 4294967296);
    let hi = top + carry;
    let lo = low - carry * 4294967296;
    if (hi === 0 && this.words.length) {
      hi = lo;
      lo = this.words.pop();
    }
    this.hi = hi;
    this.lo = lo;
    return s;
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
 * table's reach 2^40, their products 2^54), with the lookup of a 14-bit slot to its class and
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
 * class 0 z/256 of the mass, class k >= 1 the |v| in 2^(k-1) .. 2^k - 1 of a |v| - 1 geometric of
 * ratio theta / 2^32, the last class the whole tail. */
export function parametricWeights(s, z, t) {
  const theta = ONE - (ROOTS[t % 16] >> BigInt(t >> 4));
  const tails = [];
  for (let k = 1; k < s; k++) tails.push(power(theta, 2 ** (k - 1) - 1));
  tails.push(0n);
  return [BigInt(z) << 32n, ...tails.slice(0, -1).map((tail, k) => BigInt(256 - z) * (tail - tails[k + 1]))];
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

/** The decoded values (NaN at invalid nodes), row-major rows x cols. */
function decodeGrid(payload, grid, p) {
  const { rows, cols } = grid;
  const mask = (p.flips ? decodeFlips : decodeMask)(payload, rows, cols);
  const periodic = isPeriodic(grid);
  const shapes = bandShapes(rows, cols, p);
  const relevant = p.v3 ? relevance3(mask, rows, cols, p, periodic) : relevantPeriodized2d(mask, rows, cols, p.wavelet, p.levels);
  const q = [decodeBand0(payload, shapes[0])];
  for (let b = 1; b < shapes.length; b++) q.push(decodeDetail(payload, q, b, shapes, relevant, p));
  const bands = dequantise(q, shapes, grid, p, periodic);
  const w = p.v3 ? inverse3(bands, shapes, rows, cols, p, periodic) : inversePeriodized2d(bands, shapes, rows, cols, p.wavelet, p.levels);
  const k = p.correction > 0 ? decodeCorrection(payload, mask, rows, cols) : null;
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

/** The integers of detail band b, row by row in even and odd passes: magnitudes grouped by
 * context, then the signs of the nonzero ones (Order of the integers, 5). */
export function decodeDetail(payload, q, b, shapes, relevant, p) {
  const shape = shapes[b];
  const { rows, cols } = shape;
  const out = new Float64Array(rows * cols);
  const parentIndex = shape.level < p.levels ? b - 3 : -1;
  const parent = parentIndex > 0 && shapes[parentIndex].rows * shapes[parentIndex].cols ? parentIndex : -1;
  const ratio = parent > 0 ? p.steps[parent] / p.steps[b] : 0;
  const earlier = Array.from({ length: shape.orient - 1 }, (_, i) => b - shape.orient + 1 + i);
  const parentAt = (r, c) => {
    const ps = shapes[parent];
    return q[parent][Math.min(r >> 1, ps.rows - 1) * ps.cols + Math.min(c >> 1, ps.cols - 1)];
  };
  const [wa, wp, wt] = SIGN_WEIGHTS[shape.orient];
  const context = new Int8Array(cols);   // each column's context in the pass, -1 if not coded
  for (let r = 0; r < rows; r++) {
    for (const odd of [0, 1]) {
      context.fill(-1);
      for (let c = odd; c < cols; c += 2) {
        if (!relevant[b][r * cols + c]) continue;
        let a = parent > 0 ? Math.abs(parentAt(r, c)) * ratio : 0;
        for (const e of earlier) a += at(q[e], shapes[e], r, c);
        a += at(out, shape, r - 1, c) + (at(out, shape, r - 1, c - 1) + at(out, shape, r - 1, c + 1) + at(out, shape, r - 2, c)) / 2;
        if (odd) a += at(out, shape, r, c - 1) + at(out, shape, r, c + 1);
        let n = 0;
        while (n < 10 && THRESHOLDS[n] <= a) n++;
        context[c] = n;
      }
      for (let n = 0; n <= 10; n++) {
        for (let c = odd; c < cols; c += 2) if (context[c] === n) out[r * cols + c] = payload.unsigned(4 + n);
      }
      for (let c = odd; c < cols; c += 2) {
        const i = r * cols + c;
        if (!out[i]) continue;
        const above = r ? Math.sign(out[i - cols]) : 0;
        const par = parent > 0 ? Math.sign(parentAt(r, c)) : 0;
        const t = odd ? (c > 0 ? Math.sign(out[i - 1]) : 0) + (c + 1 < cols ? Math.sign(out[i + 1]) : 0) : 0;
        const score = wa * above + wp * par + wt * t;
        const context = (odd ? 4 : 0) + Math.min(Math.abs(score), 3);
        const flip = payload.symbol(15 + context);
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
 * wrapping round when `wrap`): the row-low (r x ceil(c/2)) and row-high (r x floor(c/2)) marks. */
function markRows(a, r, c, reach, wrap) {
  const lc = (c + 1) >> 1;
  const hc = c >> 1;
  const low = new Uint8Array(r * lc);
  const high = new Uint8Array(r * hc);
  const near = (base, centre, d) => {
    for (let t = centre - d; t <= centre + d; t++) {
      const j = wrap ? (t + c) % c : t;
      if (j >= 0 && j < c && a[base + j]) return 1;
    }
    return 0;
  };
  for (let i = 0; i < r; i++) {
    for (let k = 0; k < lc; k++) low[i * lc + k] = near(i * c, 2 * k, reach[0]);
    for (let k = 0; k < hc; k++) high[i * hc + k] = near(i * c, 2 * k + 1, reach[1]);
  }
  return [low, high];
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
    if (!factors || b === 0) return band.map((v) => v * step);
    const g = resample(factors, shapes[0].rows, shapes[0].cols, shape.rows, shape.cols);
    return band.map((v, i) => v * (step * g[i]));
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
  const tmp = new Float64Array(m1 * n2);
  for (let j = 0; j < n2; j++) {
    const col = linear((i) => g[i * n2 + j], n1, m1);
    col.forEach((x, i) => (tmp[i * n2 + j] = x));
  }
  const out = new Float64Array(m1 * m2);
  for (let i = 0; i < m1; i++) out.set(linear((j) => tmp[i * n2 + j], n2, m2), i * m2);
  return out;
}

/** One axis of the resampling: n input nodes to m output cells. */
function linear(get, n, m) {
  const out = new Float64Array(m);
  for (let i = 0; i < m; i++) {
    if (n === 1) {
      out[i] = get(0);
      continue;
    }
    const u = Math.min(Math.max(((i + 0.5) * n) / m - 0.5, 0), n - 1);
    const j = Math.min(Math.floor(u), n - 2);
    const w = u - j;
    out[i] = (1 - w) * get(j) + w * get(j + 1);
  }
  return out;
}

/** The inverse 3.0 transform of the dequantised bands: coarsest level first, each level
 * columns before rows. `merge(low, high, n, wrap)` is one inverse level of a signal: by default
 * the lifting of p.wavelet (the colour section's integer 5/3 gives its own). */
export function inverse3(bands, shapes, rows, cols, p, periodic, merge = liftingMerge(LIFTING[p.wavelet])) {
  let low = bands[0];
  for (let l = p.levels; l >= 1; l--) {
    const b = 1 + 3 * (p.levels - l);
    const { r, c } = shapes[b].input;
    const lc = Math.ceil(c / 2);
    const hc = c - lc;
    const rowLow = mergeColumns(low, bands[b], r, lc, merge);
    const rowHigh = mergeColumns(bands[b + 1], bands[b + 2], r, hc, merge);
    const wrap = periodic && c % 2 === 0 && c > 2;
    const out = new Float64Array(r * c);
    for (let i = 0; i < r; i++) {
      out.set(merge(rowLow.subarray(i * lc, (i + 1) * lc), rowHigh.subarray(i * hc, (i + 1) * hc), c, wrap), i * c);
    }
    low = out;
  }
  return low;
}

/** Columns of a low (ceil(r/2) x w) and a high (floor(r/2) x w) half merged into r x w. */
function mergeColumns(lo, hi, r, w, merge) {
  const lr = (r + 1) >> 1;
  const low = transpose(lo, lr, w);
  const high = transpose(hi, r - lr, w);
  const out = new Float64Array(w * r);
  for (let j = 0; j < w; j++) out.set(merge(low.subarray(j * lr, (j + 1) * lr), high.subarray(j * (r - lr), (j + 1) * (r - lr)), r, false), j * r);
  return transpose(out, w, r);
}

/** The inverse level of a wavelet's lifting steps, as a merge of inverse3. */
const liftingMerge = (lift) => (low, high, n, wrap) => inverseLevel(low, high, n, lift, wrap);

/** One inverse level of an n-sample signal from its low and high coefficients: undo the
 * scales, then the lifting steps from the last to the first (a d step reads only s and an
 * s step only d, so each updates in place as if all k at once); interleave. */
function inverseLevel(low, high, n, lift, wrap) {
  if (n === 1) return Float64Array.of(low[0] / Math.SQRT2);
  const lowScale = Math.SQRT2 / lift.k;
  const highScale = -lift.k / Math.SQRT2;
  const ns = low.length;
  const nd = high.length;
  const s = new Float64Array(ns);
  const d = new Float64Array(nd);
  for (let k = 0; k < ns; k++) s[k] = low[k] / lowScale;
  for (let k = 0; k < nd; k++) d[k] = high[k] / highScale;
  const dBefore = wrap ? nd - 1 : 0;       // the index of d_(-1)
  for (let step = lift.steps.length - 1; step >= 0; step--) {
    const a = lift.steps[step];
    if (step % 2 === 0) {
      for (let k = 0; k < nd; k++) d[k] -= a * (s[k] + (k + 1 < ns ? s[k + 1] : wrap ? s[0] : s[ns - 1]));
    } else {
      for (let k = 0; k < ns; k++) s[k] -= a * ((k > 0 ? d[k - 1] : d[dBefore]) + (k < nd ? d[k] : d[nd - 1]));
    }
  }
  const x = new Float64Array(n);
  for (let k = 0; k < ns; k++) x[2 * k] = s[k];
  for (let k = 0; k < nd; k++) x[2 * k + 1] = d[k];
  return x;
}
