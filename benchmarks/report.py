"""The outputs of the rate-distortion benchmark: JSON of every point, markdown report, plots.

Also the whole-process timings of the CLI (``mzc --help`` and the README pipeline), which
need subprocesses rather than the in-process timing of the codecs.
"""

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from importlib import metadata
from pathlib import Path

import numpy as np

README_PIPELINE = [["slice", "{face}"], ["encode", "--dwt2d", "--rmse", "0.05"], ["decode"], ["densify", "-n", "3"],
                   ["triangulate", "-o", "{out}"]]
PACKAGES = ("numpy", "scipy", "PyWavelets", "DracoPy", "imagecodecs", "lerc", "zfpy", "pysz", "constriction")
DWT2D_SECONDS = 0.5     # issue 6: encode + decode of a face sliced at 0.5 mm, compute time
SLICE_SECONDS = 0.2     # issue 11: slicing a face at 0.5 mm in the default projection, compute time
PARTS = {"whole": "whole-surface", "heightfield": "height-field"}
STATISTICS = {"rms": "RMS", "hausdorff": "Hausdorff"}
NODE_VALUES = {"planar": "node values are heights", "cylindrical": "node values are distances from an axis",
               "spherical": "node values are distances along rays from a centre behind the face"}


def terminal_progress():
    """A function printing a line of progress to stderr when it is a terminal, doing nothing otherwise."""
    if sys.stderr.isatty():
        return lambda text: print(text, file=sys.stderr, flush=True)
    return lambda text: None


# --------------------------------------------------------------------------- CLI timings


