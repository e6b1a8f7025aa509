"""The outputs of the rate-distortion benchmark: JSON of every point, markdown report, plots.

Also the whole-process timings of the CLI (``mzc --help`` and the README pipeline), which
need subprocesses rather than the in-process timing of the codecs.
"""

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

README_PIPELINE = [["slice", "{face}"], ["encode", "--dwt", "-q", "10"], ["decode"], ["densify", "-n", "3"],
                   ["triangulate", "-o", "{out}"]]
PACKAGES = ("numpy", "scipy", "PyWavelets", "DracoPy", "imagecodecs", "lerc", "zfpy", "pysz", "constriction")
DWT2D_SECONDS = 0.5     # issue 6: encode + decode of a face sliced at 0.5 mm, compute time


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


def pareto(points, error_key):
    """(errors, bytes) of the points no other point beats in both, by increasing bytes."""
    ordered = sorted(points, key=lambda p: (p["bytes"], p[error_key]["rms"]))
    front, best = [], np.inf
    for p in ordered:
        error = p[error_key]["rms"]
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


def item_ratios(result, targets, error_key="heightfield"):
    """{peer: [ratio or None per target]}: peer bytes / best mzc bytes at equal error.

    Peers are interpolated strictly; mzc contenders whose cheapest setting is already more
    accurate than the target count at that setting's bytes, which can only overstate mzc.
    """
    curves = defaultdict(list)
    for p in result["points"]:
        curves[(p["family"], p["contender"])].append(p)
    fronts = {key: pareto(points, error_key) for key, points in curves.items()}
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
    """{corpus: {peer: [(geometric mean ratio, items counted) per target]}}."""
    collected = defaultdict(lambda: defaultdict(lambda: [[] for _ in targets]))
    for result in results:
        for peer, ratios in item_ratios(result, targets).items():
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


def curves_of(results, corpus, error_key):
    """{contender: [(error, bytes)] per setting}: geometric means over the corpus's items."""
    grouped = defaultdict(lambda: defaultdict(list))
    for result in results:
        if result["corpus"] == corpus:
            for p in result["points"]:
                grouped[p["contender"]][str(p["setting"])].append((p[error_key]["rms"], p["bytes"]))
    curves = {}
    for name, settings in grouped.items():
        points = [np.exp(np.mean(np.log(np.array(v)), axis=0)) for v in settings.values()
                  if all(np.isfinite(e) and e > 0 for e, _ in v)]
        curves[name] = sorted(map(tuple, points), key=lambda p: p[1])
    return curves


