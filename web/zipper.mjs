// The zipper (spec/zgrid.md, Zipping the charts; mzc/ops/zipper.py is the reference): the
// triangles that close the seams between the chart meshes of a multi-chart grid, from the
// meshes alone, with binary64 operations in the spec's order, so that the stitches are mzc's.
//
//   import { zipCharts } from "./zipper.mjs";
//   const { positions, indices } = zipCharts(positions, indices, charts, spacing);
//
// The steps, each a function below: the boundary edges (boundaryEdges); each boundary
// vertex's nearest boundary vertices (neighbours); coincident vertices of two charts welded
// (welded); the gap's half-edges, wedges and rungs threaded into faces (Gap); each face filled
// by ear clipping (fill); the creases of the seams put back (creased).

const REACH = 3.0;        // spacings: the longest rung
const CANDIDATES = 8;     // the nearest boundary vertices looked at for a partner
const FACING = -0.5;      // cosine of normals that face each other
const AHEAD = 0.5;        // cosine within which a point lies ahead of a surface, not beside it
const WELD = 1e-9;        // spacings: boundary vertices of two charts this close are one
const LONGEST = 6.0;      // spacings: the longest edge a filling may add (a face on a rim that needs more stays open)
const RIM_SHARE = 0.25;   // a face more of whose vertices have no other chart near lies on a rim
const QUALITY = 0.05;     // the least quality an ear's cost divides by
const SHARP = 0.94;       // cosine of 20 degrees: ends whose tangent planes bend by 20-160 degrees meet in a crease
const CREASE_REACH = 0.5; // the crease point lies at most this share of its edge's length from the edge's middle

/** {positions, indices}: the chart meshes (`positions` Float64Array n * 3, `indices` m * 3,
 * `charts` the chart of each vertex, sampled at `spacing`) with their seams closed: the
 * points, then any the filling added, then the creases'; the triangles (over welded
 * vertices), then the stitches split at the creases. */
export function zipCharts(positions, indices, charts, spacing) {
  const n = positions.length / 3;
  let triangles = new Int32Array(indices);
  let boundary = boundaryEdges(triangles, n);
  if (!boundary.tail.length) return { positions, indices };
  let near = neighbours(positions, boundary, spacing);
  const welding = welded(positions, triangles, charts, boundary, near, spacing);
  if (welding) {
    ({ triangles, boundary } = welding);
    if (!boundary.tail.length) return { positions, indices: new Uint32Array(triangles) };
    near = neighbours(positions, boundary, spacing);
  }
  const gap = new Gap(positions, triangles, charts, boundary, near, spacing);
  const { added, stitches } = gap.filled();
  const points = new Float64Array(positions.length + added.length);
  points.set(positions);
  points.set(added, positions.length);
  const { creases, pieces } = creased(points, stitches, boundary, gap.vertex, gap.normal, spacing);
  return { positions: joined(Float64Array, points, creases), indices: joined(Uint32Array, triangles, pieces) };
}

/** A `Type` array of the values of `first`, then those of `second`. */
function joined(Type, first, second) {
  const out = new Type(first.length + second.length);
  out.set(first);
  out.set(second, first.length);
  return out;
}

/** {creases, pieces}: the points put on the seams' creases (x y z each, numbered after `points`)
 * and the `stitches` split at them (spec/zgrid.md, Zipping the charts, step 10): each edge of
 * the stitches that is not a chart's (`boundary`) and whose ends' unit normals (`normal`, the
 * sums at the boundary vertices `vertex`; none elsewhere) bend by 20 to 160 degrees is split
 * at the point of their tangent planes' crease nearest its middle, when that lies within
 * CREASE_REACH of its length and a `spacing` of the middle; the edges of a stitch a piece of
 * which would turn over are moved back to their middles, round by round. */
