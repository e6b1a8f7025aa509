// The inverse transforms of the row codecs dft, dct and dwt (spec/dft.md, dct.md, dwt.md).
// spec/arithmetic.md promises their bits only for given numpy, SciPy and PyWavelets
// versions, and to one part in 10^12 across them: these direct sums meet the latter.

import { FILTERS } from "./pywt.mjs";

/** s(j) = a0 + sum (an cos(2 pi n j/m) + bn sin(2 pi n j/m)) + aN (-1)^j (even m only). */
export function dftRow(a0, aN, an, bn, L, m) {
  return Array.from({ length: m }, (_, j) => {
    let s = a0;
    for (let n = 1; n <= L; n++) {
      const angle = (2 * Math.PI * ((n * j) % m)) / m;
      s += (an[n - 1] ?? 0) * Math.cos(angle) + (bn[n - 1] ?? 0) * Math.sin(angle);
    }
    return m % 2 === 0 ? s + aN * (j % 2 ? -1 : 1) : s;
  });
}

/** The inverse orthonormal DCT-II of the kept coefficients B(1..K), the rest 0. */
export function dctRow(B, m) {
  const cosines = Array.from({ length: 4 * m }, (_, i) => Math.cos((Math.PI * i) / (2 * m)));
  return Array.from({ length: m }, (_, n) => {
    let s = 0;
    B.forEach((b, k) => {
      s += (k ? Math.sqrt(2 / m) : 1 / Math.sqrt(m)) * b * cosines[((2 * n + 1) * k) % (4 * m)];
    });
    return s;
  });
}

/** The lengths vector L (len(A_J), len(D_J), ..., len(D_1), m) of a row of m samples, or
 * null for a wavelet without filters here. J = min(level, floor(log2(m / (F - 1)))). */
export function dwtLengths(wavelet, level, m) {
  const filters = FILTERS[wavelet === "db1" ? "haar" : wavelet];
  if (!filters) return null;
  const F = filters[0].length;
  let J = 0;
  while (J < level && 2 ** (J + 1) * (F - 1) <= m) J++;
  const lengths = [m];
  for (let l = 1; l <= J; l++) lengths.unshift(Math.floor((lengths[0] + F - 1) / 2));
  return [lengths[0], ...lengths];
}

/** pywt.waverec(C padded with zeros, wavelet, mode="symmetric"), its first m values. */
export function dwtRow(kept, L, wavelet) {
  const [lo, hi] = FILTERS[wavelet === "db1" ? "haar" : wavelet];
  const C = Float64Array.from({ length: L.slice(0, -1).reduce((a, b) => a + b, 0) }, (_, i) => kept[i] ?? 0);
  if (L.length === 2) return Array.from(C.subarray(0, L[1]));
  let a = C.subarray(0, L[0]);
  let at = L[0];
  for (const n of L.slice(1, -1)) {
    const d = C.subarray(at, at + n);
    at += n;
    if (a.length === d.length + 1) a = a.subarray(0, d.length);
    a = idwtValid(a, d, lo, hi);
  }
  return Array.from(a.subarray(0, L[L.length - 1]));
}

/** One inverse level, PyWavelets' upsampling_convolution_valid_sf of a with rec_lo, then
 * of d with rec_hi, into 2N - F + 2 values. */
function idwtValid(a, d, lo, hi) {
  const F = lo.length;
  const N = a.length;
  const out = new Float64Array(2 * N - F + 2);
  for (const [input, filter] of [[a, lo], [d, hi]]) {
    for (let o = 0, i = F / 2 - 1; i < N; i++, o += 2) {
      let even = 0;
      let odd = 0;
      for (let j = 0; j < F / 2; j++) {
        even += filter[2 * j] * input[i - j];
        odd += filter[2 * j + 1] * input[i - j];
      }
      out[o] += even;
      out[o + 1] += odd;
    }
  }
  return out;
}
