// A three.js loader of mzc's files, used as DRACOLoader is (three is a peer: imported from
// "three", which a page maps with an import map and node finds in node_modules):
//
//   import { MZCLoader } from "./MZCLoader.mjs";
//   new MZCLoader().load("face.mzw2", (geometry) => scene.add(new Mesh(geometry, material)));
//   const geometry = new MZCLoader().parse(arrayBuffer);
//
// The geometry has `position`, `index` and computed `normal` attributes: web/triangulate.mjs's
// mesh of the decoded grid, as `mzc triangulate` makes it, its positions float32 about the
// centre of their bounding box (recentred: a georeferenced or far-off grid keeps its detail),
// which userData.mzc.centre holds in float64: place the mesh at it for the input frame,
//
//   mesh.position.fromArray(geometry.userData.mzc.centre);
//
// A grid with colours (mzc-zgrid 5.x) gives a `color` attribute too: each vertex's red, green and
// blue bytes, normalised (uint8 read as 0..1; a material with `vertexColors: true` shows them).
//
// Its userData.mzc says what was read: {bytes, rows, cols, nodes (valid), vertices, triangles,
// decodeMs, triangulateMs, kind, version, units, centre}.

import { BufferAttribute, BufferGeometry, FileLoader, Loader } from "three";
import { decode } from "./mzc.mjs";
import { recentred, triangulate } from "./triangulate.mjs";

export class MZCLoader extends Loader {
  /** A loader whose meshes take `jumpAngle` degrees (undefined: mzc's default) as their depth-jump angle. */
  constructor(manager) {
    super(manager);
    this.jumpAngle = undefined;
  }

  /** Sets the depth-jump angle in degrees (0 joins every neighbour); returns the loader. */
  setJumpAngle(degrees) {
    this.jumpAngle = degrees;
    return this;
  }

  /** Fetches `url` and calls onLoad with its BufferGeometry (onError with a bad file's MzcError). */
  load(url, onLoad, onProgress, onError) {
    const loader = new FileLoader(this.manager);
    loader.setPath(this.path);
    loader.setResponseType("arraybuffer");
    loader.setRequestHeader(this.requestHeader);
    loader.setWithCredentials(this.withCredentials);
    loader.load(url, (buffer) => {
      try {
        onLoad(this.parse(buffer));
      } catch (error) {
        if (onError) onError(error);
        else console.error(error);
        this.manager.itemError(url);
      }
    }, onProgress, onError);
  }

  /** The BufferGeometry of an mzc file's bytes (an ArrayBuffer or a Uint8Array). */
  parse(buffer) {
    const bytes = buffer instanceof Uint8Array ? buffer : new Uint8Array(buffer);
    const start = performance.now();
    const grid = decode(bytes);
    const decoded = performance.now();
    const { positions, indices, colors } = triangulate(grid, { jumpAngle: this.jumpAngle });
    const { local, centre } = recentred(positions);
    const geometry = new BufferGeometry();
    geometry.setAttribute("position", new BufferAttribute(local, 3));
    if (colors) geometry.setAttribute("color", new BufferAttribute(colors, 3, true));
    geometry.setIndex(new BufferAttribute(indices, 1));
    geometry.computeVertexNormals();
    geometry.userData.mzc = {
      bytes: bytes.length, rows: grid.rows, cols: grid.cols, nodes: validNodes(grid.z),
      vertices: positions.length / 3, triangles: indices.length / 3,
      decodeMs: decoded - start, triangulateMs: performance.now() - decoded,
      kind: grid.kind, version: grid.version, units: grid.units, centre,
    };
    return geometry;
  }
}

/** The number of valid (not NaN) values of a grid. */
function validNodes(z) {
  let count = 0;
  for (const value of z) if (!Number.isNaN(value)) count++;
  return count;
}