function creased(points, stitches, boundary, vertex, normal, spacing) {
  const size = points.length / 3;
  const keyOf = (a, b) => Math.min(a, b) * size + Math.max(a, b);
  const keys = Float64Array.from(stitches, (v, i) => keyOf(v, stitches[i % 3 === 2 ? i - 2 : i + 1]));
  const edges = ascendingOnce(keys);
  const which = Int32Array.from(keys, (key) => lowerBound(edges, key));
  const unit = new Float64Array(3 * size);   // zero where the filling added a point, or the normals cancel
  vertex.forEach((v, r) => {
    const x = normal[3 * r], y = normal[3 * r + 1], z = normal[3 * r + 2], length = Math.sqrt(x * x + y * y + z * z);
    for (let d = 0; d < 3; d++) unit[3 * v + d] = normal[3 * r + d] / (length > 0 ? length : Infinity);
  });
  const chartEdges = new Set(Array.from(boundary.tail, (a, e) => keyOf(a, boundary.head[e])));
  const middle = new Float64Array(3 * edges.length), crease = new Float64Array(3 * edges.length);
  const fresh = new Int32Array(edges.length).fill(-1), bent = [];
  edges.forEach((key, e) => {
    const a = Math.floor(key / size), b = key - a * size;
    const pa = points.subarray(3 * a, 3 * a + 3), pb = points.subarray(3 * b, 3 * b + 3);
    const na = unit.subarray(3 * a, 3 * a + 3), nb = unit.subarray(3 * b, 3 * b + 3);
    const m = [(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2];
    const cosine = dot3(na, nb), across = 1.0 - cosine * cosine;
    const alongA = dot3(na, [pa[0] - m[0], pa[1] - m[1], pa[2] - m[2]]);
    const alongB = dot3(nb, [pb[0] - m[0], pb[1] - m[1], pb[2] - m[2]]);
    let sharp = across > 1.0 - SHARP * SHARP && dot3(na, na) > 0 && dot3(nb, nb) > 0;
    const divisor = sharp ? across : 1.0;
    const alpha = (alongA - cosine * alongB) / divisor, beta = (alongB - cosine * alongA) / divisor;
    const c = [0, 1, 2].map((d) => m[d] + alpha * na[d] + beta * nb[d]);
    const off = [c[0] - m[0], c[1] - m[1], c[2] - m[2]], side = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
    sharp &&= Math.sqrt(dot3(off, off)) <= Math.min(CREASE_REACH * Math.sqrt(dot3(side, side)), spacing) && !chartEdges.has(key);
    middle.set(m, 3 * e);
    crease.set(c, 3 * e);
    if (sharp) fresh[e] = size + bent.push(e) - 1;
  });
  const { pieces, parent } = split(stitches, Int32Array.from(which, (e) => fresh[e]));
  while (movedBack(points, stitches, which, pieces, parent, bent, crease, middle));
  const creases = new Float64Array(3 * bent.length);
  bent.forEach((e, i) => creases.set(crease.subarray(3 * e, 3 * e + 3), 3 * i));
  return { creases, pieces };
}

/** Whether a round (spec/zgrid.md, step 10) moved crease points back: each edge (its `crease`
 * and `middle`, 3 per edge) of a stitch (its edges `which`, 3 per stitch) with one of its
 * `pieces` (from stitch `parent`) turned over, its normal not within 90 degrees of the
 * stitch's own, whose crease is not at its middle, moves there, all after the test. A piece's
 * corner v is a point (v < the point count) or split edge `bent`[v - count]'s crease. */
function movedBack(points, stitches, which, pieces, parent, bent, crease, middle) {
  const size = points.length / 3, back = new Set(), corner = new Float64Array(9);
  for (let i = 0; i < parent.length; i++) {
    if (pieces[3 * i] < size && pieces[3 * i + 1] < size && pieces[3 * i + 2] < size) continue;   // not split
    for (let j = 0; j < 3; j++) {
      const v = pieces[3 * i + j], from = v < size ? points : crease, at = 3 * (v < size ? v : bent[v - size]);
      for (let d = 0; d < 3; d++) corner[3 * j + d] = from[at + d];
    }
    const f = parent[i], [n0, n1, n2] = normalOf(points, stitches[3 * f], stitches[3 * f + 1], stitches[3 * f + 2]);
    const [p0, p1, p2] = normalOf(corner, 0, 1, 2);
    if (!((n0 * n0 + n1 * n1) + n2 * n2 > 0 && (p0 * n0 + p1 * n1) + p2 * n2 <= 0)) continue;
    for (let k = 0; k < 3; k++) {
      const e = which[3 * f + k];
      if (crease[3 * e] !== middle[3 * e] || crease[3 * e + 1] !== middle[3 * e + 1] || crease[3 * e + 2] !== middle[3 * e + 2]) {
        back.add(e);   // at its middle, a sliver may still turn
      }
    }
  }
  for (const e of back) crease.set(middle.subarray(3 * e, 3 * e + 3), 3 * e);
  return back.size > 0;
}

/** The values of `keys` (a Float64Array), each once, ascending. */
function ascendingOnce(keys) {
  const sorted = keys.slice().sort();
  let count = 0;
  sorted.forEach((key, i) => { if (i === 0 || key !== sorted[i - 1]) sorted[count++] = key; });
  return sorted.subarray(0, count);
}

/** The first index of ascending `values` whose value is not below `value`. */
function lowerBound(values, value) {
  let low = 0, high = values.length;
  while (low < high) {
    const mid = (low + high) >> 1;
    if (values[mid] < value) low = mid + 1;
    else high = mid;
  }
  return low;
}

/** {pieces, parent}: `triangles` with each edge k (corners k, k + 1) whose `middle` (3 per
 * triangle) is not -1 split there, in mzc's order (spec/zgrid.md, step 10): the triangles
 * with none as they were; then for k = 0, 1, 2 those with one split edge k, each in two, and
 * those with two, k and k + 1, each in three; then those with three, each in four; and the
 * triangle each piece comes from. */
function split(triangles, middle) {
  const count = triangles.length / 3, out = [], parent = [];
  const cuts = (f) => (middle[3 * f] >= 0) + (middle[3 * f + 1] >= 0) + (middle[3 * f + 2] >= 0);
  const pieces = (test, ...shapes) => {
    const chosen = [];
    for (let f = 0; f < count; f++) if (test(f)) chosen.push(f);
    for (const shape of shapes) for (const f of chosen) { out.push(...shape(f)); parent.push(f); }
  };
  const corner = (f, k) => triangles[3 * f + k % 3], cut = (f, k) => middle[3 * f + k % 3];
  pieces((f) => cuts(f) === 0, (f) => [corner(f, 0), corner(f, 1), corner(f, 2)]);
  for (let k = 0; k < 3; k++) {
    const t = (f, i) => corner(f, k + i), m = (f, i) => cut(f, k + i);
    pieces((f) => cuts(f) === 1 && m(f, 0) >= 0, (f) => [t(f, 0), m(f, 0), t(f, 2)], (f) => [m(f, 0), t(f, 1), t(f, 2)]);
    pieces((f) => cuts(f) === 2 && m(f, 2) < 0, (f) => [m(f, 0), t(f, 1), m(f, 1)], (f) => [t(f, 0), m(f, 0), m(f, 1)],
      (f) => [t(f, 0), m(f, 1), t(f, 2)]);
  }
  pieces((f) => cuts(f) === 3, (f) => [corner(f, 0), cut(f, 0), cut(f, 2)], (f) => [cut(f, 0), corner(f, 1), cut(f, 1)],
    (f) => [cut(f, 2), cut(f, 1), corner(f, 2)], (f) => [cut(f, 0), cut(f, 1), cut(f, 2)]);
  return { pieces: Uint32Array.from(out), parent };
}

/** The colours (n * 3 bytes) of the zipped mesh's points: the charts' own (the first `count`), then
 * for each point the zipper added the colour of the nearest of those (the first of equally near
 * ones), as mzc colours them (mzc.ops.colouring.nearest_colours). */
export function nearestColours(positions, count, colors) {
  const out = new Uint8Array(positions.length);
  out.set(colors);
  for (let a = count; a < positions.length / 3; a++) {
    let best = 0, nearest = Infinity;
    for (let k = 0; k < count; k++) {
      const dx = positions[3 * k] - positions[3 * a], dy = positions[3 * k + 1] - positions[3 * a + 1], dz = positions[3 * k + 2] - positions[3 * a + 2];
      const d = dx * dx + dy * dy + dz * dz;
      if (d < nearest) [best, nearest] = [k, d];
    }
    out.copyWithin(3 * a, 3 * best, 3 * best + 3);
  }
  return out;
}

/** {tail, head, triangle} (Int32Arrays): the edges of `t` (over n vertices) in one triangle
 * only (no other runs them either way, and they run once), each as its triangle runs it, in
 * the order of the triangles' edges 0-1, 1-2, 2-0. */
function boundaryEdges(t, n) {
  const first = new Int32Array(n + 1), out = new Int32Array(t.length), heads = new Int32Array(t.length);
  for (let e = 0; e < t.length; e++) {
    heads[e] = t[e % 3 === 2 ? e - 2 : e + 1];
    first[t[e] + 1]++;
  }
  for (let v = 0; v < n; v++) first[v + 1] += first[v];
  const fill = first.slice();
  for (let e = 0; e < t.length; e++) out[fill[t[e]]++] = heads[e];
  const tail = [], head = [], triangle = [];
  for (let e = 0; e < t.length; e++) {
    const a = t[e], b = heads[e];
    let j = first[b], runs = 0;
    while (j < first[b + 1] && out[j] !== a) j++;
    for (let i = first[a]; j === first[b + 1] && i < first[a + 1]; i++) runs += out[i] === b ? 1 : 0;
    if (runs === 1) {
      tail.push(a);
      head.push(b);
      triangle.push((e / 3) | 0);
    }
  }
  return { tail: Int32Array.from(tail), head: Int32Array.from(head), triangle: Int32Array.from(triangle) };
}

/** The boundary vertices (`vertex`, ascending) and for each its `k` nearest boundary vertices
 * closer than REACH spacings (squared distances compared: dx dx + dy dy + dz dz < (REACH
 * spacing)^2), nearest first, a tie by number: `candidate` (numbered as `vertex`; its count
 * where there are fewer) and `distance` (the square root; Infinity), k per vertex. */
function neighbours(p, boundary, spacing) {
  const vertex = Int32Array.from(new Set([...boundary.tail, ...boundary.head])).sort();
  const size = vertex.length, k = Math.min(CANDIDATES, size);
  const reach = REACH * spacing, bound = reach * reach, side = reach * 1.001;   // cells a little wider than the reach
  const cells = new Map(), cell = new Float64Array(3 * size);
  vertex.forEach((v, r) => {
    for (let d = 0; d < 3; d++) cell[3 * r + d] = Math.floor(p[3 * v + d] / side);
    const key = cellKey(cell[3 * r], cell[3 * r + 1], cell[3 * r + 2]);
    if (!cells.has(key)) cells.set(key, []);
    cells.get(key).push(r);
  });
  const candidate = new Int32Array(size * k).fill(size), distance = new Float64Array(size * k).fill(Infinity);
  for (let r = 0; r < size; r++) {
    const v = vertex[r], at = r * k;
    let count = 0;
    for (let i = -1; i <= 1; i++) {
      for (let j = -1; j <= 1; j++) {
        for (let l = -1; l <= 1; l++) {
          for (const s of cells.get(cellKey(cell[3 * r] + i, cell[3 * r + 1] + j, cell[3 * r + 2] + l)) ?? []) {
            const w = vertex[s];
            const dx = p[3 * w] - p[3 * v], dy = p[3 * w + 1] - p[3 * v + 1], dz = p[3 * w + 2] - p[3 * v + 2];
            const d = dx * dx + dy * dy + dz * dz;
            if (!(d < bound) || (count === k && !(d < distance[at + k - 1] || (d === distance[at + k - 1] && s < candidate[at + k - 1])))) continue;
            let place = Math.min(count, k - 1);   // insertion into the row, kept in (d, number) order
            while (place > 0 && (d < distance[at + place - 1] || (d === distance[at + place - 1] && s < candidate[at + place - 1]))) {
              distance[at + place] = distance[at + place - 1];
              candidate[at + place] = candidate[at + place - 1];
              place--;
            }
            distance[at + place] = d;
            candidate[at + place] = s;
            count = Math.min(count + 1, k);
          }
        }
      }
    }
    for (let c = 0; c < count; c++) distance[at + c] = Math.sqrt(distance[at + c]);
  }
  return { vertex, k, candidate, distance };
}

/** The key of cell (i, j, l), integers: one number while each is under 2^17 in magnitude, else a string. */
function cellKey(i, j, l) {
  return Math.abs(i) < 131072 && Math.abs(j) < 131072 && Math.abs(l) < 131072 ? (i * 262144 + j) * 262144 + l : `${i},${j},${l}`;
}

/** {triangles, boundary} with the boundary vertices of different charts within WELD spacings
 * of each other made one (the lowest number, through chains of up to three), the boundary
 * edges this joins dropped; null if none. Pairs whose welding would run an edge twice the
 * same way or collapse a triangle are kept apart, and the rest tried again. */
function welded(p, t, chart, boundary, near, spacing) {
  const n = p.length / 3, { vertex, k, candidate, distance } = near;
  let pairs = [];
  for (let e = 0; e < distance.length; e++) {
    if (!(distance[e] <= WELD * spacing)) continue;
    const a = vertex[(e / k) | 0], b = vertex[candidate[e]];
    if (chart[a] !== chart[b]) pairs.push(a < b ? [a, b] : [b, a]);
  }
  while (pairs.length) {
    let one = Int32Array.from({ length: n }, (_, v) => v);
    for (let step = 0; step < 3; step++) {
      const from = pairs.map(([a]) => one[a]);
      pairs.forEach(([, b], i) => { if (from[i] < one[b]) one[b] = from[i]; });
      const last = one;
      one = last.map((v) => last[v]);
    }
    const corners = t.map((v) => one[v]);
    const welds = new Set();
    one.forEach((w, v) => { if (w !== v) welds.add(w); });
    const blamed = clashes(t, corners, welds);
    for (let f = 0; f < t.length; f += 3) {
      const [a, b, c] = [corners[f], corners[f + 1], corners[f + 2]];
      if ((a === b || b === c || c === a) && t[f] !== t[f + 1] && t[f + 1] !== t[f + 2] && t[f + 2] !== t[f]) {
        for (let i = 0; i < 3; i++) blamed.add(t[f + i]);
      }
    }
    if (!blamed.size) return { triangles: corners, boundary: joinedDropped(boundary, one, n) };
    const blamedOne = new Set([...blamed].map((v) => one[v]));
    const apart = pairs.map(([a, b]) => blamedOne.has(one[a]) || blamedOne.has(one[b]));
    if (!apart.some(Boolean)) return null;
    pairs = pairs.filter((_, i) => !apart[i]);
  }
  return null;
}

/** The vertices (of `t`) of the edges that `corners` (over welded vertices) run twice the same
 * way, among the triangles with a corner in `welds`, where one of those runs has changed. */
function clashes(t, corners, welds) {
  const size = t.reduce((a, b) => Math.max(a, b), 0) + 1;
  const groups = new Map();   // directed edge key -> [changed, [tail, head]...]
  for (let f = 0; f < t.length; f += 3) {
    if (!(welds.has(corners[f]) || welds.has(corners[f + 1]) || welds.has(corners[f + 2]))) continue;
    for (let i = 0; i < 3; i++) {
      const j = f + (i + 1) % 3, key = corners[f + i] * size + corners[j];
      if (!groups.has(key)) groups.set(key, { changed: false, ends: [] });
      const group = groups.get(key);
      group.changed ||= t[f + i] !== corners[f + i] || t[j] !== corners[j];
      group.ends.push(t[f + i], t[j]);
    }
  }
  const blamed = new Set();
  for (const { changed, ends } of groups.values()) if (changed && ends.length > 2) ends.forEach((v) => blamed.add(v));
  return blamed;
}

/** The boundary edges over the welded vertices (`one`), those now run both ways dropped. */
function joinedDropped(boundary, one, n) {
  const tail = boundary.tail.map((v) => one[v]), head = boundary.head.map((v) => one[v]);
  const runs = new Set(Array.from(tail, (a, e) => a * n + head[e]));
  const keep = Array.from(tail, (a, e) => !runs.has(head[e] * n + a));
  const kept = (values) => values.filter((_, e) => keep[e]);
  return { tail: kept(tail), head: kept(head), triangle: kept(boundary.triangle) };
}

/** numpy's float remainder of x by 4: in [0, 4) (4 itself when a tiny negative is lifted), 0 as +0. */
function mod4(x) {
  const r = x % 4;
  return r < 0 ? r + 4 : r === 0 ? 0 : r;
}

/** A stand-in for the angle of (x, y) counterclockwise in [0, 4) from +x (atan2's order),
 * in additions and one division. */
function pseudoAngle(x, y) {
  const size = Math.abs(x) + Math.abs(y);
  const along = size > 0 ? x / size : 0;
  return y >= 0 ? 1.0 - along : mod4(3.0 + along);
}

/** The right-handed frame (first, second, unit normal: nine numbers) about normal (x, y, z):
 * the unit normal ((0, 0, 1) for a zero one), the axis of its least component less its part
 * along it, normalised, and their cross product. */
function tangentFrame(x, y, z) {
  const size = Math.sqrt(x * x + y * y + z * z);
  const s = size > 0 ? size : 1.0;
  const u = size === 0 ? [0, 0, 1] : [x / s, y / s, z / s];
  const a = Math.abs(u[0]), b = Math.abs(u[1]), c = Math.abs(u[2]);
  const least = a <= b && a <= c ? 0 : b <= c ? 1 : 2;
  const axis = [0, 0, 0];
  axis[least] = 1;
  const along = axis[0] * u[0] + axis[1] * u[1] + axis[2] * u[2];
  const f = [axis[0] - along * u[0], axis[1] - along * u[1], axis[2] - along * u[2]];
  const length = Math.sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  f[0] /= length; f[1] /= length; f[2] /= length;
  return [...f, u[1] * f[2] - u[2] * f[1], u[2] * f[0] - u[0] * f[2], u[0] * f[1] - u[1] * f[0], ...u];
}

/** The normal (twice the area) of triangle a b c of points p, as (b - a) x (c - a). */
function normalOf(p, a, b, c) {
  const ab = [p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]];
  const ac = [p[3 * c] - p[3 * a], p[3 * c + 1] - p[3 * a + 1], p[3 * c + 2] - p[3 * a + 2]];
  return [ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]];
}

