// dwt2d 2.0's transform (spec/dwt2d.md, Transform of 2.0 and Relevant coefficients):
// PyWavelets' wavedec2 and waverec2 in mode "periodization", with its filters and the
// order in which its C code adds the products, so the bits are PyWavelets'.

/** PyWavelets' reconstruction filters (rec_lo, rec_hi) of each wavelet 2.0 allows. */
export const FILTERS = {
  "bior4.4": [[0.0, -0.06453888262869706, -0.04068941760916406, 0.41809227322161724, 0.7884856164055829, 0.41809227322161724, -0.04068941760916406, -0.06453888262869706, 0.0, 0.0],
    [0.0, -0.03782845550726404, -0.023849465019556843, 0.11062440441843718, 0.37740285561283066, -0.8526986790088938, 0.37740285561283066, 0.11062440441843718, -0.023849465019556843, -0.03782845550726404]],
  "bior2.2": [[0.0, 0.3535533905932738, 0.7071067811865476, 0.3535533905932738, 0.0, 0.0],
    [0.0, 0.1767766952966369, 0.3535533905932738, -1.0606601717798212, 0.3535533905932738, 0.1767766952966369]],
  "bior3.3": [[0.0, 0.0, 0.1767766952966369, 0.5303300858899106, 0.5303300858899106, 0.1767766952966369, 0.0, 0.0],
    [0.06629126073623882, 0.1988737822087165, -0.15467960838455727, -0.9943689110435825, 0.9943689110435825, 0.15467960838455727, -0.1988737822087165, -0.06629126073623882]],
  db2: [[0.48296291314453416, 0.8365163037378079, 0.2241438680420134, -0.12940952255126037],
    [-0.12940952255126037, -0.2241438680420134, 0.8365163037378079, -0.48296291314453416]],
  db4: [[0.2303778133088965, 0.7148465705529157, 0.6308807679298589, -0.027983769416859854, -0.18703481171909309, 0.030841381835560764, 0.0328830116668852, -0.010597401785069032],
    [-0.010597401785069032, -0.0328830116668852, 0.030841381835560764, 0.18703481171909309, -0.027983769416859854, -0.6308807679298589, 0.7148465705529157, -0.2303778133088965]],
  sym4: [[0.0322231006040427, -0.012603967262037833, -0.09921954357684722, 0.29785779560527736, 0.8037387518059161, 0.49761866763201545, -0.02963552764599851, -0.07576571478927333],
    [-0.07576571478927333, 0.02963552764599851, 0.49761866763201545, -0.8037387518059161, 0.29785779560527736, 0.09921954357684722, -0.012603967262037833, -0.0322231006040427]],
  coif1: [[-0.07273261951252645, 0.3378976624574818, 0.8525720202116004, 0.3848648468648578, -0.07273261951252645, -0.015655728135791993],
    [-0.015655728135791993, 0.07273261951252645, 0.3848648468648578, -0.8525720202116004, 0.3378976624574818, 0.07273261951252645]],
  haar: [[0.7071067811865476, 0.7071067811865476], [0.7071067811865476, -0.7071067811865476]],
};

/** A 2D array: rows x cols values, row-major. */
const array = (rows, cols, data = new Float64Array(rows * cols)) => ({ rows, cols, data });

/** Applies a 1D transform `fn(line) -> [a, b]` along axis 0 (down the columns) or 1 (along
 * the rows) of a 2D array, giving two arrays. */
function alongAxis(x, axis, fn) {
  const lines = axis === 1 ? x.rows : x.cols;
  const n = axis === 1 ? x.cols : x.rows;
  const index = axis === 1 ? (l, i) => l * x.cols + i : (l, i) => i * x.cols + l;
  let out;
  for (let l = 0; l < lines; l++) {
    const parts = fn(Float64Array.from({ length: n }, (_, i) => x.data[index(l, i)]));
    out ??= parts.map((p) => (axis === 1 ? array(x.rows, p.length) : array(p.length, x.cols)));
    parts.forEach((p, k) => p.forEach((v, i) => (out[k].data[axis === 1 ? l * p.length + i : i * x.cols + l] = v)));
  }
  return out;
}

/** One level of a periodization analysis with a filter of F ones: output o sums the
 * samples at (F/2 + 2o - j) mod N', j < F, of the signal made even by repeating its last. */
function onesAnalysis(x, F) {
  const n = x.length + (x.length % 2);
  const ext = (i) => x[Math.min(((i % n) + n) % n, x.length - 1)];
  const out = new Float64Array(n / 2);
  for (let o = 0; o < n / 2; o++) for (let j = 0; j < F; j++) out[o] += ext(F / 2 + 2 * o - j);
  return [out];
}

/** The relevant coefficients of 2.0 (band order): `> 0` of wavedec2 of the mask with all
 * filters replaced by ones of the wavelet's filter length. */
