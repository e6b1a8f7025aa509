"""Binning against Delaunay: how far apart the two ways of slicing a point cloud are, and how fast.

    python benchmarks/clouds.py [--points 1000000] [--out DIR]

1. The 13 faces' vertices as clouds (``shared/data/faces``): each sliced on the planar grid
   looking along +z, the way the faces look (a bare cloud's ``auto`` view, from unoriented
   normals, may look from the side, where Delaunay of the overlapping profile is noise), by
   Delaunay (``--cloud delaunay``) at its default spacing (half the median edge) and by
   binning (``--cloud bin``) on the same grid, and again both at binning's default spacing
   (the median point spacing). Each is compared with the face mesh itself cut on the same
   grid (the exact heights), and with the other.
2. A million-point cloud: a synthetic terrain (``lidar_cloud``, ground points only, 3 cm of
   noise) sliced both ways at binning's default spacing, each against the true surface; CPU
   time and peak memory of each (in child processes).

Writes clouds-results.md and clouds-results.json into --out (default: this directory).
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from corpora import FACES, mesh_files

HERE = Path(__file__).resolve().parent
NOISE = 0.03          # m of height noise on the synthetic terrain's points
VEGETATION = 0.35     # the share of points above the ground (class 5) in lidar_cloud


def terrain_height(x, y):
    """The synthetic terrain (m) at x, y (m): rolling hills, a ridge and a slope."""
    return 30 * np.sin(x / 170.0) * np.cos(y / 230.0) + 12 * np.sin((x + 2 * y) / 61.0) + 0.02 * x


def lidar_cloud(points, seed=0, vegetation=VEGETATION):
    """(xyz (n, 3), ASPRS classes (n,)) of an airborne survey of 1 km x 1 km of terrain in UTM-like
    coordinates: ground points (class 2) with NOISE of noise, a share ``vegetation`` of points
    0.5-15 m above it (class 5)."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 1000, points), rng.uniform(0, 1000, points)
    z = terrain_height(x, y) + rng.normal(0, NOISE, points)
    above = rng.random(points) < vegetation
    z[above] += rng.uniform(0.5, 15, above.sum())
    return np.column_stack([x + 500000, y + 4100000, z + 100]), np.where(above, 5, 2).astype(np.uint8)


def write_laz(path, points, seed=0, vegetation=VEGETATION):
    """Write ``lidar_cloud(points)`` as LAZ (LAS 1.2, point format 3, 1 cm quanta) to ``path``."""
    import laspy

    xyz, classes = lidar_cloud(points, seed, vegetation)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = [0.01, 0.01, 0.01], [500000, 4100000, 0]
    data = laspy.LasData(header)
    data.x, data.y, data.z = xyz.T
    data.classification = classes
    data.write(path)


def compare(a, b):
    """{rms, median, p99, max, both} of |a - b| over the nodes valid in both grids."""
    both = np.isfinite(a) & np.isfinite(b)
    difference = np.abs(a - b)[both]
    return {"rms": float(np.sqrt(np.mean(difference ** 2))), "median": float(np.median(difference)),
            "p99": float(np.percentile(difference, 99)), "max": float(difference.max()), "both": int(both.sum())}


def face_rows():
    """Part 1: per face, Delaunay and binning on one grid, at each method's default spacing."""
    from mzc.meshes import Mesh, read_mesh
    from mzc.ops.slicing import slice_in_frame, slice_surface

    rows = []
    for path in (p for p in mesh_files(FACES) if p.suffix == ".ply"):
        mesh = read_mesh(path)
        cloud = Mesh(mesh.points)
        for default in ("delaunay", "bin"):
            spacing = slice_surface(cloud, cloud=default, view="+z").d1
            grids, seconds = {}, {}
            for method in ("delaunay", "bin"):
                start = time.process_time()
                grids[method] = slice_surface(cloud, d1=spacing, d2=spacing, cloud=method, view="+z")
                seconds[method] = time.process_time() - start
            grid = grids["bin"]
            exact = slice_in_frame(mesh, grid.transform[:, :3], grid.transform[:, 3], d1=spacing, d2=spacing).z
            rows.append({"face": path.name, "vertices": len(mesh.points), "spacing_of": default, "spacing": spacing,
                         "shape": list(grid.shape),
                         **{f"{m}_valid": int(np.isfinite(grids[m].z).sum()) for m in grids},
                         **{f"{m}_cpu_s": seconds[m] for m in grids},
                         **{f"{m}_vs_mesh": compare(grids[m].z, exact) for m in grids},
                         "bin_vs_delaunay": compare(grids["bin"].z, grids["delaunay"].z)})
            print(f"{path.name} {default}: {rows[-1]['bin_vs_delaunay']}", file=sys.stderr)
    return rows


CHILD = """import json, resource, sys, time
import numpy as np
sys.path.insert(0, {here!r})
from clouds import terrain_height
from mzc.meshes import read_mesh
from mzc.ops.slicing import slice_surface
mesh = read_mesh({path!r})
start = time.process_time()
grid = slice_surface(mesh, d1={spacing!r}, d2={spacing!r}, cloud={method!r})
cpu = time.process_time() - start
nodes = grid.to_input_frame(grid.node_points()[grid.valid])
error = nodes[:, 2] - 100 - terrain_height(nodes[:, 0] - 500000, nodes[:, 1] - 4100000)
np.save({out!r}, grid.z)
print(json.dumps({{"cpu_s": cpu, "valid": int(grid.valid.sum()), "nodes": int(grid.z.size),
                   "vs_truth_rms": float(np.sqrt(np.mean(error ** 2))), "vs_truth_max": float(np.abs(error).max()),
                   "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}}))
"""


