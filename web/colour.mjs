// The colour section, versions 1, 2 and 3 (spec/colour.md): the R x C x 3 8-bit image of a grid's
// nodes (version 2: of its colours sampled K times finer, ((R - 1) K + 1) x ((C - 1) K + 1) x 3;
// version 3: version 2 on a multi-chart grid, no sample between two charts valid) from its bytes,
// the grid's validity mask and its charts. A dwt2d payload of the three YCoCg-R channels' bands
// (the integer LeGall 5/3 or dwt2d 3.0's CDF 9/7), then an optional correction layer.
//
//   import { decodeColour } from "./colour.mjs";
//   const rgb = decodeColour(bytes, { rows, cols, valid, charts });   // Uint8Array, rows * cols * 3 (version 1)

import { fail, crc32, chartLabels } from "./header.mjs";
import { Payload, bandShapes, relevance3, decodeBand0, decodeDetail, decodeCorrection, inverse3 } from "./dwt2d.mjs";

const MAGIC = [0x6d, 0x7a, 0x63, 0x43];   // "mzcC"
const HEADERS = { 1: 30, 2: 31, 3: 31 };  // a version's header bytes (versions 2 and 3 add the scale K after cols)
const MAX_SCALE = 8;
const MAX_NODES = 100_000_000;
const UNIT = 16;                          // a step's sixteenths of a level
const MAX_SIDE = 2 ** 24;
const MAX_QUANTUM = 2 ** 24;
const WAVELETS = ["bior2.2", "bior4.4"];  // the relevance of transform 0 and 1
const STEP_FACTORS = [[177, 116, 63], [177, 116, 63], [256, 199, 116]];   // H, V, D in 256ths, levels 1..3
const BAND0_FACTOR = 248;

/** A grid decoded by `decodeCompact` with its colours: its `colourSection` decoded over its valid
 * nodes and its charts (a multi-chart grid's chart records) into `colors` (spec/dwt2d.md, Colours
 * of 7.0), and for a version 2 or 3 section the finer image as `fineColors` with its `colourScale`,
 * `colors` then its node samples; a grid without one as it is. */
export function withColours({ colourSection, ...grid }) {
  if (!colourSection) return grid;
  const valid = Uint8Array.from(grid.z, (v) => (Number.isNaN(v) ? 0 : 1));
  const image = decodeColour(colourSection, { rows: grid.rows, cols: grid.cols, valid, charts: grid.charts });
  const scale = colourScale(colourSection);
  if (scale === 1) return { ...grid, colors: image };
  return { ...grid, colors: nodeSamples(image, grid.rows, grid.cols, scale), fineColors: image, colourScale: scale };
}

/** K of a decoded colour section (1 for version 1). */
function colourScale(bytes) {
  return bytes[4] === 1 ? 1 : bytes[13];
}

/** The nodes' colours (rows * cols * 3) of an image of colours `scale` times finer: samples (rK, cK). */
export function nodeSamples(image, rows, cols, scale) {
  const width = (cols - 1) * scale + 1;
  const out = new Uint8Array(rows * cols * 3);
  for (let r = 0; r < rows; r++) {
    for (let c = 0; c < cols; c++) out.set(image.subarray(3 * (r * scale * width + c * scale), 3 * (r * scale * width + c * scale) + 3), 3 * (r * cols + c));
  }
  return out;
}

/** The validity (0/1, row by row) of the colour samples `scale` times finer than a grid's `valid`
 * nodes: a sample is valid where every node of the cell, edge or node it lies in is, and of a
 * multi-chart grid's `charts` lies in one chart (spec/zgrid.md, Colours finer than the nodes). */
export function fineMask(valid, rows, cols, scale, charts) {
  const fineRows = (rows - 1) * scale + 1, fineCols = (cols - 1) * scale + 1;
  const label = charts ? chartLabels(charts, rows, cols) : new Int32Array(rows * cols);   // without charts, one
  const out = new Uint8Array(fineRows * fineCols);
  for (let a = 0; a < fineRows; a++) {
    const r0 = Math.floor(a / scale) * cols, r1 = Math.ceil(a / scale) * cols;
    for (let b = 0; b < fineCols; b++) {
      const c0 = Math.floor(b / scale), c1 = Math.ceil(b / scale), first = label[r0 + c0];
      out[a * fineCols + b] = valid[r0 + c0] && valid[r0 + c1] && valid[r1 + c0] && valid[r1 + c1]
        && label[r0 + c1] === first && label[r1 + c0] === first && label[r1 + c1] === first ? 1 : 0;
    }
  }
  return out;
}

