"""Speed of every mzc stage on f18 beside Draco, JPEG 2000 and SPERR, and how it scales (issue 15).

    python benchmarks/speed.py [--quick] [--repeats N] [--sizes 0.1,0.4,1.6,6.4,25] [--out DIR]
                               [--stage-timeout S] [--memory-cap-gb G]

Three parts, each measuring mzc beside its reference in the same run, interleaved, since
the machine is shared and noisy (medians and minima of the repeats; ratios of medians):

1. Command line, on f18: ``python -c "import numpy"``, ``mzc --help``, the five-filter
   pipeline ``mzc slice | mzc encode --dwt2d --rmse 0.05 | mzc decode | mzc densify -n 3 |
   mzc triangulate -o out.ply``, and each of its stages on its own (input and output files
   in a temporary folder), on every grid of ``GRIDS``. One round runs all of them in an
   order shuffled per round; wall time and peak RSS of each process.
2. In process, on the same grids: ``mzc.slice/encode/decode/densify/triangulate`` of the
   Python API beside Draco (encode at compression level 10 of the original mesh, decode)
   and the grid peers JPEG 2000 (lossless and at the error of ``--rmse 0.05``) and SPERR,
   taken from ``contenders.py`` with their container, mask and fill. Every call of a round
   runs on fixed inputs, in an order rotated per round.
3. Scaling: synthetic planar grids of ``--sizes`` million nodes (``terrain``), each stage
   (encode, decode, densify -n 1, triangulate) a command-line process with wall time and
   peak RSS, a time limit and an address-space cap; the growth exponent between sizes.
   A stage that fails, runs out of memory or out of time is a row with the reason, and is
   not tried at larger sizes.

Writes speed-results.md (the done-when checks of issue 15 first, pass or fail per line)
and speed-results.json (every run) into --out (default: this directory). Progress goes to
stderr only when it is a terminal.
"""

import datetime
import gc
import json
import math
import os
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import contenders  # noqa: E402 - after the path to this folder
from corpora import FACES  # noqa: E402
from report import benchmark_parser, git_commit, machine, run_stages, versions  # noqa: E402
from scaling import RMSE as TERRAIN_RMSE  # noqa: E402
from scaling import terrain_grid  # noqa: E402

FACE = "f18.ply"
# The grids of f18: what `mzc slice f18.ply` gives (spacing from the data, default projection),
# the 0.5 mm in the default projection, and the 420 x 336 grid, which is
# 0.5 mm in planes (the default projection when the issue was written).
GRIDS = {
    "default": {"cli": [], "api": {}},
    "0.5 mm": {"cli": ["--d1", "0.5", "--d2", "0.5"], "api": {"d1": 0.5, "d2": 0.5}},
    "0.5 mm planar": {"cli": ["--d1", "0.5", "--d2", "0.5", "--projection", "planar"],
                      "api": {"d1": 0.5, "d2": 0.5, "projection": "planar"}},
}
CHECKED_GRIDS = ("0.5 mm", "0.5 mm planar")   # the done-when conditions speak of f18 at 0.5 mm
QUICK_GRIDS = ("default",)      # the smallest grid: the quick run is a test of the harness
RMSE = 0.05                     # mm: `mzc encode --dwt2d --rmse 0.05`
ENCODE = ["--dwt2d", "--rmse", str(RMSE)]
SCALE_ENCODE = ["--dwt2d", "--rmse", str(TERRAIN_RMSE)]   # the terrain is in metres
DENSIFY = 3                     # rows inserted on f18 (the pipeline's -n 3)
SCALE_DENSIFY = 1               # and at scale (-n 1)
DRACO_BITS = 11                 # f18 spans 210 mm: steps of 0.1 mm, about the RMS error of --rmse 0.05
PIPELINE_SECONDS = 2.0          # issue 15: the pipeline under 2 s of wall time ...
NUMPY_RATIO = 8.0               # ... and at most 8x `python -c "import numpy"`
DRACO_RATIO = 3.0               # dwt2d encode and decode each at most 3x Draco's
MEMORY_BYTES = 4e9              # the largest grid within 4 GB (peak RSS) ...
EXPONENT = 1.1                  # ... and every stage's time at most n^1.1 from 1.6 M nodes on
EXPONENT_FROM, EXPONENT_TO = 1.6, 25.0   # M nodes
SIZES = (0.1, 0.4, 1.6, 6.4, 25.0)
QUICK_SIZES = (0.01, 0.04)
REPEATS = 5
QUICK_REPEATS = 1
SCALE_REPEATS_BELOW = 2.0       # sizes under this many M nodes are run 3 times (median), larger ones once
STAGE_TIMEOUT = 600.0           # seconds per scaling stage
MEMORY_CAP_GB = 12.0            # address-space cap of a scaling stage: fails cleanly instead of swamping the box
SEED = 15
LAZ_POINTS = 1_000_000          # issue 16: a LAZ cloud of about a million points ...
QUICK_LAZ_POINTS = 100_000
LAZ_SECONDS = 10.0              # ... slices in under 10 s (command line, wall)
FACE_DIFF_SECONDS = 1.0         # issue 15: `mzc diff --surface` on a face within a second (wall)
LARGE_SIDE = 1000               # issue 16: `diff --surface` of two 1,000,000-vertex meshes ...
QUICK_LARGE_SIDE = 100
LARGE_DIFF_SECONDS = 30.0       # ... in under 30 s (wall) ...
LARGE_DIFF_BYTES = 2e9          # ... and 2 GB (peak RSS)
PACKAGES = ("numpy", "scipy", "PyWavelets", "constriction", "DracoPy", "imagecodecs")
SCALE_STAGES = ("encode", "decode", f"densify -n {SCALE_DENSIFY}", "triangulate")
MEMORY_STAGES = SCALE_STAGES[:3]   # the memory condition: encode, decode, densify


def progress(message):
    """A progress line on stderr, only when it is a terminal (a test or a log stays clean)."""
    if sys.stderr.isatty():
        print(message, file=sys.stderr, flush=True)


