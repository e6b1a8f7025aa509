// The text header shared by every mzc format (spec/zgrid.md), its CRC-32 check, and the
// raw z-grid writer: the parts of mzc.mjs that every format's decoder uses.

/** A refused file: one line naming the field and what is wrong with it. */
export class MzcError extends Error {}

/** Throws the MzcError of a field (null: of the whole file). */
export const fail = (field, message) => {
  throw new MzcError(field ? `${field}: ${message}` : message);
};

// ---------------------------------------------------------------------------------------
// Text header (spec/zgrid.md, Layout and Header lines)

const MAX_NODES = 100_000_000;
const TEXT = new TextDecoder("utf-8", { fatal: true });
const SPACE = "\\t-\\r\\x1c-\\x20\\x85\\xa0\\u1680\\u2000-\\u200a\\u2028\\u2029\\u202f\\u205f\\u3000";   // Python's str.isspace()
const SPACES = new RegExp(`[${SPACE}]+`, "u");
const NOT_TOKEN = new RegExp(`[${SPACE}\\x00-\\x1f\\x7f]`, "u");
const NOT_PRINTABLE = /[\p{C}\p{Z}]/u;   // where Python's str.isprintable() is false (but for " ")
const NUMBER = /^[+-]?(\d+(_\d+)*\.?(\d+(_\d+)*)?|\.\d+(_\d+)*)([eE][+-]?\d+)?$/;

/** A header word as Python's float() reads a finite decimal (`12`, `-0.25`, `1e-3`, `1_000`),
 * else NaN; with `underscores` false, as mzc reads a row's numbers (no `_`). */
export function pythonFloat(word, underscores = true) {
  if (!NUMBER.test(word) || (!underscores && word.includes("_"))) return NaN;
  return Number(word.replace(/_/g, ""));
}

/** A line's words, split as Python's str.split() splits them. */
export const words = (line) => line.split(SPACES).filter((w) => w !== "");

/** The bytes up to and including the `data` line, split into text lines, and the offset of
 * the body that follows it. */
export function splitHeader(bytes) {
  let start = 0;
  const lines = [];
  for (;;) {
    const end = bytes.indexOf(10, start);
    if (end < 0) fail("data", "no `data` line: the file was cut short or is not an mzc file");
    let line;
    try {
      line = TEXT.decode(bytes.subarray(start, end));
    } catch {
      fail(null, `line ${lines.length + 1} is not UTF-8 text`);
    }
    lines.push(line);
    start = end + 1;
    if (line === "data" || line === "data\r") return { lines, body: start };
  }
}

/** A text body's lines as mzc splits them (Python's str.splitlines(): `\n`, `\r\n`, and also
 * a lone `\r`, `\v`, `\f`, ...), without the NUL bytes that may pad its end and trailing
 * blank lines. */
export function bodyLines(body) {
  let end = body.length;
  while (end && body[end - 1] === 0) end--;
  let text;
  try {
    text = TEXT.decode(body.subarray(0, end));
  } catch {
    fail("data", "data is not UTF-8 text");
  }
  const lines = text.split(/\r\n|[\n\r\v\f\x1c-\x1e\x85\u2028\u2029]/u);
  while (lines.length && !words(lines[lines.length - 1]).length) lines.pop();
  return lines;
}

/** The kind and version of a magic line `mzc-KIND MAJOR.MINOR`. */
export function parseMagic(line) {
  const m = /^mzc-([a-z0-9]+) (\d+)\.(\d+)$/.exec(line);
  if (!m) fail(null, "not an mzc file (no `mzc-KIND MAJOR.MINOR` magic line)");
  return { kind: m[1], major: Number(m[2]), minor: Number(m[3]) };
}

/** Header lines as a map keyword -> values (comments and blank lines dropped); a keyword
 * given twice, or a line ending in \r when `crlf` is refused, is an error. */
