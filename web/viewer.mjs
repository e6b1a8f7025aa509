// web/viewer.html's page: an mzc file opened, dropped or named in the address
// (viewer.html?file=URL&original=URL) is decoded and triangulated by MZCLoader and shown lit
// and orbitable, with its bytes, nodes and decode time; with the original mesh (PLY or OBJ)
// each vertex is coloured by its distance to the original's nearest vertex.
// document.body.dataset.state becomes "ready" (or "error") when a file is shown.

import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { MZCLoader } from "./MZCLoader.mjs";
import { meshPoints } from "./meshpoints.mjs";

const ORIGINAL = /\.(ply|obj)$/i;

/** The renderer, scene, camera, lights and controls, drawing on every frame. */
function stage() {
  const renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  document.getElementById("view").append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x20242a);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1e7);
  scene.add(camera, new THREE.HemisphereLight(0xffffff, 0x404040, 1.2));
  const light = new THREE.DirectionalLight(0xffffff, 2.0);
  light.position.set(0.5, 0.8, 1);
  camera.add(light);   // a headlight: the surface is lit from where it is seen
  const controls = new OrbitControls(camera, renderer.domElement);
  const resize = () => {
    renderer.setSize(window.innerWidth, window.innerHeight);
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
  };
  window.addEventListener("resize", resize);
  resize();
  renderer.setAnimationLoop(() => renderer.render(scene, camera));
  return { scene, camera, controls, shown: null };
}

/** Shows `geometry` alone, the camera looking at it down -z (a face's, a terrain's view). */
function show(view, geometry) {
  if (view.shown) {
    view.scene.remove(view.shown);
    view.shown.geometry.dispose();
  }
  const material = new THREE.MeshStandardMaterial({ color: 0xd8c8b0, roughness: 0.75, side: THREE.DoubleSide,
    vertexColors: geometry.hasAttribute("color") });
  view.shown = new THREE.Mesh(geometry, material);
  view.scene.add(view.shown);
  geometry.computeBoundingSphere();
  const { center, radius } = geometry.boundingSphere;
  view.camera.position.set(center.x, center.y, center.z + 3.2 * (radius || 1));
  view.camera.near = radius / 100;
  view.camera.far = radius * 100;
  view.camera.updateProjectionMatrix();
  view.controls.target.copy(center);
  view.controls.update();
}

/** Colours each vertex of `geometry` by its distance to the nearest of `points` (n * 3), blue
 * at 0 to red at the largest; returns {largest, rms} of those distances. */
function colourByError(geometry, points) {
  const nearest = new NearestVertex(points);
  const position = geometry.attributes.position;
  const distance = Float64Array.from({ length: position.count }, (_, i) => nearest.distance(position.getX(i), position.getY(i), position.getZ(i)));
  const largest = distance.reduce((a, b) => Math.max(a, b), 0);
  const colours = new Float32Array(position.count * 3);
  const colour = new THREE.Color();
  distance.forEach((d, i) => colour.setHSL(0.66 * (1 - (largest > 0 ? d / largest : 0)), 0.9, 0.5).toArray(colours, 3 * i));
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  return { largest, rms: Math.sqrt(distance.reduce((a, d) => a + d * d, 0) / Math.max(distance.length, 1)) };
}

/** The nearest of a set of points, by a grid of cubic cells holding about one point each. */
class NearestVertex {
  constructor(points) {
    this.points = points;
    const n = points.length / 3;
    this.low = [0, 1, 2].map((k) => minimum(points, k));
    const extent = [0, 1, 2].map((k) => maximum(points, k) - this.low[k]);
    this.size = Math.max(Math.cbrt(extent[0] * extent[1] * extent[2] / Math.max(n, 1)), Math.max(...extent) / 1024, 1e-300);
    const dims = () => extent.map((e) => Math.floor(e / this.size) + 1);
    while (dims().reduce((a, b) => a * b) > 4 * n + 64) this.size *= 1.25;   // a flat set: cells of its area
    this.dims = dims();
    this.cell = (k, x) => Math.min(Math.max(Math.floor((x - this.low[k]) / this.size), 0), this.dims[k] - 1);
    const key = Uint32Array.from({ length: n }, (_, i) => this.key(this.cell(0, points[3 * i]), this.cell(1, points[3 * i + 1]), this.cell(2, points[3 * i + 2])));
    this.start = new Uint32Array(this.dims[0] * this.dims[1] * this.dims[2] + 1);
    for (const k of key) this.start[k + 1]++;
    for (let k = 1; k < this.start.length; k++) this.start[k] += this.start[k - 1];
    const fill = this.start.slice(0, -1);
    this.order = new Uint32Array(n);
    key.forEach((k, i) => { this.order[fill[k]++] = i; });
  }

  /** The number of cell (i, j, k). */
  key(i, j, k) {
    return i + this.dims[0] * (j + this.dims[1] * k);
  }