def mzc_command(*words):
    """The argv of an mzc command of this interpreter (as ``report.run_stages`` runs them)."""
    return [sys.executable, "-m", "mzc", *map(str, words)]


# --------------------------------------------------------------------------- processes


# A small Python that runs the command and writes its exit status, wall seconds, peak RSS
# (kB) and CPU seconds (user + system) to the file named first, from ``RUSAGE_CHILDREN``:
# of the command alone. Measured there
# rather than by this process's own ``os.wait4`` since a child inherits the RSS of the
# process it was forked from: this one holds the face, its grids and the peers' libraries.
WRAPPER = """import resource, subprocess, sys, time
start = time.perf_counter()
code = subprocess.run(sys.argv[2:]).returncode
wall = time.perf_counter() - start
with open(sys.argv[1], "w") as out:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    out.write(f"{code} {wall!r} {usage.ru_maxrss} {usage.ru_utime + usage.ru_stime!r}")
"""
MEMORY_WORDS = ("MemoryError", "Unable to allocate", "out of memory", "Cannot allocate memory", "bad_alloc")


def run_command(argv, timeout=None, memory_cap=None):
    """Run ``argv`` under ``WRAPPER`` (stdout discarded, stderr kept in a file so that a chatty
    child cannot block); {wall_s, cpu_s, peak_mb, status, error}.

    Wall time and peak RSS are the command's own, as the wrapper measured them. ``timeout``
    kills the wrapper's whole session after that many seconds; ``memory_cap`` (bytes) caps
    the address space (RLIMIT_AS, inherited by the command), so that a stage which would
    swamp the shared machine fails with a MemoryError instead. status is "ok", "timeout",
    "out of memory" or "failed".
    """
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (int(memory_cap), int(memory_cap)))

    timed_out = threading.Event()
    with tempfile.TemporaryFile() as errors, tempfile.NamedTemporaryFile("r") as measured:
        start = time.perf_counter()
        process = subprocess.Popen([sys.executable, "-c", WRAPPER, measured.name, *map(str, argv)],
                                   stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=errors,
                                   preexec_fn=limit if memory_cap else None, start_new_session=True)

        def kill():
            timed_out.set()
            os.killpg(process.pid, signal.SIGKILL)

        timer = threading.Timer(timeout, kill) if timeout else None
        if timer:
            timer.start()
        process.wait()
        wall = time.perf_counter() - start
        if timer:
            timer.cancel()
        errors.seek(0)
        message = errors.read().decode(errors="replace").strip()
        words = measured.read().split()
    if len(words) == 4:   # the wrapper finished: the command's own figures
        code, wall, peak, cpu = int(words[0]), float(words[1]), int(words[2]) * 1024 / 1e6, float(words[3])
    else:
        code, peak, cpu = process.returncode, None, None
    result = {"wall_s": wall, "cpu_s": cpu, "peak_mb": peak, "status": "ok", "error": None}
    last = (message.splitlines() or [""])[-1][-300:]
    if timed_out.is_set():
        result.update(status="timeout", error=f"killed after the {timeout:.0f} s limit")
    elif code == -signal.SIGKILL:
        result.update(status="out of memory", error="SIGKILL (the kernel's out-of-memory killer)")
    elif code and any(word in message for word in MEMORY_WORDS):
        result.update(status="out of memory", error=f"exit {code}: {last}")
    elif code:
        result.update(status="failed", error=f"exit {code}: {last}")
    return result


def stage_commands(face, flags, folder, name):
    """[(stage, argv)] of the five stages on their own for one grid, each reading the file the
    previous one wrote in ``folder``: the pipeline's filters with files instead of pipes."""
    base = folder / name.replace(" ", "-")
    return [("slice", mzc_command("slice", face, *flags, "-o", f"{base}.zg")),
            ("encode", mzc_command("encode", *ENCODE, f"{base}.zg", "-o", f"{base}.mzw2")),
            ("decode", mzc_command("decode", f"{base}.mzw2", "-o", f"{base}-back.zg")),
            (f"densify -n {DENSIFY}", mzc_command("densify", "-n", DENSIFY, f"{base}-back.zg", "-o",
                                                  f"{base}-dense.zg")),
            ("triangulate", mzc_command("triangulate", f"{base}-dense.zg", "-o", f"{base}.ply"))]


def pipeline_stages(face, flags, out):
    """The five-filter pipeline's stages (``report.run_stages`` form) with the grid's slice flags."""
    return [["slice", str(face), *flags], ["encode", *ENCODE], ["decode"], ["densify", "-n", str(DENSIFY)],
            ["triangulate", "-o", str(out)]]


def cli_rounds(face, grids, repeats, folder, seed=SEED):
    """{row: [run per round]} of part 1: start-up commands, pipelines and single stages.

    Each round runs every item once in an order shuffled per round (a grid's stages stay in
    order, as each reads the previous one's output); a failed command is kept as a run with
    its error, and its figures are left out of the medians.
    """
    items = {"python -c pass": [(None, [sys.executable, "-c", "pass"])],
             'python -c "import numpy"': [(None, [sys.executable, "-c", "import numpy"])],
             "mzc --help": [(None, mzc_command("--help"))]}
    for name in grids:
        items[f"pipeline {name}"] = "pipeline"
        items[f"stages {name}"] = stage_commands(face, GRIDS[name]["cli"], folder, name)
    rng = np.random.default_rng(seed)
    runs = {}
    for r in range(repeats):
        order = list(items)
        rng.shuffle(order)
        for item in order:
            progress(f"cli round {r + 1}/{repeats}: {item}")
            if items[item] == "pipeline":
                name = item.removeprefix("pipeline ")
                wall, peaks, error = run_stages(pipeline_stages(face, GRIDS[name]["cli"], folder / "out.ply"))
                runs.setdefault(item, []).append({"wall_s": wall, "peak_mb": max(peaks) * 1.048576,
                                                  "status": "failed" if error else "ok", "error": error})
                continue
            for stage, argv in items[item]:
                key = item if stage is None else f"{item.removeprefix('stages ')}: {stage}"
                runs.setdefault(key, []).append(run_command(argv))
    return runs


