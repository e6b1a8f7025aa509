"""Colour finer than the nodes (issue 32, slice --colour-scale K): bytes and the textured rebuild's
colour error at K = 1, 2, 4 on the textured scans.

    python benchmarks/fine_colour.py [--quick] [--out DIR]

Scans (tests/data/public): VTK's fran (a 256 x 256 photographic texture) and trimesh's fuze bottle
(a 1024 x 1024 JPEG label), each sliced as one grid (``charts=1``) and as its default multi-chart
grid (``charts="auto"``, each chart's colours sampled on its own node lines, the samples between
two charts' blocks invalid, colour section version 3) at its default spacing with
``mzc.slice(..., colour_scale=K)``, coded by ``mzc.encode(grid,
"dwt2d")`` (the default shape target) with its colours at ``colour_psnr`` 36 (the default) and
40 dB, decoded, and written as ``triangulate --texture`` writes it (``mzc.meshes.obj.textured``:
an OBJ whose vertices' texture coordinates point into the PNG of the colour image), read back by
mzc's OBJ reader. Colour error: at points drawn by area on the source surface (benchmarks/objects.py
``samples_on``), the rebuilt colour looked up through the rebuilt texture at the rebuilt surface's
point nearest each (``mzc.ops.colouring.surface_colours``) against the source's own texture colour
there, RMS over the three channels in 8-bit levels, and PSNR; only the points within two node
spacings of the rebuilt surface count (a one-grid slice of the bottle sees its front alone), and
the share counted is reported. "uncoded" is the same of the grid before coding. For reference,
K = 1 at half the default spacing: the K = 2 image's lattice as nodes, the shape coded that finely
too, and a textured mesh of four times the vertices (``--texture`` keeps every node); the colour
is looked up through the rebuilt surface, so a finer shape also places it better.
Writes fine-colour-results.md and fine-colour-results.json into --out.
"""

import tempfile
import time
import warnings
from pathlib import Path

from startup import HERE  # first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from objects import Surface, samples_on
from report import benchmark_parser, fmt, stamped, write_report

PUBLIC = HERE.parent / "tests" / "data" / "public"
SCANS = {"fran": PUBLIC / "fran" / "fran.obj", "fuze": PUBLIC / "fuze" / "fuze.obj"}
CASES = ((1, 1), (2, 1), (4, 1), (1, 2))   # (colour scale K, nodes a default spacing): the last the K = 2 image's
                                           # samples as nodes, shape and all (slice --d1 at half the spacing)
CHARTS = (1, "auto")   # one grid, and the default multi-chart grid
PSNRS = (36.0, 40.0)   # dB: the colour section's targets
SAMPLES, QUICK_SAMPLES = 200_000, 40_000
NEAR = 2.0   # node spacings: a sample farther from the rebuilt surface is not seen by the grid
PACKAGES = ("numpy", "scipy", "constriction", "Pillow")


def textured_error(grid, mesh, samples, reference, folder):
    """(colour RMS, PSNR, share of the samples counted) of ``grid``'s textured rebuild (written and
    read back as ``triangulate --texture`` writes it) at ``samples`` against ``reference``."""
    from mzc.measure.metrics import nearest_triangles
    from mzc.meshes import read_mesh
    from mzc.meshes.obj import textured
    from mzc.ops.colouring import surface_colours
    from mzc.ops.triangulation import node_mesh

    for path, data in textured(grid, node_mesh(grid), str(folder / "t.obj"), str(folder / "t.png")):
        Path(path).write_bytes(data)
    rebuilt = read_mesh(folder / "t.obj")
    distance = nearest_triangles(samples, rebuilt.points, rebuilt.triangles)[0]
    seen = distance <= NEAR * max(grid.d1, grid.d2)   # the spacings are lengths (at R0 on a central grid)
    error = surface_colours(samples[seen], rebuilt) - reference[seen]
    mse = float(np.mean(error ** 2))
    return float(np.sqrt(mse)), float(10 * np.log10(255.0 ** 2 / mse)), float(seen.mean())


