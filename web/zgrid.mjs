// The z-grid itself (spec/zgrid.md): `mzc decode` reads it as any grid and writes it again,
// so decode() reads its plain (1.x, 2.x) and raw (3.x, 4.0, 5.x with colours, 6.0 with colours
// finer than the nodes, of a multi-chart grid too: no sample between two charts valid) bodies too.

import { fineMask, nodeSamples } from "./colour.mjs";
import { fail, headerFields, fieldReader, gridFields, checkChecksum, checkCharts, VIEWS, words, bodyLines, COUNTED_SINCE } from "./header.mjs";

const NUMBER = /^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/;
const SAMPLES = { float64: 8, float32: 4 };

/** Decodes a z-grid file (bytes; its header lines; the body's offset; its magic). */
export function decodeZgrid(bytes, lines, body, magic) {
  const raw = magic.major >= 3;
  const fields = headerFields(lines, !raw);
  const h = fieldReader(fields);
  checkChecksum(bytes, lines, fields, raw);
  const grid = gridFields(h, { projected: magic.major >= 2,
    georef: magic.minor >= 1 && [1, 3, 5].includes(magic.major) || magic.major === 6,
    counted: magic.minor >= (COUNTED_SINCE[magic.major] ?? Infinity) });
  const charts = h.has("charts") ? chartsLine(h, magic) : undefined;
  let data = bytes.subarray(body);
  let colors;
  const scale = magic.major >= 6 ? colourScaleLine(h, grid) : 1;
  if (magic.major >= 5) [data, colors] = colourBytes(h, data, grid, scale);
  const z = raw ? rawBody(h, data, grid) : plainBody(data, grid);
  if (charts) checkCharts(charts, grid, z);
  if (scale > 1) {
    const samples = fineMask(Uint8Array.from(z, (v) => (Number.isNaN(v) ? 0 : 1)), grid.rows, grid.cols, scale, charts);
    samples.forEach((v, i) => v || colors.fill(0, 3 * i, 3 * i + 3));
    return { ...grid, z, charts, colors: nodeSamples(colors, grid.rows, grid.cols, scale), fineColors: colors, colourScale: scale };
  }
  if (colors) z.forEach((v, i) => Number.isNaN(v) && colors.fill(0, 3 * i, 3 * i + 3));
  return { ...grid, z, charts, colors };
}

/** The `colour_scale` line of a 6.0 file (required): K in 2..8, its image of samples within the limits. */
function colourScaleLine(h, grid) {
  const scale = h.integer("colour_scale", 2, 8);
  const rows = (grid.rows - 1) * scale + 1, cols = (grid.cols - 1) * scale + 1;
  if (rows > 1_000_000 || cols > 1_000_000 || rows * cols > 100_000_000) fail("colour_scale", `${rows} x ${cols} colour samples is too large`);
  return scale;
}

/** A 5.x or 6.0 body split into its heights and a copy of its colours (Colours): the `colours rgb8`
 * line, then the body's last bytes, red, green, blue a node (6.0: a sample, ((rows - 1) K + 1) x
 * ((cols - 1) K + 1) of them); an invalid node's (sample's) are made 0 by the caller. */
function colourBytes(h, data, grid, scale) {
  h.word("colours", ["rgb8"]);
  const size = ((grid.rows - 1) * scale + 1) * ((grid.cols - 1) * scale + 1) * 3;
  if (data.length < size) fail("data", `the raw body has ${data.length} bytes, fewer than the ${size} of the colours alone`);
  return [data.subarray(0, data.length - size), data.slice(data.length - size)];
}

/** The `charts` line of a 4.0 file: seven words a chart (view, then six integers). */
function chartsLine(h, magic) {
  if (magic.major < 4) fail("charts", "a multi-chart grid needs a newer major version of this format");
  const w = h.words("charts");
  if (!w.length || w.length % 7) fail("charts", `expected 7 values per chart, found ${w.length}`);
  if (w.length / 7 > 65536) fail("charts", `${w.length / 7} charts: at most 65536`);
  const charts = [];
  for (let at = 0; at < w.length; at += 7) {
    if (!VIEWS.includes(w[at])) fail("charts", `${w[at]} is not a view (${VIEWS.join(", ")})`);
    const n = w.slice(at + 1, at + 7).map((word) => (/^[+-]?\d{1,18}$/.test(word) ? Number(word) : fail("charts", `not an integer: ${word}`)));
    charts.push({ view: w[at], row0: n[0], col0: n[1], rows: n[2], cols: n[3], i0: n[4], j0: n[5] });
  }
  return charts;
}

/** The values of a raw body: exactly rows x cols little-endian samples of the `raw` type. */
function rawBody(h, body, grid) {
  const sample = h.word("raw", Object.keys(SAMPLES));
  const size = grid.rows * grid.cols * SAMPLES[sample];
  if (body.length !== size) fail("data", `the raw body has ${body.length} bytes, but rows x cols of ${sample} take ${size}`);
  const view = new DataView(body.buffer, body.byteOffset, body.length);
  const z = new Float64Array(grid.rows * grid.cols);
  for (let i = 0; i < z.length; i++) {
    z[i] = sample === "float64" ? view.getFloat64(8 * i, true) : view.getFloat32(4 * i, true);
    if (Math.abs(z[i]) === Infinity) fail("data", `the value at row ${Math.floor(i / grid.cols) + 1} is infinite`);
  }
  return z;
}

/** The values of a plain body: `rows` lines of `cols` numbers, the `nodata` token or a
 * `nan` (any case) marking an invalid node. */
function plainBody(body, grid) {
  const lines = bodyLines(body);
  if (lines.length !== grid.rows) fail("data", `header says rows ${grid.rows} but the data has ${lines.length} row line(s)`);
  const z = new Float64Array(grid.rows * grid.cols);
  lines.forEach((line, r) => {
    const tokens = words(line);
    if (tokens.length !== grid.cols) fail("data", `row ${r + 1}: header says cols ${grid.cols} but this row has ${tokens.length} value(s)`);
    tokens.forEach((t, c) => (z[r * grid.cols + c] = value(t, grid.nodata, r)));
  });
  return z;
}

/** One plain value: NaN for the no-data token or `nan`; a finite decimal; else refused. */
function value(token, nodata, r) {
  if (token === nodata || /^[+-]?nan$/i.test(token)) return NaN;
  if (/^[+-]?(inf|infinity)$/i.test(token)) fail("data", `row ${r + 1}: a value is infinite`);
  if (!NUMBER.test(token)) fail("data", `row ${r + 1}: not a number: ${JSON.stringify(token.slice(0, 40))}`);
  return Number(token);
}
