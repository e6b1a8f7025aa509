"""Multi-chart grids' spacing against bytes at equal whole-surface error (issue 28).

    python benchmarks/chart_spacing.py [--quick] [--out DIR] [--workers N]

For every object of shared/data/objects, its multi-chart grid is cut by ``mzc.slice(original,
d1=k * s0)`` at multiples k of s0, the spacing its own sampling suggests
(``mzc.ops.slicing.source_spacing``: half the median triangle edge, a cloud's half median
nearest-point distance, at most 1/200 of the longest side; the multi-chart default before
issue 28's spacing change), and by ``mzc.slice(original)`` at the default of the code run.
Each grid is rebuilt uncoded (the floor) and coded by ``mzc.encode(grid, "dwt2d", rmse=r * D
/ 100)`` over a ladder of r, every rebuild by ``mzc.triangulate(..., vertices="all")`` (every
node kept: the codec, not the simplification, is measured) and measured over the whole
surface by ``objects.errors`` (fewer samples than objects.py: SAMPLES each way). mzc's bytes at
0.05 and 0.1% D are interpolated on its Pareto front (``report.bytes_at``), Draco's are those
of benchmarks/objects-results.json (100,000 samples each way), and their ratio is
``report.item_ratios``'s. The ogre's slice + encode and decode + triangulate (default: the
rebuild simplified to the source's vertex count) are timed in CPU seconds at each spacing.
Writes chart-spacing-results.md and .json into --out (default: this directory).
"""

import datetime
import json
import sys
import time
import warnings
from pathlib import Path

from startup import HERE  # first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import OBJECTS, mesh_files
from objects import (
    COVERAGE,
    DRACO,
    FLOOR_HAUSDORFF,
    FLOOR_RMS,
    ISSUE_RANGE,
    Surface,
    errors,
    timed,
)
from report import benchmark_parser, bytes_at, fmt, git_commit, item_ratios, machine, pareto

FACTORS, QUICK_FACTORS = (1, 1.5, 2, 3, 4, 6), (1, 2, 4)   # k: the spacing is k * s0
LADDER = (0.01, 0.015, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15)    # dwt2d rmse targets, % of D
SAMPLES, QUICK_SAMPLES = 30_000, 10_000   # per direction, per rebuild
TIMED_OBJECT, REPEATS = "ogre", 3
DEFAULT = "default"   # the row of mzc.slice's own default spacing
MZC = "mzc dwt2d"


def run_grid(mesh, original, d1, samples):
    """The floor and the dwt2d ladder of ``mzc.slice(mesh, d1=d1)`` (``d1`` None: the default)."""
    import mzc

    grid = mzc.slice(mesh) if d1 is None else mzc.slice(mesh, d1=d1)
    row = {"d1": float(grid.d1), "shape": list(grid.shape), "nodes": int(np.sum(grid.valid)),
           "floor": errors(original, Surface.of(mzc.triangulate(grid, vertices="all")), samples), "points": []}
    for r in LADDER:
        data = mzc.encode(grid, "dwt2d", rmse=r * original.diagonal / 100)
        rebuild = Surface.of(mzc.triangulate(mzc.decode(data), vertices="all"))
        row["format"] = data.split(b"\n", 1)[0].decode()
        row["points"].append({"contender": MZC, "family": "mzc", "setting": r, "bytes": len(data),
                              **errors(original, rebuild, samples)})
    return row


def cpu_times(mesh, d1, diagonal):
    """Median CPU seconds of slice + encode at 0.05% D and of decode + triangulate (default)."""
    import mzc

    def sliced_and_encoded():
        grid = mzc.slice(mesh) if d1 is None else mzc.slice(mesh, d1=d1)
        return mzc.encode(grid, "dwt2d", rmse=0.05 * diagonal / 100)

    encode, data = timed(sliced_and_encoded, REPEATS)
    decode, _ = timed(lambda: mzc.triangulate(mzc.decode(data)), REPEATS)
    return {"slice_encode_cpu_s": encode["cpu_s"], "decode_triangulate_cpu_s": decode["cpu_s"]}