def million_rows(points, folder):
    """Part 2: the synthetic terrain sliced both ways at binning's default spacing, in child processes."""
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    path = folder / "terrain.laz"
    write_laz(path, points, vegetation=0.0)
    spacing = slice_surface(read_mesh(path), cloud="bin").d1
    result = {"points": points, "spacing": spacing}
    for method in ("bin", "delaunay"):
        out = folder / f"{method}.npy"
        code = CHILD.format(here=str(HERE), path=str(path), spacing=spacing, method=method, out=str(out))
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        result[method] = json.loads(done.stdout)
        print(f"million {method}: {result[method]}", file=sys.stderr)
    result["bin_vs_delaunay"] = compare(np.load(folder / "bin.npy"), np.load(folder / "delaunay.npy"))
    return result


def markdown(faces, million):
    """The report."""
    def fig(value):
        return f"{value:.4f}"

    def spread(figures):
        return f"{figures['rms']:.3f}, {figures['median']:.4f}, {figures['p99']:.3f}"

    lines = ["# Point clouds: binning against Delaunay", "",
             "Written by `python benchmarks/clouds.py` (see its docstring for the method). Distances are along "
             "the node lines (heights), RMS and max over the nodes valid in both grids compared; the faces in "
             "mm, the terrain in m. CPU seconds of `slice_surface` alone (the view search included).", "",
             "## The 13 faces' vertices as clouds", "",
             "| face | vertices | spacing (of) | grid | valid: Delaunay / bin | Delaunay vs mesh: RMS, median, p99 | "
             "bin vs mesh: RMS, median, p99 | bin vs Delaunay: RMS, median, p99 | CPU s: Delaunay / bin |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in faces:
        lines.append(
            f"| {row['face']} | {row['vertices']:,} | {row['spacing']:.3f} ({row['spacing_of']}) | "
            f"{row['shape'][0]} x {row['shape'][1]} | {row['delaunay_valid']:,} / {row['bin_valid']:,} | "
            f"{spread(row['delaunay_vs_mesh'])} | {spread(row['bin_vs_mesh'])} | {spread(row['bin_vs_delaunay'])} | "
            f"{row['delaunay_cpu_s']:.2f} / {row['bin_cpu_s']:.2f} |")
    for default in ("delaunay", "bin"):
        chosen = [row for row in faces if row["spacing_of"] == default]
        if chosen:
            lines += ["", f"At {default}'s default spacing, medians over the faces: from the mesh, Delaunay "
                      f"{np.median([r['delaunay_vs_mesh']['rms'] for r in chosen]):.3f} mm RMS (median node "
                      f"{np.median([r['delaunay_vs_mesh']['median'] for r in chosen]):.4f}), binning "
                      f"{np.median([r['bin_vs_mesh']['rms'] for r in chosen]):.3f} mm (median node "
                      f"{np.median([r['bin_vs_mesh']['median'] for r in chosen]):.4f}); binning from Delaunay "
                      f"{np.median([r['bin_vs_delaunay']['rms'] for r in chosen]):.3f} mm RMS (median node "
                      f"{np.median([r['bin_vs_delaunay']['median'] for r in chosen]):.4f}); valid nodes binned / "
                      f"Delaunay {np.median([r['bin_valid'] / r['delaunay_valid'] for r in chosen]):.3f}."]
    if million:
        b, d = million["bin"], million["delaunay"]
        lines += ["", f"## A {million['points']:,}-point terrain", "",
                  f"Synthetic terrain (`lidar_cloud`, ground only, {NOISE} m of noise), as LAZ; both methods at "
                  f"binning's default spacing {million['spacing']:.3f} m.", "",
                  "| method | valid nodes | vs the true surface: RMS (max) | CPU s | peak RSS MB |",
                  "|---|---|---|---|---|",
                  f"| bin | {b['valid']:,} of {b['nodes']:,} | {fig(b['vs_truth_rms'])} ({b['vs_truth_max']:.3f}) | "
                  f"{b['cpu_s']:.2f} | {b['peak_mb']:.0f} |",
                  f"| delaunay | {d['valid']:,} of {d['nodes']:,} | {fig(d['vs_truth_rms'])} ({d['vs_truth_max']:.3f}) "
                  f"| {d['cpu_s']:.2f} | {d['peak_mb']:.0f} |", "",
                  f"Binning against Delaunay: RMS {fig(million['bin_vs_delaunay']['rms'])} m, max "
                  f"{million['bin_vs_delaunay']['max']:.3f} m over {million['bin_vs_delaunay']['both']:,} nodes; "
                  f"CPU {d['cpu_s'] / b['cpu_s']:.0f}x less, memory {d['peak_mb'] / b['peak_mb']:.1f}x less."]
    return "\n".join(lines) + "\n"


def main():
    import tempfile

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--out", type=Path, default=HERE)
    args = parser.parse_args()
    faces = face_rows() if FACES.is_dir() else []
    with tempfile.TemporaryDirectory(prefix="bench-clouds-", dir="/tmp") as folder:
        million = million_rows(args.points, Path(folder)) if args.points else None
    (args.out / "clouds-results.json").write_text(json.dumps({"faces": faces, "million": million}, indent=1) + "\n")
    (args.out / "clouds-results.md").write_text(markdown(faces, million))


if __name__ == "__main__":
    main()
