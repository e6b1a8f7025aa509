// The original mesh web/viewer.html measures a decoded surface against: a PLY (ascii or
// binary: its vertex element's x, y, z and its faces' vertex lists) or an OBJ (its `v` and `f`
// lines), read minimally, polygons split into fans; and the distance from a point to it.

const PLY_TYPES = {
  char: ["Int8", 1], int8: ["Int8", 1], uchar: ["Uint8", 1], uint8: ["Uint8", 1],
  short: ["Int16", 2], int16: ["Int16", 2], ushort: ["Uint16", 2], uint16: ["Uint16", 2],
  int: ["Int32", 4], int32: ["Int32", 4], uint: ["Uint32", 4], uint32: ["Uint32", 4],
  float: ["Float32", 4], float32: ["Float32", 4], double: ["Float64", 8], float64: ["Float64", 8],
};

/** {points: Float64Array (n * 3), triangles: Uint32Array (m * 3)} of a PLY or OBJ file's bytes, by its name. */
export function readMesh(bytes, name) {
  return /\.ply$/i.test(name) ? plyMesh(bytes) : objMesh(new TextDecoder().decode(bytes));
}

/** The triangles of a polygon's corners, a fan about its first, pushed onto `out`. */
function pushFan(corners, out) {
  for (let k = 2; k < corners.length; k++) out.push(corners[0], corners[k - 1], corners[k]);
}

/** The `v` and `f` lines of OBJ text (a face corner's vertex before its first `/`; negative: counted back). */
function objMesh(text) {
  const values = [], triangles = [];
  for (const line of text.split(/\r\n|\r|\n/)) {
    const words = line.trim().split(/\s+/);
    if (words[0] === "v") values.push(Number(words[1]), Number(words[2]), Number(words[3]));
    if (words[0] === "f") {
      const count = values.length / 3;
      pushFan(words.slice(1).map((w) => { const i = parseInt(w, 10); return i < 0 ? count + i : i - 1; }), triangles);
    }
  }
  return { points: Float64Array.from(values), triangles: Uint32Array.from(triangles) };
}

/** The header of a PLY: its format, the bytes it takes and its elements with their properties. */
function plyHeader(bytes) {
  const head = new TextDecoder("latin1").decode(bytes.subarray(0, Math.min(bytes.length, 65536)));
  const end = head.search(/end_header\r?\n/);
  if (!head.startsWith("ply") || end < 0) throw new Error("not a PLY file (no ply ... end_header)");
  const elements = [];
  let format = "ascii";
  for (const line of head.slice(0, end).split(/\r?\n/)) {
    const w = line.trim().split(/\s+/);
    if (w[0] === "format") format = w[1];
    if (w[0] === "element") elements.push({ name: w[1], count: Number(w[2]), properties: [] });
    if (w[0] === "property") elements.at(-1).properties.push({ name: w.at(-1), type: w[1], count: w[2], item: w[3] });
  }
  return { format, elements, length: end + head.slice(end).indexOf("\n") + 1 };
}

/** A PLY's vertices' x y z and its faces' first list property, as triangles. */
function plyMesh(bytes) {
  const { format, elements, length } = plyHeader(bytes);
  const vertex = elements.find((e) => e.name === "vertex");
  if (!vertex) throw new Error("the PLY file has no vertex element");
  const axes = ["x", "y", "z"].map((a) => vertex.properties.findIndex((p) => p.name === a));
  if (axes.includes(-1)) throw new Error("the PLY vertices have no x, y or z");
  const points = new Float64Array(vertex.count * 3), triangles = [];
  const read = format === "ascii" ? asciiRecords(bytes.subarray(length)) : binaryRecords(bytes, length, format === "binary_little_endian");
  for (const element of elements) {
    for (let i = 0; i < element.count; i++) {
      const record = read(element);
      if (element === vertex) axes.forEach((p, k) => { points[3 * i + k] = record[p]; });
      if (element.name === "face") pushFan(record.find(Array.isArray) ?? [], triangles);
    }
  }
  return { points, triangles: Uint32Array.from(triangles) };
}

/** A reader of an ascii PLY body's records: read(element) -> its property values (lists as arrays). */
function asciiRecords(body) {
  const words = new TextDecoder().decode(body).split(/\s+/).filter((w) => w !== "");
  let at = 0;
  return (element) => element.properties.map((p) => {
    if (p.type !== "list") return Number(words[at++]);
    const count = Number(words[at++]);
    return words.slice(at, (at += count)).map(Number);
  });
}

/** A reader of a binary PLY body's records from `offset`: read(element) -> its property values. */
function binaryRecords(bytes, offset, little) {
  const data = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const value = (type) => {
    const [name, size] = PLY_TYPES[type] ?? [];
    if (!name) throw new Error(`a PLY property of type ${type} is not read here`);
    const v = data[`get${name}`](offset, little);
    offset += size;
    return v;
  };
  return (element) => element.properties.map((p) => (p.type !== "list" ? value(p.type)
    : Array.from({ length: value(p.count) }, () => value(p.item))));
}

/** The distance from each queried point to a mesh: to the nearest point of the triangles about
 * the mesh's vertex nearest the query (of its vertex alone when it is in no triangle). */
export class Distance {
  constructor({ points, triangles }) {
    this.points = points;
    this.triangles = triangles;
    this.nearest = new NearestVertex(points);
    this.around = incidence(triangles, points.length / 3);
  }