def run_stages(stages):
    """Run ``python -m mzc`` stages piped together; (wall seconds, [peak RSS MiB per stage], error)."""
    start = time.perf_counter()
    processes, previous = [], None
    for stage in stages:
        process = subprocess.Popen([sys.executable, "-m", "mzc", *stage], stdin=previous,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        if previous is not None:
            previous.close()
        previous = process.stdout
        processes.append(process)
    previous.read()
    peaks, error = [], None
    for stage, process in zip(stages, processes):
        _pid, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        peaks.append(usage.ru_maxrss / 1024)
        message = process.stderr.read().decode(errors="replace").strip()
        if process.returncode and error is None:
            error = f"mzc {stage[0]}: exit {process.returncode}: {message[-300:]}"
    return time.perf_counter() - start, peaks, error


def pipeline_timings(face, repeats):
    """Median wall time and peak memory of ``mzc --help`` and of the README pipeline on ``face``."""
    rows = {"mzc --help": [["--help"]]}
    with tempfile.TemporaryDirectory() as scratch:
        if face:
            out = str(Path(scratch) / "out.ply")
            rows[f"README pipeline on {Path(face).name}"] = [
                [word.format(face=face, out=out) for word in stage] for stage in README_PIPELINE]
        return {name: timed(stages, repeats) for name, stages in rows.items()}


def timed(stages, repeats):
    runs = [run_stages(stages) for _ in range(repeats)]
    return {"command": " | ".join("mzc " + " ".join(s) for s in stages),
            "wall_s": float(np.median([r[0] for r in runs])),
            "peak_rss_mib": [max(r[1][k] for r in runs) for k in range(len(stages))],
            "error": next((r[2] for r in runs if r[2]), None)}


# --------------------------------------------------------------------------- rate-distortion


def error_of(point, measure):
    """The error of a point (or of a ``measure`` dict of parts) by ``measure``, "part statistic"
    such as "whole rms", "whole hausdorff" or "heightfield rms"."""
    part, statistic = measure.split()
    return point[part][statistic]


def measure_label(measure):
    """"whole rms" -> "whole-surface RMS"."""
    part, statistic = measure.split()
    return f"{PARTS[part]} {STATISTICS[statistic]}"


def pareto(points, measure):
    """(errors, bytes) of the points no other point beats in both, by increasing bytes."""
    ordered = sorted(points, key=lambda p: (p["bytes"], error_of(p, measure)))
    front, best = [], np.inf
    for p in ordered:
        error = error_of(p, measure)
        if np.isfinite(error) and error < best:
            front.append((error, p["bytes"]))
            best = error
    return front


def bytes_at(front, error, below_cheapest=False):
    """Bytes at ``error`` interpolated log-log on a Pareto front; None outside its error range.

    With ``below_cheapest``, an error above the whole front (even the cheapest setting is
    more accurate) costs the cheapest setting's bytes: an upper bound on what it would cost.
    """
    if len(front) == 0:
        return None
    errors = np.log([e for e, _ in front])[::-1]
    sizes = np.log([b for _, b in front])[::-1]
    if below_cheapest and np.log(error) > errors[-1]:
        return float(np.exp(sizes[-1]))
    if not errors[0] <= np.log(error) <= errors[-1]:
        return None
    return float(np.exp(np.interp(np.log(error), errors, sizes)))


def item_ratios(result, targets, measure):
    """{peer: [ratio or None per target]}: peer bytes / best mzc bytes at equal error by ``measure``.

    Peers are interpolated strictly; mzc contenders whose cheapest setting is already more
    accurate than the target count at that setting's bytes, which can only overstate mzc.
    """
    curves = defaultdict(list)
    for p in result["points"]:
        curves[(p["family"], p["contender"])].append(p)
    fronts = {key: pareto(points, measure) for key, points in curves.items()}
    errors = [t * result["unit"] for t in targets]
    best = []
    for error in errors:
        sizes = [bytes_at(front, error, below_cheapest=True) for (family, _), front in fronts.items()
                 if family == "mzc"]
        sizes = [s for s in sizes if s is not None]
        best.append(min(sizes) if sizes else None)
    return {name: [None if b is None or (s := bytes_at(front, e)) is None else s / b
                   for e, b in zip(errors, best)]
            for (family, name), front in fronts.items() if family == "peer"}


def summary_ratios(results, targets):
    """{measure: {corpus: {peer: [(geometric mean ratio, items counted) per target]}}} for the
    ``targets`` {measure: target errors in units} of the run."""
    return {measure: measure_ratios(results, errors, measure) for measure, errors in targets.items()}


def measure_ratios(results, targets, measure):
    """{corpus: {peer: [(geometric mean ratio, items counted) per target]}} by one measure."""
    collected = defaultdict(lambda: defaultdict(lambda: [[] for _ in targets]))
    for result in results:
        for peer, ratios in item_ratios(result, targets, measure).items():
            for k, ratio in enumerate(ratios):
                if ratio is not None:
                    collected[result["corpus"]][peer][k].append(ratio)
    return {corpus: {peer: [(float(np.exp(np.mean(np.log(r)))) if r else None, len(r)) for r in per]
                     for peer, per in peers.items()}
            for corpus, peers in collected.items()}


def speed_table(results):
    """{contender: median over items of (encode s, decode s, bytes)} for the face corpus."""
    rows = defaultdict(list)
    for result in results:
        if result["corpus"] == "faces":
            for name, t in result["timing"].items():
                rows[name].append((t["encode_s"], t["decode_s"], t["bytes"], t["setting"]))
    return {name: {"encode_s": float(np.median([r[0] for r in v])), "decode_s": float(np.median([r[1] for r in v])),
                   "bytes": float(np.median([r[2] for r in v])), "setting": v[0][3], "items": len(v)}
            for name, v in rows.items()}


# --------------------------------------------------------------------------- plots


def curves_of(results, corpus, measure):
    """{contender: [(error, bytes)] per setting}: geometric means over the corpus's items."""
    grouped = defaultdict(lambda: defaultdict(list))
    for result in results:
        if result["corpus"] == corpus:
            for p in result["points"]:
                grouped[p["contender"]][str(p["setting"])].append((error_of(p, measure), p["bytes"]))
    curves = {}
    for name, settings in grouped.items():
        points = [np.exp(np.mean(np.log(np.array(v)), axis=0)) for v in settings.values()
                  if all(np.isfinite(e) and e > 0 for e, _ in v)]
        curves[name] = sorted(map(tuple, points), key=lambda p: p[1])
    return curves


def plot_corpus(path, results, corpus, units, measures):
    """Bytes against error (log-log), one panel per measure (the primary, whole-surface RMS,
    first), one curve per contender."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(measures), figsize=(7.5 * len(measures), 6.5), squeeze=False)
    for axis, measure in zip(axes[0], measures):
        label = measure_label(measure)
        draw_curves(axis, curves_of(results, corpus, measure), plt, f"{label} point-to-surface distance ({units})",
                    f"{corpus}: {label}")
    figure.legend(*axes[0][0].get_legend_handles_labels(), loc="center right", fontsize=8)
    figure.tight_layout(rect=(0, 0, 0.86, 1))
    figure.savefig(path, dpi=110)
    plt.close(figure)


def draw_curves(axis, curves, plt, xlabel, title):
    """One panel of bytes against error (log-log): a curve per contender of ``curves`` (``curves_of``),
    mzc's solid and the peers' dashed."""
    for name, colour in curve_colours(curves, plt).items():
        if curves[name]:
            errors, sizes = zip(*curves[name])
            style = "-" if name.startswith("mzc") else "--"
            axis.plot(errors, sizes, style, marker="o", markersize=3, label=name, color=colour)
    axis.set(xscale="log", yscale="log", xlabel=xlabel, ylabel="bytes", title=title)
    axis.grid(True, which="both", alpha=0.3)


def curve_colours(curves, plt):
    """{contender: colour}, sorted by name: mzc's from tab20b, the peers' from tab20, so
    neither family runs out of the 20 distinct colours of one map."""
    names = sorted(curves)
    colours = {}
    for family, cmap in (("mzc", "tab20b"), ("peer", "tab20")):
        members = [n for n in names if n.startswith("mzc") == (family == "mzc")]
        colours.update({name: plt.get_cmap(cmap)(k % 20) for k, name in enumerate(members)})
    return {name: colours[name] for name in names}


# --------------------------------------------------------------------------- markdown


def machine():
    """A one-line description of the machine and Python."""
    cpu = platform.processor() or platform.machine()
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
        cpu = next(line.split(":", 1)[1].strip() for line in lines if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return (f"{cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}, "
            f"Python {platform.python_version()}")


def versions(packages=PACKAGES):
    """{package: version} of ``packages``, "absent" for those not installed."""
    found = {}
    for name in packages:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "absent"
    return found


def fmt(value, digits=3):
    return "n/a" if value is None else f"{value:.{digits}g}"


def markdown(results, missing, checks, pipeline, settings, ratios, speeds):
    """The report text."""
    lines = [
        "# mzc rate-distortion benchmark",
        "",
        f"Generated {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z} by `python benchmarks/rd.py"
        f"{' --quick' if settings['quick'] else ''}` on {machine()}; {settings['workers']} worker processes, "
        f"one thread each; total wall time {settings['wall_s']:.0f} s.",
        "",
        "Package versions: " + ", ".join(f"{k} {v}" for k, v in versions().items()) + ".",
        "",
        *method_section(settings, results),
        *ratio_section(ratios, settings, results),
        *speed_section(speeds, settings),
        *slicing_section(results, settings),
        *pipeline_section(pipeline),
        *clock_section(results, settings),
        *check_section(checks),
        *floor_section(results),
        *problems_section(results, missing),
        "",
        "Every point (bytes, bits per vertex, both error views with RMS, mean and Hausdorff each way) is in "
        "`rd-results.json`; the curves are in `rd-<corpus>.png`.",
    ]
    return "\n".join(lines) + "\n"


def method_section(settings, results):
    from contenders import GRID_HEADER, QUANTISER

    return [
        "## Method",
        "",
        "- Corpus: the faces of `shared/data/faces` (mm) and matplotlib's two DEMs (`mzc.samples.jacksboro`, "
        "`topobathy`; m), each as a grid and as its mesh (`grid_to_mesh`).",
        f"- Grid contenders code mzc's z-grid of the face sliced at {settings['grid_step']} mm in the default "
        f"projection (`slice_surface(mesh, d1={settings['grid_step']}, d2={settings['grid_step']})`: "
        f"{face_grids(results)}) or, for the DEMs, the DEM grid itself (planar). "
        f"The thesis codecs also run on the planar thesis grid (d1 = {settings['thesis_grid']['d1']}, "
        f"d2 = {settings['thesis_grid']['d2']} mm), decoded then densified with n = 3. Draco and xz code the "
        "original mesh.",
        f"- Rate: bytes of the file as stored. Grid peers (SZ3, zfp, SPERR, LERC, JPEG-*, HTJ2K) store a "
        f"{GRID_HEADER.size}-byte binary grid header (shape, spacings, origin, 3x4 transform, one byte for the "
        "projection and a float64 radius, 0 for planar: what `grid_to_mesh` needs to rebuild the same grid), "
        "the validity mask coded by mzc's own dwt2d mask coder (8.0's predicted flips through rANS, as mzc's "
        "own files pay; "
        f"{mask_sizes(results)}) and their payload; invalid nodes are filled first with the biharmonic fill "
        "mzc's encoder codes. "
        "LERC codes the mask itself inside its blob. SZ3, zfp and SPERR code the float64 values (SPERR "
        "without its own 10-byte shape header, which the container holds). The JPEG family and HTJ2K code "
        "the values quantised to 16 bits over their range (step about 0.0013 mm on a face), plus "
        f"{QUANTISER.size} bytes for offset and step. Bits per vertex divide by the original mesh's vertex count.",
        "- Settings: SZ3, LERC, SPERR and mzc dwt2d at the same absolute error bounds; SPERR also at PSNR "
        "targets (its mode for an RMS target; it has none for RMS itself); JPEG 2000 (OpenJPEG) at PSNR "
        "targets; HTJ2K (OpenJPH, irreversible 9/7; OpenJPEG only decodes the HT block coder) at base "
        "quantisation steps in units, OpenJPH having no rate control.",
        f"- Error, identical for every contender: decode, turn into a mesh (grids through `grid_to_mesh`, "
        "zero-area triangles dropped), and measure the symmetric point-to-surface distance to the original mesh "
        f"with `mzc.measure.metrics.surface_distance_parts` ({settings['samples']:,} area-weighted samples per surface "
        f"and direction, seed {settings['seed']}): the code of `mzc diff A B --surface --heightfield`. "
        "The primary figure is the distance over the whole surface, every triangle of both meshes; its "
        "Hausdorff is the largest sampled distance, an estimate from below that grows with the sample count "
        "(see the sample-count check of a full run). "
        "The secondary one, the height-field part, keeps original triangles whose normal has z above 0.5 and "
        "that are seen from +z (no other triangle above their centroid), and decoded samples whose nearest "
        "original triangle is one of those (`mzc.measure.metrics.heightfield_filters`).",
        "- Summary ratios: on each item, each contender's Pareto front of (error, bytes) by the table's measure "
        "is interpolated log-log at the target error; mzc's best is the smallest over all mzc contenders there. "
        "An mzc contender whose cheapest setting is already below the target counts at that setting's bytes "
        "(which can only overstate mzc); peers are never extrapolated. "
        "Ratio = peer bytes / mzc's best bytes (above 1: mzc is smaller), geometric mean over the items where "
        "the peer reaches the target (the count is given). Targets for the faces: "
        + "; ".join(f"{measure_label(m)} {', '.join(map(str, t))} mm" for m, t in settings["targets"].items())
        + "; the DEMs use the same multiples of their unit (the power of ten nearest 1/100 of their height range).",
        f"- Speed: encode (input grid or mesh to bytes) and decode (bytes to mesh, including densify and "
        f"`grid_to_mesh`) in process, median of {settings['repeats']} runs at the middle setting of each ladder "
        "(the first being that setting's rate-distortion point), then the median over faces. Slicing is "
        "common to all grid contenders and left out (its own timing is below).",
        "",
    ]


def face_grids(results):
    """The faces' grids in words, from the run itself: projection(s), what the values are, median shape."""
    faces = [r for r in results if r["corpus"] == "faces"]
    if not faces:
        return "no face in this run"
    projections = sorted({r["grid_projection"] for r in faces})
    rows, cols = np.median([r["grid_shape"] for r in faces], axis=0)
    return "; ".join(f"{name}, {NODE_VALUES[name]}" for name in projections) + \
        f"; median {rows:.0f} x {cols:.0f} nodes"


def mask_sizes(results):
    """The coded validity masks' sizes in words, from the run itself: medians over faces and DEMs."""
    sizes = {"a face": [r["mask_bytes"] for r in results if r["corpus"] == "faces"],
             "a DEM": [r["mask_bytes"] for r in results if r["corpus"] != "faces"]}
    return ", ".join(f"median {np.median(v):.0f} bytes on {label}" for label, v in sizes.items() if v)


def ratio_section(ratios, settings, results):
    """One table per measure and corpus: the whole-surface ones first (primary), then the height-field one."""
    lines = []
    for measure, by_corpus in ratios.items():
        role = "primary" if measure.startswith("whole") else "secondary"
        lines += [f"## Summary ratio ({role}): peer bytes / mzc's best bytes at equal {measure_label(measure)}",
                  "", "Geometric mean over items; in brackets the number of items where the peer reaches the error.",
                  ""]
        for corpus, peers in by_corpus.items():
            unit, units = next((r["unit"], r["units"]) for r in results if r["corpus"] == corpus)
            header = [f"{t * unit:g} {units}" for t in settings["targets"][measure]]
            lines += [f"**{corpus}**", "", "| peer | " + " | ".join(header) + " |",
                      "|---|" + "---|" * len(header)]
            for peer, values in sorted(peers.items()):
                lines.append(f"| {peer} | " + " | ".join(f"{fmt(r)} ({n})" for r, n in values) + " |")
            lines.append("")
    return lines


def speed_section(speeds, settings):
    lines = ["## Speed on the faces (median over faces of the median of "
             f"{settings['repeats']} runs, one core)", "",
             "| contender | setting | bytes | encode ms | decode ms |", "|---|---|---|---|---|"]
    for name, s in sorted(speeds.items(), key=lambda kv: kv[1]["encode_s"] + kv[1]["decode_s"]):
        lines.append(f"| {name} | {s['setting']} | {s['bytes']:.0f} | {1000 * s['encode_s']:.1f} | "
                     f"{1000 * s['decode_s']:.1f} |")
    lines.append("")
    for name, s in sorted(speeds.items()):
        if name.startswith("mzc dwt2d"):
            total = s["encode_s"] + s["decode_s"]
            verdict = "met" if total < DWT2D_SECONDS else "NOT met"
            lines.append(f"- {name}: encode + decode {1000 * total:.0f} ms, target < {1000 * DWT2D_SECONDS:.0f} ms "
                         f"for a face sliced at 0.5 mm: {verdict}.")
    return lines + [""]


def slicing_section(results, settings):
    """CPU seconds of slicing each face at the grid step, in the default projection and in planes."""
    faces = [r for r in results if "slice_cpu_s" in r]
    if not faces:
        return []
    default = float(np.median([r["slice_cpu_s"]["default"] for r in faces]))
    planar = float(np.median([r["slice_cpu_s"]["planar"] for r in faces]))
    slowest = max(faces, key=lambda r: r["slice_cpu_s"]["default"])
    verdict = "met" if slowest["slice_cpu_s"]["default"] < SLICE_SECONDS else "NOT met"
    return ["## Slicing a face (CPU seconds, the fastest of 3 runs in the worker process)", "",
            f"- At {settings['grid_step']} mm, median over {len(faces)} faces: default projection (auto; "
            f"it chose {face_grids(results)}) {default:.3f} s, planar {planar:.3f} s (ratio "
            f"{default / planar:.2f}); slowest face {slowest['item']} {slowest['slice_cpu_s']['default']:.3f} s. "
            f"Target < {SLICE_SECONDS} s for every face: {verdict}.", ""]


def pipeline_section(pipeline):
    lines = ["## Whole-process CLI timings (median wall time; peak RSS per process)", "",
             "| what | wall s | peak RSS MiB per stage | status |", "|---|---|---|---|"]
    for name, row in pipeline.items():
        peaks = " / ".join(f"{m:.0f}" for m in row["peak_rss_mib"])
        lines.append(f"| {name}: `{row['command']}` | {row['wall_s']:.2f} | {peaks} | {row['error'] or 'ok'} |")
    return lines + [""]


def clock_section(results, settings):
    totals = defaultdict(float)
    for result in results:
        for phase, seconds in result["clock"].items():
            totals[phase] += seconds
    busy = sum(totals.values())
    lines = ["## Where the run time goes (CPU seconds summed over workers)", "",
             "| phase | s | share |", "|---|---|---|"]
    for phase, seconds in sorted(totals.items(), key=lambda kv: -kv[1]):
        lines.append(f"| {phase} | {seconds:.0f} | {100 * seconds / busy:.0f}% |")
    return lines + ["", "load = reading, slicing and the height-field filter; encode/decode = the one pass per "
                    "point; metric = the distance measurement; timing = the repeated runs of the speed table.", ""]


def check_section(checks):
    """Each summary measure of the sample-count check at n and 5n samples."""
    if not checks:
        return []
    lines = ["## Sample-count check (each summary measure at the chosen count n and 5 times as many)", "",
             "| item | contender | setting | measure | at n | at 5n | change |", "|---|---|---|---|---|---|---|"]
    for c in checks:
        for measure, (a, b) in c["errors"].items():
            lines.append(f"| {c['item']} | {c['contender']} | {c['setting']} | {measure_label(measure)} | "
                         f"{a:.4f} | {b:.4f} | {100 * (a - b) / b:+.1f}% |")
    return lines + [""]


def floor_section(results):
    lines = ["## Floors: error of the uncompressed z-grid (what no grid codec can beat)", "",
             "| item | grid | whole RMS | whole Hausdorff | height-field RMS | height-field Hausdorff |",
             "|---|---|---|---|---|---|"]
    for result in results:
        for p in result["points"]:
            if p["contender"] == "mzc zgrid (lossless)":
                hf, whole = p["heightfield"], p["whole"]
                lines.append(f"| {result['item']} | {result['grid_projection']} "
                             f"{result['grid_shape'][0]} x {result['grid_shape'][1]} | {whole['rms']:.4f} | "
                             f"{whole['hausdorff']:.3f} | {hf['rms']:.4f} | {hf['hausdorff']:.3f} |")
    return lines + [""]


def problems_section(results, missing):
    lines = ["## Missing contenders and failures", ""]
    lines += [f"- missing: {name}: {why}" for name, why in missing.items()] or ["- no contender missing"]
    skipped = defaultdict(list)
    for r in results:
        for k in r.get("skipped", []):
            skipped[(k["contender"], k["setting"])].append(r["item"])
    lines += [f"- not applicable: {name} at {setting} on {', '.join(items)} (outside the codec's range)"
              for (name, setting), items in skipped.items()]
    failures = [(r["item"], f) for r in results for f in r["failures"]]
    lines += [f"- failed: {item}, {f['contender']} at {f['setting']}: {f['error'][:200]}" for item, f in failures] \
        or ["- no failure"]
    return lines


def write_outputs(out, results, missing, checks, pipeline, settings):
    """rd-results.json, rd-results.md and rd-<corpus>.png into ``out``."""
    ratios = summary_ratios(results, settings["targets"])
    speeds = speed_table(results)
    document = {"settings": settings, "machine": machine(), "versions": versions(), "missing": missing,
                "summary_ratios": ratios, "speed": speeds, "pipeline": pipeline, "sample_check": checks,
                "items": results}
    (out / "rd-results.json").write_text(json.dumps(document, indent=1, default=float) + "\n")
    (out / "rd-results.md").write_text(markdown(results, missing, checks, pipeline, settings, ratios, speeds))
    for corpus in dict.fromkeys(r["corpus"] for r in results):
        units = next(r["units"] for r in results if r["corpus"] == corpus)
        plot_corpus(out / f"rd-{corpus}.png", results, corpus, units, list(settings["targets"]))


def benchmark_parser(doc, quick_help, workers=False):
    """The arguments every benchmark script takes: ``--quick`` (``quick_help`` says what it
    keeps), ``--out`` (the folder of the reports, benchmarks/ by default) and, with
    ``workers``, ``--workers`` (processes; two at most, this machine's cores); its description
    the first paragraph of the script's ``doc``."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent,
                        help="output directory (default: benchmarks/)")
    if workers:
        parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    return parser


def git_commit():
    """The short commit of the repository the benchmarks are in, "+" when its tracked files
    have changes: the code a report measured."""
    def git(*words):
        return subprocess.run(["git", *words], cwd=Path(__file__).resolve().parent, capture_output=True,
                              text=True).stdout.strip()

    changed = git("status", "--porcelain", "--untracked-files=no", "--", ".")
    return (git("rev-parse", "--short", "HEAD") or "unknown") + ("+" if changed else "")


def stamped(packages, started, **fields):
    """A report's document: the commit, date, machine and ``packages``' versions it was measured
    with, ``fields``, and the seconds since ``started`` (a time.perf_counter())."""
    return {"commit": git_commit(), "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
            "machine": machine(), "versions": versions(packages), **fields,
            "seconds": time.perf_counter() - started}


def write_report(out, name, document, render):
    """``name``-results.json and ``name``-results.md (``render(document)``) into the folder ``out``;
    the markdown printed too."""
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}-results.json").write_text(json.dumps(document, indent=1) + "\n")
    (out / f"{name}-results.md").write_text(render(document))
    print(render(document))
