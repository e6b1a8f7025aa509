"""Three more places issue 33's margin over JPEG 2000 was looked for, and not found (issue 33).

    python benchmarks/codec_limits.py [--quick] [--out DIR] [--workers N]

Issue 33 asks that the best grid peer need at least 1.3 times mzc's bytes at whole-surface RMS
0.05, 0.1 and 0.2 mm on the faces; rd.py measures JPEG 2000 at 1.19, 1.30 and 1.45 times, SPERR at
1.23-1.24 (rd-results.md). encoder-gains-results.md and context-study-results.md measured the
encoder's quantisation, wavelets, levels and entropy contexts one by one (3% at most). This study
measures three more, on every face of the shared data:

- **decoder offsets**: the decoder puts a nonzero q at q * step; a Laplacian's values within a
  bin lie nearer zero, so image codecs reconstruct at (|q| - delta) * step. Each face's file at a
  ladder of ``--rmse`` targets is decoded again with every detail coefficient moved by delta
  toward zero (the same bytes), and its RMS surface error estimated at the nodes (the encoder's own
  estimate, ``Prepared.surface_rms``); the ratio of errors becomes one of bytes through the face's
  own slope of log bytes over log error along the ladder.
- **mirror symmetry**: a face is nearly symmetric about a vertical plane. The grid is split at the
  column about which it is most symmetric into its symmetric part (coded on one half only) and
  its antisymmetric part (coded whole; its errors weighed as the surface's, dwt2d's ``surface``),
  their error budgets summing in squares to the target (the best of four splits); the two files'
  bytes, less one header, over the grid's own file at the same target.
- **the grid**: rd.py gives every grid codec the faces sliced at 0.5 mm, while ``mzc slice`` cuts
  them at their own spacing (about 0.75 mm). JPEG 2000's and SPERR's bytes over mzc's (dwt2d
  ``--rmse``) at equal whole-surface RMS, on both grids, measured as rd.py measures (its
  contenders, ``run_point``, 8,000 samples a side, Pareto fronts interpolated log-log).

Writes codec-limits-results.md and codec-limits-results.json into --out (default: this directory).
"""

import time
import warnings
from multiprocessing import Pool

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import faces_measured
from report import benchmark_parser, bytes_at, fmt, pareto, stamped, write_report

OFFSETS = (0.05, 0.1, 0.2)                 # delta, in steps
LADDER = (0.035, 0.05, 0.07, 0.1, 0.14)    # mm, --rmse targets of the offsets' files
MIRROR_TARGETS = (0.05, 0.1, 0.2)          # mm, --rmse of the mirror split
SHARES = (0.5, 0.6, 0.7, 0.8)              # of the squared target, the symmetric part's
AXIS_SEARCH = 60                           # columns either side of the middle searched for the axis
TARGETS = (0.05, 0.1, 0.2)                 # mm, whole-surface RMS of the grid comparison
PEERS = ("JPEG 2000", "SPERR psnr")
MZC = "mzc dwt2d --rmse"
RD_STEP = 0.5                              # mm, rd.py's grid
SAMPLES = 8_000                            # rd.py's
QUICK_FACES = 2
PACKAGES = ("numpy", "scipy", "PyWavelets", "imagecodecs", "constriction")


# --------------------------------------------------------------------------- decoder offsets


def offsets_of(grid):
    """{delta: [(bytes, RMS today, RMS with delta)] along LADDER} of one grid's files."""
    from mzc.codecs import dwt2d

    prepared = dwt2d.Prepared(grid, dwt2d.DEFAULT_WAVELET, None, dwt2d.SLOPE_LIMIT)
    rows = {delta: [] for delta in OFFSETS}
    for target in LADDER:
        data, _ = dwt2d.encode_whole(grid, rmse=target)
        step = file_step(data, grid)
        qflat, z = prepared.decoded(step)
        today = prepared.surface_rms((qflat, z))
        for delta in OFFSETS:
            rows[delta].append((len(data), today, prepared.surface_rms((qflat, offset_decoded(prepared, qflat, step,
                                                                                               delta)))))
    return rows


def file_step(data, grid):
    """The finest detail step a dwt2d 10.x file of ``grid`` holds."""
    from mzc.codecs import dwt2d
    from mzc.codecs.dwt2d import compact
    from mzc.codecs.dwt2d import wavelet as w2

    header = compact.read(data, "<bytes>")[0]
    return dwt2d.read_codec_fields(header, grid.shape, w2.TRANSFORMS[header.major])[2][-1]