const dot3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/** The walk (weakly connected component) of each half-edge along `next` (-1: none), numbered
 * by their least half-edges' order. */
function walks(next) {
  const root = Int32Array.from({ length: next.length }, (_, i) => i);
  const find = (i) => { while (root[i] !== i) { root[i] = root[root[i]]; i = root[i]; } return i; };
  next.forEach((j, i) => { if (j >= 0) { const a = find(i), b = find(j); if (a !== b) root[Math.max(a, b)] = Math.min(a, b); } });
  const label = new Int32Array(next.length).fill(-1), out = new Int32Array(next.length);
  let count = 0;
  for (let i = 0; i < next.length; i++) {
    const r = find(i);
    if (label[r] < 0) label[r] = count++;
    out[i] = label[r];
  }
  return out;
}

/** The gap between the charts: its half-edges (the boundary edges reversed, then the rungs one
 * way, then the other) over the boundary vertices numbered 0.. (`vertex` their mesh numbers),
 * and each one's `next` around its face. */
class Gap {
  constructor(points, triangles, chart, boundary, near, spacing) {
    this.vertex = near.vertex;
    this.near = near;
    this.spacing = spacing;
    this.pointCount = points.length / 3;
    const size = this.size = this.vertex.length;
    this.p = new Float64Array(3 * size);
    const rank = new Int32Array(this.pointCount).fill(-1);
    for (let r = 0; r < size; r++) {
      const v = this.vertex[r];
      rank[v] = r;
      for (let d = 0; d < 3; d++) this.p[3 * r + d] = points[3 * v + d];
    }
    const normal = new Float64Array(3 * size);
    this.edges = new Set();
    for (let f = 0; f < triangles.length; f += 3) {
      if (rank[triangles[f]] < 0 && rank[triangles[f + 1]] < 0 && rank[triangles[f + 2]] < 0) continue;
      const r = [rank[triangles[f]], rank[triangles[f + 1]], rank[triangles[f + 2]]];
      const m = normalOf(points, triangles[f], triangles[f + 1], triangles[f + 2]);
      for (let d = 0; d < 3; d++) for (const c of r) if (c >= 0) normal[3 * c + d] += m[d];
      for (let i = 0; i < 3; i++) if (r[i] >= 0 && r[(i + 1) % 3] >= 0) this.edges.add(this.key(r[i], r[(i + 1) % 3]));
    }
    this.normal = normal;
    this.frame = new Float64Array(9 * size);
    for (let r = 0; r < size; r++) this.frame.set(tangentFrame(normal[3 * r], normal[3 * r + 1], normal[3 * r + 2]), 9 * r);
    this.chart = Int32Array.from(this.vertex, (v) => chart[v]);
    this.source = Int32Array.from(boundary.head, (v) => rank[v]);
    this.target = Int32Array.from(boundary.tail, (v) => rank[v]);
    this.beside = new Float64Array(3 * boundary.triangle.length);
    boundary.triangle.forEach((f, e) => this.beside.set(normalOf(points, triangles[3 * f], triangles[3 * f + 1], triangles[3 * f + 2]), 3 * e));
    this.gapCount = this.source.length;
    const wedgeNext = this.turns();
    const rungs = this.rungs(wedgeNext);
    this.next = this.threaded(wedgeNext, rungs);
    this.source = Int32Array.from([...this.source, ...rungs.map((r) => r[0]), ...rungs.map((r) => r[1])]);
    this.target = Int32Array.from([...this.target, ...rungs.map((r) => r[1]), ...rungs.map((r) => r[0])]);
  }

