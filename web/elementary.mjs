// The elementary functions of spec/arithmetic.md that the decoders need (dwt2d's slope
// factors need cos; triangulate.mjs's rays sin and cos): binary64 operations in the order
// written, so every machine computes the bits mzc computes.

/** A binary64 constant from C's hexadecimal notation `1.HHHH` and a binary exponent. */
const hex = (mantissa, exponent) => {
  const [whole, frac = ""] = mantissa.split(".");
  return parseInt(whole + frac, 16) * 2 ** (exponent - 4 * frac.length);
};

const PIO2_1 = hex("1.921fb544", 0);
const PIO2_2 = hex("1.0b4611a6", -34);
const PIO2_3 = hex("1.3198a2e037073", -69);
const TWO_OVER_PI = hex("1.45f306dc9c883", -1);
const PI_HI = hex("1.921fb54442d18", 1);
const PIO4 = hex("1.921fb54442d18", -1);

/** F(n) = 1/n!, rounded to nearest (n! is exact in binary64 up to 18). */
const F = (n) => {
  let f = 1;
  for (let i = 2; i <= n; i++) f *= i;
  return 1 / f;
};
const [F3, F4, F5, F6, F7, F8, F9, F10, F11, F12, F13, F14, F15, F16, F17, F18] =
  Array.from({ length: 16 }, (_, i) => F(i + 3));

/** S(r), the sine polynomial on the reduced argument. */
function sinPoly(r) {
  const r2 = r * r;
  return r + (r * r2) * (-F3 + r2 * (F5 + r2 * (-F7 + r2 * (F9 + r2 * (-F11 + r2 * (F13 + r2 * (-F15 + r2 * F17)))))));
}

/** C(r), the cosine polynomial on the reduced argument. */
function cosPoly(r) {
  const r2 = r * r;
  const h = 0.5 * r2;
  const w = 1 - h;
  return w + (((1 - w) - h) + (r2 * r2) * (F4 + r2 * (-F6 + r2 * (F8 + r2 * (-F10 + r2 * (F12 + r2 * (-F14 + r2 * (F16 - r2 * F18))))))));
}

/** [q, r]: the quadrant and reduced argument of |x| (spec/arithmetic.md, sin and cos). */
function reduced(x) {
  let a = Math.abs(x);
  if (a <= PIO4) return [0, a];
  if (a >= 2 ** 20) a %= 2 * PI_HI;
  const k = Math.floor(a * TWO_OVER_PI + 0.5);
  return [k - 4 * Math.floor(k * 0.25), ((a - k * PIO2_1) - k * PIO2_2) - k * PIO2_3];
}

/** cos(x) as spec/arithmetic.md computes it (within 1 ulp for |x| < 2^20). */
export function cos(x) {
  if (!Number.isFinite(x)) return NaN;
  const [q, r] = reduced(x);
  return [cosPoly(r), -sinPoly(r), -cosPoly(r), sinPoly(r)][q];
}

/** sin(x) as spec/arithmetic.md computes it (the central projections' rays). */
export function sin(x) {
  if (!Number.isFinite(x)) return NaN;
  const [q, r] = reduced(x);
  const s = [sinPoly(r), cosPoly(r), -sinPoly(r), -cosPoly(r)][q];
  return x < 0 || Object.is(x, -0) ? -s : s;
}