/** The image (Uint8Array, rows * cols * 3: red, green, blue a node, 0 at invalid nodes) of a colour
 * section that spans `bytes`, decoded with `mask` ({rows, cols, valid: rows * cols 0/1, charts: a
 * multi-chart grid's, else absent}); any damage, a mask of another shape, or a section of another
 * kind of grid (version 3 without charts, version 2 with them) throws an MzcError. */
export function decodeColour(bytes, mask) {
  if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
  const h = sectionHeader(bytes, mask);
  const nodes = Uint8Array.from(mask.valid, (v) => (v ? 1 : 0));
  const valid = h.scale === 1 ? nodes : fineMask(nodes, mask.rows, mask.cols, h.scale, mask.charts);
  const payload = new Payload(bytes.subarray(HEADERS[h.version]), false);
  const p = { v3: true, levels: h.levels, wavelet: WAVELETS[h.transform] };
  const shapes = bandShapes(h.rows, h.cols, p);
  const relevant = relevance3(valid, h.rows, h.cols, p, false);
  const planes = h.steps.map((step) => {
    const steps = h.transform ? new Array(1 + 3 * h.levels).fill(step) : bandSteps(step, h.levels);
    const q = [decodeBand0(payload, shapes[0])];
    const bands = { ...p, steps: steps.map((s) => s / UNIT) };
    for (let b = 1; b < shapes.length; b++) q.push(decodeDetail(payload, q, b, shapes, relevant, bands));
    if (q.some((band) => band.some((v) => Math.abs(v) > MAX_QUANTUM))) fail("colour", "a quantised coefficient is far outside 8-bit colour");
    return channelPlane(q, steps, shapes, h, p);
  });
  const image = clip(rgbOf(planes), valid);
  if (h.correction) {
    const k = [0, 1, 2].map(() => decodeCorrection(payload, valid, h.rows, h.cols));
    if (k.some((grid) => grid.some((v) => Math.abs(v) > 255))) fail("colour", "a correction is larger than 255 levels");
    for (let i = 0; i < image.length; i++) image[i] += h.correction * k[i % 3][Math.floor(i / 3)];
    clip(image, valid);
  }
  payload.finish();
  return Uint8Array.from(image);
}

/** The header's fields (Layout; of versions 2 and 3, Layout of version 2), each checked, with the
 * section's length and CRC-32; its version against the grid's charts first. */
function sectionHeader(bytes, mask) {
  if (bytes.length >= 4 && MAGIC.some((b, i) => bytes[i] !== b)) fail("colour", "not a colour section (no mzcC)");
  const version = bytes[4];
  if (bytes.length >= 5 && !HEADERS[version]) fail("colour", `colour section version ${version} (this decoder reads ${Object.keys(HEADERS).join(", ")})`);
  const size = HEADERS[version] ?? HEADERS[1];
  if (bytes.length < size) fail("colour", `colour section of ${bytes.length} bytes ends inside its ${size}-byte header`);
  checkVersionOnCharts(version, mask.charts);
  const at = size - 30;   // versions 2 and 3's fields after cols lie a byte further
  const view = new DataView(bytes.buffer, bytes.byteOffset, size);
  const h = {
    version, rows: view.getUint32(5, true), cols: view.getUint32(9, true), scale: at ? bytes[13] : 1,
    levels: bytes[13 + at], transform: bytes[14 + at],
    steps: [view.getUint16(15 + at, true), view.getUint16(17 + at, true), view.getUint16(19 + at, true)], correction: bytes[21 + at],
  };
  const length = view.getUint32(22 + at, true);
  if (at && !(h.scale >= 2 && h.scale <= MAX_SCALE)) fail("colour", `colour scale ${h.scale} (allowed 2..${MAX_SCALE})`);
  const fineRows = (mask.rows - 1) * h.scale + 1, fineCols = (mask.cols - 1) * h.scale + 1;
  if (fineRows > 1_000_000 || fineCols > 1_000_000 || fineRows * fineCols > MAX_NODES) fail("colour", `colour scale ${h.scale}: ${fineRows} x ${fineCols} samples is too large`);
  if (h.rows !== fineRows || h.cols !== fineCols) fail("colour", `the section's image is ${h.rows} x ${h.cols} samples, the mask's ${fineRows} x ${fineCols}`);
  if (Math.min(h.rows, h.cols) < 1 || Math.max(h.rows, h.cols) > MAX_SIDE) fail("colour", `a colour grid of ${h.rows} x ${h.cols} nodes`);
  if (h.levels > 12) fail("colour", `${h.levels} wavelet levels (allowed 0..12)`);
  if (h.transform > 1) fail("colour", `transform ${h.transform} (0 or 1)`);
  if (Math.min(...h.steps) < UNIT) fail("colour", "a step below 1 level");
  if (bytes.length !== size + length) fail("colour", `the section declares ${size + length} bytes and has ${bytes.length}`);
  if (crc32(bytes.subarray(0, size - 4), bytes.subarray(size)) !== view.getUint32(size - 4, true)) fail("colour", "the colour section's CRC-32 does not match");
  return h;
}

