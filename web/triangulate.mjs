// The mesh of a decoded grid, as `mzc triangulate --vertices all` makes it (spec/zgrid.md, Connectivity;
// mzc/ops/triangulation.py): its valid nodes' points in the input frame, unused nodes
// dropped, the triangles 1-2-3 of every cell, row by row, then every 2-4-3; the cells
// between the last column and the first of a full turn; a pole row's valid nodes one vertex
// at their mean point; no triangle with a depth-jump edge. Binary64 operations in mzc's
// order, with spec/arithmetic.md's sin and cos, so the points are mzc's bits.
//
//   import { triangulate } from "./triangulate.mjs";
//   const { positions, indices } = triangulate(decode(bytes));   // Float64Array, Uint32Array
//
//   const { local, centre } = recentred(positions);   // Float32Array about the box's centre
//
// A multi-chart grid gives each chart's mesh, one after the other, zipped along their seams
// into one surface by web/zipper.mjs (spec/zgrid.md, Zipping the charts), as mzc zips them.

import { IDENTITY, fail } from "./header.mjs";
import { cos, sin } from "./elementary.mjs";
import { zipCharts, nearestColours } from "./zipper.mjs";

export const JUMP_ANGLE = 3;         // degrees: an edge this close to its node line is a depth jump
export const CHART_JUMP_ANGLE = 30;  // a chart's (its surface faces its lines within 60 degrees)
const FULL_TURN_TOLERANCE = 1e-9;

/** The columns of each chart view's rotation (spec/zgrid.md, Charts), row by row. */
const VIEW_AXES = {
  "+z": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "-z": [[-1, 0, 0], [0, 1, 0], [0, 0, -1]],
  "+x": [[0, 0, -1], [0, 1, 0], [1, 0, 0]], "-x": [[0, 0, 1], [0, 1, 0], [-1, 0, 0]],
  "+y": [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], "-y": [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
};

/** {positions: Float64Array (n * 3), indices: Uint32Array (m * 3)}: the mesh of a decoded
 * grid (see the top). `jumpAngle` in degrees, 0 joining every neighbour; by default 3, or 30
 * within a chart. `zip` false leaves a multi-chart grid's seams open: its charts' meshes one
 * after the other, with `charts`, the chart of each vertex. */
export function triangulate(grid, { jumpAngle, zip = true } = {}) {
  if (!grid.charts) return gridMesh(metricFrame(grid), jumpAngle ?? JUMP_ANGLE);
  const meshes = chartGrids(grid).map((chart) => gridMesh(chart, jumpAngle ?? CHART_JUMP_ANGLE));
  const charts = joined(meshes);
  if (!zip) return charts;
  const zipped = zipCharts(charts.positions, charts.indices, charts.charts, Math.max(grid.d1, grid.d2));
  return charts.colors ? { ...zipped, colors: nearestColours(zipped.positions, charts.positions.length / 3, charts.colors) } : zipped;
}

/** {local: Float32Array, centre: [x, y, z]}: `positions` (Float64Array, n * 3) less the centre
 * of their bounding box ((min + max) / 2 on each axis; 0 0 0 for none), rounded to float32.
 * float32 holds about 7 digits: a georeferenced grid (UTM metres in the millions) or any far
 * from the origin would lose its detail to the offset; about its centre only the mesh's own
 * extent counts. The input frame is local + centre (three.js: a mesh's `position`). */
export function recentred(positions) {
  const low = [Infinity, Infinity, Infinity], high = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    low[i % 3] = Math.min(low[i % 3], positions[i]);
    high[i % 3] = Math.max(high[i % 3], positions[i]);
  }
  const centre = positions.length ? low.map((x, d) => (x + high[d]) / 2) : [0, 0, 0];
  const local = new Float32Array(positions.length);
  for (let i = 0; i < positions.length; i++) local[i] = positions[i] - centre[i % 3];
  return { local, centre };
}