def run_scan(name, path, count):
    """Every row of one scan: each scale uncoded and at each colour target."""
    import mzc
    from mzc.codecs.dwt2d import compact

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the texture coordinates and normals it does not keep
        mesh = mzc.read(str(path))
    from mzc.ops.colouring import surface_colours

    samples = samples_on(Surface.of(mesh), count, np.random.default_rng(32))
    reference = surface_colours(samples, mesh)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for charts in CHARTS:
            spacing = None
            for scale, density in CASES:
                start = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    finer = {} if spacing is None else {"d1": spacing[0] / density, "d2": spacing[1] / density}
                    grid = mzc.slice(mesh, charts=charts, colour_scale=scale, **finer)
                sliced = time.perf_counter() - start
                spacing = spacing or (grid.d1, grid.d2)
                case = {"scale": scale, "density": density, "charts": len(grid.charts or [grid])}
                rms, psnr, seen = textured_error(grid, mesh, samples, reference, Path(folder))
                rows.append({**case, "target": None, "grid": list(grid.shape), "slice_s": sliced, "colour_rms": rms,
                             "colour_psnr": psnr, "seen": seen})
                for target in PSNRS:
                    start = time.perf_counter()
                    data = mzc.encode(grid, "dwt2d", colour_psnr=target)
                    encoded = time.perf_counter() - start
                    decoded = mzc.decode(data)
                    rms, psnr, seen = textured_error(decoded, mesh, samples, reference, Path(folder))
                    rows.append({**case, "target": target, "bytes": len(data),
                                 "colour_bytes": len(compact.read(data, "mzc")[2]), "encode_s": encoded,
                                 "colour_rms": rms, "colour_psnr": psnr, "seen": seen})
    return {"scan": name, "path": str(path.relative_to(HERE.parent)), "rows": rows}


def markdown(document):
    """The report: method, then a table a scan."""
    lines = ["# Colour finer than the nodes: `slice --colour-scale K` (issue 32)", "",
             f"`python benchmarks/fine_colour.py{' --quick' if document['quick'] else ''}` at commit "
             f"{document['commit']}, {document['date']}, on {document['machine']}; {document['seconds']:.0f} s.",
             "Package versions: " + ", ".join(f"{k} {v}" for k, v in document["versions"].items()) + ".", "",
             __doc__.split("\n\n", 2)[2].split("Writes")[0].replace("\n", " ").strip(),
             f"{document['samples']} samples a scan.", ""]
    for s in document["scans"]:
        lines += [f"## {s['scan']}", "",
                  "| charts | K | spacing | colour target | grid | bytes (of them colour) | colour RMS | PSNR | "
                  "samples seen | slice / encode s |", "|---" * 10 + "|"]
        for r in s["rows"]:
            target = "uncoded" if r["target"] is None else f"{r['target']:g} dB"
            size = "" if r["target"] is None else f"{r['bytes']} ({r['colour_bytes']})"
            grid = f"{r['grid'][0]} x {r['grid'][1]}" if "grid" in r else ""
            seconds = fmt(r["slice_s"]) if r["target"] is None else fmt(r["encode_s"])
            spacing = "default" if r["density"] == 1 else f"1/{r['density']}"
            lines.append(f"| {r['charts']} | {r['scale']} | {spacing} | {target} | {grid} | {size} | "
                         f"{fmt(r['colour_rms'])} | {fmt(r['colour_psnr'])} | {100 * r['seen']:.0f}% | {seconds} |")
        lines.append("")
    return "\n".join(lines)


def main():
    args = benchmark_parser(__doc__, f"{QUICK_SAMPLES} samples instead of {SAMPLES}").parse_args()
    started = time.perf_counter()
    count = QUICK_SAMPLES if args.quick else SAMPLES
    scans = [run_scan(name, path, count) for name, path in SCANS.items() if path.is_file()]
    document = stamped(PACKAGES, started, quick=args.quick, samples=count, scans=scans)
    write_report(args.out, "fine-colour", document, markdown)


if __name__ == "__main__":
    main()
