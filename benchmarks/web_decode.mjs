// The node half of benchmarks/web_decode.py: in this one process, web/'s `decode` of an mzc
// file and Draco's WebAssembly decoder (draco3d from npm) of a Draco file, alternated.
//
//   node benchmarks/web_decode.mjs WEB_DIR MZC_FILE DRACO_FILE NODE_MODULES WARMUPS RUNS
//
// Draco's decode is what three.js's DRACOLoader does: the buffer to a mesh, its positions as
// float32 and its triangles as uint32 out of the module's heap. Each round times both, in an
// order that swaps every round; wall (performance.now) and CPU (process.cpuUsage: user +
// system) milliseconds of every run are printed as one JSON object on stdout.

import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import { join, resolve } from "node:path";
import { pathToFileURL } from "node:url";

const [web, mzcFile, dracoFile, modules, warmups, runs] = process.argv.slice(2);
const { decode } = await import(pathToFileURL(join(resolve(web), "mzc.mjs")).href);
const draco3d = createRequire(join(resolve(modules), "noop.js"))("draco3d");

/** The wall and CPU milliseconds of f() and its result. */
function timed(f) {
  const cpu = process.cpuUsage();
  const start = performance.now();
  const result = f();
  const wall = performance.now() - start;
  const { user, system } = process.cpuUsage(cpu);
  return { wall, cpu: (user + system) / 1000, result };
}

/** Draco's bytes decoded to {positions: Float32Array, indices: Uint32Array}, as DRACOLoader does. */
function dracoDecode(module, bytes) {
  const decoder = new module.Decoder();
  const mesh = new module.Mesh();
  try {
    const status = decoder.DecodeArrayToMesh(bytes, bytes.byteLength, mesh);
    if (!status.ok() || mesh.ptr === 0) throw new Error(`draco: ${status.error_msg()}`);
    const attribute = decoder.GetAttribute(mesh, decoder.GetAttributeId(mesh, module.POSITION));
    const count = mesh.num_points() * 3;
    const size = count * 4;
    const ptr = module._malloc(size);
    decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, module.DT_FLOAT32, size, ptr);
    const positions = new Float32Array(module.HEAPF32.buffer, ptr, count).slice();
    module._free(ptr);
    const indexCount = mesh.num_faces() * 3;
    const iptr = module._malloc(indexCount * 4);
    decoder.GetTrianglesUInt32Array(mesh, indexCount * 4, iptr);
    const indices = new Uint32Array(module.HEAPU32.buffer, iptr, indexCount).slice();
    module._free(iptr);
    return { positions, indices };
  } finally {
    module.destroy(mesh);
    module.destroy(decoder);
  }
}

const mzcBytes = new Uint8Array(readFileSync(mzcFile));
const dracoBytes = new Int8Array(readFileSync(dracoFile));
const instantiate = performance.now();
const module = await draco3d.createDecoderModule({});
const instantiateMs = performance.now() - instantiate;

const contenders = { mzc: () => decode(mzcBytes), draco: () => dracoDecode(module, dracoBytes) };
const times = { mzc: { wall: [], cpu: [] }, draco: { wall: [], cpu: [] } };
const last = {};
for (let round = 0; round < Number(warmups) + Number(runs); round++) {
  const order = round % 2 ? ["draco", "mzc"] : ["mzc", "draco"];
  for (const name of order) {
    const { wall, cpu, result } = timed(contenders[name]);
    last[name] = result;
    if (round >= Number(warmups)) {
      times[name].wall.push(wall);
      times[name].cpu.push(cpu);
    }
  }
}
const valid = last.mzc.z.reduce((n, v) => n + !Number.isNaN(v), 0);
process.stdout.write(JSON.stringify({
  node: process.version,
  times,
  draco_instantiate_ms: instantiateMs,
  grid: { rows: last.mzc.rows, cols: last.mzc.cols, valid, version: last.mzc.version },
  draco_mesh: { vertices: last.draco.positions.length / 3, triangles: last.draco.indices.length / 3 },
}));