  /** The distance from (x, y, z) to the mesh (see the class). */
  to(x, y, z) {
    const [vertex, squared] = this.nearest.find(x, y, z);
    let best = squared;
    const { start, triangle } = this.around;
    for (let s = start[vertex]; s < start[vertex + 1]; s++) {
      best = Math.min(best, squaredToTriangle([x, y, z], ...[0, 1, 2].map((k) => this.point(this.triangles[3 * triangle[s] + k]))));
    }
    return Math.sqrt(best);
  }

  /** Vertex i's point. */
  point(i) {
    return [this.points[3 * i], this.points[3 * i + 1], this.points[3 * i + 2]];
  }
}

/** {start, triangle}: the triangles about each of `count` vertices, vertex v's at start[v] .. start[v+1]. */
function incidence(triangles, count) {
  const start = new Uint32Array(count + 1);
  for (const v of triangles) start[v + 1]++;
  for (let v = 0; v < count; v++) start[v + 1] += start[v];
  const fill = start.slice(0, -1), triangle = new Uint32Array(triangles.length);
  triangles.forEach((v, corner) => { triangle[fill[v]++] = Math.floor(corner / 3); });
  return { start, triangle };
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/** The squared distance from p to triangle abc (its closest point, by the region p projects to:
 * Ericson, Real-Time Collision Detection, 5.1.5). */
function squaredToTriangle(p, a, b, c) {
  const ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const d1 = dot(ab, ap), d2 = dot(ac, ap);
  const to = (q) => { const d = sub(p, q); return dot(d, d); };
  const at = (t, s) => [a[0] + t * ab[0] + s * ac[0], a[1] + t * ab[1] + s * ac[1], a[2] + t * ab[2] + s * ac[2]];
  if (d1 <= 0 && d2 <= 0) return to(a);
  const bp = sub(p, b), d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return to(b);
  const vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return to(at(d1 / (d1 - d3), 0));
  const cp = sub(p, c), d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return to(c);
  const vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return to(at(0, d2 / (d2 - d6)));
  const va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return to([b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])]);
  }
  const denominator = 1 / (va + vb + vc);
  return to(at(vb * denominator, vc * denominator));
}

/** The nearest of a set of points, by a grid of cubic cells holding a few points each. */
class NearestVertex {
  constructor(points) {
    this.points = points;
    const n = points.length / 3;
    this.low = [0, 1, 2].map((k) => extreme(points, k, Math.min));
    const extent = [0, 1, 2].map((k) => extreme(points, k, Math.max) - this.low[k]);
    this.size = Math.max(Math.cbrt(extent[0] * extent[1] * extent[2] / Math.max(n, 1)), Math.max(...extent) / 1024, 1e-300);
    const dims = () => extent.map((e) => Math.floor(e / this.size) + 1);
    while (dims().reduce((a, b) => a * b) > 4 * n + 64) this.size *= 1.25;   // a flat set: cells of its area
    this.dims = dims();
    const key = Uint32Array.from({ length: n }, (_, i) => this.key(...[0, 1, 2].map((k) => this.cell(k, points[3 * i + k]))));
    this.start = new Uint32Array(this.dims[0] * this.dims[1] * this.dims[2] + 1);
    for (const k of key) this.start[k + 1]++;
    for (let k = 1; k < this.start.length; k++) this.start[k] += this.start[k - 1];
    const fill = this.start.slice(0, -1);
    this.order = new Uint32Array(n);
    key.forEach((k, i) => { this.order[fill[k]++] = i; });
  }

  /** The cell along axis k of coordinate x (clamped to the grid). */
  cell(k, x) {
    return Math.min(Math.max(Math.floor((x - this.low[k]) / this.size), 0), this.dims[k] - 1);
  }

  /** The number of cell (i, j, k). */
  key(i, j, k) {
    return i + this.dims[0] * (j + this.dims[1] * k);
  }

  /** [index, squared distance] of the point nearest (x, y, z): shells of cells about its own,
   * outwards, until the next shell can hold none nearer. */
  find(x, y, z) {
    const at = [this.cell(0, x), this.cell(1, y), this.cell(2, z)];
    let best = Infinity, index = 0;
    for (let shell = 0; shell <= Math.max(...this.dims); shell++) {
      this.forShell(at, shell, (cell) => {
        for (let s = this.start[cell]; s < this.start[cell + 1]; s++) {
          const p = 3 * this.order[s];
          const dx = this.points[p] - x, dy = this.points[p + 1] - y, dz = this.points[p + 2] - z;
          const d = dx * dx + dy * dy + dz * dz;
          if (d < best) { best = d; index = this.order[s]; }
        }
      });
      if (best <= (shell * this.size) ** 2) break;   // the points beyond lie farther
    }
    return [index, best];
  }

  /** Calls visit(cell) for each cell of the grid at Chebyshev distance `shell` from cell `at`. */
  forShell([ci, cj, ck], shell, visit) {
    for (let i = Math.max(ci - shell, 0); i <= Math.min(ci + shell, this.dims[0] - 1); i++) {
      for (let j = Math.max(cj - shell, 0); j <= Math.min(cj + shell, this.dims[1] - 1); j++) {
        const edge = Math.abs(i - ci) === shell || Math.abs(j - cj) === shell;
        for (let k = ck - shell; k <= ck + shell; k += edge ? 1 : 2 * shell) {
          if (k >= 0 && k < this.dims[2]) visit(this.key(i, j, k));
        }
      }
    }
  }
}

/** The smallest or largest (`pick`) of coordinate k of points (n * 3); 0 for none. */
function extreme(points, k, pick) {
  let m = NaN;
  for (let i = k; i < points.length; i += 3) m = Number.isNaN(m) ? points[i] : pick(m, points[i]);
  return Number.isNaN(m) ? 0 : m;
}
