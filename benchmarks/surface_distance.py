"""How fast ``mzc diff --surface`` measures, and whether it measures the same.

1. A face: f18 against its decoded mesh (slice, dwt2d at RMSE 0.05, decode, densify -n 3,
   triangulate), ``surface_distance`` with the default 100,000 samples per side, by the
   method on main (``git show main:mzc/measure/metrics.py``, loaded into a temporary
   module, never committed) and by this tree's, timed alternately in one process (the
   machine is shared, so the ratio is the figure to trust), and whether the figures agree.
2. Two pairs of 1,000,000-vertex meshes, each measured in a child process whose time and
   peak resident memory (``os.wait4``) are reported: a wavy sheet against a perturbed copy,
   and a bumpy torus (closed, up to four layers over a point, so no height field) against
   a perturbed copy.
3. Every face against the next one, 20,000 samples per side, old and new, and whether the
   figures agree.

    python benchmarks/surface_distance.py [--faces DIR] [--rounds N] [--out FILE.md]
"""

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FACES = Path("/work/shared/data/faces")
SIDE = 1000   # vertices per side of the large meshes: 1,000,000 vertices, about 2,000,000 triangles


def old_metrics():
    """main's mzc/measure/metrics.py as a module of its own (from git, in a temporary file)."""
    source = subprocess.run(["git", "-C", str(ROOT), "show", "main:mzc/measure/metrics.py"], check=True,
                            capture_output=True, text=True).stdout
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as file:
        file.write(source)
    spec = importlib.util.spec_from_file_location("main_metrics", file.name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    os.unlink(file.name)
    return module


def decoded_face(face, folder):
    """The mesh that f18 comes back as through the pipeline of the README."""
    out = Path(folder) / "decoded.ply"
    mzc = [sys.executable, "-m", "mzc"]
    grid = subprocess.run([*mzc, "slice", str(face)], check=True, capture_output=True).stdout
    for step in (["encode", "--dwt2d", "--rmse", "0.05"], ["decode"], ["densify", "-n", "3"]):
        grid = subprocess.run([*mzc, *step], input=grid, check=True, capture_output=True).stdout
    subprocess.run([*mzc, "triangulate", "-o", str(out)], input=grid, check=True)
    return out


def face_rows(faces, rounds):
    """f18 against its decoded mesh: old and new seconds (best of ``rounds``) and the figures."""
    from mzc.measure import metrics
    from mzc.meshes import read_mesh

    old = old_metrics()
    with tempfile.TemporaryDirectory() as folder:
        a, b = read_mesh(faces / "f18.ply"), read_mesh(decoded_face(faces / "f18.ply", folder))
    meshes = (a.points, a.triangles), (b.points, b.triangles)
    times, cpu, figures = {"old": [], "new": []}, {"old": [], "new": []}, {}
    for _ in range(rounds):
        for name, module in (("old", old), ("new", metrics)):
            start, start_cpu = time.perf_counter(), time.process_time()
            figures[name] = module.surface_distance(*meshes)
            times[name].append(time.perf_counter() - start)
            cpu[name].append(time.process_time() - start_cpu)
    worst = max(abs(figures["new"][k] - v) / max(abs(v), 1e-300) for k, v in figures["old"].items())
    return {"vertices": [len(a.points), len(b.points)], "triangles": [len(a.triangles), len(b.triangles)],
            "old_s": min(times["old"]), "new_s": min(times["new"]), "old_all_s": times["old"],
            "new_all_s": times["new"], "old_cpu_s": min(cpu["old"]), "new_cpu_s": min(cpu["new"]),
            "largest_relative_difference": worst, "figures": figures["new"]}


def all_faces_rows(faces, old, samples=20_000):
    """Every face against the next one (the 13 faces in a ring), ``samples`` per side: old
    and new seconds and the largest relative difference of their figures."""
    from mzc.measure import metrics
    from mzc.meshes import read_mesh

    paths = sorted(faces.glob("*.ply")) + sorted(faces.glob("*.obj"))
    meshes = [read_mesh(path) for path in paths]
    rows = []
    for index, path in enumerate(paths):
        a, b = meshes[index], meshes[(index + 1) % len(paths)]
        pair, figures, seconds = ((a.points, a.triangles), (b.points, b.triangles)), {}, {}
        for name, module in (("old", old), ("new", metrics)):
            start = time.perf_counter()
            figures[name] = module.surface_distance(*pair, samples=samples)
            seconds[name] = time.perf_counter() - start
        worst = max(abs(figures["new"][k] - v) / max(abs(v), 1e-300) for k, v in figures["old"].items())
        rows.append({"a": path.name, "b": paths[(index + 1) % len(paths)].name, "old_s": seconds["old"],
                     "new_s": seconds["new"], "largest_relative_difference": worst, "rms": figures["new"]["rms"]})
    return rows


def wavy_sheet(side, rng, perturb):
    """A side x side grid of a wavy sheet, 100 x 100 units, optionally with its heights jittered."""
    from mzc.grid import ZGrid
    from mzc.ops.triangulation import grid_to_mesh

    y, x = np.mgrid[0:side, 0:side] * (100 / (side - 1))
    z = 3 * np.sin(x / 4) * np.cos(y / 5) + np.sin(x * y / 300)
    if perturb:
        z = z + rng.normal(scale=0.02, size=z.shape)
    mesh = grid_to_mesh(ZGrid(z, 100 / (side - 1), 100 / (side - 1)))
    return mesh.points, mesh.triangles


def torus(side, rng, perturb):
    """A closed bumpy torus of side x side vertices (periodic both ways), optionally jittered
    along its normal."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, side, endpoint=False), np.linspace(0, 2 * np.pi, side,
                                                                                     endpoint=False), indexing="ij")
    tube = 10 + 0.5 * np.sin(7 * u) * np.cos(5 * v)
    if perturb:
        tube = tube + rng.normal(scale=0.02, size=tube.shape)
    points = np.stack([(30 + tube * np.cos(v)) * np.cos(u), (30 + tube * np.cos(v)) * np.sin(u), tube * np.sin(v)],
                      axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
    a, b, c, d = i * side + j, ((i + 1) % side) * side + j, ((i + 1) % side) * side + (j + 1) % side, \
        i * side + (j + 1) % side
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return points, triangles


SHAPES = {"wavy sheet": wavy_sheet, "bumpy torus": torus}


def child(shape, side):
    """Make the pair of meshes and measure; print seconds and figures as JSON."""
    from mzc.measure.metrics import surface_distance

    rng = np.random.default_rng(1)
    start = time.perf_counter()
    first, second = SHAPES[shape](side, rng, False), SHAPES[shape](side, rng, True)
    made = time.perf_counter()
    figures = surface_distance(first, second)
    print(json.dumps({"vertices": [len(first[0]), len(second[0])], "triangles": [len(first[1]), len(second[1])],
                      "make_s": made - start, "distance_s": time.perf_counter() - made, "figures": figures}))


def large_row(shape, side):
    """One large pair measured in a child process: its output and peak RSS in MB."""
    process = subprocess.Popen([sys.executable, __file__, "--child", shape, "--side", str(side)],
                               stdout=subprocess.PIPE, text=True, cwd=ROOT)
    output = process.stdout.read()
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode:
        return {"shape": shape, "failed": process.returncode}
    return {"shape": shape, **json.loads(output), "peak_rss_mb": usage.ru_maxrss / 1024,
            "cpu_s": usage.ru_utime + usage.ru_stime}


def markdown(face, large, faces):
    lines = ["# Point-to-surface distance (`mzc diff --surface`): speed and memory", "",
             "Written by `benchmarks/surface_distance.py`. The machine is shared (2 cores), so times",
             "are noisy: the old and new methods ran alternately in one process and the ratio is the",
             "figure to trust.", "", "## f18 against its decoded mesh (100,000 samples per side)", "",
             f"A: {face['vertices'][0]:,} vertices, {face['triangles'][0]:,} triangles; B (slice, dwt2d RMSE 0.05,"
             f" decode, densify -n 3, triangulate): {face['vertices'][1]:,} vertices, {face['triangles'][1]:,}"
             " triangles.", "",
             "| method | best of runs (s) | all runs (s) | CPU, best (s, both cores) |", "|---|---|---|---|",
             f"| main | {face['old_s']:.2f} | {', '.join(f'{t:.2f}' for t in face['old_all_s'])} | "
             f"{face['old_cpu_s']:.2f} |",
             f"| this branch | {face['new_s']:.2f} | {', '.join(f'{t:.2f}' for t in face['new_all_s'])} | "
             f"{face['new_cpu_s']:.2f} |", "",
             f"Speed-up {face['old_s'] / face['new_s']:.1f}x in time, "
             f"{face['old_cpu_s'] / face['new_cpu_s']:.1f}x in CPU; "
             f"load average {os.getloadavg()[0]:.1f} at the end. Largest relative difference of the figures: "
             f"{face['largest_relative_difference']:.1e}.", "",
             "```", json.dumps(face["figures"], indent=1), "```", "",
             "## 1,000,000-vertex meshes (100,000 samples per side, one child process each)", "",
             "| pair | vertices | triangles | making (s) | distance (s) | child's CPU, all of it (s) | peak RSS (MB) "
             "| rms | hausdorff |", "|---|---|---|---|---|---|---|---|---|"]
    for row in large:
        if "failed" in row:
            lines.append(f"| {row['shape']} | failed with exit status {row['failed']} | | | | | | | |")
            continue
        lines.append(f"| {row['shape']} vs perturbed copy | {row['vertices'][0]:,} | {row['triangles'][0]:,} | "
                     f"{row['make_s']:.1f} | {row['distance_s']:.1f} | {row['cpu_s']:.1f} | {row['peak_rss_mb']:.0f} | "
                     f"{row['figures']['rms']:.4g} | {row['figures']['hausdorff']:.4g} |")
    lines += ["", "## Every face against the next (20,000 samples per side)", "",
              "| A | B | main (s) | this branch (s) | largest relative difference | rms |", "|---|---|---|---|---|---|"]
    lines += [f"| {row['a']} | {row['b']} | {row['old_s']:.2f} | {row['new_s']:.2f} | "
              f"{row['largest_relative_difference']:.1e} | {row['rms']:.4g} |" for row in faces]
    lines += ["", f"Load average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores."]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--faces", type=Path, default=FACES)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--side", type=int, default=SIDE)
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "surface-distance-results.md")
    parser.add_argument("--child", choices=sorted(SHAPES), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child(args.child, args.side)
    large = [large_row(shape, args.side) for shape in SHAPES]
    print(json.dumps(large, indent=1), flush=True)
    face = face_rows(args.faces, args.rounds)
    print(json.dumps(face, indent=1), flush=True)
    faces = all_faces_rows(args.faces, old_metrics())
    print(json.dumps(faces, indent=1), flush=True)
    args.out.write_text(markdown(face, large, faces))


if __name__ == "__main__":
    main()