def offset_decoded(prepared, qflat, step, delta):
    """The heights of the integer bands ``qflat`` (coded at ``step``) with every nonzero detail
    coefficient reconstructed delta steps nearer zero."""
    from mzc.codecs import dwt2d
    from mzc.codecs.dwt2d import wavelet as w2

    written = dwt2d.header_steps(step, prepared.levels)
    steps = dwt2d.band_steps(prepared.geometry, written, [q.shape for q in qflat], qflat[0], prepared.slope_limit)
    moved = [qflat[0]] + [q - delta * np.sign(q) for q in qflat[1:]]
    return prepared.transform.inverse(w2.dequantise(moved, steps), prepared.grid.shape, prepared.wavelet,
                                      prepared.levels, prepared.geometry.periodic)


def offset_bytes(rows):
    """Bytes at equal error with the offset over today's, geometric mean over the ladder: the
    error ratio raised to the ladder's own slope of log bytes over log error."""
    size, today, moved = (np.array(column, dtype=float) for column in zip(*rows))
    slope = -np.polyfit(np.log(today), np.log(size), 1)[0]
    return float(np.exp(np.mean(np.log(moved / today)) * slope)), float(slope)


# --------------------------------------------------------------------------- mirror symmetry


def mirror_axis(grid):
    """(2 x the axis column, RMS of z less its mirror image) of the column about which the valid
    heights are most symmetric, searched AXIS_SEARCH columns either side of the middle."""
    z, valid = grid.z, grid.valid
    best = None
    for twice in range(grid.shape[1] - AXIS_SEARCH, grid.shape[1] + AXIS_SEARCH + 1):
        mirrored, both = mirror(z, valid, twice)
        if both.sum() >= 0.5 * valid.sum():
            error = float(np.sqrt(np.mean((z[both] - mirrored[both]) ** 2)))
            best = min(best or (twice, error), (twice, error), key=lambda pair: pair[1])
    return best


def mirror(z, valid, twice):
    """(z mirrored about column twice / 2, where both a node and its image are valid)."""
    columns = twice - np.arange(z.shape[1])
    inside = (columns >= 0) & (columns < z.shape[1])
    mirrored = np.full(z.shape, np.nan)
    mirrored[:, inside] = z[:, columns[inside]]
    image = np.zeros(z.shape, dtype=bool)
    image[:, inside] = valid[:, columns[inside]]
    return mirrored, valid & image


def mirror_bytes(grid):
    """{target: (bytes of the grid coded whole, of the split, the symmetric part's share)} and the
    axis's asymmetry RMS, on the nodes valid with their image (the grid itself is coded there too)."""
    from mzc.codecs import dwt2d

    twice, asymmetry = mirror_axis(grid)
    mirrored, both = mirror(grid.z, grid.valid, twice)
    whole = grid.with_z(np.where(both, grid.z, np.nan))
    half = (np.arange(grid.shape[1]) <= twice / 2)[None, :]
    symmetric = grid.with_z(np.where(both & half, (grid.z + mirrored) / 2, np.nan))
    antisymmetric = grid.with_z(np.where(both, (grid.z - mirrored) / 2, np.nan))
    rows = {}
    for target in MIRROR_TARGETS:
        alone = dwt2d.encode_whole(whole, rmse=target)[0]
        split = min((len(dwt2d.encode_whole(symmetric, rmse=target * np.sqrt(share))[0])
                     + len(dwt2d.encode_whole(antisymmetric, rmse=target * np.sqrt(1 - share), surface=whole)[0])
                     - header_bytes(alone), share) for share in SHARES)
        rows[target] = (len(alone), *split)
    return rows, asymmetry


def header_bytes(data):
    """The bytes of a dwt2d file outside its payload (one of the split's two files goes without)."""
    from mzc.codecs.dwt2d.anatomy import parts

    return parts(data)["header"]


# --------------------------------------------------------------------------- the grid


def grid_ratios(mesh, grid):
    """{peer: [its bytes over mzc's at each of TARGETS, None where either misses it]} on ``grid``."""
    import rd
    from contenders import all_contenders

    from mzc.measure.metrics import heightfield_filters

    original = (mesh.points, mesh.triangles)
    filters = heightfield_filters(*original)
    wanted = {MZC, *PEERS}
    fronts = {}
    for contender in (c for c in all_contenders()[0] if c.name in wanted):
        points = [rd.run_point(contender, grid, setting, 1.0, original, filters, SAMPLES, len(mesh.points))
                  for setting in contender.ladder]
        fronts[contender.name] = [bytes_at(pareto(points, "whole rms"), target) for target in TARGETS]
    return {peer: [p / m if p and m else None for p, m in zip(fronts[peer], fronts[MZC])] for peer in PEERS}


