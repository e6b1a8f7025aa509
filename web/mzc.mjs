// mzc's decoders in one dependency-free ES module, written from spec/ alone.
//
//   import { decode, writeZgrid } from "./mzc.mjs";
//   const grid = decode(bytes);     // {kind, version, rows, cols, z: Float64Array, d1, d2, ...,
//                                   //  colors: Uint8Array rows * cols * 3 of a z-grid 5.x or 6.0
//                                   //  or a dwt2d file with colours (7.0 to 10.x, 11.0's tiles),
//                                   //  fineColors, colourScale: a 6.0's samples K times finer}
//   const zg = writeZgrid(grid);    // the raw float64 z-grid `mzc decode` writes
//
// decode() reads the formats of DECODERS below. Every bad file throws an MzcError with one
// line of text; nothing is returned half decoded.

import { MzcError, fail, parseMagic, splitHeader, writeZgrid, formatNumber, checkMajor } from "./header.mjs";
import { compactMagic } from "./compact.mjs";
import { decodeDwt2d, decodeCompact } from "./dwt2d.mjs";
import { withColours } from "./colour.mjs";
import { ROW_CODECS } from "./rows.mjs";
import { decodeZgrid } from "./zgrid.mjs";

export { MzcError, writeZgrid, formatNumber };

/** Each format's decoder by the kind of its magic line. */
const DECODERS = { dwt2d: (...file) => decodeDwt2d(...file, withColours), zgrid: decodeZgrid, ...ROW_CODECS };

/** The major versions read of each kind, [oldest, newest] (tests/test_web.py asks for them). */
export const READS = { dwt2d: [2, 11], zgrid: [1, 6], poly: [1, 2], dft: [1, 2], dct: [1, 2], dwt: [1, 2] };

/** Decodes the bytes of an mzc file into its grid; throws MzcError on any bad file. */
export function decode(bytes) {
  if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
  const compact = compactMagic(bytes);
  const { lines, body } = compact ? {} : splitHeader(bytes);
  const magic = compact ?? parseMagic(lines[0]);
  const decoder = DECODERS[magic.kind];
  if (!decoder) fail(null, `mzc-${magic.kind} is not a format this decoder reads`);
  checkMajor(magic, ...READS[magic.kind]);
  const grid = compact ? withColours(decodeCompact(bytes, compact.end, magic)) : decoder(bytes, lines, body, magic);
  checkMagnitudes(grid);
  return { kind: magic.kind, version: `${magic.major}.${magic.minor}`, ...grid };
}

const MAX_MAGNITUDE = 1e100;

/** Refuses a grid whose origin, transform shift or heights exceed 10^100 in magnitude, as
 * mzc's readers do (mzc.limits; spec/zgrid.md says only "finite"). */
function checkMagnitudes(grid) {
  const t = grid.transform ?? [];
  largest(grid.origin, "origin");
  largest([t[3], t[7], t[11]].filter((v) => v !== undefined), "transform");
  largest(grid.z, "data");
}

/** Refuses values (an array or a typed array) of which one exceeds 10^100 in magnitude. */
function largest(values, field) {
  for (let i = 0; i < values.length; i++) {
    const v = Math.abs(values[i]);
    if (v > MAX_MAGNITUDE) fail(field, `${v.toPrecision(3)} is beyond ${MAX_MAGNITUDE} in magnitude`);
  }
}