def run_object(job):
    """Every spacing of one object: {"item", "diagonal", "vertices", "s0", "rows": {k: run_grid}}."""
    import mzc
    from mzc.ops.slicing import source_spacing

    path, factors, samples = job
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = mzc.read(path)
        original = Surface.of(mesh)
        s0, default = source_spacing(mesh), run_grid(mesh, original, None, samples)
        rows = {str(k): dict(default) if k * s0 == default["d1"] else run_grid(mesh, original, k * s0, samples)
                for k in factors}   # a factor at the default's spacing is its grid, measured already
        rows[DEFAULT] = default
        if Path(path).stem == TIMED_OBJECT:
            for k, row in rows.items():
                row["times"] = cpu_times(mesh, None if k == DEFAULT else float(k) * s0, original.diagonal)
    return {"item": Path(path).stem, "diagonal": original.diagonal, "vertices": len(original.points),
            "triangles": len(original.triangles), "s0": s0, "rows": rows, "wall_s": time.perf_counter() - started}


def draco_points(path=HERE / "objects-results.json"):
    """{object: Draco's points} of objects.py's last run (errors in % of D), {} without it."""
    if not path.exists():
        return {}
    return {item["item"]: [p for p in item["points"] if p["contender"] == DRACO]
            for item in json.loads(path.read_text())["items"]}


def figures(row, draco):
    """mzc bytes and Draco / mzc at ISSUE_RANGE's ends, and which floor targets are met."""
    front = pareto(row["points"], "whole rms")
    sizes = [bytes_at(front, t, below_cheapest=True) for t in ISSUE_RANGE]
    ratios = item_ratios({"points": row["points"] + draco, "unit": 1.0}, ISSUE_RANGE, "whole rms").get(DRACO)
    floor = row["floor"]
    met = {"rms": floor["whole"]["rms"] <= FLOOR_RMS, "hausdorff": floor["whole"]["hausdorff"] <= FLOOR_HAUSDORFF,
           "coverage": floor["coverage"] >= COVERAGE}
    return {"mzc_bytes": sizes, "draco_ratio": ratios or [None, None], "floor_met": met}


def met_letters(row):
    """The floor targets ``row`` meets as letters: R(MS), H(ausdorff), C(overage); "-" for none."""
    return "".join(c for c, ok in zip("RHC", row["figures"]["floor_met"].values()) if ok) or "-"


def pair(values, shown):
    """Two figures as "a / b", "-" for a missing one."""
    return " / ".join("-" if v is None else shown(v) for v in values)


def summary_lines(document):
    """Per object, the former default (k = 1: the source's spacing) beside the default of the
    commit run: nodes, floor targets met, bytes and Draco / mzc at 0.05 and 0.1% D."""
    lines = ["## The former default (k = 1) and the default of this commit", "",
             "| item | nodes | floor targets met | mzc KB at 0.05 / 0.1% D | Draco / mzc at 0.05 / 0.1% D |",
             "|---|---|---|---|---|"]
    for item in document["items"]:
        before, after = item["rows"]["1"], item["rows"][DEFAULT]
        kb = [pair(row["figures"]["mzc_bytes"], lambda b: f"{b / 1000:.1f}") for row in (before, after)]
        ratio = [pair(row["figures"]["draco_ratio"], fmt) for row in (before, after)]
        lines.append(f"| {item['item']} | {before['nodes']:,} -> {after['nodes']:,} | {met_letters(before)} -> "
                     f"{met_letters(after)} | {kb[0]} -> {kb[1]} | {ratio[0]} -> {ratio[1]} |")
    return lines + [""]


