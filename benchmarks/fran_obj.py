"""Convert VTK's textured face scan ``fran_cut.vtk`` (legacy ASCII polydata: points, triangles,
per-point texture coordinates) into the textured OBJ that mzc reads (``fran.obj`` with
``mtllib fran.mtl``, whose ``map_Kd`` names the texture ``fran_cut.png``, copied as it is).

    python benchmarks/fran_obj.py fran_cut.vtk OUT_DIR

Made tests/data/public/fran/ (see its README.md): the points, triangles and texture
coordinates are written as the numbers read (shortest round-trip repr of their float64), one ``vt`` a vertex, and each
face corner names its vertex's ``vt`` (``f a/a b/b c/c``, 1-based).
"""

import re
import sys
from pathlib import Path

import numpy as np

MTL = "newmtl fran\nKa 1 1 1\nKd 1 1 1\nmap_Kd fran_cut.png\n"   # fran.mtl: the texture, beside it


def sections(text):
    """The numbers after each of the keyword lines POINTS, POLYGONS and TEXTURE_COORDINATES of a
    legacy ASCII VTK polydata file, up to the next keyword line, as float arrays by keyword."""
    found, current = {}, None
    for line in text.splitlines():
        words = line.split()
        if words and re.fullmatch(r"[A-Z_]+", words[0]):
            current = words[0] if words[0] in ("POINTS", "POLYGONS", "TEXTURE_COORDINATES") else None
            found.setdefault(current, [])
        elif current:
            found[current].append(line)
    return {k: np.array(" ".join(v).split(), dtype=np.float64) for k, v in found.items() if k}


def obj_text(points, triangles, uv):
    """OBJ text: ``mtllib fran.mtl``, a ``v`` and a ``vt`` line per point, ``f`` lines whose corners
    use the same index for both."""
    corners = triangles + 1
    return ("mtllib fran.mtl\nusemtl fran\n" + "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
            + "".join(f"vt {u!r} {v!r}\n" for u, v in uv.tolist())
            + "".join(f"f {a}/{a} {b}/{b} {c}/{c}\n" for a, b, c in corners.tolist()))


def main():
    source, out = Path(sys.argv[1]), Path(sys.argv[2])
    found = sections(source.read_text())
    points = found["POINTS"].reshape(-1, 3)
    cells = found["POLYGONS"].astype(np.int64).reshape(-1, 4)
    if not (cells[:, 0] == 3).all():
        raise SystemExit(f"{source}: only triangles are converted")
    uv = found["TEXTURE_COORDINATES"].reshape(-1, 2)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fran.obj").write_text(obj_text(points, cells[:, 1:], uv))
    (out / "fran.mtl").write_text(MTL)


if __name__ == "__main__":
    main()