export function headerFields(lines, crlf) {
  const fields = new Map();
  for (const raw of lines.slice(1, -1)) {
    if (raw.endsWith("\r") && !crlf) fail("data", "header line ends in \\r\\n (a text-mode copy corrupts the payload)");
    const line = raw.replace(/\r$/, "");
    const [keyword, ...values] = words(line);
    if (keyword === undefined || line.startsWith("#")) continue;
    if (fields.has(keyword)) fail(keyword, "given twice");
    fields.set(keyword, values);
  }
  if (lines[lines.length - 1].endsWith("\r") && !crlf) fail("data", "header line ends in \\r\\n");
  return fields;
}

/** A header reader over the fields map: typed accessors that refuse bad values by name. */
export function fieldReader(fields) {
  const valuesOf = (key, count, required) => {
    const v = fields.get(key);
    if (v === undefined) {
      if (required) fail(key, "missing");
      return undefined;
    }
    if (count !== undefined && v.length !== count) fail(key, `expected ${count} value(s), found ${v.length}`);
    return v;
  };
  const float = (key, word) => {
    const x = pythonFloat(word);
    if (!Number.isFinite(x)) fail(key, `not a finite number: ${JSON.stringify(word.slice(0, 40))}`);
    return x;
  };
  return {
    has: (key) => fields.has(key),
    words: valuesOf,
    floats(key, count, required = true) {
      const v = valuesOf(key, count, required);
      return v && v.map((w) => float(key, w));
    },
    float(key, required = true, low = -Infinity, high = Infinity) {
      const v = valuesOf(key, 1, required);
      if (!v) return undefined;
      const x = float(key, v[0]);
      if (!(x >= low && x <= high)) fail(key, `${v[0]} is outside ${low} .. ${high}`);
      return x;
    },
    integer(key, low, high, required = true) {
      const v = valuesOf(key, 1, required);
      if (!v) return undefined;
      if (!/^[+-]?\d+$/.test(v[0])) fail(key, `not an integer: ${v[0]}`);
      const n = Number(v[0]);
      if (!(n >= low && n <= high)) fail(key, `${v[0]} is outside ${low} .. ${high}`);
      return n;
    },
    word(key, choices, required = true) {
      const v = valuesOf(key, 1, required);
      if (!v) return undefined;
      if (choices && !choices.includes(v[0])) fail(key, `${v[0]} is not one of ${choices.join(", ")}`);
      return v[0];
    },
  };
}

/** A `units` or `nodata` token: 1 to 64 printable characters, no space or control. */
function token(h, key, fallback) {
  const w = h.word(key, null, false);
  if (w === undefined) return fallback;
  if ([...w].length > 64 || NOT_TOKEN.test(w)) fail(key, "not a token of 1 to 64 printable characters");
  return w;
}

const TWO_PI = 2 * Math.PI;

/** The grid fields of spec/zgrid.md common to every format, checked as the spec says:
 * `projected` says whether the version may hold a central projection, `georef` whether
 * its `crs` and `raster` lines are read (older minors ignore them). */
export function gridFields(h, { projected, georef, counted }) {
  const rows = h.integer("rows", 1, 1_000_000);
  const cols = h.integer("cols", 1, 1_000_000);
  if (rows * cols > MAX_NODES) fail("rows", `${rows} x ${cols} is more than ${MAX_NODES} nodes`);
  const d1 = h.float("d1", true, 1e-50, 1e50);
  const d2 = h.float("d2", true, 1e-50, 1e50);
  const origin = h.floats("origin", 2, false) ?? [0, 0];
  let projection = "planar";
  if (h.has("projection")) {
    projection = h.word("projection", ["planar", "cylindrical", "spherical"]);
    if (projection !== "planar" && !projected) fail("projection", `${projection} needs a newer major version of this format`);
  }
  let radius;
  if (projection === "planar") {
    if (h.has("radius")) fail("radius", "only a central projection has a radius");
  } else {
    radius = h.float("radius", true, 1e-50, 1e50);
    if (cols * d2 > TWO_PI * radius * (1 + 1e-9)) fail("d2", "the columns span more than a full turn");
    if (projection === "spherical") {
      const pole = (Math.PI / 2) * radius * (1 + 1e-9);
      if (Math.abs(origin[1]) > pole || Math.abs(origin[1] + (rows - 1) * d1) > pole) fail("d1", "the rows pass a pole");
    }
  }
  const transform = h.floats("transform", 12, false);
  if (transform) checkRotation(transform);
  const grid = {
    rows, cols, d1, d2, origin, projection, radius, transform,
    units: token(h, "units", undefined),
    nodata: token(h, "nodata", "nan"),
  };
  if (georef) Object.assign(grid, georeference(h, projection));
  if (counted && h.has("source_vertices")) grid.sourceVertices = sourceVertices(h);
  return grid;
}