# --------------------------------------------------------------------------- run


def face_row(path):
    """Every study's figures for one face."""
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    warnings.simplefilter("ignore")
    mesh = read_mesh(str(path))
    grid = slice_surface(mesh)
    offsets = {delta: offset_bytes(rows) for delta, rows in offsets_of(grid).items()}
    mirrored, asymmetry = mirror_bytes(grid)
    fine = slice_surface(mesh, d1=RD_STEP, d2=RD_STEP)
    return {"face": path.stem, "grid": list(grid.shape), "fine_grid": list(fine.shape),
            "offsets": {str(d): {"bytes": b, "slope": s} for d, (b, s) in offsets.items()},
            "mirror": {str(t): dict(zip(("whole", "split", "share"), row)) for t, row in mirrored.items()},
            "asymmetry_rms": asymmetry,
            "grids": {"default": grid_ratios(mesh, grid), f"{RD_STEP:g} mm": grid_ratios(mesh, fine)}}


def geomean(values):
    """Geometric mean of the values that are there, None when none is."""
    values = [v for v in values if v]
    return float(np.exp(np.mean(np.log(values)))) if values else None


def markdown(document):
    """The report."""
    rows = document["rows"]
    lines = ["# Where issue 33's margin was looked for: decoder offsets, mirror symmetry, the grid", "",
             f"Generated {document['date']} by `benchmarks/codec_limits.py` at commit {document['commit']}, "
             f"{document['seconds']:.0f} s on {document['machine']}.", "",
             f"{len(rows)} faces. See the script's docstring for the method. Below 1: fewer bytes than today.", "",
             "## Decoder offsets", "",
             "Bytes at equal RMS surface error (node estimate) with every nonzero detail coefficient "
             "reconstructed delta steps nearer zero, over today's (geometric mean over faces; range):", "",
             "| delta | bytes | range | slope of log bytes over log error |", "|---|---|---|---|"]
    for delta in OFFSETS:
        values = [r["offsets"][str(delta)]["bytes"] for r in rows]
        slopes = [r["offsets"][str(delta)]["slope"] for r in rows]
        lines.append(f"| {delta:g} | {fmt(geomean(values), 4)} | {min(values):.4f}-{max(values):.4f} | "
                     f"{np.median(slopes):.2f} (median) |")
    lines += ["", "## Mirror symmetry", "",
              "The symmetric half and the antisymmetric part, coded apart, over the grid coded whole at the "
              "same RMS target (geometric mean over faces; range). Asymmetry RMS (z less its mirror image "
              f"about the best axis): median {np.median([r['asymmetry_rms'] for r in rows]):.2f} mm.", "",
              "| target mm | split / whole | range |", "|---|---|---|"]
    for target in MIRROR_TARGETS:
        ratios = [r["mirror"][str(target)]["split"] / r["mirror"][str(target)]["whole"] for r in rows]
        lines.append(f"| {target:g} | {fmt(geomean(ratios), 3)} | {min(ratios):.3f}-{max(ratios):.3f} |")
    lines += ["", "## The grid", "",
              "Peer bytes over mzc's (dwt2d --rmse) at equal whole-surface RMS, geometric mean over faces, "
              f"on mzc's default grid and on rd.py's {RD_STEP:g} mm grid (median shapes "
              f"{median_shape(rows, 'grid')} and {median_shape(rows, 'fine_grid')}):", "",
              "| grid | peer | " + " | ".join(f"{t:g} mm" for t in TARGETS) + " |",
              "|---|---|" + "---|" * len(TARGETS)]
    for grid in rows[0]["grids"]:
        for peer in PEERS:
            means = [geomean([r["grids"][grid][peer][i] for r in rows]) for i in range(len(TARGETS))]
            lines.append(f"| {grid} | {peer} | " + " | ".join(fmt(m, 3) for m in means) + " |")
    return "\n".join(lines) + "\n"


def median_shape(rows, key):
    """The median rows x columns of ``key``'s grids."""
    return " x ".join(str(int(np.median([r[key][axis] for r in rows]))) for axis in (0, 1))


def main():
    args = benchmark_parser(__doc__, f"the first {QUICK_FACES} faces", workers=True).parse_args()
    started = time.perf_counter()
    faces = faces_measured("codec_limits", args.quick, quick_count=QUICK_FACES)
    with Pool(args.workers) as pool:
        rows = pool.map(face_row, faces, chunksize=1)
    write_report(args.out, "codec-limits", stamped(PACKAGES, started, quick=args.quick, rows=rows), markdown)


if __name__ == "__main__":
    main()
