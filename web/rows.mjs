// The per-row codec files `mzc-poly`, `mzc-dft`, `mzc-dct` and `mzc-dwt` (spec/rows.md):
// their common layout (header, row lines `v1 v2 numbers...`, holes section), and the
// polynomial codec's evaluation (spec/poly.md), bit for bit as spec/arithmetic.md promises.
// The transforms of dft, dct and dwt are in transforms.mjs.

import { fail, headerFields, fieldReader, gridFields, checkChecksum, pythonFloat, words, bodyLines } from "./header.mjs";
import { dftRow, dctRow, dwtRow, dwtLengths } from "./transforms.mjs";

/** Reads a row codec file of `codec` (ROW_CODECS below) into its grid. */
function decodeRows(codec, bytes, lines, body, magic) {
  const fields = headerFields(lines, true);
  const h = fieldReader(fields);
  checkChecksum(bytes, lines, fields, magic.minor >= 1);
  const grid = gridFields(h, { projected: magic.major === 2, georef: magic.major === 1 && magic.minor >= 2 });
  const options = codec.options(h);
  const text = bodyLines(bytes.subarray(body));
  const z = new Float64Array(grid.rows * grid.cols).fill(NaN);
  const spans = [];
  for (let r = 0; r < grid.rows; r++) {
    if (r >= text.length) fail("data", `${grid.rows} row lines expected, found ${r}`);
    spans.push(readRow(text[r], r, grid, options, codec, z));
  }
  applyHoles(text.slice(grid.rows), spans, grid, z);
  return { ...grid, z };
}

/** Decodes row r's line into z; returns its span [v1, v2] (1-based), or null. */
function readRow(line, r, grid, options, codec, z) {
  const tokens = words(line);
  const where = `row ${r + 1}`;
  if (tokens[0] === "0" && tokens[1] === "0" && tokens.length === 2) return null;
  const [v1, v2] = tokens.slice(0, 2).map(Number);
  if (tokens.length < 2 || !/^\d+$/.test(tokens[0]) || !/^\d+$/.test(tokens[1]) || v1 < 1 || v1 > v2 || v2 > grid.cols) {
    fail("span", `${where}: v1 v2 must be integers with 1 <= v1 <= v2 <= ${grid.cols}`);
  }
  const numbers = tokens.slice(2).map((w, i) => {
    const x = pythonFloat(w, false);
    if (!Number.isFinite(x)) fail("coefficients", `${where}: number ${i + 1} is ${JSON.stringify(w)}: coefficients must be finite`);
    return x;
  });
  const values = codec.row(numbers, v2 - v1 + 1, v1, options, grid, where);
  values.forEach((v, j) => {
    if (!Number.isFinite(v)) fail("data", `${where}: a decoded height is not finite`);
    z[r * grid.cols + v1 - 1 + j] = v;
  });
  return [v1, v2];
}

/** The optional `holes K` section: K lines `r s1 e1 [s2 e2 ...]` setting runs invalid. */
function applyHoles(lines, spans, grid, z) {
  if (!lines.length) return;
  const head = words(lines[0]);
  if (head[0] !== "holes" || head.length !== 2 || !/^\d+$/.test(head[1])) fail("holes", "expected 'holes COUNT' after the row lines");
  if (Number(head[1]) !== lines.length - 1) fail("holes", `says ${head[1]} hole line(s) but ${lines.length - 1} follow`);
  for (const line of lines.slice(1)) {
    const tokens = words(line);
    if (!tokens.every((w) => /^\d+$/.test(w))) fail("holes", "hole lines hold integers 'row start end ...'");
    const [r, ...runs] = tokens.map(Number);
    if (r < 1 || r > grid.rows || runs.length < 2 || runs.length % 2) fail("holes", "expected 'row start end [start end ...]' with a row in 1..rows");
    const span = spans[r - 1];
    for (let i = 0, last = span ? span[0] : Infinity; i < runs.length; i += 2) {
      const [s, e] = [runs[i], runs[i + 1]];
      if (!span || s <= last || e < s || e >= span[1] || (i && s <= last + 1)) {
        fail("holes", `run ${s}..${e} is not inside row ${r}'s span in increasing order`);
      }
      z.fill(NaN, (r - 1) * grid.cols + s - 1, (r - 1) * grid.cols + e);
      last = e;
    }
  }
}