  /** One number for the undirected edge a-b between boundary vertices. */
  key(a, b) {
    return Math.min(a, b) * this.size + Math.max(a, b);
  }

  /** The pseudo-angle of direction a -> b in the frame whose first and second axes are at
   * `frame`[at], [at + 3] (by default a's own frame). */
  angle(a, b, frame = this.frame, at = 9 * a) {
    const p = this.p;
    const d0 = p[3 * b] - p[3 * a], d1 = p[3 * b + 1] - p[3 * a + 1], d2 = p[3 * b + 2] - p[3 * a + 2];
    return pseudoAngle(d0 * frame[at] + d1 * frame[at + 1] + d2 * frame[at + 2],
      d0 * frame[at + 3] + d1 * frame[at + 4] + d2 * frame[at + 5]);
  }

  /** Each gap half-edge's next around its face (-1 for none): about each vertex, its half-edges'
   * ends clockwise (leaving first at a tie, then by number) from the first arriving one, the
   * k-th arriving followed by the k-th leaving. */
  turns() {
    const count = this.gapCount, { source, target } = this;
    const at = new Int32Array(2 * count), angle = new Float64Array(2 * count);
    for (let h = 0; h < count; h++) {
      at[h] = source[h];
      angle[h] = this.angle(source[h], target[h]);
      at[count + h] = target[h];
      angle[count + h] = this.angle(target[h], source[h]);
    }
    const order = Array.from({ length: 2 * count }, (_, i) => i);
    order.sort((a, b) => at[a] - at[b] || (angle[a] !== angle[b] ? (angle[a] > angle[b] ? -1 : 1) : 0) ||
      (a >= count) - (b >= count) || a - b);
    const next = new Int32Array(count).fill(-1);
    for (let start = 0; start < order.length;) {
      let end = start;
      while (end < order.length && at[order[end]] === at[order[start]]) end++;
      const group = order.slice(start, end);
      const first = Math.max(group.findIndex((h) => h >= count), 0);
      const rotated = [...group.slice(first), ...group.slice(0, first)];
      const arrive = rotated.filter((h) => h >= count), leave = rotated.filter((h) => h < count);
      arrive.forEach((h, i) => { next[h - count] = i < leave.length ? leave[i] : -1; });
      start = end;
    }
    return next;
  }

