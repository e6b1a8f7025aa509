"""What a shared prior could save on the faces, before it is built (issue 33), leave-one-out.

    python benchmarks/prior_study.py [--quick] [--out DIR]

The issue asks for ``mzc train`` (a prior learnt from a collection: a mean surface on the grid,
statistics, entropy models) and ``encode --prior``, measured leave-one-out on the faces against
zstd dictionaries as the idea's anchor. This study measures the two ideas' room first, each face
held out in turn and the prior made of the 12 others, nothing of the held-out face in it:

- **zstd dictionary** (the anchor): a zstd dictionary (2 KB) trained on the other faces' mzc files
  at every target compresses the held-out face's file (zstd level 19; its frame header counted).
- **mean surface**: the 13 faces share one mesh topology (30,204 vertices, the same triangles, one
  frame), so the prior's mean face is the mean of the others' vertices. Its heights along the
  held-out face's own node lines (``mzc.ops.slicing.values_along``: what a decoder holding the
  prior computes from the grid's header) are subtracted from the face's grid, where the mean has
  no value the nearest node's that has one (``scipy.ndimage.distance_transform_edt``); the
  residual (same mask and spacing, as a planar grid: its values are not distances from the
  centre of the face's projection) is coded by dwt2d at an rmse ladder; the rebuild is the mean
  plus the decoded residual.

Both are compared with mzc's file of the face alone, at equal whole-surface RMS (benchmarks/objects.py's
``errors``: area-weighted samples each way, point to surface, mm) interpolated log-log on each one's
Pareto front (report.bytes_at) at 0.05, 0.1 and 0.2 mm. The prior itself (a mean mesh, or a
dictionary) is shared by every file and not counted. Writes prior-study-results.md and .json.
"""

import sys
import time
import warnings

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import faces_measured
from objects import QUICK_SAMPLES, Surface, errors
from report import benchmark_parser, bytes_at, fmt, pareto, stamped, write_report

TARGETS = (0.05, 0.1, 0.2)   # mm, whole-surface RMS
LADDER = (0.03, 0.05, 0.07, 0.1, 0.14, 0.2, 0.28)   # mm: the rmse targets of both mzc files
ZSTD_LEVEL = 19
DICTIONARY_BYTES = 2048   # about the files' headers and tables: what they could share
RESIDUAL = "mzc on the mean face's residual"
EITHER = "the smaller of mzc and the residual (an encoder trying both, a flag in the file)"
PACKAGES = ("numpy", "scipy", "constriction", "zstandard")
SAMPLES = 30000   # per direction: the faces' errors are smooth, 30,000 samples settle them to ~1%


def mean_on_nodes(grid, points, triangles):
    """The heights of the mesh (``points``, ``triangles``, in the grid's input frame) along ``grid``'s
    node lines, where it has none the nearest node's that has one: what a decoder with the prior
    computes from the header alone."""
    from scipy.ndimage import distance_transform_edt

    from mzc.ops.slicing import values_along

    rows, cols = grid.shape
    xs, ys = grid.origin[0] + grid.d2 * np.arange(cols), grid.origin[1] + grid.d1 * np.arange(rows)
    heights = values_along(grid.projection, grid.radius, grid.to_grid_frame(points), triangles, xs, ys)
    missing = np.isnan(heights)
    if missing.all():
        raise ValueError("the mean face meets none of the grid's node lines")
    nearest = distance_transform_edt(missing, return_distances=False, return_indices=True)
    return heights[tuple(nearest)]


def planar(values, grid):
    """``values`` (the residual heights) as a planar grid of ``grid``'s spacing: the encoder's slope
    and metric weights read a central grid's values as distances from its centre, which a residual
    is not, so its rmse would not be the residual's RMS."""
    import mzc

    return mzc.ZGrid(values, grid.d1, grid.d2)


def rebuilt_error(grid, decoded_z, source):
    """Whole-surface errors (mm) of the grid of heights ``decoded_z`` (the frame of ``grid``) against the face."""
    import mzc

    rebuilt = mzc.triangulate(grid.with_z(decoded_z), vertices="all")
    return errors(source, Surface.of(rebuilt), SAMPLES)["whole"]["rms"] * source.diagonal / 100   # % of D -> mm