/** Refuses a section of version 3 (colours finer than the nodes of a multi-chart grid) on a grid
 * without charts, and of version 2 on a grid with them: its sample mask would be another
 * (mzc.codecs.dwt2d.colour.charts_fault, word for word). */
function checkVersionOnCharts(version, charts) {
  if (version === 3 && !charts) fail("colour", "a colour section of version 3 belongs to a multi-chart grid, and this grid has no charts");
  if (version === 2 && charts) fail("colour", "a colour section of version 2 belongs to a grid without charts, and this grid has charts");
}

/** Transform 0's step of every band (sixteenths) from a channel's step S (Band steps). */
function bandSteps(step, levels) {
  const steps = [Math.max(UNIT, Math.floor((step * BAND0_FACTOR) / 2 ** (8 + levels)))];
  for (let level = levels; level >= 1; level--) {
    for (const f of STEP_FACTORS) {
      const factor = level <= 3 ? f[level - 1] : Math.floor(f[2] / 2 ** (level - 3));
      steps.push(Math.max(UNIT, Math.floor((step * factor) / 256)));
    }
  }
  return steps;
}

/** A channel's plane of integers from its band integers: transform 0 dequantised in integers and
 * merged by the integer 5/3, transform 1 q * (S / 16) in binary64 through the CDF 9/7, rounded to
 * the nearest integer, ties to even. */
function channelPlane(q, steps, shapes, h, p) {
  if (h.transform) {
    const bands = q.map((band, b) => band.map((v) => v * (steps[b] / UNIT)));
    return inverse3(bands, shapes, h.rows, h.cols, p, false).map(roundHalfEven);
  }
  const bands = q.map((band, b) => band.map((v) => Math.sign(v) * Math.floor((Math.abs(v) * steps[b] + UNIT / 2) / UNIT)));
  return inverse3(bands, shapes, h.rows, h.cols, p, false, merge53);
}

/** x rounded to the nearest integer, ties to even (numpy's rint). */
function roundHalfEven(x) {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/** One inverse level, in place, of the integer LeGall 5/3 (JPEG 2000's reversible): w signals of
 * n samples from their ceil(n/2) low rows s and floor(n/2) high rows d, each w wide; symmetric
 * extension (d_-1 = d_0, past the ends the last). */
function merge53(s, d, n, w) {
  if (n === 1) return;
  const ns = (n + 1) >> 1, nd = n >> 1;
  for (let k = 0; k < ns; k++) {
    const before = (k ? k - 1 : 0) * w, after = Math.min(k, nd - 1) * w;
    for (let j = 0; j < w; j++) s[k * w + j] -= Math.floor((d[before + j] + d[after + j] + 2) / 4);
  }
  for (let k = 0; k < nd; k++) {
    const next = Math.min(k + 1, ns - 1) * w;
    for (let j = 0; j < w; j++) d[k * w + j] += Math.floor((s[k * w + j] + s[next + j]) / 2);
  }
}

/** The interleaved R, G, B of the Y, Co, Cg planes (the inverse of YCoCg-R). */
function rgbOf([y, co, cg]) {
  const out = new Float64Array(y.length * 3);
  for (let i = 0; i < y.length; i++) {
    const t = y[i] - Math.floor(cg[i] / 2);
    const b = t - Math.floor(co[i] / 2);
    out[3 * i] = b + co[i];
    out[3 * i + 1] = cg[i] + t;
    out[3 * i + 2] = b;
  }
  return out;
}

/** Every value held to 0..255 at valid nodes, 0 at invalid ones (in place). */
function clip(image, valid) {
  for (let i = 0; i < image.length; i++) image[i] = valid[Math.floor(i / 3)] ? Math.min(Math.max(image[i], 0), 255) : 0;
  return image;
}