  /** Per vertex, the gap half-edges that arrive at it (each names the wedge starting there), by number. */
  wedgeTable() {
    const table = Array.from({ length: this.size }, () => []);
    for (let h = 0; h < this.gapCount; h++) table[this.target[h]].push(h);
    return table;
  }

  /** [a, b, wedge at a, wedge at b] of each rung: each vertex and its partner where they are each
   * other's, then on each boundary loop left without one, its vertex nearest its partner (not
   * loose first) and that partner; none without wedges, none twice, none along an existing edge. */
  rungs(wedgeNext) {
    const { partner, gap, wedge, farWedge, loose } = this.partners(wedgeNext);
    const size = this.size;
    const loop = new Int32Array(size);
    const walk = walks(wedgeNext);
    for (let h = 0; h < this.gapCount; h++) loop[this.source[h]] = walk[h];
    const mutual = Array.from(partner, (q, i) => q >= 0 && !loose[i] && partner[q] === i && !loose[q]);
    const ends = [];
    for (let i = 0; i < size; i++) if (mutual[i] && i < partner[i]) ends.push(i);
    const alone = new Uint8Array(loop.reduce((a, b) => Math.max(a, b), -1) + 1).fill(1);
    for (let i = 0; i < size; i++) if (mutual[i]) alone[loop[i]] = 0;
    const lonely = [];
    for (let i = 0; i < size; i++) if (alone[loop[i]] && partner[i] >= 0) lonely.push(i);
    lonely.sort((a, b) => loop[a] - loop[b] || loose[a] - loose[b] || (gap[a] !== gap[b] ? (gap[a] < gap[b] ? -1 : 1) : 0) || a - b);
    lonely.forEach((i, at) => {
      if (at > 0 && loop[lonely[at - 1]] === loop[i]) return;
      if (!(mutual[partner[i]] && partner[partner[i]] === i)) ends.push(i);
    });
    const seen = new Set(), rungs = [];
    for (const i of ends) {
      if (wedge[i] < 0 || farWedge[i] < 0) continue;
      const key = this.key(i, partner[i]);
      if (seen.has(key)) continue;
      seen.add(key);
      if (!this.edges.has(key)) rungs.push([i, partner[i], wedge[i], farWedge[i]]);
    }
    return rungs;
  }