// mzc/georef.py's reading of a WKT: the keywords that open a CRS, by kind, and its ellipsoid and unit.
const CRS_KINDS = {
  geographic: ["GEOGCS", "GEOGCRS", "GEOGRAPHICCRS"], projected: ["PROJCS", "PROJCRS", "PROJECTEDCRS"],
  geodetic: ["GEODCRS", "GEODETICCRS", "GEOCCS"], engineering: ["LOCAL_CS", "ENGCRS", "ENGINEERINGCRS"],
};
const FIRST_CRS = new RegExp(`\\b(${Object.values(CRS_KINDS).flat().join("|")})\\s*\\[`, "i");
const QUOTED = /"(?:[^"]|"")*"/g;
const ELLIPSOID = /\b(?:SPHEROID|ELLIPSOID)\s*\[\s*"[^"]*"\s*,\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)/i;
const ANGLE_UNIT = /\bANGLEUNIT\s*\[\s*"[^"]*"\s*,\s*([-+0-9.eE]+)/i;
const WKT1_UNIT = /\bUNIT\s*\[\s*"[^"]*"\s*,\s*([-+0-9.eE]+)/i;
const WGS84 = [6378137, 298.257223563];

/** Whether a WKT's first CRS (outside quoted names) is geographic: x and y longitude and latitude. */
function isGeographic(wkt) {
  const found = FIRST_CRS.exec(wkt.replace(QUOTED, '""'));
  if (!found) return false;
  const keyword = found[1].toUpperCase();
  if (CRS_KINDS.geographic.includes(keyword)) return true;
  return keyword !== "GEOCCS" && CRS_KINDS.geodetic.includes(keyword) && /\bCS\s*\[\s*ellipsoidal/i.test(wkt.slice(found.index + found[0].length));
}

/** A number of a WKT as Python's float reads the regular expressions' matches (NaN: not one). */
const wktNumber = (text) => (/^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(text) ? Number(text) : NaN);

/** [metres per unit of longitude, per unit of latitude] at `latitude` on the WKT's ellipsoid (mzc's metres_per_unit). */
function metresPerUnit(wkt, latitude) {
  const ellipsoid = ELLIPSOID.exec(wkt);
  const numbers = ellipsoid ? [wktNumber(ellipsoid[1]), wktNumber(ellipsoid[2])] : WGS84;
  const [axis, inverse] = numbers.some(Number.isNaN) ? WGS84 : numbers;
  const flattening = inverse > 0 ? 1 / inverse : 0;
  const squared = flattening * (2 - flattening);
  const found = ANGLE_UNIT.exec(wkt) ?? WKT1_UNIT.exec(wkt);
  const factor = found ? wktNumber(found[1]) : Math.PI / 180;
  const unit = factor > 0 && factor < 10 ? factor : Math.PI / 180;
  const phi = latitude * unit;
  const sine = sin(phi);
  const across = 1 - squared * sine * sine;
  return [axis / Math.sqrt(across) * cos(phi) * unit, axis * (1 - squared) / (across * Math.sqrt(across)) * unit];
}

/** The grid itself, or a geographic one's nodes in metres of the local equirectangular
 * projection about its centre, as mzc measures it before it triangulates (mzc's metric_frame). */
function metricFrame(grid) {
  if (!grid.crs || !isGeographic(grid.crs)) return grid;
  if (grid.transform && grid.transform.some((v, i) => v !== IDENTITY[i])) {
    fail("transform", "a geographic grid turned by a transform cannot be measured in metres");
  }
  const centre = [grid.origin[0] + grid.d2 * (grid.cols - 1) / 2, grid.origin[1] + grid.d1 * (grid.rows - 1) / 2];
  const [east, north] = metresPerUnit(grid.crs, centre[1]);
  return { ...grid, d1: grid.d1 * north, d2: grid.d2 * east, crs: undefined,
    origin: [(grid.origin[0] - centre[0]) * east, (grid.origin[1] - centre[1]) * north] };
}

/** Each chart of a multi-chart grid as a planar grid of its own: its block, its origin on the
 * lattice, the grid's transform turned to look along its view (mzc's ZGrid.chart_grids). */
function chartGrids(grid) {
  const t = grid.transform ?? IDENTITY;
  return grid.charts.map((c) => {
    const z = new Float64Array(c.rows * c.cols);
    const colors = grid.colors && new Uint8Array(c.rows * c.cols * 3);
    for (let r = 0; r < c.rows; r++) {
      const from = (c.row0 + r) * grid.cols + c.col0;
      z.set(grid.z.subarray(from, from + c.cols), r * c.cols);
      colors?.set(grid.colors.subarray(3 * from, 3 * (from + c.cols)), 3 * r * c.cols);
    }
    const v = VIEW_AXES[c.view];   // v[k]: the k-th axis (a column of the view's rotation)
    const transform = [];
    for (let i = 0; i < 3; i++) {
      for (let j = 0; j < 3; j++) transform.push(t[4 * i] * v[j][0] + t[4 * i + 1] * v[j][1] + t[4 * i + 2] * v[j][2]);
      transform.push(t[4 * i + 3]);
    }
    return { rows: c.rows, cols: c.cols, z, colors, d1: grid.d1, d2: grid.d2, origin: [c.i0 * grid.d2, c.j0 * grid.d1], projection: "planar", transform };
  });
}

/** One mesh of several (the charts'), each's vertices after the last's, with the chart of each
 * vertex (and their colours, when they have them). */
function joined(meshes) {
  const vertices = meshes.reduce((n, m) => n + m.positions.length / 3, 0);
  const positions = new Float64Array(vertices * 3);
  const indices = new Uint32Array(meshes.reduce((n, m) => n + m.indices.length, 0));
  const charts = new Uint32Array(vertices);
  const colors = meshes[0]?.colors && new Uint8Array(vertices * 3);
  let point = 0, corner = 0;
  meshes.forEach((m, chart) => {
    positions.set(m.positions, point * 3);
    colors?.set(m.colors, point * 3);
    for (let k = 0; k < m.indices.length; k++) indices[corner + k] = m.indices[k] + point;
    charts.fill(chart, point, point + m.positions.length / 3);
    point += m.positions.length / 3;
    corner += m.indices.length;
  });
  return colors ? { positions, indices, charts, colors } : { positions, indices, charts };
}

/** The mesh of one grid (no charts): its triangles over the node numbers, then the used nodes'
 * points, and their colours (3 bytes a vertex: a pole's vertex its first node's) when the grid has them. */
function gridMesh(grid, jumpAngle) {
  const shape = Shape.of(grid);
  const triangles = nodeTriangles(grid, shape, jumps(grid, shape, jumpAngle));
  const number = new Int32Array(grid.rows * grid.cols).fill(-1);
  for (const node of triangles) number[node] = 0;
  let count = 0;
  for (let node = 0; node < number.length; node++) if (number[node] === 0) number[node] = count++;
  const indices = triangles.map((node) => number[node]);
  const positions = points(grid, shape, number, count);
  if (!grid.colors) return { positions, indices };
  const colors = new Uint8Array(count * 3);
  number.forEach((k, node) => k >= 0 && colors.set(grid.colors.subarray(3 * node, 3 * node + 3), 3 * k));
  return { positions, indices, colors };
}

/** What the grid's projection makes of its rows and columns: u and v of each, the rays'
 * sines and cosines, whether the columns make a full turn and which rows are poles. */
class Shape {
  static of(grid) {
    const s = new Shape();
    const { rows, cols, d1, d2, origin, projection, radius } = grid;
    s.planar = projection === "planar";
    s.us = Float64Array.from({ length: cols }, (_, c) => origin[0] + d2 * c);
    s.vs = Float64Array.from({ length: rows }, (_, r) => origin[1] + d1 * r);
    const turn = 2 * Math.PI * radius;
    s.periodic = !s.planar && Math.abs(cols * d2 - turn) <= FULL_TURN_TOLERANCE * turn;
    s.pole = s.vs.map((v) => (projection === "spherical" && Math.abs(v) >= 0.5 * Math.PI * radius * (1 - FULL_TURN_TOLERANCE) ? 1 : 0));
    if (!s.planar) {
      s.sinA = s.us.map((u) => sin(u / radius));
      s.cosA = s.us.map((u) => cos(u / radius));
    }
    if (projection === "spherical") {
      s.ring = s.vs.map((v) => cos(v / radius));
      s.sinE = s.vs.map((v) => sin(v / radius));
    }
    s.cells = cols - 1 + (s.periodic ? 1 : 0);
    return s;
  }
}

/** sin^2 of an angle in radians. */
const squaredSine = (angle) => sin(angle) * sin(angle);

/** The geometry of each edge kind as mzc's EdgeChords gives it: {across, along, diagonal},
 * each {spread (per row; null on planar grids), rise}, such that an edge between values a and
 * b has |e|^2 = (b - a)^2 + a b spread + rise and 4|m|^2 = (a + b)^2 - a b spread; with
 * cosine2, cos^2 of the jump angle. Null for no jumps (an angle of 0). */
function jumps(grid, shape, angle) {
  if (angle <= 0) return null;
  const c = cos(angle * (Math.PI / 180));
  const { d1, d2, radius, projection, rows } = grid;
  const perRow = (f) => Float64Array.from({ length: rows }, (_, r) => f(r));
  const kinds = (across, along, diagonal) => ({ cosine2: c * c, across, along, diagonal });
  if (projection === "planar") {
    return kinds({ spread: null, rise: d1 * d1 }, { spread: null, rise: d2 * d2 }, { spread: null, rise: d1 * d1 + d2 * d2 });
  }
  const turn = 4 * squaredSine(d2 / radius / 2);
  if (projection === "cylindrical") {
    return kinds({ spread: perRow(() => 0), rise: d1 * d1 }, { spread: perRow(() => turn), rise: 0 },
      { spread: perRow(() => turn), rise: d1 * d1 });
  }
  const tilt = 4 * squaredSine(d1 / radius / 2);
  const ring = shape.ring;
  return kinds({ spread: perRow(() => tilt), rise: 0 }, { spread: perRow((r) => ring[r] * ring[r] * turn), rise: 0 },
    { spread: perRow((r) => (r + 1 < rows ? tilt + ring[r] * ring[r + 1] * turn : 0)), rise: 0 });
}

/** Whether the edge between values a and b of an edge kind ({spread, rise} of `jumps`) from
 * row r is a jump (mzc's is_jump: (b^2 - a^2)^2 > cos^2 |e|^2 4|m|^2, or on planar grids
 * (b - a)^2 > cos^2 |e|^2): no square root or division. */
function isJump(a, b, { spread, rise }, r, cosine2) {
  const delta = b - a;
  if (spread === null) return delta * delta > cosine2 * (delta * delta + rise);
  const total = b + a;
  const product = a * b * spread[r];
  const lhs = delta * total;
  return lhs * lhs > cosine2 * (delta * delta + product + rise) * (total * total - product);
}

/** The triangles over the grid's node numbers (Uint32Array, three a triangle): every cell's
 * 1-2-3 where its corners are valid and no edge is a jump, row by row, then every 2-4-3; a
 * pole row's nodes made its first valid one, and the triangles this collapses dropped. */
function nodeTriangles(grid, shape, jump) {
  const { rows, cols, z } = grid;
  const pole = Int32Array.from(shape.pole, (p, r) => (p ? firstValid(z, r, cols) : -1));
  const merged = (node) => { const p = pole[(node / cols) | 0]; return p >= 0 ? p : node; };
  const out = new Uint32Array(Math.max(rows - 1, 0) * shape.cells * 6);
  let size = 0;
  for (const which of [0, 1]) {
    for (let r = 0; r + 1 < rows; r++) {
      for (let c = 0; c < shape.cells; c++) {
        const n1 = r * cols + c, n2 = r * cols + (c + 1) % cols;
        const [a, b, d] = which === 0 ? [n1, n2, n1 + cols] : [n2, n2 + cols, n1 + cols];
        if (Number.isNaN(z[a]) || Number.isNaN(z[b]) || Number.isNaN(z[d])) continue;
        if (jump && cellJumps(z, cols, shape, jump, r, n1, n2, which)) continue;
        const [ma, mb, md] = [merged(a), merged(b), merged(d)];
        if (ma !== mb && mb !== md && ma !== md) { out[size++] = ma; out[size++] = mb; out[size++] = md; }
      }
    }
  }
  return out.subarray(0, size);
}

/** The node number of row r's first valid node, or -1 for none. */
function firstValid(z, r, cols) {
  for (let c = 0; c < cols; c++) if (!Number.isNaN(z[r * cols + c])) return r * cols + c;
  return -1;
}

/** Whether triangle 1-2-3 (`which` 0) or 2-4-3 (1) of the cell of corners n1 (row r) and n2
 * has a jump edge (edges within a pole row never are jumps). */
function cellJumps(z, cols, shape, jump, r, n1, n2, which) {
  const { cosine2 } = jump;
  const row = r + which;
  const along = !shape.pole[row] && isJump(z[n1 + which * cols], z[n2 + which * cols], jump.along, row, cosine2);
  const across = which === 0 ? isJump(z[n1], z[n1 + cols], jump.across, r, cosine2) : isJump(z[n2], z[n2 + cols], jump.across, r, cosine2);
  return along || across || isJump(z[n2], z[n1 + cols], jump.diagonal, r, cosine2);
}

/** The input-frame points (n * 3) of the used nodes (`number` >= 0), in node order: a pole
 * row's vertex at the mean of its valid nodes' points. */
function points(grid, shape, number, count) {
  const { rows, cols, z } = grid;
  const out = new Float64Array(count * 3);
  for (let r = 0; r < rows; r++) {
    for (let c = 0; c < cols; c++) {
      const k = number[r * cols + c];
      if (k < 0) continue;
      const p = shape.pole[r] ? poleMean(grid, shape, r) : gridPoint(grid, shape, r, c);
      inputFrame(grid.transform, p, out, 3 * k);
    }
  }
  return out;
}

/** The grid-frame point of node (r, c) (spec/zgrid.md, Projections; mzc's point_components). */
function gridPoint(grid, shape, r, c) {
  const w = grid.z[r * grid.cols + c];
  if (shape.planar) return [shape.us[c], shape.vs[r], w];
  if (grid.projection === "cylindrical") return [w * shape.sinA[c], shape.vs[r], w * shape.cosA[c]];
  return [w * (shape.ring[r] * shape.sinA[c]), w * shape.sinE[r], w * (shape.ring[r] * shape.cosA[c])];
}

/** The mean of the grid-frame points of row r's valid nodes (summed in order, then divided). */
function poleMean(grid, shape, r) {
  const sum = [0, 0, 0];
  let n = 0;
  for (let c = 0; c < grid.cols; c++) {
    if (Number.isNaN(grid.z[r * grid.cols + c])) continue;
    gridPoint(grid, shape, r, c).forEach((x, i) => { sum[i] += x; });
    n++;
  }
  return sum.map((x) => x / n);
}

/** Writes R p + t ([R | t] the grid's transform, row by row; none: the identity, applied all
 * the same, as mzc applies it: -0 becomes 0) at out[at..]. */
function inputFrame(t = IDENTITY, [x, y, z], out, at) {
  for (let i = 0; i < 3; i++) out[at + i] = x * t[4 * i] + y * t[4 * i + 1] + z * t[4 * i + 2] + t[4 * i + 3];
}