def peak_of(runs):
    """The largest peak RSS (MB) of ``runs``, None when none was measured."""
    peaks = [run["peak_mb"] for run in runs if run["peak_mb"] is not None]
    return max(peaks) if peaks else None


def summary(runs):
    """{median_s, min_s, runs, ok, peak_mb, error} of a row's runs (the ok ones)."""
    walls = [run["wall_s"] for run in runs if run["status"] == "ok"]
    errors = [run["error"] for run in runs if run["status"] != "ok"]
    return {"median_s": float(np.median(walls)) if walls else None, "min_s": min(walls) if walls else None,
            "runs": len(runs), "ok": len(walls), "peak_mb": peak_of(runs),
            "error": errors[0] if errors else None}


# --------------------------------------------------------------------------- in process


def grid_psnr(grid, rmse=RMSE):
    """The PSNR (dB, over the filled grid's value range, as JPEG 2000 and SPERR count it) of an
    RMS error ``rmse``: the peers' setting for an error comparable to ``--rmse 0.05``."""
    z = contenders.filled(grid)
    return float(20 * np.log10((z.max() - z.min()) / rmse))


def node_rms(reference, decoded):
    """RMS distance (mm) from each vertex of a decoded grid mesh to the nearest vertex of the sliced
    grid's mesh: the node error a grid contender made, for context. Nearest, not same-index,
    since a decode may drop or keep a vertex the other mesh does not (a triangle more or
    less at a depth jump); for errors well under the node spacing the nearest is the same node."""
    from scipy.spatial import cKDTree

    distances, _ = cKDTree(reference[0]).query(decoded[0])
    return float(np.sqrt(np.mean(distances ** 2)))


def api_tasks(mesh, grids, missing):
    """({task: callable}, {task: facts}) of part 2, every input made once beforehand.

    Tasks are "<grid>: <stage>" for mzc's stages and the grid peers, and "Draco: encode" /
    "Draco: decode" on the original mesh (the same for every grid). Facts are the bytes and
    node RMS error of each coder's output. Making the inputs also warms every import.
    """
    import mzc
    from mzc.errors import MzcWarning

    warnings.simplefilter("ignore", MzcWarning)   # the planar grid's "meets only 49% of the area": known
    table = {c.name: c for c in contenders.all_contenders()[0]}
    tasks, facts = {}, {}
    pair = (mesh.points, mesh.triangles)
    draco = table.get("Draco")
    if draco:
        data = draco.encode(pair, DRACO_BITS, 1.0)
        tasks["Draco: encode"] = lambda: draco.encode(pair, DRACO_BITS, 1.0)
        tasks["Draco: decode"] = lambda data=data: draco.decode(data)
        facts["Draco"] = {"bytes": len(data), "setting": f"{DRACO_BITS} bits, level 10", "rms_mm": None}
    else:
        missing["Draco"] = "not in the contenders table (DracoPy missing?)"
    for name in grids:
        options = GRIDS[name]["api"]
        grid = mzc.slice(mesh, **options)
        data = mzc.encode(grid, rmse=RMSE)
        back = mzc.decode(data)
        dense = mzc.densify(back, DENSIFY)
        reference = contenders.mesh_pair(grid)
        tasks[f"{name}: slice"] = lambda options=options: mzc.slice(mesh, **options)
        tasks[f"{name}: encode"] = lambda grid=grid: mzc.encode(grid, rmse=RMSE)
        tasks[f"{name}: decode"] = lambda data=data: mzc.decode(data)
        tasks[f"{name}: densify -n {DENSIFY}"] = lambda back=back: mzc.densify(back, DENSIFY)
        tasks[f"{name}: triangulate"] = lambda dense=dense: mzc.triangulate(dense)
        tasks[f"{name}: decode to mesh"] = lambda data=data: mzc.triangulate(mzc.decode(data))
        tasks[f"{name}: smooth fill"] = lambda grid=grid: contenders.filled(grid)
        facts[f"{name}: mzc dwt2d --rmse {RMSE}"] = {
            "bytes": len(data), "setting": f"rmse {RMSE}", "rms_mm": node_rms(reference, contenders.mesh_pair(back)),
            "grid": {"shape": list(grid.shape), "projection": grid.projection, "d1": grid.d1,
                     "valid": int(grid.valid.sum())}}
        psnr = round(grid_psnr(grid), 1)
        for peer, setting, label in (("JPEG 2000", 0, "JPEG 2000 lossless"), ("JPEG 2000", psnr, "JPEG 2000"),
                                     ("SPERR psnr", psnr, "SPERR")):
            contender = table.get(peer)
            if contender is None:
                missing[label] = f"{peer} not in the contenders table"
                continue
            encoded = contender.encode(grid, setting, 1.0)
            facts[f"{name}: {label}"] = {"bytes": len(encoded), "setting": "lossless 16-bit" if setting == 0
                                         else f"{setting} dB", "rms_mm": node_rms(reference, contender.decode(encoded))}
            tasks[f"{name}: {label} encode"] = lambda c=contender, s=setting, g=grid: c.encode(g, s, 1.0)
            tasks[f"{name}: {label} decode"] = lambda c=contender, e=encoded: c.decode(e)
    return tasks, facts


def api_rounds(tasks, repeats):
    """{task: [seconds per round]}: every task once per round, the order rotated by one each
    round so that no task always follows the same neighbour; garbage collected before each."""
    names = list(tasks)
    times = {name: [] for name in names}
    for r in range(repeats):
        progress(f"in-process round {r + 1}/{repeats}")
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            gc.collect()
            start = time.perf_counter()
            tasks[name]()
            times[name].append(time.perf_counter() - start)
    return times


# --------------------------------------------------------------------------- scaling


def grid_shape(mnodes):
    """(rows, cols) of about ``mnodes`` million nodes, 4:5 as a face grid."""
    rows = max(2, round(math.sqrt(mnodes * 1e6 * 0.8)))
    return rows, max(2, round(mnodes * 1e6 / rows))