def markdown(document):
    """The report: the summary, then per object a row per spacing."""
    s = document["settings"]
    lines = ["# Multi-chart grid spacing against bytes (issue 28)", "",
             f"Generated {document['generated']} by `python benchmarks/chart_spacing.py` on {document['machine']}, "
             f"commit {document['commit']}; total wall time {s['wall_s']:.0f} s.", "",
             "## Method", "",
             "- Each object of `shared/data/objects` is cut by `mzc.slice(original, d1=k * s0)`, s0 the spacing its "
             "own sampling suggests (`mzc.ops.slicing.source_spacing`: half the median triangle edge, a cloud's "
             "half median nearest-point distance, at most 1/200 of the longest side: the multi-chart default "
             "before this change), and by `mzc.slice(original)` at the default of the commit run (row "
             f"'{DEFAULT}').",
             f"- Floor: the grid rebuilt uncoded. Ladder: `mzc.encode(grid, \"dwt2d\", rmse=r * D / 100)` for r in "
             f"{', '.join(map(str, s['ladder']))} (% of D), files `{document['format']}`. Every rebuild is "
             "`mzc.triangulate(..., vertices=\"all\")` (every node kept).",
             f"- Whole-surface error as `benchmarks/objects.py` measures it (`objects.errors`), but with "
             f"{s['samples']:,} samples each way (objects.py: 100,000), seed 0; in % of D.",
             "- mzc KB at 0.05 / 0.1% D: interpolated log-log on the Pareto front (`report.bytes_at`; the cheapest "
             "setting's bytes when even it is more accurate). Draco / mzc: `report.item_ratios` against Draco's "
             "points of `objects-results.json` (6..14 bits, 100,000 samples each way); '-' where mzc's front does "
             "not reach the target.",
             f"- Floor targets (issue 28): RMS <= {FLOOR_RMS}% D, Hausdorff <= {FLOOR_HAUSDORFF}% D, >= "
             f"{COVERAGE}% of the area within 0.1% D; 'met' lists those met (R, H, C).",
             f"- CPU seconds ({TIMED_OBJECT}, median of {REPEATS}): slice + encode at 0.05% D, decode + "
             "triangulate (default: simplified to the source's vertex count).", "", *summary_lines(document)]
    for item in document["items"]:
        lines += [f"## {item['item']}", "",
                  f"D {fmt(item['diagonal'], 4)}, {item['vertices']:,} vertices, {item['triangles']:,} triangles, "
                  f"s0 {fmt(item['s0'], 4)}.", "",
                  "| k | d1 | nodes | nodes / vertex | floor RMS % D | floor Hausdorff % D | area within 0.1% D "
                  "| met | mzc KB at 0.05 / 0.1% D | Draco / mzc at 0.05 / 0.1% D |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for k, row in item["rows"].items():
            f, floor = row["figures"], row["floor"]
            met = met_letters(row)
            kb, ratio = pair(f["mzc_bytes"], lambda b: f"{b / 1000:.1f}"), pair(f["draco_ratio"], fmt)
            lines.append(f"| {k} | {fmt(row['d1'], 4)} | {row['nodes']:,} | {row['nodes'] / item['vertices']:.2f} | "
                         f"{fmt(floor['whole']['rms'])} | {fmt(floor['whole']['hausdorff'])} | "
                         f"{floor['coverage']:.1f}% | {met} | {kb} | {ratio} |")
        timed_rows = {k: row["times"] for k, row in item["rows"].items() if "times" in row}
        if timed_rows:
            lines += ["", "| k | slice + encode CPU s | decode + triangulate CPU s |", "|---|---|---|"]
            lines += [f"| {k} | {t['slice_encode_cpu_s']:.2f} | {t['decode_triangulate_cpu_s']:.2f} |"
                      for k, t in timed_rows.items()]
        lines.append("")
    return "\n".join(lines)


def main(argv=None):
    import multiprocessing

    args = benchmark_parser(__doc__, "hand and dragon, k in 1, 2, 4, fewer samples", workers=True).parse_args(argv)
    paths = [str(p) for p in mesh_files(OBJECTS)]
    if args.quick:
        paths = [p for p in paths if Path(p).stem in ("hand", "dragon")]
    if not paths:
        print(f"chart_spacing.py: skipped: no objects in {OBJECTS}", file=sys.stderr)
        return
    factors, samples = (QUICK_FACTORS, QUICK_SAMPLES) if args.quick else (FACTORS, SAMPLES)
    started = time.perf_counter()
    jobs = sorted(((p, factors, samples) for p in paths), key=lambda job: -Path(job[0]).stat().st_size)
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        items = {item["item"]: item for item in pool.imap_unordered(run_object, jobs)}
    draco = draco_points()
    for item in items.values():
        for row in item["rows"].values():
            row["figures"] = figures(row, draco.get(item["item"], []))
    settings = {"quick": args.quick, "factors": factors, "ladder": LADDER, "samples": samples,
                "wall_s": time.perf_counter() - started}
    document = {"generated": f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}", "machine": machine(),
                "commit": git_commit(), "settings": settings, "items": [items[Path(p).stem] for p in paths]}
    document["format"] = document["items"][0]["rows"][DEFAULT]["format"]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "chart-spacing-results.json").write_text(json.dumps(document, indent=1, default=float) + "\n")
    (args.out / "chart-spacing-results.md").write_text(markdown(document))


if __name__ == "__main__":
    main()