/** Refuses a transform whose 3 x 3 part is not a rotation (orthonormal, det +1, 1e-6). */
function checkRotation(t) {
  const col = (j) => [t[j], t[4 + j], t[8 + j]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const [x, y, z] = [col(0), col(1), col(2)];
  const cross = [x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]];
  const ok = [[x, x, 1], [y, y, 1], [z, z, 1], [x, y, 0], [x, z, 0], [y, z, 0]].every(([a, b, e]) => Math.abs(dot(a, b) - e) <= 1e-6);
  if (!ok || Math.abs(dot(cross, z) - 1) > 1e-6) fail("transform", "the 3x3 part is not a rotation (orthonormal, det +1)");
}

/** The `crs` (rest of the line, runs of spaces as one) and `raster` lines of a planar grid. */
function georeference(h, projection) {
  const out = {};
  if (h.has("crs")) {
    const text = h.words("crs").join(" ");
    if (text.length < 1 || [...text].length > 16384) fail("crs", "WKT of 1 to 16,384 characters expected");
    if (NOT_PRINTABLE.test(text.replaceAll(" ", ""))) fail("crs", "the CRS holds a control character");
    out.crs = text;
  }
  if (h.has("raster")) {
    const [cells, rows, sample] = h.words("raster", 3);
    if (!["area", "point"].includes(cells) || !["down", "up"].includes(rows)
      || !["uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64"].includes(sample)) {
      fail("raster", `not CELLS ROWS SAMPLE: ${h.words("raster").join(" ")}`);
    }
    out.raster = [cells, rows, sample];
  }
  if ((out.crs || out.raster) && projection !== "planar") fail("crs", "a projected grid has no crs or raster");
  return out;
}

// ---------------------------------------------------------------------------------------
// Charts (spec/zgrid.md, Charts)

/** The chart views in the order of their numbers in a dwt2d file. */
export const VIEWS = ["+z", "-z", "+x", "-x", "+y", "-y"];

/** Refuses charts that leave the array, overlap, or leave a valid node (z not NaN) outside
 * them, and a multi-chart grid that is not planar at origin 0 0 without crs and raster. */
export function checkCharts(charts, grid, z) {
  if (grid.projection !== "planar" || grid.crs !== undefined || grid.raster !== undefined) {
    fail("charts", "a multi-chart grid is planar, without crs or raster");
  }
  if (grid.origin[0] !== 0 || grid.origin[1] !== 0) fail("origin", "a multi-chart grid's origin is 0 0");
  const owner = chartLabels(charts, grid.rows, grid.cols);
  z.forEach((v, i) => {
    if (!Number.isNaN(v) && owner[i] < 0) fail("charts", "a valid node lies outside every chart");
  });
}

/** The number of the chart each node (row by row) of a rows x cols multi-chart grid lies in, -1
 * outside them (mzc.grid.chart_labels), refusing charts that leave the array or overlap: the
 * labels checkCharts reads, and colour.mjs's fineMask. */