def scale_commands(folder):
    """[(stage, argv, input it needs)]: encode and decode in turn, densify and triangulate of the
    generated grid itself (the decoded one has the same nodes; this keeps them independent of
    a failed encode)."""
    grid, coded, back = folder / "grid.zg", folder / "grid.mzw2", folder / "back.zg"
    return [("encode", mzc_command("encode", *SCALE_ENCODE, grid, "-o", coded), grid),
            ("decode", mzc_command("decode", coded, "-o", back), coded),
            (SCALE_STAGES[2], mzc_command("densify", "-n", SCALE_DENSIFY, grid, "-o", folder / "dense.zg"), grid),
            ("triangulate", mzc_command("triangulate", grid, "-o", folder / "mesh.ply"), grid)]


def scaling(sizes, folder, timeout, memory_cap, quick):
    """[row per size and stage] of part 3: {mnodes, nodes, shape, stage, runs, wall_s, peak_mb,
    status, error}. A stage that did not finish at some size is skipped at the larger ones
    (recorded with that reason) to keep the run time bounded."""
    import mzc

    rows, given_up = [], {}
    for mnodes in sorted(sizes):
        shape = grid_shape(mnodes)
        progress(f"scaling {mnodes:g} M nodes {shape}: generating")
        start = time.perf_counter()
        mzc.write(folder / "grid.zg", terrain_grid(*shape, SEED))
        generated = time.perf_counter() - start
        gc.collect()
        repeats = 1 if quick or mnodes >= SCALE_REPEATS_BELOW else 3
        for stage, argv, needs in scale_commands(folder):
            row = {"mnodes": mnodes, "nodes": shape[0] * shape[1], "shape": list(shape), "stage": stage,
                   "generate_s": generated, "runs": []}
            if stage in given_up:
                row.update(status="skipped", error=given_up[stage], wall_s=None, cpu_s=None, peak_mb=None)
            elif not needs.exists():
                row.update(status="skipped", error="no input: the stage before it failed", wall_s=None, cpu_s=None,
                           peak_mb=None)
            else:
                for _ in range(repeats):
                    progress(f"scaling {mnodes:g} M nodes: {stage}")
                    row["runs"].append(run_command(argv, timeout, memory_cap))
                    if row["runs"][-1]["status"] != "ok":
                        break
                bad = [run for run in row["runs"] if run["status"] != "ok"]
                walls = [run["wall_s"] for run in row["runs"]]
                cpus = [run["cpu_s"] for run in row["runs"]]
                row.update(status=bad[0]["status"] if bad else "ok", error=bad[0]["error"] if bad else None,
                           wall_s=None if bad else float(np.median(walls)),
                           cpu_s=None if bad or None in cpus else float(np.median(cpus)),
                           peak_mb=peak_of(row["runs"]))
                if bad:
                    given_up[stage] = f"{bad[0]['status']} at {mnodes:g} M nodes"
            rows.append(row)
        for path in folder.iterdir():
            path.unlink()
    return rows


def exponents(rows, stage, start=EXPONENT_FROM, clock="wall_s"):
    """(consecutive [(from M, to M, exponent)], (from M, to M, exponent) or None): the slope of
    log time (``clock``: "wall_s", the issue's, or "cpu_s", which other processes of the
    shared machine stretch far less) against log nodes between finished sizes of ``stage``,
    and from the first size of at least ``start`` M nodes to the largest finished one."""
    done = [(r["nodes"], r[clock], r["mnodes"]) for r in rows
            if r["stage"] == stage and r["status"] == "ok" and r.get(clock)]

    def slope(a, b):
        return float(np.log(b[1] / a[1]) / np.log(b[0] / a[0]))

    steps = [(a[2], b[2], slope(a, b)) for a, b in zip(done, done[1:])]
    big = [d for d in done if d[2] >= start]
    overall = (big[0][2], big[-1][2], slope(big[0], big[-1])) if len(big) >= 2 else None
    return steps, overall


# --------------------------------------------------------------------------- checks


def verdict(ok):
    return "**pass**" if ok else "**FAIL**"


def checks(cli, api, scale_rows, sizes, grids):
    """[(condition, measured, pass/fail/not measured)] of issue 15's done-when conditions."""
    lines = []
    numpy_s = cli['python -c "import numpy"']["median_s"]
    checked = [g for g in CHECKED_GRIDS if g in grids] or list(grids)   # a quick run checks the grid it has
    for name in checked:
        pipe = cli[f"pipeline {name}"]
        if pipe["median_s"] is None:
            lines += [(f"pipeline on f18 {name}: under {PIPELINE_SECONDS:g} s", f"failed: {pipe['error']}", False)]
            continue
        lines.append((f"pipeline on f18 {name}: under {PIPELINE_SECONDS:g} s wall",
                      f"median {pipe['median_s']:.2f} s (min {pipe['min_s']:.2f})",
                      pipe["median_s"] < PIPELINE_SECONDS))
        ratio = pipe["median_s"] / numpy_s
        lines.append((f"pipeline on f18 {name}: at most {NUMPY_RATIO:g}x `python -c \"import numpy\"`",
                      f"{ratio:.1f}x ({pipe['median_s']:.2f} s / {numpy_s:.3f} s)", ratio <= NUMPY_RATIO))
    for name in checked:
        for stage in ("encode", "decode"):
            mine, draco = api.get(f"{name}: {stage}"), api.get(f"Draco: {stage}")
            label = f"in process, dwt2d {stage} of f18 {name}: at most {DRACO_RATIO:g}x Draco's {stage}"
            if not draco:
                lines.append((label, "Draco not available", None))
                continue
            ratio = mine["median_s"] / draco["median_s"]
            lines.append((label, f"{ratio:.1f}x ({1000 * mine['median_s']:.1f} ms / {1000 * draco['median_s']:.1f} ms)",
                          ratio <= DRACO_RATIO))
    largest = max(sizes)
    for stage in MEMORY_STAGES:
        row = next(r for r in scale_rows if r["stage"] == stage and r["mnodes"] == largest)
        label = f"{largest:g} M nodes, {stage}: within {MEMORY_BYTES / 1e9:g} GB"
        if row["status"] != "ok":
            lines.append((label, f"{row['status']}: {row['error']}", False))
        elif row["peak_mb"] is None:
            lines.append((label, "peak RSS not measured", None))
        else:
            lines.append((label, f"peak RSS {row['peak_mb'] / 1000:.2f} GB", row["peak_mb"] * 1e6 <= MEMORY_BYTES))
    for stage in SCALE_STAGES:
        label = f"{stage}: time at most n^{EXPONENT:g} from {EXPONENT_FROM:g} M to {EXPONENT_TO:g} M nodes"
        _, overall = exponents(scale_rows, stage)
        if largest < EXPONENT_TO or EXPONENT_FROM not in sizes:
            lines.append((label, f"not measured: the sizes do not span {EXPONENT_FROM:g} M to {EXPONENT_TO:g} M" +
                          (f" (exponent {overall[2]:.2f} over {overall[0]:g}-{overall[1]:g} M)" if overall else ""),
                          None))
        elif overall is None or overall[1] != largest:
            failed = next((r for r in scale_rows if r["stage"] == stage and r["status"] != "ok"), None)
            lines.append((label, f"not finished: {failed['status']}: {failed['error']}" if failed else "no data",
                          False))
        else:
            _, cpu = exponents(scale_rows, stage, clock="cpu_s")
            cpu_text = "" if cpu is None else f" (of CPU time {cpu[2]:.2f})"
            lines.append((label, f"exponent {overall[2]:.2f}{cpu_text}", overall[2] <= EXPONENT))
    return lines


