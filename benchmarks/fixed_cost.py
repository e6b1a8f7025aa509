"""Where the bytes of a small dwt2d file go (issue 33): header, mask, entropy tables, coefficients.

For every face (``--faces`` DIR, default /work/shared/data/faces) at RMS targets of 0.05, 0.1 and 0.2 mm
on ``mzc.slice``'s default grid, it encodes the grid as the encoder writes it by default and splits
the file (``mzc.codecs.dwt2d.anatomy.parts``; the mask's share of the rANS words is its symbols' ideal cost
under the file's own models): the fixed cost is header + mask + tables, what every file
pays before its first coefficient. Run: ``python benchmarks/fixed_cost.py [--quick]``.
"""

import argparse
import sys
from pathlib import Path

from corpora import FACES, mesh_files

import mzc
from mzc.codecs.dwt2d.anatomy import parts

TARGETS = (0.05, 0.1, 0.2)
COLUMNS = ("header", "mask", "tables", "coefficients", "total")


def table(faces):
    """Rows (face, target, {part: bytes}) of every face at every target."""
    rows = []
    for face in faces:
        grid = mzc.slice(str(face))
        for target in TARGETS:
            data = mzc.encode(grid, "dwt2d", rmse=target)
            rows.append((face.stem, target, {**parts(data), "total": len(data)}))
    return rows


def markdown(rows):
    """The rows as a markdown table, then the medians of each part over the files."""
    import numpy as np

    lines = ["| face | rmse | " + " | ".join(COLUMNS) + " | fixed |", "|---" * (len(COLUMNS) + 3) + "|"]
    for face, target, split in rows:
        fixed = split["header"] + split["mask"] + split["tables"]
        lines.append(f"| {face} | {target} | " + " | ".join(str(split[c]) for c in COLUMNS) + f" | {fixed} |")
    medians = {c: float(np.median([split[c] for _, _, split in rows])) for c in COLUMNS}
    fixed = float(np.median([s["header"] + s["mask"] + s["tables"] for _, _, s in rows]))
    lines.append("| median | | " + " | ".join(f"{medians[c]:g}" for c in COLUMNS) + f" | {fixed:g} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--faces", type=Path, default=FACES)
    parser.add_argument("--quick", action="store_true", help="f18 and m56 only")
    args = parser.parse_args()
    faces = mesh_files(args.faces)
    if args.quick:
        faces = [f for f in faces if f.stem in ("f18", "m56")]
    if not faces:
        sys.exit(f"fixed_cost: no faces under {args.faces}")
    print(markdown(table(faces)))


if __name__ == "__main__":
    main()