  /** Per boundary vertex: its partner (-1 for none), how far, the wedges the rung between them
   * lies in at both ends, and whether it is `loose` (the nearest other chart's vertex, not
   * seen from wedges: a last resort). Sets `seam`: whether another chart's boundary lies
   * within REACH of each, not across air. */
  partners(wedgeNext) {
    const size = this.size, wedges = this.wedgeTable(), { k, candidate, distance } = this.near;
    const partner = new Int32Array(size).fill(-1), gap = new Float64Array(size).fill(Infinity);
    const wedge = new Int32Array(size).fill(-1), farWedge = new Int32Array(size).fill(-1);
    const loose = new Uint8Array(size).fill(1);
    this.seam = new Uint8Array(size);
    const frame = new Float64Array(9), u = this.frame;
    for (let here = 0; here < size; here++) {
      for (let c = 0; c < k && loose[here]; c++) {
        const other = candidate[here * k + c];
        if (other >= size || this.chart[other] === this.chart[here] || this.acrossAir(here, other)) continue;
        if (!this.seam[here]) {
          this.seam[here] = 1;
          partner[here] = other;
          gap[here] = distance[here * k + c];
          wedge[here] = wedges[here][0] ?? -1;
          farWedge[here] = wedges[other][0] ?? -1;
        }
        frame.set(tangentFrame(u[9 * here + 6] + u[9 * other + 6], u[9 * here + 7] + u[9 * other + 7], u[9 * here + 8] + u[9 * other + 8]));
        const atHere = this.wedgeOf(wedges, wedgeNext, here, other, frame), atOther = this.wedgeOf(wedges, wedgeNext, other, here, frame);
        if (atHere >= 0 && atOther >= 0) {
          partner[here] = other;
          gap[here] = distance[here * k + c];
          wedge[here] = atHere;
          farWedge[here] = atOther;
          loose[here] = 0;
        }
      }
    }
    return { partner, gap, wedge, farWedge, loose };
  }

  /** Whether boundary vertices a and b face each other across air: normals opposed, and b in
   * front of a more than beside it. */
  acrossAir(a, b) {
    const u = this.frame, p = this.p;
    const facing = u[9 * a + 6] * u[9 * b + 6] + u[9 * a + 7] * u[9 * b + 7] + u[9 * a + 8] * u[9 * b + 8];
    const o = [p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]];
    const ahead = o[0] * u[9 * a + 6] + o[1] * u[9 * a + 7] + o[2] * u[9 * a + 8];
    return facing < FACING && ahead > AHEAD * Math.sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
  }

  /** The first wedge at `at` (by its arriving half-edge, in `wedges` order) that the direction
   * at -> towards lies in, seen in `frame`; -1 for none. A wedge turns clockwise from the
   * direction back along its arriving half-edge to the one out along the half-edge that
   * leaves next (all round when they coincide). */
  wedgeOf(wedges, wedgeNext, at, towards, frame) {
    for (const arrive of wedges[at]) {
      const leave = wedgeNext[arrive];
      if (leave < 0) continue;
      const start = this.angle(at, this.source[arrive], frame, 0);
      const span = mod4(start - this.angle(at, this.target[leave], frame, 0));
      const turn = mod4(start - this.angle(at, towards, frame, 0));
      if (turn > 0 && (turn < span || span === 0)) return arrive;
    }
    return -1;
  }

  /** The next of each half-edge (gap's, then rungs' a -> b, then b -> a): in each wedge, the
   * gap's arriving half-edge, the rungs leaving in it (clockwise about the vertex's normal) and
   * the gap's leaving one follow each other; a rung's arriving half-edge goes on as its leaving
   * twin would. */
  threaded(wedgeNext, rungs) {
    const count = wedgeNext.length, size = rungs.length;
    const leaving = [...rungs.map((r) => r[0]), ...rungs.map((r) => r[1])];
    const towards = [...rungs.map((r) => r[1]), ...rungs.map((r) => r[0])];
    const wedge = [...rungs.map((r) => r[2]), ...rungs.map((r) => r[3])];
    const turn = leaving.map((v, i) => mod4(this.angle(v, this.source[wedge[i]]) - this.angle(v, towards[i])));
    const order = leaving.map((_, i) => i).sort((a, b) => wedge[a] - wedge[b] || (turn[a] !== turn[b] ? (turn[a] < turn[b] ? -1 : 1) : 0) || a - b);
    const next = Int32Array.from([...wedgeNext, ...new Array(2 * size).fill(-1)]);
    const twin = (half) => (half < count + size ? half + size : half - size);
    order.forEach((i, at) => {
      const half = count + i;
      if (at === 0 || wedge[order[at - 1]] !== wedge[i]) next[wedge[i]] = half;
      const last = at + 1 === order.length || wedge[order[at + 1]] !== wedge[i];
      next[twin(half)] = last ? wedgeNext[wedge[i]] : count + order[at + 1];
    });
    return next;
  }

  /** {added, stitches}: the points added (x y z each) and the triangles over the mesh's vertices. */
  filled() {
    const k = this.source.length, u = this.frame;
    const reference = new Float64Array(3 * k);
    reference.set(this.beside);
    for (let h = this.gapCount; h < k; h++) {
      for (let d = 0; d < 3; d++) reference[3 * h + d] = u[9 * this.source[h] + 6 + d] + u[9 * this.target[h] + 6 + d];
    }
    const { triangles, added } = fill(this.p, this.source, this.target, this.next, this.gapCount, reference, this.edges,
      LONGEST * this.spacing, this.rims(), (a, b) => this.key(a, b));
    const stitches = Uint32Array.from(triangles, (v) => (v < this.size ? this.vertex[v] : v - this.size + this.pointCount));
    return { added: Float64Array.from(added), stitches };
  }

  /** Whether each half-edge's face lies on a rim: more than RIM_SHARE of its half-edges start on
   * one (not `seam`). Its filling stays open where it would cut longer than LONGEST spacings; a
   * gap between charts makes no such cut and is closed, by fans where it must. */
  rims() {
    const face = walks(this.next), rim = new Float64Array(this.next.length), all = new Float64Array(this.next.length);
    face.forEach((f, h) => { all[f] += 1; rim[f] += this.seam[this.source[h]] ? 0 : 1; });
    return Uint8Array.from(face, (f) => (rim[f] > RIM_SHARE * all[f] ? 1 : 0));
  }
}