# --------------------------------------------------------------------------- a LAZ cloud (issue 16)


def laz_slice(folder, points, repeats):
    """`mzc slice survey.laz --classes 2` of a generated airborne survey of ``points`` points
    (``clouds.write_laz``: ground and 35% vegetation, 1 cm quanta), a process per round: its
    wall time and peak RSS (``summary``), or why it was not measured."""
    try:
        import laspy  # noqa: F401 - the las extra writes the cloud
    except ImportError:
        return {"points": points, "error": "laspy is not installed (pip install -e '.[las]')"}
    from clouds import write_laz

    path = folder / "survey.laz"
    write_laz(path, points)
    runs = [run_command(mzc_command("slice", path, "--classes", "2", "-o", folder / "survey.zg"))
            for _ in range(repeats)]
    return {"points": points, "bytes": path.stat().st_size, **summary(runs), "all_runs": runs}


def laz_checks(laz):
    """Issue 16's done-when line: the LAZ cloud slices in under LAZ_SECONDS."""
    label = f"LAZ cloud of {laz['points']:,} points: `mzc slice --classes 2` under {LAZ_SECONDS:g} s wall"
    if laz.get("median_s") is None:
        return [(label, f"not measured: {laz['error']}", None if "laspy" in str(laz["error"]) else False)]
    return [(label, f"median {laz['median_s']:.2f} s (min {laz['min_s']:.2f}), peak RSS {laz['peak_mb']:.0f} MB, "
             f"{laz['bytes'] / 1e6:.1f} MB of LAZ", laz["median_s"] < LAZ_SECONDS)]


# --------------------------------------------------------------------------- diff --surface (issues 15, 16)


def surface_diffs(face, rebuilt, folder, side, repeats):
    """`mzc diff A B --surface` as a process, wall time and peak RSS (``summary``): the face
    against its rebuild (``rebuilt``, a triangulate output of part 1) ``repeats`` times, and
    each pair of ``surface_distance.SHAPES`` (side x side vertices, the second jittered) once."""
    from surface_distance import SHAPES

    import mzc

    diffs = {"face": summary([run_command(mzc_command("diff", face, rebuilt, "--surface")) for _ in range(repeats)])}
    rng = np.random.default_rng(1)
    for shape, make in SHAPES.items():
        paths = [folder / f"{shape.replace(' ', '-')}-{i}.ply" for i in range(2)]
        for path, jittered in zip(paths, (False, True)):
            mzc.write(path, mzc.Mesh(*make(side, rng, jittered)))
        progress(f"diff --surface: {shape}")
        diffs[shape] = {"vertices": side * side, **summary([run_command(mzc_command("diff", *paths, "--surface"))])}
    return diffs


def surface_checks(diffs, rebuilt_grid):
    """Issue 15's line (a face within FACE_DIFF_SECONDS) and issue 16's (each large pair within
    LARGE_DIFF_SECONDS and LARGE_DIFF_BYTES)."""
    face = diffs["face"]
    label = f"`mzc diff {FACE} rebuilt.ply --surface` ({rebuilt_grid} grid): within {FACE_DIFF_SECONDS:g} s wall"
    lines = [(label, f"failed: {face['error']}", False) if face["median_s"] is None else
             (label, f"median {face['median_s']:.2f} s (min {face['min_s']:.2f}), peak RSS {face['peak_mb']:.0f} MB",
              face["median_s"] <= FACE_DIFF_SECONDS)]
    for shape, row in diffs.items():
        if shape == "face":
            continue
        label = (f"`mzc diff --surface` of two {row['vertices']:,}-vertex meshes ({shape}): under "
                 f"{LARGE_DIFF_SECONDS:g} s and {LARGE_DIFF_BYTES / 1e9:g} GB")
        lines.append((label, f"failed: {row['error']}", False) if row["median_s"] is None else
                     (label, f"{row['median_s']:.2f} s, peak RSS {row['peak_mb']:.0f} MB",
                      row["median_s"] < LARGE_DIFF_SECONDS and row["peak_mb"] * 1e6 < LARGE_DIFF_BYTES))
    return lines


# --------------------------------------------------------------------------- report


def ms(seconds):
    return "n/a" if seconds is None else f"{1000 * seconds:.1f}"


def mb(megabytes):
    return "n/a" if megabytes is None else f"{megabytes:.0f}"


def sec(seconds, digits=2):
    return "n/a" if seconds is None else f"{seconds:.{digits}f}"


