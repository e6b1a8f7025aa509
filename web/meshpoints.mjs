// The vertices of an original mesh for web/viewer.html's error colouring: a PLY (ascii or
// binary, its vertex element's x, y, z) or an OBJ (its `v` lines), read minimally; faces
// and other elements are not read.

const PLY_TYPES = {
  char: ["Int8", 1], int8: ["Int8", 1], uchar: ["Uint8", 1], uint8: ["Uint8", 1],
  short: ["Int16", 2], int16: ["Int16", 2], ushort: ["Uint16", 2], uint16: ["Uint16", 2],
  int: ["Int32", 4], int32: ["Int32", 4], uint: ["Uint32", 4], uint32: ["Uint32", 4],
  float: ["Float32", 4], float32: ["Float32", 4], double: ["Float64", 8], float64: ["Float64", 8],
};

/** The points (Float64Array, n * 3) of a PLY or OBJ file's bytes, by its name's extension. */
export function meshPoints(bytes, name) {
  return /\.ply$/i.test(name) ? plyPoints(bytes) : objPoints(new TextDecoder().decode(bytes));
}

/** The x y z of each `v` line of OBJ text. */
function objPoints(text) {
  const values = [];
  for (const line of text.split(/\r\n|\r|\n/)) {
    const words = line.trim().split(/\s+/);
    if (words[0] === "v") values.push(Number(words[1]), Number(words[2]), Number(words[3]));
  }
  return Float64Array.from(values);
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
    if (w[0] === "property") elements.at(-1).properties.push({ name: w.at(-1), type: w[1], list: w[1] === "list" });
  }
  return { format, elements, length: end + head.slice(end).indexOf("\n") + 1 };
}

/** The x y z of a PLY's vertex element (in binary files the elements before it must have no lists). */
function plyPoints(bytes) {
  const { format, elements, length } = plyHeader(bytes);
  const at = elements.findIndex((e) => e.name === "vertex");
  if (at < 0) throw new Error("the PLY file has no vertex element");
  const vertex = elements[at];
  const axes = ["x", "y", "z"].map((a) => vertex.properties.findIndex((p) => p.name === a));
  if (axes.includes(-1)) throw new Error("the PLY vertices have no x, y or z");
  const out = new Float64Array(vertex.count * 3);
  if (format === "ascii") {
    const lines = new TextDecoder().decode(bytes.subarray(length)).split(/\r?\n/).filter((l) => l.trim() !== "");
    const before = elements.slice(0, at).reduce((n, e) => n + e.count, 0);
    for (let i = 0; i < vertex.count; i++) {
      const w = lines[before + i].trim().split(/\s+/);
      axes.forEach((p, k) => { out[3 * i + k] = Number(w[p]); });
    }
    return out;
  }
  const little = format === "binary_little_endian";
  const size = (e) => e.properties.reduce((n, p) => {
    if (p.list || !PLY_TYPES[p.type]) throw new Error(`a PLY ${e.name} property of type ${p.type} is not read here`);
    return n + PLY_TYPES[p.type][1];
  }, 0);
  let offset = length + elements.slice(0, at).reduce((n, e) => n + e.count * size(e), 0);
  const stride = size(vertex);
  const starts = vertex.properties.map((_, p) => vertex.properties.slice(0, p).reduce((n, q) => n + PLY_TYPES[q.type][1], 0));
  const data = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  for (let i = 0; i < vertex.count; i++, offset += stride) {
    axes.forEach((p, k) => { out[3 * i + k] = data[`get${PLY_TYPES[vertex.properties[p].type][0]}`](offset + starts[p], little); });
  }
  return out;
}