/** The triangles (over the n vertices of `p`, n + i for added point i) and the added points
 * that fill every closed face of the half-edges (source, target, next; the first `rungs`
 * the gap's, the rest the rungs' a -> b then b -> a), each face by ear clipping as
 * spec/zgrid.md says; `reference` (3 per half-edge) the normal beside each, `edges` the keys
 * (`key`) of the edges that exist, `longest` the longest cut, `rim` per half-edge whether its
 * face lies on a rim (left open past `longest`; a gap's face makes no longer cut). */
function fill(p, source, target, next, rungs, reference, edges, longest, rim, key) {
  const n = p.length / 3, k = source.length;
  const edgeSet = new Set(edges);
  for (let h = 0; h < k; h++) edgeSet.add(key(source[h], target[h]));
  const vertex = new Int32Array(k + 1), prev = new Int32Array(k + 1), nxt = new Int32Array(k + 1);
  const version = new Float64Array(k + 1), ref = new Float64Array(3 * (k + 1));
  const depth = new Int32Array(n).fill(-1), walked = new Int32Array(n).fill(-1), crossed = new Uint8Array(k - rungs + 1);
  const out = [], added = [], heap = [];
  let rimHere = false;
  const area = [0, 0, 0];
  const point = (v) => [p[3 * v], p[3 * v + 1], p[3 * v + 2]];
  const distance2 = (a, b) => { const d = [p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]]; return dot3(d, d); };
  const hasEdge = (a, b) => edgeSet.has(key(a, b));
  const before = (a, b) => (a.fold !== b.fold ? a.fold < b.fold : a.cost !== b.cost ? a.cost < b.cost : a.at < b.at);

  const push = (ear) => {
    let i = heap.length;
    heap.push(ear);
    while (i > 0 && before(ear, heap[(i - 1) >> 1])) { heap[i] = heap[(i - 1) >> 1]; i = (i - 1) >> 1; }
    heap[i] = ear;
  };
  const pop = () => {
    const top = heap[0], last = heap.pop();
    if (!heap.length) return top;
    let i = 0;
    for (;;) {
      let child = 2 * i + 1;
      if (child >= heap.length) break;
      if (child + 1 < heap.length && before(heap[child + 1], heap[child])) child++;
      if (!before(heap[child], last)) break;
      heap[i] = heap[child];
      i = child;
    }
    heap[i] = last;
    return top;
  };
  const folds = (normal, size, r) => { const length = Math.sqrt(dot3(r, r)); return length > 0 && dot3(normal, r) < FACING * size * length; };
  const refAt = (i) => [ref[3 * i], ref[3 * i + 1], ref[3 * i + 2]];
  // [folds (0/1), quality, normal] of triangle u v w (positions)
  const earFolds = (a, b, c) => {
    const normal = normalOf(p, vertex[a], vertex[b], vertex[c]);
    const size = Math.sqrt(dot3(normal, normal));
    const sides = distance2(vertex[a], vertex[b]) + distance2(vertex[b], vertex[c]) + distance2(vertex[c], vertex[a]);
    let quality = sides > 0 ? 2.0 * Math.sqrt(3.0) * size / sides : 0.0;
    if (quality < QUALITY) quality = QUALITY;
    const fold = size === 0 || folds(normal, size, refAt(a)) || folds(normal, size, refAt(b)) || folds(normal, size, area);
    return [fold ? 1 : 0, quality, normal];
  };
  const consider = (i) => {   // a gap's ear that cuts longer than `longest` is not considered
    const j = prev[i], l = nxt[i];
    version[i]++;
    if (vertex[j] === vertex[l] || hasEdge(vertex[j], vertex[l])) return;
    const length = Math.sqrt(distance2(vertex[j], vertex[l]));
    if (!rimHere && !(length <= longest)) return;
    const [fold, quality] = earFolds(j, i, l);
    push({ fold, cost: length / quality, at: i, version: version[i] });
  };
  const quadFolds = (a, b, c, d) => {   // [folds, cost], or null when the cut exists or is too long
    const length = Math.sqrt(distance2(vertex[a], vertex[c]));
    if (vertex[a] === vertex[c] || hasEdge(vertex[a], vertex[c]) || !(length <= longest)) return null;
    const [f1, q1, first] = earFolds(a, b, c), [f2, q2, second] = earFolds(c, d, a);
    const s1 = Math.sqrt(dot3(first, first)), s2 = Math.sqrt(dot3(second, second));
    const count = f1 + f2 + (dot3(first, second) < FACING * s1 * s2 ? 1 : 0);
    return [count, length / (q1 < q2 ? q1 : q2)];
  };
  const fan = (at) => {   // a fan about the mean of the positions `at`: true, or false for a rim's spoke too long
    const centre = [0.0, 0.0, 0.0];
    for (const i of at) for (let d = 0; d < 3; d++) centre[d] += p[3 * vertex[i] + d];
    for (let d = 0; d < 3; d++) centre[d] /= at.length;
    for (const i of at) {
      const a = point(vertex[i]), d = [a[0] - centre[0], a[1] - centre[1], a[2] - centre[2]];
      if (rimHere && !(Math.sqrt(dot3(d, d)) <= longest)) return false;
    }
    const made = n + added.length / 3;
    added.push(...centre);
    at.forEach((i, c) => out.push(vertex[i], vertex[at[(c + 1) % at.length]], made));
    return true;
  };
  const fans = (start, count) => {   // a fan for each simple cycle of the live cycle: true, or false
    const stack = [];
    let ok = true, i = start;
    for (let c = 0; c <= count; c++, i = nxt[i]) {
      const v = vertex[i];
      if (depth[v] >= 0) {
        const from = depth[v];
        if (stack.length - from > 2 && !fan(stack.slice(from))) ok = false;
        for (let j = from; j < stack.length; j++) depth[vertex[stack[j]]] = -1;
        stack.length = from;
      }
      if (c < count) { depth[v] = stack.length; stack.push(i); }
    }
    return ok;
  };
  const fillable = (hs, into) => {
    const beside = [0.0, 0.0, 0.0];
    let rung = false;
    into[0] = into[1] = into[2] = 0.0;
    hs.forEach((h, i) => {
      const r = [reference[3 * h], reference[3 * h + 1], reference[3 * h + 2]], length = Math.sqrt(dot3(r, r));
      for (let d = 0; d < 3 && length > 0; d++) beside[d] += r[d] / length;
      rung ||= h >= rungs;
      if (i === 0 || i + 1 === hs.length) return;
      const normal = normalOf(p, source[hs[0]], source[h], source[hs[i + 1]]);
      for (let d = 0; d < 3; d++) into[d] += normal[d];
    });
    return rung || dot3(into, beside) > 0;
  };
  const clip = (hs) => {
    const count = hs.length;
    hs.forEach((h, i) => {
      vertex[i] = source[h];
      ref.set(reference.subarray(3 * h, 3 * h + 3), 3 * i);
      prev[i] = i === 0 ? count - 1 : i - 1;
      nxt[i] = i === count - 1 ? 0 : i + 1;
      version[i] = 0;
    });
    if (!fillable(hs, area)) return;
    heap.length = 0;
    for (let i = 0; i < count; i++) consider(i);
    const made = out.length, addedBefore = added.length, cuts = [];
    let alive = count, any = 0, open = false;
    const cut = (a, b) => { edgeSet.add(key(a, b)); cuts.push(a, b); };
    while (alive > 4 && heap.length > 0 && !open) {
      const ear = pop(), i = ear.at;
      if (ear.version !== version[i]) continue;
      const j = prev[i], l = nxt[i], u = vertex[j], w = vertex[l];
      if (hasEdge(u, w)) { version[i]++; continue; }
      if (!(Math.sqrt(distance2(u, w)) <= longest)) { open = true; break; }   // on a rim: a gap's are not considered
      out.push(u, vertex[i], w);
      cut(u, w);
      ref.set(normalOf(p, u, vertex[i], w), 3 * j);
      version[i]++;
      nxt[j] = l;
      prev[l] = j;
      alive--;
      any = j;
      consider(j);
      consider(l);
    }
    if (!open && alive === 4) {   // the last cut sees both triangles it leaves
      let a = any, b = nxt[a], c = nxt[b], d = nxt[c];
      let first = quadFolds(a, b, c, d);
      const second = quadFolds(b, c, d, a);
      if (second && (!first || second[0] < first[0] || (second[0] === first[0] && second[1] < first[1]))) {
        [a, b, c, d] = [b, c, d, any];
        first = second;
      }
      if (first) {
        out.push(vertex[a], vertex[b], vertex[c]);
        cut(vertex[a], vertex[c]);
        nxt[a] = c;
        any = a;
        alive = 3;
      }
    }
    if (!open && alive === 3) {
      const j = nxt[any], l = nxt[j];
      out.push(vertex[any], vertex[j], vertex[l]);
    } else if (open || !fans(any, alive)) {
      out.length = made;
      added.length = addedBefore;
      for (let c = 0; c < cuts.length; c += 2) edgeSet.delete(key(cuts[c], cuts[c + 1]));
    }
  };
  const walksARungTwice = (hs) => {
    const pairs = (k - rungs) / 2;
    let twice = false;
    for (const h of hs) if (h >= rungs) crossed[h - rungs] = 1;
    for (const h of hs) {
      const half = h - rungs;
      if (half >= 0) twice ||= crossed[half < pairs ? half + pairs : half - pairs] === 1;
    }
    for (const h of hs) if (h >= rungs) crossed[h - rungs] = 0;
    return twice;
  };
  const fillWalk = (walk) => {
    const stack = [], scratch = [0, 0, 0];
    for (const h of walk) {
      const v = source[h], from = walked[v];
      if (from >= 0) {
        const cycle = stack.slice(from);
        if (cycle.length < 3 || (fillable(cycle, scratch) && !walksARungTwice(cycle))) {
          if (cycle.length > 2) clip(cycle);
          for (const g of cycle) walked[source[g]] = -1;
          stack.length = from;
        }
      }
      walked[v] = stack.length;
      stack.push(h);
    }
    if (stack.length > 2) clip(stack);
    for (const g of stack) walked[source[g]] = -1;
  };
  const done = new Uint8Array(k);
  for (let h0 = 0; h0 < k; h0++) {
    if (done[h0]) continue;
    const walk = [];
    let h = h0;
    for (; h >= 0 && !done[h]; h = next[h]) { done[h] = 1; walk.push(h); }
    rimHere = rim[h0] === 1;
    if (h === h0) fillWalk(walk);
  }
  return { triangles: out, added };
}