def markdown(document):
    """The report text from the JSON document."""
    d, s = document, document["settings"]
    mark = {True: "**pass**", False: "**FAIL**", None: "not measured"}
    lines = [
        "# mzc speed benchmark (issue 15)",
        "",
        f"Generated {d['generated']} by `python benchmarks/speed.py{''.join(' ' + a for a in s['argv'])}` at "
        f"commit {d['commit']} on {d['machine']}; " + ", ".join(f"{k} {v}" for k, v in d["versions"].items()) +
        f". Load average (1 min) {d['load'][0]:.2f} at the start, {d['load'][1]:.2f} after the command-line part, "
        f"{d['load'][2]:.2f} after the in-process part, {d['load'][3]:.2f} at the end: the machine (2 cores) is "
        f"shared, so other processes ran meanwhile; every comparison below is between runs interleaved in the same "
        f"run. Total wall time {d['wall_s']:.0f} s.",
        "",
        "## Done-when checks",
        "",
        "| condition | measured | verdict |",
        "|---|---|---|",
        *(f"| {label} | {measured} | {mark[ok]} |" for label, measured, ok in d["checks"]),
        "",
        "## Method",
        "",
        f"- Face: `{FACE}` of `shared/data/faces` ({d['face']['vertices']:,} vertices, {d['face']['triangles']:,} "
        f"triangles). Grids: " + "; ".join(
            f"**{name}** (`mzc slice {FACE}{''.join(' ' + w for w in GRIDS[name]['cli'])}`: "
            f"{g['shape'][0]} x {g['shape'][1]} nodes, {g['projection']}, d1 = {g['d1']:.3g} mm, "
            f"{g['valid']:,} valid)" for name, g in d["grids"].items()) +
        ". The issue's 0.5 mm grid of 420 x 336 nodes is the planar one: planes were the default projection "
        "when it was written; the default projection of a face is now spherical.",
        f"- Command line: every command is `{Path(sys.executable).name} -m mzc ...` of this venv, its stdout "
        "to /dev/null or its `-o` file in a temporary folder; wall time of the whole process, peak RSS from "
        f"`os.wait4`. {s['repeats']} rounds; each runs every row once, in an order shuffled per round (the "
        "stages of one grid stay in order, each reading the file the one before wrote). The pipeline is "
        f"`mzc slice {FACE} [grid options] | mzc encode {' '.join(ENCODE)} | mzc decode | mzc densify -n "
        f"{DENSIFY} | mzc triangulate -o out.ply`, five processes joined by pipes (`report.run_stages`). mzc's "
        "modules are compiled to bytecode first, as installing a wheel does (`compile_bytecode`).",
        f"- In process: `mzc.slice(mesh, ...)`, `mzc.encode(grid, rmse={RMSE})`, `mzc.decode(data)`, "
        f"`mzc.densify(grid, {DENSIFY})`, `mzc.triangulate(grid)` on inputs made once beforehand (the mesh read "
        f"once); wall time (`time.perf_counter`) of each call, {s['repeats']} rounds, the order of the calls "
        "rotated each round, garbage collected before each. Draco (DracoPy) codes the original mesh at "
        f"{DRACO_BITS}-bit positions and compression level 10 (`contenders.draco_encode`); its decode gives the "
        "mesh. The grid peers are `contenders.py`'s JPEG 2000 (OpenJPEG, the grid quantised to 16 bits over its "
        "range; lossless, and at the PSNR of an RMS error of 0.05 mm over the filled grid's range) and SPERR "
        "(its PSNR mode at that PSNR), single-threaded, with the contenders' container: the validity mask coded "
        "by mzc's mask coder and the invalid nodes filled by mzc's encoder's biharmonic fill before coding (the "
        "fill is timed on its own too); their decode, like Draco's, ends in a mesh, so mzc's `decode to mesh` "
        "(decode + triangulate) is the like-for-like figure, `decode` (to the z-grid) the issue's.",
        "- Scaling: `terrain_grid(rows, cols, seed)` of `benchmarks/scaling.py` (planar, 1 m spacing, octaves "
        "of smooth noise, a wobbly border and interior holes), written as a raw "
        f"z-grid; then `mzc encode {' '.join(SCALE_ENCODE)}`, `mzc decode` of its output, `mzc densify -n "
        f"{SCALE_DENSIFY}` and `mzc triangulate -o mesh.ply` of the grid, each a process with a time limit of "
        f"{s['stage_timeout']:g} s and an address-space cap (RLIMIT_AS) of {s['memory_cap_gb']:g} GB; sizes under "
        f"{SCALE_REPEATS_BELOW:g} M nodes run 3 times (median), larger ones once. The exponent is the slope of "
        "log wall time against log nodes; wall time includes the start-up (about the `mzc --help` row below), "
        "which flattens the small sizes' exponents. The verdicts are on wall time, as the issue asks; CPU time "
        "(user + system of the stage's process) is beside it, since the other processes of the shared machine "
        "stretch wall time much more than CPU time. GB = 10^9 bytes.",
        "- LAZ cloud (issue 16): `clouds.write_laz` writes a generated airborne survey (1 km x 1 km of terrain, "
        "65% ground points, 35% vegetation above it, LAS 1.2 with 1 cm quanta, as LAZ); `mzc slice survey.laz "
        f"--classes 2 -o survey.zg` runs {s['repeats']} times, each a process (wall time and peak RSS, the "
        "LAZ read through laspy and lazrs included).",
        "- `diff --surface` (issues 15 and 16): `mzc diff f18.ply rebuilt.ply --surface`, the rebuild being the "
        "triangulate output of part 1 on the first checked grid, a process per round; then the pairs of "
        "`surface_distance.py`'s large meshes (a wavy sheet and a closed bumpy torus of side x side vertices, the "
        "second of each pair jittered), written as binary PLY, `mzc diff a.ply b.ply --surface` once each; wall "
        "time and peak RSS from the wrapper.",
        "",
        *cli_section(d),
        *stage_section(d),
        *peer_section(d),
        *scaling_section(d),
    ]
    if d["missing"]:
        lines += ["## Not measured", "", *(f"- {k}: {v}" for k, v in d["missing"].items()), ""]
    lines += ["Every run is in `speed-results.json`."]
    return "\n".join(lines) + "\n"