export function relevantPeriodized2d(mask, rows, cols, wavelet, levels) {
  const F = FILTERS[wavelet][0].length;
  let a = array(rows, cols, Float64Array.from(mask));
  const detail = [];
  for (let l = 1; l <= levels; l++) {
    const [lo] = alongAxis(a, 0, (x) => onesAnalysis(x, F));
    const [aa] = alongAxis(lo, 1, (x) => onesAnalysis(x, F));
    detail.unshift([aa, aa, aa]);   // every band of a level has one shape and, with ones, one sum
    a = aa;
  }
  return [a, ...detail.flat()].map((band) => band.data.map((v) => (v > 0 ? 1 : 0)));
}

/** Adds to `out` (length 2N) the periodization upsampling of `input` (length N) with a
 * filter of even length F, in the order of PyWavelets' valid_sf_periodization. */
function upsample(input, filter, out) {
  const N = input.length;
  const F = filter.length;
  const half = F / 2;
  const start = F >> 2;
  const end = N + start - (half % 2 ? 0 : 1);
  const put = (o, j, v) => {
    out[o] += filter[2 * j] * v;
    out[o + 1] += filter[2 * j + 1] * v;
  };
  let i = start;
  let o = 0;
  if (half % 2 === 0) {
    let j = 0;
    while (j <= start - 1) {
      for (let k = 0; k < N && j <= start - 1; k++, j++) {
        out[2 * N - 1] += filter[2 * (start - 1 - j)] * input[k];
        out[0] += filter[2 * (start - 1 - j) + 1] * input[k];
      }
    }
    for (; j <= N + start - 1 && j < half; j++) {
      out[2 * N - 1] += filter[2 * j] * input[N + start - 1 - j];
      out[0] += filter[2 * j + 1] * input[N + start - 1 - j];
    }
    while (j < half) {
      for (let k = 0; k < N && j < half; k++, j++) {
        out[2 * N - 1] += filter[2 * j] * input[N - 1 - k];
        out[0] += filter[2 * j + 1] * input[N - 1 - k];
      }
    }
    o = 1;
  }
  const wrapLeft = (j) => {
    while (j < half) for (let k = 0; k < N && j < half; k++, j++) put(o, j, input[N - 1 - k]);
  };
  const wrapRight = (j) => {
    while (i - j >= N) {
      for (let k = 0; k < N && i - j >= N; k++, j++) {
        out[o] += filter[2 * (i - N - j)] * input[k];
        out[o + 1] += filter[2 * (i - N - j) + 1] * input[k];
      }
    }
    return j;
  };
  for (; i < half && i < N; i++, o += 2) {
    let j = 0;
    for (; j <= i; j++) put(o, j, input[i - j]);
    wrapLeft(j);
  }
  for (; i < N; i++, o += 2) for (let j = 0; j < half; j++) put(o, j, input[i - j]);
  for (; i < half && i < end; i++, o += 2) {
    let j = wrapRight(0);
    for (; j <= i && j < half; j++) put(o, j, input[i - j]);
    wrapLeft(j);
  }
  for (; i < end; i++, o += 2) {
    let j = wrapRight(0);
    for (; j <= i && j < half; j++) put(o, j, input[i - j]);
  }
}

/** One inverse level of a 1D signal: the approximation's upsampling, then the detail's. */
function synthesis(a, d, [lo, hi]) {
  const out = new Float64Array(2 * a.length);
  upsample(a, lo, out);
  upsample(d, hi, out);
  return out;
}

/** Applies `synthesis` along an axis to pairs of arrays of one shape. */
function mergeAlong(a, d, axis, filters) {
  const out = axis === 1 ? array(a.rows, 2 * a.cols) : array(2 * a.rows, a.cols);
  const lines = axis === 1 ? a.rows : a.cols;
  const n = axis === 1 ? a.cols : a.rows;
  const index = (cols, l, i) => (axis === 1 ? l * cols + i : i * cols + l);
  for (let l = 0; l < lines; l++) {
    const line = (x) => Float64Array.from({ length: n }, (_, i) => x.data[index(x.cols, l, i)]);
    synthesis(line(a), line(d), filters).forEach((v, i) => (out.data[index(out.cols, l, i)] = v));
  }
  return out;
}

/** waverec2 of the dequantised bands in mode periodization (idwt2: along the rows, then
 * down the columns), each approximation cut to its details' shape; the first rows x cols. */
export function inversePeriodized2d(bands, shapes, rows, cols, wavelet, levels) {
  const filters = FILTERS[wavelet];
  let a = array(shapes[0].rows, shapes[0].cols, bands[0]);
  for (let l = levels; l >= 1; l--) {
    const b = 1 + 3 * (levels - l);
    const { rows: r, cols: c } = shapes[b];
    a = cut(a, r, c);
    const [h, v, d] = [0, 1, 2].map((k) => array(r, c, bands[b + k]));
    a = mergeAlong(mergeAlong(a, v, 1, filters), mergeAlong(h, d, 1, filters), 0, filters);
  }
  return cut(a, rows, cols).data;
}

/** The first r x c values of a 2D array. */
function cut(x, r, c) {
  if (x.rows === r && x.cols === c) return x;
  const out = array(r, c);
  for (let i = 0; i < r; i++) out.data.set(x.data.subarray(i * x.cols, i * x.cols + c), i * c);
  return out;
}