/** The quality factor line of dft, dct and dwt. */
const quality = (h) => h.integer("quality", 1, 100);

/** Refuses a row whose count of numbers is not `expected`. */
function expectCount(numbers, expected, where, what) {
  if (numbers.length !== expected) fail("coefficients", `${where}: expected ${expected} ${what}, found ${numbers.length}`);
}

/** The polynomial codec (spec/poly.md): Clenshaw's recurrence or Horner's rule. */
const POLY = {
  options: (h) => ({ basis: h.word("basis", ["chebyshev", "power"]), degree: h.integer("degree", 0, 10000) }),
  row(c, m, v1, { basis, degree }, grid, where) {
    const k = Math.min(degree, m - 1);
    expectCount(c, k + 1, where, "coefficients");
    return Array.from({ length: m }, (_, j) => (basis === "chebyshev" ? clenshaw(c, chebyshevPoint(j, m)) : horner(c, (v1 + j) * grid.d2)));
  },
};

/** t of sample j of m, as numpy.linspace(-1, 1, m) computes it: j (2 / (m - 1)) + -1, the
 * last exactly 1 (spec/poly.md writes -1 + 2j/(m-1), whose last bits differ); 0 for m = 1. */
function chebyshevPoint(j, m) {
  if (m === 1) return 0;
  return j === m - 1 ? 1 : j * (2 / (m - 1)) + -1;
}

/** sum c(i) T_i(t) by Clenshaw's recurrence, in spec/poly.md's order of operations. */
function clenshaw(c, t) {
  let b = 0;
  let b1 = 0;
  const t2 = 2 * t;
  for (let i = c.length - 1; i >= 1; i--) [b, b1] = [c[i] + t2 * b - b1, b];
  return (c[0] + t * b) - b1;
}

/** c(0) x^k + ... + c(k) by Horner's rule (MATLAB's polyval). */
function horner(c, x) {
  let z = 0;
  for (const ci of c) z = z * x + ci;
  return z;
}

/** The DFT codec (spec/dft.md): a0 aN L an(1..K) bn(1..K). */
const DFT = {
  options: (h) => ({ quality: quality(h) }),
  row(numbers, m, v1, { quality: q }, grid, where) {
    const L = Math.floor((m + 1) / 2) - 1;
    const K = Math.floor((q * L) / 100);
    expectCount(numbers, 3 + 2 * K, where, "DFT numbers");
    if (numbers[2] !== L) fail("coefficients", `${where}: L is ${numbers[2]}, the span's is ${L}`);
    return dftRow(numbers[0], numbers[1], numbers.slice(3, 3 + K), numbers.slice(3 + K), L, m);
  },
};

/** The DCT codec (spec/dct.md): the first K orthonormal DCT-II coefficients. */
const DCT = {
  options: (h) => ({ quality: quality(h) }),
  row(numbers, m, v1, { quality: q }, grid, where) {
    expectCount(numbers, Math.floor((q * m) / 100), where, "DCT coefficients");
    return dctRow(numbers, m);
  },
};

/** The DWT codec (spec/dwt.md): the lengths vector L, then the kept prefix of C. */
const DWT = {
  options: (h) => ({ quality: quality(h), wavelet: h.word("wavelet"), level: h.integer("level", 1, 32) }),
  row(numbers, m, v1, options, grid, where) {
    const L = dwtLengths(options.wavelet, options.level, m);
    if (!L) fail("wavelet", `${options.wavelet} is not a wavelet this decoder knows`);
    const D = L.slice(1, -1).reduce((a, b) => a + b, 0);
    const N = L[0] + Math.floor((options.quality * D) / 100);
    expectCount(numbers, L.length + N, where, "numbers (lengths and kept coefficients)");
    if (numbers.slice(0, L.length).some((v, i) => v !== L[i])) fail("coefficients", `${where}: the lengths vector is not ${L.join(" ")}`);
    return dwtRow(numbers.slice(L.length), L, options.wavelet);
  },
};

/** Each row codec's decoder by kind, for mzc.mjs's table. */
export const ROW_CODECS = Object.fromEntries(Object.entries({ poly: POLY, dft: DFT, dct: DCT, dwt: DWT })
  .map(([kind, codec]) => [kind, (...args) => decodeRows(codec, ...args)]));