  /** The distance from (x, y, z) to the nearest point: shells of cells about its own, outwards,
   * until the next shell can hold none nearer. */
  distance(x, y, z) {
    const at = [this.cell(0, x), this.cell(1, y), this.cell(2, z)];
    let best = Infinity;   // squared
    for (let shell = 0; shell <= Math.max(...this.dims); shell++) {
      this.forShell(at, shell, (cell) => {
        for (let s = this.start[cell]; s < this.start[cell + 1]; s++) {
          const p = 3 * this.order[s];
          const dx = this.points[p] - x, dy = this.points[p + 1] - y, dz = this.points[p + 2] - z;
          best = Math.min(best, dx * dx + dy * dy + dz * dz);
        }
      });
      if (best <= (shell * this.size) ** 2) break;   // the points beyond lie farther
    }
    return Math.sqrt(best);
  }

  /** Calls visit(cell) for each cell of the grid at Chebyshev distance `shell` from cell `at`. */
  forShell(at, shell, visit) {
    const [ci, cj, ck] = at;
    for (let i = Math.max(ci - shell, 0); i <= Math.min(ci + shell, this.dims[0] - 1); i++) {
      for (let j = Math.max(cj - shell, 0); j <= Math.min(cj + shell, this.dims[1] - 1); j++) {
        const edge = Math.abs(i - ci) === shell || Math.abs(j - cj) === shell;
        const step = edge ? 1 : 2 * shell;
        for (let k = ck - shell; k <= ck + shell; k += Math.max(step, 1)) {
          if (k >= 0 && k < this.dims[2]) visit(this.key(i, j, k));
        }
      }
    }
  }
}

/** The smallest and largest of coordinate k of points (n * 3). */
function minimum(points, k) {
  let m = Infinity;
  for (let i = k; i < points.length; i += 3) m = Math.min(m, points[i]);
  return Number.isFinite(m) ? m : 0;
}
function maximum(points, k) {
  let m = -Infinity;
  for (let i = k; i < points.length; i += 3) m = Math.max(m, points[i]);
  return Number.isFinite(m) ? m : 0;
}

/** Fills the info table with [label, value] rows. */
function tell(rows) {
  document.getElementById("info").replaceChildren(...rows.map(([label, value]) => {
    const row = document.createElement("tr");
    row.append(Object.assign(document.createElement("td"), { textContent: label }),
      Object.assign(document.createElement("td"), { textContent: value }));
    if (label === "nodes") row.id = "nodes";
    return row;
  }));
}

/** The info rows of a geometry MZCLoader made, and of the error when there is one. */
function infoRows(name, info, error) {
  const n = (x) => x.toLocaleString("en-US");
  const unit = info.units ? ` ${info.units}` : "";
  const rows = [["file", name], ["format", `mzc-${info.kind} ${info.version}`], ["bytes", n(info.bytes)],
    ["grid", `${n(info.rows)} x ${n(info.cols)}`], ["nodes", n(info.nodes)], ["vertices", n(info.vertices)],
    ["triangles", n(info.triangles)], ["decode", `${info.decodeMs.toFixed(1)} ms`],
    ["triangulate", `${info.triangulateMs.toFixed(1)} ms`]];
  if (error) rows.push(["largest error", `${error.largest.toPrecision(3)}${unit}`], ["rms error", `${error.rms.toPrecision(3)}${unit}`],
    ["", "to the original's nearest vertex"]);
  return rows;
}

/** Decodes and shows an mzc file's bytes, coloured by the error to `original` (bytes of a
 * PLY or OBJ, or null). */
function open(view, name, bytes, originalName, original) {
  const geometry = new MZCLoader().parse(bytes);
  const error = original ? colourByError(geometry, meshPoints(original, originalName)) : null;
  show(view, geometry);
  tell(infoRows(name, geometry.userData.mzc, error));
  document.getElementById("error").textContent = "";
  document.body.dataset.state = "ready";
}

/** Runs `work`, showing any error it throws in the panel. */
async function reporting(work) {
  try {
    await work();
  } catch (error) {
    document.getElementById("error").textContent = error.message;
    document.body.dataset.state = "error";
  }
}

/** Opens the files chosen or dropped: the mzc file, and the original mesh among them if any. */
function openFiles(view, files) {
  const list = [...files];
  const original = list.find((f) => ORIGINAL.test(f.name));
  const file = list.find((f) => !ORIGINAL.test(f.name));
  if (!file) return;
  reporting(async () => open(view, file.name, new Uint8Array(await file.arrayBuffer()), original?.name,
    original ? new Uint8Array(await original.arrayBuffer()) : null));
}

/** The bytes at a URL. */
async function fetched(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return new Uint8Array(await response.arrayBuffer());
}

/** Wires the file input, drag and drop, and the address's ?file=&original=. */
function main() {
  const view = stage();
  document.getElementById("files").addEventListener("change", (event) => openFiles(view, event.target.files));
  window.addEventListener("dragover", (event) => { event.preventDefault(); document.body.classList.add("dragging"); });
  window.addEventListener("dragleave", () => document.body.classList.remove("dragging"));
  window.addEventListener("drop", (event) => {
    event.preventDefault();
    document.body.classList.remove("dragging");
    openFiles(view, event.dataTransfer.files);
  });
  const query = new URLSearchParams(location.search);
  const file = query.get("file"), original = query.get("original");
  if (file) reporting(async () => open(view, file, await fetched(file), original, original ? await fetched(original) : null));
}

main();