def cli_section(d):
    """Start-up commands and the pipelines, CLI wall."""
    cli = d["cli"]
    numpy_s = cli['python -c "import numpy"']["median_s"]
    lines = ["## Start-up and the five-filter pipeline (command line, wall)", "",
             "| command | median s | min s | runs ok | peak RSS MB | median / `import numpy` |",
             "|---|---|---|---|---|---|"]
    for row in ("python -c pass", 'python -c "import numpy"', "mzc --help",
                *(f"pipeline {name}" for name in d["grids"])):
        r = cli[row]
        ratio = "n/a" if r["median_s"] is None or not numpy_s else f"{r['median_s'] / numpy_s:.2f}"
        label = f"pipeline on f18, {row.removeprefix('pipeline ')} grid" if row.startswith("pipeline") else f"`{row}`"
        failure = f" ({r['error']})" if r["error"] else ""
        lines.append(f"| {label}{failure} | {sec(r['median_s'], 3)} | {sec(r['min_s'], 3)} | {r['ok']}/{r['runs']} | "
                     f"{mb(r['peak_mb'])} | {ratio} |")
    return lines + ["", "Peak RSS of a pipeline is its largest process's, from `os.wait4` in `report.run_stages`: a "
                    "forked child starts with the RSS of this process (about 40 MB during this part), a floor under "
                    "that figure; the other rows are measured by a small wrapper process (`WRAPPER`).", ""]


def stage_section(d):
    """Every stage on every grid: CLI wall and in-process compute."""
    cli, api = d["cli"], d["api"]
    lines = ["## Every stage on f18: command line and in process", "",
             "CLI: the stage as its own process, file in and file out (start-up, imports and file I/O included). "
             "In process: the same work through the Python API. Medians (min) of the rounds; ms.", "",
             "| grid | stage | CLI wall | CLI min | CLI peak RSS MB | in process | in-process min | CLI - in process |",
             "|---|---|---|---|---|---|---|---|"]
    for name in d["grids"]:
        stages = ["slice", "encode", "decode", f"densify -n {DENSIFY}", "triangulate"]
        for stage in stages:
            c, a = cli.get(f"{name}: {stage}"), api.get(f"{name}: {stage}")
            gap = ms(c["median_s"] - a["median_s"]) if c and a and c["median_s"] is not None else "n/a"
            lines.append(f"| {name} | {stage} | {ms(c and c['median_s'])} | {ms(c and c['min_s'])} | "
                         f"{mb(c and c['peak_mb'])} | {ms(a and a['median_s'])} | {ms(a and a['min_s'])} | {gap} |")
        total_cli = sum(cli[f"{name}: {stage}"]["median_s"] or 0 for stage in stages)
        total_api = sum(api[f"{name}: {stage}"]["median_s"] for stage in stages)
        lines.append(f"| {name} | **all five** | {ms(total_cli)} | | | {ms(total_api)} | | "
                     f"{ms(total_cli - total_api)} |")
    return lines + [""]


def peer_section(d):
    """mzc's codec beside Draco, JPEG 2000 and SPERR, in process."""
    api, facts = d["api"], d["facts"]
    draco = facts.get("Draco")
    lines = ["## Beside Draco, JPEG 2000 and SPERR (in process)", "",
             "Medians (min) of the rounds in ms; ratios are of medians, to Draco's encode and decode of the "
             "original mesh. Bytes are the file as stored; RMS (mm) is the node error: each decoded vertex's distance "
             "to the nearest vertex of the sliced grid's mesh (none for Draco, which codes the original mesh). "
             f"mzc's `--rmse {RMSE}` is a target for the distance between the surfaces, along their normals; the "
             "node error, along the node lines, is larger where the surface leans from them.", "",
             "| coder | input | setting | bytes | RMS mm | encode ms | min | / Draco | decode ms | min | / Draco |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]

    def row(label, source, fact, encode, decode):
        ratios = []
        for key, value in (("encode", encode), ("decode", decode)):
            base = api.get(f"Draco: {key}")
            ratios.append("n/a" if value is None or base is None else f"{value['median_s'] / base['median_s']:.2f}")
        rms = "n/a" if fact.get("rms_mm") is None else f"{fact['rms_mm']:.4f}"
        lines.append(f"| {label} | {source} | {fact['setting']} | {fact['bytes']:,} | {rms} | "
                     f"{ms(encode and encode['median_s'])} | {ms(encode and encode['min_s'])} | {ratios[0]} | "
                     f"{ms(decode and decode['median_s'])} | {ms(decode and decode['min_s'])} | {ratios[1]} |")

    if draco:
        row("Draco", "f18 mesh", draco, api["Draco: encode"], api["Draco: decode"])
    for name in d["grids"]:
        fact = facts[f"{name}: mzc dwt2d --rmse {RMSE}"]
        row("mzc dwt2d (decode to z-grid)", f"{name} grid", fact, api[f"{name}: encode"], api[f"{name}: decode"])
        row("mzc dwt2d (decode to mesh)", f"{name} grid", fact, None, api[f"{name}: decode to mesh"])
        for label in ("JPEG 2000 lossless", "JPEG 2000", "SPERR"):
            if f"{name}: {label}" in facts:
                row(label, f"{name} grid", facts[f"{name}: {label}"], api[f"{name}: {label} encode"],
                    api[f"{name}: {label} decode"])
        fill = api[f"{name}: smooth fill"]
        lines.append(f"| (smooth fill, inside every grid peer's encode) | {name} grid | | | | {ms(fill['median_s'])} "
                     f"| {ms(fill['min_s'])} | | | | |")
    return lines + [""]


def scaling_section(d):
    """The scaling table and the exponents."""
    rows = d["scaling"]
    lines = ["## Scaling (command line, synthetic planar grids)", "",
             "| M nodes | shape | stage | wall s | CPU s | runs | peak RSS MB | exponent from the size before "
             "(wall) | (CPU) | status |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        step, cpu_step = ((next((f"{e:.2f}" for a, b, e in exponents(rows, row["stage"], clock=clock)[0]
                                 if b == row["mnodes"]), "")) for clock in ("wall_s", "cpu_s"))
        status = row["status"] if row["status"] == "ok" else f"{row['status']}: {row['error']}"
        lines.append(f"| {row['mnodes']:g} | {row['shape'][0]} x {row['shape'][1]} | {row['stage']} | "
                     f"{sec(row['wall_s'])} | {sec(row.get('cpu_s'))} | {len(row['runs'])} | "
                     f"{mb(row['peak_mb'])} | {step} | {cpu_step} | {status} |")
    lines += ["", f"| stage | exponent of wall time from the first size of at least {EXPONENT_FROM:g} M to the "
              "largest finished | of CPU time |", "|---|---|---|"]
    for stage in SCALE_STAGES:
        cells = []
        for clock in ("wall_s", "cpu_s"):
            _, overall = exponents(rows, stage, clock=clock)
            cells.append("n/a" if overall is None else f"{overall[2]:.2f} ({overall[0]:g} to {overall[1]:g} M)")
        lines.append(f"| {stage} | {cells[0]} | {cells[1]} |")
    return lines + [""]