def plot_corpus(path, results, corpus, units):
    """Bytes against RMS error (log-log), whole surface and height-field part, one curve per contender."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = plt.get_cmap("tab20")
    figure, axes = plt.subplots(1, 2, figsize=(15, 6.5))
    for axis, key, title in zip(axes, ("whole", "heightfield"), ("whole surface", "height-field part")):
        for k, (name, points) in enumerate(sorted(curves_of(results, corpus, key).items())):
            if points:
                errors, sizes = zip(*points)
                style = "-" if name.startswith("mzc") else "--"
                axis.plot(errors, sizes, style, marker="o", markersize=3, label=name, color=colours(k))
        axis.set(xscale="log", yscale="log", xlabel=f"RMS point-to-surface distance ({units})",
                 ylabel="bytes", title=f"{corpus}: {title}")
        axis.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=7, ncol=2)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


# --------------------------------------------------------------------------- markdown


def machine():
    """A one-line description of the machine and Python."""
    cpu = platform.processor() or platform.machine()
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
        cpu = next(line.split(":", 1)[1].strip() for line in lines if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return f"{cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}, Python {platform.python_version()}"


def versions():
    found = {}
    for name in PACKAGES:
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
        *method_section(settings),
        *ratio_section(ratios, settings, results),
        *speed_section(speeds, settings),
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


def method_section(settings):
    return [
        "## Method",
        "",
        f"- Corpus: the faces of `shared/data/faces` (mm) and matplotlib's two DEMs (`mzc.samples.jacksboro`, "
        "`topobathy`; m), each as a grid and as its mesh (`grid_to_mesh`).",
        f"- Grid contenders code mzc's z-grid of the face sliced at {settings['grid_step']} mm "
        "(`slice_surface(mesh, d1=0.5, d2=0.5)`, about 420 x 340 nodes) or, for the DEMs, the DEM grid itself. "
        f"The thesis codecs also run on the thesis grid (d1 = {settings['thesis_grid']['d1']}, "
        f"d2 = {settings['thesis_grid']['d2']} mm), decoded then densified with n = 3. Draco and xz code the "
        "original mesh.",
        "- Rate: bytes of the file as stored. Grid peers (SZ3, zfp, JPEG-*) store a 136-byte binary grid header "
        "(shape, spacings, origin, 3x4 transform), the validity mask coded by mzc's own dwt2d mask coder (row "
        "spans through rANS; about 290 bytes on a face) and their payload; invalid nodes are filled with "
        "mzc's harmonic fill first. LERC codes the mask itself inside its blob. The JPEG family codes the heights "
        "quantised to 16 bits over their range (step about 0.002 mm on a face), plus 16 bytes for offset and step. "
        "Bits per vertex divide by the original mesh's vertex count.",
        f"- Error, identical for every contender: decode, turn into a mesh (grids through `grid_to_mesh`, "
        "zero-area triangles dropped), and measure the symmetric point-to-surface distance to the original mesh "
        f"with `mzc.metrics.surface_distance_parts` ({settings['samples']:,} area-weighted samples per surface "
        f"and direction, seed {settings['seed']}): the code of `mzc diff A B --surface --heightfield`. "
        "The height-field part keeps original triangles whose normal has z above 0.5 and that are seen from +z "
        "(no other triangle above their centroid), and decoded samples whose nearest original triangle is one "
        "of those (`mzc.metrics.heightfield_filters`).",
        "- Summary ratio: on each item, each contender's Pareto front of (height-field RMS, bytes) is "
        "interpolated log-log at the target error; mzc's best is the smallest over all mzc contenders there. "
        "An mzc contender whose cheapest setting is already below the target counts at that setting's bytes "
        "(which can only overstate mzc); peers are never extrapolated. "
        "Ratio = peer bytes / mzc's best bytes (above 1: mzc is smaller), geometric mean over the items where "
        "the peer reaches the target (the count is given). Faces use "
        f"{', '.join(map(str, settings['targets']))} mm; the DEMs use the same multiples of their unit "
        "(the power of ten nearest 1/100 of their height range).",
        f"- Speed: encode (input grid or mesh to bytes) and decode (bytes to mesh, including densify and "
        f"`grid_to_mesh`) in process, median of {settings['repeats']} runs at the middle setting of each ladder, "
        "then the median over faces. Slicing (about 0.1 s per face) is common to all grid contenders and left out.",
        "",
    ]


def ratio_section(ratios, settings, results):
    lines = ["## Summary ratio: peer bytes / mzc's best bytes at equal height-field RMS error", "",
             "Geometric mean over items; in brackets the number of items where the peer reaches the error.", ""]
    for corpus, peers in ratios.items():
        unit, units = next((r["unit"], r["units"]) for r in results if r["corpus"] == corpus)
        header = [f"{t * unit:g} {units}" for t in settings["targets"]]
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
    if not checks:
        return []
    lines = ["## Sample-count check (height-field RMS at the chosen count and 5 times as many)", "",
             "| item | contender | setting | RMS at n | RMS at 5n | change |", "|---|---|---|---|---|---|"]
    for c in checks:
        a, b = c["heightfield_rms"]
        lines.append(f"| {c['item']} | {c['contender']} | {c['setting']} | {a:.4f} | {b:.4f} | "
                     f"{100 * (a - b) / b:+.1f}% |")
    return lines + [""]


def floor_section(results):
    lines = ["## Floors: error of the uncompressed z-grid (what no grid codec can beat)", "",
             "| item | grid | height-field RMS | height-field Hausdorff | whole RMS | whole Hausdorff |",
             "|---|---|---|---|---|---|"]
    for result in results:
        for p in result["points"]:
            if p["contender"] == "mzc zgrid (lossless)":
                hf, whole = p["heightfield"], p["whole"]
                lines.append(f"| {result['item']} | {result['grid_shape'][0]} x {result['grid_shape'][1]} | "
                             f"{hf['rms']:.4f} | {hf['hausdorff']:.3f} | {whole['rms']:.4f} | "
                             f"{whole['hausdorff']:.3f} |")
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
        plot_corpus(out / f"rd-{corpus}.png", results, corpus, units)