export function chartLabels(charts, rows, cols) {
  const label = new Int32Array(rows * cols).fill(-1);
  charts.forEach((c, n) => {
    if (c.row0 < 0 || c.col0 < 0 || c.rows < 1 || c.cols < 1 || c.row0 + c.rows > rows || c.col0 + c.cols > cols) {
      fail("charts", `chart ${n + 1} does not lie inside the ${rows} x ${cols} array`);
    }
    for (let r = c.row0; r < c.row0 + c.rows; r++) {
      for (let col = c.col0; col < c.col0 + c.cols; col++) {
        if (label[r * cols + col] >= 0) fail("charts", `charts ${label[r * cols + col] + 1} and ${n + 1} overlap`);
        label[r * cols + col] = n;
      }
    }
  });
  return label;
}

// ---------------------------------------------------------------------------------------
// CRC-32 (spec/zgrid.md, Checksum): zlib's.

const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; n++) {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();

/** The CRC-32 of the byte ranges given, as one stream. */
export function crc32(...parts) {
  let c = 0xffffffff;
  for (const bytes of parts) for (let i = 0; i < bytes.length; i++) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

/** Checks the `crc32` line, when present (required when `required`), over the file up to
 * `end` (all of it, or a tiled file's text header) without that line, before anything after
 * `data` is read. */
export function checkChecksum(bytes, lines, fields, required, end = bytes.length) {
  if (!fields.has("crc32")) {
    if (required) fail("crc32", "missing (this version requires a checksum)");
    return;
  }
  const words = fields.get("crc32");
  if (words.length !== 1 || !/^[0-9a-f]{8}$/.test(words[0])) fail("crc32", "not 8 lowercase hexadecimal digits");
  let start = 0;
  for (const line of lines) {
    const next = start + new TextEncoder().encode(line).length + 1;
    if (/^crc32[ \t]/.test(line)) {
      if (crc32(bytes.subarray(0, start), bytes.subarray(next, end)) !== parseInt(words[0], 16)) {
        fail("crc32", "checksum mismatch: the file was damaged, cut short or added to");
      }
      return;
    }
    start = next;
  }
}

// ---------------------------------------------------------------------------------------
// Writing the z-grid (spec/zgrid.md: header lines in the writers' order, raw float64 body)

/** The shortest text that reads back as x, as Python's repr with a trailing `.0` dropped
 * (`3`, `-0`, `0.1`, `1e-05`, `1e+16`, `1.2345678901234568e+17`). */
export function formatNumber(x) {
  if (!Number.isFinite(x)) return String(x);
  const [mantissa, exp] = x.toExponential().split("e");
  const e = Number(exp);
  const digits = mantissa.replace(/^-/, "").replace(".", "");
  const sign = x < 0 || Object.is(x, -0) ? "-" : "";
  if (e < -4 || e >= 16) {
    const m = digits.length > 1 ? `${digits[0]}.${digits.slice(1)}` : digits;
    return `${sign}${m}e${e < 0 ? "-" : "+"}${String(Math.abs(e)).padStart(2, "0")}`;
  }
  if (e < 0) return `${sign}0.${"0".repeat(-e - 1)}${digits}`;
  if (digits.length <= e + 1) return sign + digits + "0".repeat(e + 1 - digits.length);
  return `${sign}${digits.slice(0, e + 1)}.${digits.slice(e + 1)}`;
}

/** The identity transform [R | t], row by row. */
export const IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0];

/** The header lines of a grid as mzc's z-grid writer writes them, without magic and data. */
function zgridHeaderLines(grid) {
  const f = formatNumber;
  const lines = [`rows ${grid.rows}`, `cols ${grid.cols}`, `d1 ${f(grid.d1)}`, `d2 ${f(grid.d2)}`,
    `origin ${f(grid.origin[0])} ${f(grid.origin[1])}`];
  if (grid.projection !== "planar") lines.push(`projection ${grid.projection}`, `radius ${f(grid.radius)}`);
  if (grid.transform && grid.transform.some((v, i) => v !== IDENTITY[i])) lines.push(`transform ${grid.transform.map(f).join(" ")}`);
  if (grid.units !== undefined) lines.push(`units ${grid.units}`);
  lines.push(`nodata ${grid.nodata}`);
  if (grid.crs !== undefined) lines.push(`crs ${grid.crs}`);
  if (grid.raster !== undefined) lines.push(`raster ${grid.raster.join(" ")}`);
  if (grid.charts) lines.push(`charts ${grid.charts.map((c) => [c.view, c.row0, c.col0, c.rows, c.cols, c.i0, c.j0].join(" ")).join(" ")}`);
  if (grid.sourceVertices !== undefined) lines.push(`source_vertices ${grid.sourceVertices}`);
  return lines;
}

/** The version of z-grid `mzc decode` writes for a grid: 6.0 with colours finer than the nodes,
 * 5.0 with colours (5.1 with `crs` or `raster` too), 4.0 for a multi-chart grid, 3.1 with `crs` or
 * `raster`, else 3.0; with `source_vertices`, the minor that reads it (COUNTED_SINCE: 3.2, 4.1, 5.2). */
function zgridVersion(grid) {
  if (grid.fineColors) return "6.0";
  const georeferenced = grid.crs !== undefined || grid.raster !== undefined;
  const [major, minor] = grid.colors ? [5, georeferenced ? 1 : 0] : grid.charts ? [4, 0] : [3, georeferenced ? 1 : 0];
  return `${major}.${grid.sourceVertices === undefined ? minor : COUNTED_SINCE[major]}`;
}

/** Major -> the minor of a z-grid that adds the `source_vertices` line (Header lines). */
export const COUNTED_SINCE = { 1: 2, 2: 1, 3: 2, 4: 1, 5: 2, 6: 0 };
const MAX_SOURCE_VERTICES = 2n ** 53n;

/** The `source_vertices` line of a version that reads it: an integer 1 .. 2^53, compared exactly. */
function sourceVertices(h) {
  const [word] = h.words("source_vertices", 1);
  if (!/^[+-]?\d{1,18}$/.test(word ?? "")) fail("source_vertices", `not an integer: ${word}`);
  const n = BigInt(word);
  if (n < 1n || n > MAX_SOURCE_VERTICES) fail("source_vertices", `${word} is outside 1 .. ${MAX_SOURCE_VERTICES}`);
  return Number(n);
}

/** The grid as the raw float64 z-grid `mzc decode` writes by default (zgridVersion), every
 * NaN the one quiet NaN, the colours (rows x cols x 3 bytes, or the finer samples with their
 * `colour_scale`) after the heights when it has them. */
export function writeZgrid(grid) {
  const image = grid.fineColors ?? grid.colors;
  const colours = image ? ["colours rgb8", ...(grid.fineColors ? [`colour_scale ${grid.colourScale}`] : [])] : [];
  const enc = new TextEncoder();
  const head = enc.encode([`mzc-zgrid ${zgridVersion(grid)}`, ...zgridHeaderLines(grid), "raw float64", ...colours, ""].join("\n"));
  const body = new Uint8Array(grid.rows * grid.cols * 8 + (image ? image.length : 0));
  if (image) body.set(image, grid.rows * grid.cols * 8);
  const view = new DataView(body.buffer);
  grid.z.forEach((v, i) => {
    if (Number.isNaN(v)) view.setUint32(i * 8 + 4, 0x7ff80000, true);
    else view.setFloat64(i * 8, v, true);
  });
  const tail = enc.encode("data\n");
  const crc = crc32(head, tail, body).toString(16).padStart(8, "0");
  const crcLine = enc.encode(`crc32 ${crc}\n`);
  const out = new Uint8Array(head.length + crcLine.length + tail.length + body.length);
  let at = 0;
  for (const part of [head, crcLine, tail, body]) {
    out.set(part, at);
    at += part.length;
  }
  return out;
}


/** Refuses a major version outside oldest .. newest of a format. */
export function checkMajor(magic, oldest, newest) {
  if (magic.major > newest) fail(null, `mzc-${magic.kind} version ${magic.major}.x is newer than this decoder reads (${newest}.x); upgrade`);
  if (magic.major < oldest) fail(null, `mzc-${magic.kind} ${magic.major}.x was a draft of this format and is not read`);
}