# --------------------------------------------------------------------------- main


def compile_bytecode():
    """Compile mzc's modules to bytecode, as installing a wheel does: an editable install leaves
    it to the first import, and where PYTHONDONTWRITEBYTECODE is set (as on the machines these
    reports come from) every command would compile them from source again (20-40 ms a process)."""
    import compileall

    import mzc

    compileall.compile_dir(Path(mzc.__file__).parent, quiet=1)


def parse_args(argv):
    parser = benchmark_parser(__doc__, "one round, the 0.5 mm grid only, tiny scaling sizes")
    parser.add_argument("--repeats", type=int,
                        help=f"rounds of parts 1 and 2 (default {REPEATS}; quick {QUICK_REPEATS})")
    parser.add_argument("--sizes", help="scaling sizes in M nodes, comma-separated (default "
                        f"{','.join(f'{s:g}' for s in SIZES)}; quick {','.join(f'{s:g}' for s in QUICK_SIZES)})")
    parser.add_argument("--stage-timeout", type=float, default=STAGE_TIMEOUT,
                        help=f"seconds a scaling stage may take (default {STAGE_TIMEOUT:g})")
    parser.add_argument("--memory-cap-gb", type=float, default=MEMORY_CAP_GB,
                        help=f"address-space cap of a scaling stage in GB (default {MEMORY_CAP_GB:g})")
    args = parser.parse_args(argv)
    args.repeats = args.repeats or (QUICK_REPEATS if args.quick else REPEATS)
    args.sizes = tuple(float(s) for s in args.sizes.split(",")) if args.sizes else (
        QUICK_SIZES if args.quick else SIZES)
    if args.repeats < 1 or not args.sizes or min(args.sizes) <= 0:
        parser.error("--repeats must be at least 1 and --sizes positive")
    return args


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    face = FACES / FACE
    if not face.is_file():
        print(f"speed.py: skipped: no {face}", file=sys.stderr)
        return
    from mzc.api import as_mesh

    started = time.perf_counter()
    grids = QUICK_GRIDS if args.quick else tuple(GRIDS)
    load = [os.getloadavg()[0]]
    missing = {}
    with tempfile.TemporaryDirectory(prefix="bench-speed-", dir="/tmp") as scratch:
        scratch = Path(scratch)
        (scratch / "cli").mkdir()
        compile_bytecode()
        cli_runs = cli_rounds(face, grids, args.repeats, scratch / "cli")
        load.append(os.getloadavg()[0])
        mesh = as_mesh(face)
        tasks, facts = api_tasks(mesh, grids, missing)
        api_times = api_rounds(tasks, args.repeats)
        load.append(os.getloadavg()[0])
        (scratch / "scale").mkdir()
        scale_rows = scaling(args.sizes, scratch / "scale", args.stage_timeout, args.memory_cap_gb * 1e9, args.quick)
        laz = laz_slice(scratch, QUICK_LAZ_POINTS if args.quick else LAZ_POINTS, args.repeats)
        rebuilt_grid = next((g for g in CHECKED_GRIDS if g in grids), grids[0])
        diffs = surface_diffs(face, scratch / "cli" / f"{rebuilt_grid.replace(' ', '-')}.ply", scratch,
                              QUICK_LARGE_SIDE if args.quick else LARGE_SIDE, args.repeats)
    load.append(os.getloadavg()[0])
    cli = {row: summary(runs) for row, runs in cli_runs.items()}
    api = {name: {"median_s": float(np.median(t)), "min_s": min(t), "runs": t} for name, t in api_times.items()}
    grid_facts = {name: facts[f"{name}: mzc dwt2d --rmse {RMSE}"].pop("grid") for name in grids}
    document = {
        "generated": f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}", "commit": git_commit(),
        "machine": machine(), "versions": versions(PACKAGES), "load": load,
        "settings": {"argv": sys.argv[1:] if argv is None else list(argv), "quick": args.quick,
                     "repeats": args.repeats, "sizes": list(args.sizes), "stage_timeout": args.stage_timeout,
                     "memory_cap_gb": args.memory_cap_gb, "rmse": RMSE, "densify": DENSIFY,
                     "scale_densify": SCALE_DENSIFY, "draco_bits": DRACO_BITS,
                     "threads": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")}},
        "face": {"name": FACE, "vertices": len(mesh.points), "triangles": len(mesh.triangles)},
        "grids": grid_facts, "cli": cli, "cli_runs": cli_runs, "api": api, "facts": facts,
        "scaling": scale_rows, "missing": missing, "laz": laz, "surface_diffs": diffs,
    }
    document["checks"] = (checks(cli, api, scale_rows, args.sizes, grids) + laz_checks(laz)
                          + surface_checks(diffs, rebuilt_grid))
    document["wall_s"] = time.perf_counter() - started
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "speed-results.json").write_text(json.dumps(document, indent=1, default=float) + "\n")
    (args.out / "speed-results.md").write_text(markdown(document))
    failed = sum(ok is False for _, _, ok in document["checks"])
    print(f"speed.py: {len(document['checks']) - failed} of {len(document['checks'])} checks not failed; "
          f"wrote {args.out / 'speed-results.md'} in {document['wall_s']:.0f} s")


if __name__ == "__main__":
    main()
