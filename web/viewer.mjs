// web/viewer.html's page: an mzc file opened, dropped or named in the address
// (viewer.html?file=URL&original=URL) is decoded and triangulated by MZCLoader and shown lit
// and orbitable, with its bytes, nodes and decode time; with the original mesh (PLY or OBJ)
// each vertex is coloured by its distance to the original (to its triangles about its vertex
// nearest the point).
// document.body.dataset.state becomes "ready" (or "error") when a file is shown.

import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { MZCLoader } from "./MZCLoader.mjs";
import { Distance, readMesh } from "./original.mjs";

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

/** Colours each vertex of `geometry` by its distance to the `original` mesh (original.mjs's
 * Distance), blue at 0 to red at the 99th percentile and beyond (a few stray vertices would
 * make the rest blue), its positions back in the input frame (plus userData.mzc.centre);
 * returns {largest, rms, red} of those distances. */
function colourByError(geometry, original) {
  const distance = new Distance(original);
  const position = geometry.attributes.position, [x, y, z] = geometry.userData.mzc.centre;
  const d = Float64Array.from({ length: position.count }, (_, i) => distance.to(position.getX(i) + x, position.getY(i) + y, position.getZ(i) + z));
  const sorted = d.slice().sort();
  const red = sorted[Math.floor(0.99 * (sorted.length - 1))] ?? 0;
  const colours = new Float32Array(position.count * 3);
  const colour = new THREE.Color();
  d.forEach((x, i) => colour.setHSL(0.66 * (1 - (red > 0 ? Math.min(x / red, 1) : 0)), 0.9, 0.5).toArray(colours, 3 * i));
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  return { largest: sorted.at(-1) ?? 0, red, rms: Math.sqrt(d.reduce((a, x) => a + x * x, 0) / Math.max(d.length, 1)) };
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
  const length = (x) => `${x.toPrecision(3)}${unit}`;
  if (error) rows.push(["largest error", length(error.largest)], ["rms error", length(error.rms)], ["red from", length(error.red)]);
  return rows;
}

/** Decodes and shows an mzc file's bytes, coloured by the error to `original` (bytes of a
 * PLY or OBJ, or null). */
function display(view, name, bytes, originalName, original) {
  const geometry = new MZCLoader().parse(bytes);
  const error = original ? colourByError(geometry, readMesh(original, originalName)) : null;
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
  reporting(async () => display(view, file.name, new Uint8Array(await file.arrayBuffer()), original?.name,
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
  if (file) reporting(async () => display(view, file, await fetched(file), original, original ? await fetched(original) : null));
}

main();
