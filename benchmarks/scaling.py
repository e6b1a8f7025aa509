"""How encode, decode, densify and triangulate grow with the grid: wall time and peak memory per stage (issue 15).

Generates synthetic terrain z-grids with holes at 0.1 .. 25 million nodes, runs each stage
as its own ``mzc`` subprocess (so its peak RSS is the stage's alone) and prints a markdown
table with the exponent of each stage between neighbouring sizes (log of the time or memory
ratio over log of the node ratio: 1 is linear).

    python benchmarks/scaling.py                       # every size
    python benchmarks/scaling.py --sizes 0.1,0.4,1.6   # a subset (millions of nodes)

``terrain(rows, cols, seed)`` is the grid generator; other benchmarks import it.
"""

import argparse
import math
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SIZES = (0.1, 0.4, 1.6, 6.4, 25.0)     # millions of nodes
ROUGHNESS = 0.1                         # metres: amplitude of the finest noise octave (2 nodes)
RMSE = 0.02                             # metres: a fifth of the roughness, so the fine detail is coded
SPACING = 1.0                           # metres between nodes
STAGES = ("encode", "decode", "densify", "triangulate")


def terrain(rows, cols, seed):
    """A (rows, cols) synthetic terrain in metres, NaN where there is no data.

    A smooth random surface: octaves of Gaussian noise on lattices 2, 4, 8 .. nodes apart (up
    to a quarter of the grid), upsampled bicubically and summed with an amplitude proportional
    to the lattice spacing (ROUGHNESS at 2 nodes): the same statistics per node at every size,
    so the sizes compress alike, and a relief that grows with the area (~100 m at 25 M nodes).
    The data end at a wobbly oval border (NaN outside, like a survey's footprint; about a
    third of the nodes) and have interior holes, discs 2-25 nodes in radius whose count grows
    with the area (one per 40 000 nodes).
    """
    from scipy.ndimage import map_coordinates, spline_filter

    rng = np.random.default_rng(seed)
    z = np.zeros((rows, cols))
    spacing = 2                          # of the noise lattice, in nodes; amplitude grows with it
    while spacing <= max(rows, cols) / 4:
        lattice = spline_filter(rng.standard_normal((rows // spacing + 4, cols // spacing + 4)), order=3)
        c = np.arange(cols)[None, :] / spacing + 1
        for r0 in range(0, rows, 512):   # in strips: the coordinate arrays stay small
            r = np.arange(r0, min(rows, r0 + 512))[:, None] / spacing + 1
            z[r0:r0 + 512] += ROUGHNESS * spacing / 2 * map_coordinates(
                lattice, (r + 0 * c, c + 0 * r), order=3, mode="nearest", prefilter=False)
        spacing *= 2
    y, x = np.linspace(0, 1, rows), np.linspace(0, 1, cols)
    wobble = rng.standard_normal(8) * 0.04
    for r0 in range(0, rows, 512):
        v = 2 * y[r0:r0 + 512, None] - 1
        u = 2 * x[None, :] - 1
        angle = np.arctan2(v, u)
        edge = 0.92 + sum(w * np.cos((k + 2) * angle + k) for k, w in enumerate(wobble))
        z[r0:r0 + 512][np.hypot(u, v) > edge] = np.nan
    holes = max(1, rows * cols // 40_000)
    centres = rng.uniform(0, 1, (holes, 2)) * (rows, cols)
    radii = rng.uniform(2, 25, holes)
    for (cr, cc), radius in zip(centres, radii):
        r0, r1 = int(max(0, cr - radius)), int(min(rows, cr + radius + 1))
        c0, c1 = int(max(0, cc - radius)), int(min(cols, cc + radius + 1))
        rr, cc_ = np.ogrid[r0:r1, c0:c1]
        z[r0:r1, c0:c1][(rr - cr) ** 2 + (cc_ - cc) ** 2 <= radius**2] = np.nan
    return z


def terrain_grid(rows, cols, seed):
    """The ``terrain`` as a planar ZGrid, SPACING metres between nodes."""
    from mzc.grid import ZGrid

    return ZGrid(terrain(rows, cols, seed), SPACING, SPACING, units="m")


def write_terrain(path, millions, seed=15):
    """Write a square terrain of about ``millions`` million nodes as a raw float64 z-grid; its shape."""
    from mzc.formats import zgrid

    side = int(round(math.sqrt(millions * 1e6)))
    grid = terrain_grid(side, side, seed)
    path.write_bytes(zgrid.write(grid, raw="float64"))
    return grid.z.shape


def run(command):
    """(wall seconds, peak RSS in MB, CPU seconds) of one subprocess; raises when it fails. The
    CPU time (user + system) is the steadier measure on a shared machine."""
    start = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - start
    process.returncode = os.waitstatus_to_exitcode(status)
    error = process.stderr.read().decode(errors="replace")
    process.stderr.close()
    if process.returncode:
        raise RuntimeError(f"{shlex.join(command)} failed ({process.returncode}): {error.strip()[-500:]}")
    return wall, usage.ru_maxrss / 1024, usage.ru_utime + usage.ru_stime   # ru_maxrss is in KiB on Linux


def measure(millions, mzc, folder, stages):
    """(the grid's shape, {stage: (seconds, MB, CPU seconds)}) for one size."""
    grid, packed, decoded, dense, mesh = (folder / name for name in ("in.zg", "in.mzw2", "out.zg", "dense.zg",
                                                                     "mesh.ply"))
    shape = write_terrain(grid, millions)
    commands = {
        "encode": [*mzc, "encode", "--dwt2d", "--rmse", str(RMSE), str(grid), "-o", str(packed)],
        "decode": [*mzc, "decode", str(packed), "-o", str(decoded)],
        "densify": [*mzc, "densify", "-n", "1", str(grid), "-o", str(dense)],
        "triangulate": [*mzc, "triangulate", str(grid), "-o", str(mesh)],
    }
    results = {}
    for stage in stages:
        results[stage] = run(commands[stage])
        wall, mb, cpu = results[stage]
        print(f"  {millions:g} M {stage}: {wall:.1f} s ({cpu:.1f} s CPU), {mb:.0f} MB", file=sys.stderr, flush=True)
    if "encode" in stages:
        results["bytes"] = packed.stat().st_size
    for path in (grid, packed, decoded, dense, mesh):
        path.unlink(missing_ok=True)
    return shape, results


def exponent(small, large, nodes_small, nodes_large):
    """log(large / small) / log(nodes ratio): how the quantity grows with the node count."""
    return math.log(large / small) / math.log(nodes_large / nodes_small)


def table(rows, stages):
    """The markdown table: one line per size; per stage wall time, CPU time, peak memory and
    the exponents of CPU time and memory since the size before (a last line: over the range)."""
    head = ["nodes", "shape"] + [f"{stage} {what}" for stage in stages
                                 for what in ("s", "CPU s", "MB", "exp CPU", "exp MB")]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    previous = None
    for shape, results in rows:
        nodes = shape[0] * shape[1]
        cells = [f"{nodes / 1e6:.2f} M", f"{shape[0]}x{shape[1]}"]
        for stage in stages:
            seconds, mb, cpu = results[stage]
            if previous is None:
                growth = ["", ""]
            else:
                before_nodes, before = previous
                growth = [f"{exponent(before[stage][k], results[stage][k], before_nodes, nodes):.2f}" for k in (2, 1)]
            cells += [f"{seconds:.1f}", f"{cpu:.1f}", f"{mb:.0f}", *growth]
        lines.append("| " + " | ".join(cells) + " |")
        previous = (nodes, results)
    if len(rows) > 2:   # the growth over the whole range run
        (first_shape, first), (last_shape, last) = rows[0], rows[-1]
        span = (first_shape[0] * first_shape[1], last_shape[0] * last_shape[1])
        cells = [f"{span[0] / 1e6:.2f}-{span[1] / 1e6:.2f} M", ""]
        for stage in stages:
            cells += ["", "", "", *(f"{exponent(first[stage][k], last[stage][k], *span):.2f}" for k in (2, 1))]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default=",".join(f"{s:g}" for s in SIZES),
                        help="comma-separated sizes in millions of nodes (default: %(default)s)")
    parser.add_argument("--stages", default=",".join(STAGES), help="comma-separated stages (default: %(default)s)")
    parser.add_argument("--mzc", default=f"{shlex.quote(sys.executable)} -m mzc",
                        help="the command that runs mzc (default: this Python's)")
    args = parser.parse_args()
    stages = [s for s in args.stages.split(",") if s]
    unknown = set(stages) - set(STAGES)
    if unknown:
        parser.error(f"unknown stage(s) {', '.join(sorted(unknown))}")
    if "decode" in stages and "encode" not in stages:
        parser.error("decode needs encode")
    rows = []
    with tempfile.TemporaryDirectory(prefix="mzc-scaling-") as folder:
        for millions in (float(s) for s in args.sizes.split(",")):
            rows.append(measure(millions, shlex.split(args.mzc), Path(folder), stages))
    print(table(rows, stages))
    if "encode" in stages:
        print("\nencoded bytes: " + ", ".join(f"{s[0] * s[1] / 1e6:.2f} M: {r['bytes']}" for s, r in rows))


if __name__ == "__main__":
    main()