def face_points(face, faces, source, grid, dictionary):
    """Every point of one held-out ``face``: mzc alone, mzc with zstd's dictionary, mzc on the residual."""
    import mzc

    others = [mzc.read(str(f)) for f in faces if f != face]
    mean = np.mean([m.points for m in others], axis=0)
    prior = mean_on_nodes(grid, mean, others[0].triangles)
    residual = planar(np.where(grid.valid, grid.z - prior, np.nan), grid)
    points = []
    for target in LADDER:
        data = mzc.encode(grid, "dwt2d", rmse=target)
        rms = rebuilt_error(grid, mzc.decode(data).z, source)
        points.append({"method": "mzc", "setting": target, "bytes": len(data), "rms": rms})
        packed = dictionary.compress(data)
        points.append({"method": "mzc + zstd dictionary", "setting": target, "bytes": len(packed), "rms": rms})
        coded = mzc.encode(residual, "dwt2d", rmse=target)
        rms = rebuilt_error(grid, prior + mzc.decode(coded).z, source)
        points.append({"method": RESIDUAL, "setting": target, "bytes": len(coded),
                       "rms": rms})
    return points


def zstd_dictionary(face, files):
    """A zstd compressor with a dictionary trained on the other faces' files at every rmse target
    (zstd's trainer needs tens of samples: the 12 faces' at one target are too few)."""
    import zstandard

    samples = [data for (f, _), data in files.items() if f != face]
    dictionary = zstandard.train_dictionary(DICTIONARY_BYTES, samples)
    return zstandard.ZstdCompressor(level=ZSTD_LEVEL, dict_data=dictionary)


def run(faces):
    """Every face's points and its bytes at the targets, by method."""
    import mzc

    grids = {face: mzc.slice(str(face)) for face in faces}
    files = {(face, t): mzc.encode(grids[face], "dwt2d", rmse=t) for face in faces for t in LADDER}
    results = []
    for face in faces:
        source = Surface.of(mzc.read(str(face)))
        points = face_points(face, faces, source, grids[face], zstd_dictionary(face, files))
        at = {}
        for method in dict.fromkeys(p["method"] for p in points):
            front = pareto([{**p, "whole": {"rms": p["rms"]}} for p in points if p["method"] == method], "whole rms")
            at[method] = [bytes_at(front, t, below_cheapest=True) for t in TARGETS]
        at[EITHER] = [None if a is None or b is None else min(a, b) for a, b in zip(at["mzc"], at[RESIDUAL])]
        results.append({"face": face.stem, "points": points, "bytes_at": at})
        print(f"{face.stem}: " + "; ".join(f"{m} {[None if b is None else round(b) for b in v]}"
                                           for m, v in at.items()), file=sys.stderr)
    return results


def ratios(results, method):
    """Geometric means over the faces of mzc's bytes over ``method``'s at each target (None when a face has none)."""
    out = []
    for i in range(len(TARGETS)):
        pairs = [(r["bytes_at"]["mzc"][i], r["bytes_at"][method][i]) for r in results]
        pairs = [(a, b) for a, b in pairs if a and b]
        out.append(float(np.exp(np.mean([np.log(a / b) for a, b in pairs]))) if pairs else None)
    return out


def markdown(document):
    """The report: method, the gains by method, each face's bytes at the targets."""
    methods = list(document["results"][0]["bytes_at"])
    lines = ["# A shared prior for the faces, measured before it is built (issue 33)", "",
             f"`python benchmarks/prior_study.py{' --quick' if document['quick'] else ''}` at commit "
             f"{document['commit']}, {document['date']}, on {document['machine']}; {document['seconds']:.0f} s. "
             "Package versions: " + ", ".join(f"{k} {v}" for k, v in document["versions"].items()) + ".", "",
             (__doc__ or "").split("\n\n", 2)[2].split("Writes")[0].strip(), "",
             "## mzc's bytes over each method's (geometric mean over the faces; above 1: the method is smaller)", "",
             "| method | " + " | ".join(f"at {t} mm" for t in TARGETS) + " |", "|---" * (len(TARGETS) + 1) + "|"]
    for method in methods[1:]:
        lines.append(f"| {method} | " + " | ".join(fmt(r) if r else "n/a" for r in ratios(document["results"], method))
                     + " |")
    lines += ["", "## Bytes at equal whole-surface RMS, by face", "",
              "| face | " + " | ".join(f"{m} at {t} mm" for m in methods for t in TARGETS) + " |",
              "|---" * (len(methods) * len(TARGETS) + 1) + "|"]
    for r in document["results"]:
        lines.append(f"| {r['face']} | " + " | ".join("n/a" if b is None else f"{b:.0f}"
                                                     for m in methods for b in r["bytes_at"][m]) + " |")
    return "\n".join(lines) + "\n"


def main():
    args = benchmark_parser(__doc__, "four faces, fewer samples").parse_args()
    global SAMPLES
    faces = faces_measured("prior_study", args.quick, least=3)
    SAMPLES = QUICK_SAMPLES if args.quick else SAMPLES
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # example.obj's texture coordinates, named by every read
        results = run(faces)
    document = stamped(PACKAGES, started, quick=args.quick, samples=SAMPLES, results=results)
    write_report(args.out, "prior-study", document, markdown)


if __name__ == "__main__":
    main()
