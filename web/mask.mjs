// The mask of `mzc-dwt2d 8.0` (spec/dwt2d.md, Version 8.0): predicted flips through adaptive
// binary models, read from the payload's rANS state (dwt2d.mjs's Payload: hi, lo, words) before
// the bands. Mirrors mzc/codecs/dwt2d/_rows.c's decode_flips.

import { fail } from "./header.mjs";

const BIN_LIMIT = 65536;       // a model's counts stop changing at n0 + n1 = 65536
const PREFIX = 16;             // unary class models P[0..15] and top-bit models X[0..15] per set
const BINS = 2 + 2 * PREFIX;   // per context set: Z, S, P, X
const MAX_CLASS = 40;
const SAME_SET = 1, NEAR_SET = 19, GAP_SET = 21, SETS = 23;
const TWO24 = 16777216;

/** One decision of P(1) = f1 / 2^24: m = x mod 2^24, 1 when m >= F0, x = F (x >> 24) + m - B,
 * then refilled (Payload.settle); exact in doubles (F and x >> 24 split so that every product
 * stays under 2^53). */
function decision(payload, f1) {
  const f0 = TWO24 - f1;
  const m = payload.lo & 0xffffff;
  const bit = m >= f0 ? 1 : 0;
  const f = bit ? f1 : f0;
  const top = payload.hi >>> 12, bottom = ((payload.hi & 0xfff) * 256) + (payload.lo >>> 24);   // x >> 24 = top 2^20 + bottom
  const t1 = f * top;                                   // < 2^44
  const t2 = f * bottom + m - (bit ? f0 : 0);           // < 2^45
  const t1hi = Math.floor(t1 / 4096);
  payload.settle(t1hi, (t1 - t1hi * 4096) * 1048576 + t2);   // x' = t1hi 2^32 + low
  return bit;
}

/** A decision of the adaptive model at counts[i], counts[i + 1] (n0, n1), which it then updates. */
function adaptive(payload, counts, i) {
  const n = counts[i] + counts[i + 1];
  const bit = decision(payload, Math.floor(((2 * counts[i + 1] + 1) * TWO24) / (2 * n + 2)));
  if (n < BIN_LIMIT) counts[i + bit]++;
  return bit;
}

/** An integer of the context set starting at counts[at]: nonzero, sign, class in unary, the top
 * bit below the leading 1 by class, the rest of probability 1/2; null past MAX_CLASS. */
function integer(payload, counts, set, signed) {
  const at = 2 * BINS * set;
  if (!adaptive(payload, counts, at)) return 0;
  const negative = signed && adaptive(payload, counts, at + 2);
  let k = 0;
  while (adaptive(payload, counts, at + 2 * (2 + Math.min(k, PREFIX - 1)))) if (++k > MAX_CLASS) return null;
  let m = 1;
  if (k) m = 2 + adaptive(payload, counts, at + 2 * (2 + PREFIX + Math.min(k, PREFIX - 1)));
  for (let j = 1; j < k; j++) m = 2 * m + decision(payload, TWO24 / 2);
  return negative ? -m : m;
}

/** The mask (rows x cols, 1 at valid nodes) of an 8.0 payload, each row from the one above. */
export function decodeFlips(payload, rows, cols) {
  const counts = new Float64Array(2 * BINS * SETS);
  const mask = new Uint8Array(rows * cols);
  let above = [], moves = [], residuals = [];
  const bad = (r) => fail("data", `mask row ${r + 1} has spans outside the row, out of order or too many`);
  for (let r = 0; r < rows; r++) {
    const d = integer(payload, counts, 0, true);
    if (d === null || d < -above.length / 2 || d > Math.ceil(cols / 2) - above.length / 2) bad(r);
    const n = above.length + 2 * d;
    const flips = new Array(n);
    if (n && n === above.length) {
      for (let i = 0, low = 0; i < n; low = flips[i++] + 1) {
        const set = SAME_SET + (i % 2) + 2 * (Math.sign(residuals[i]) + 1) + 6 * (Math.sign(moves[i]) + 1);
        const v = integer(payload, counts, set, true);
        const f = v === null ? -1 : above[i] + moves[i] + v;
        if (f < low || f > cols) bad(r);
        moves[i] += v;
        residuals[i] = v;
        flips[i] = f;
      }
    } else {
      const next = [0, 1];
      for (let i = 0, low = 0; i < n; low = flips[i++] + 1) {
        while (next[i % 2] < above.length && above[next[i % 2]] < low) next[i % 2] += 2;
        const near = next[i % 2] < above.length;
        const v = integer(payload, counts, near ? NEAR_SET + (i % 2) : GAP_SET + Math.min(i, 1), near);
        const f = v === null ? -1 : (near ? above[next[i % 2]] : low) + v;
        if (f < low || f > cols) bad(r);
        flips[i] = f;
      }
      moves = new Array(n).fill(0);
      residuals = new Array(n).fill(0);
    }
    for (let i = 0; i < n; i += 2) mask.fill(1, r * cols + flips[i], r * cols + flips[i + 1]);
    above = flips;
  }
  return mask;
}
