"""Throughput of ``mzc batch encode`` against a shell loop of the filters, on the shared faces.

    python benchmarks/batch.py [--faces N] [--repeats R] [--out PATH]

N face files (the faces of shared/data/faces linked under the names face000.ply ...,
cycling through them) go through ``mzc batch encode DIR -o OUT --dwt2d --rmse 0.05`` on its
default local cluster, and through a bash loop of ``mzc slice "$f" | mzc encode --dwt2d
--rmse 0.05`` over the same files. Both run as subprocesses of this venv's ``mzc``, timed
whole (interpreter and cluster start-up included), the two alternating in each of R
repeats since the machine is shared. The report gives items/s of both and their ratio
against the issue's targets, whether the outputs are byte-identical, where a face's time
goes in the batch (its manifest's timings) and what bounds the rate. Writes the markdown
report to --out (default benchmarks/batch-results.md) and a JSON of every run beside it.
"""

import argparse
import csv
import datetime
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from corpora import FACES, mesh_files  # noqa: E402
from report import machine  # noqa: E402 - after the path to this folder

ENCODE = ("--dwt2d", "--rmse", "0.05")
STAGES = ("read", "slice", "encode", "write")
TARGET_RATIO = 4.0      # the issue: batch at least 4x the shell loop ...
TARGET_RATE = 4.0       # ... and at least 4 faces/s, on this 2-core machine
PACKAGES = ("numpy", "PyWavelets", "dask", "distributed")
ROW_KEYS = ("input", "output_bytes", "seconds", "timings", "status", "error")   # of the manifest, kept in the JSON
LOOP = """set -eo pipefail
for f in "$IN"/*; do
  name=${f##*/}
  "$MZC" slice "$f" | "$MZC" encode "$@" > "$OUT/${name%.*}$EXT"
done"""


def face_sources():
    """The 13 faces: the PLY files, then example.obj; [] when the folder is absent."""
    return mesh_files(FACES)


def link_faces(sources, count, folder):
    """``count`` symlinks face000.ply ... in ``folder``, cycling through ``sources``; their total bytes."""
    folder.mkdir()
    for i in range(count):
        source = sources[i % len(sources)]
        (folder / f"face{i:03d}{source.suffix}").symlink_to(source)
    return sum(sources[i % len(sources)].stat().st_size for i in range(count))


def timed_run(command, env=None):
    """Run ``command``; (wall s, CPU s of it and all its children, stderr). Exits on a failure."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        sys.exit(f"batch.py: {command[0]} ... exited {done.returncode}: {done.stderr.strip()[-500:]}")
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu, done.stderr.strip()


def run_batch(mzc, inputs, out):
    """``mzc batch encode`` of ``inputs`` into ``out``: its times, summary line and manifest rows."""
    wall, cpu, stderr = timed_run([str(mzc), "batch", "encode", str(inputs), "-o", str(out), *ENCODE])
    with open(out / "manifest.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    return {"wall_s": wall, "cpu_s": cpu, "summary": stderr.splitlines()[-1],
            "rows": [{key: row[key] for key in ROW_KEYS} for row in rows]}


def run_loop(mzc, inputs, out, extension):
    """The bash loop of the filters over ``inputs`` into ``out``: its times."""
    out.mkdir()
    env = {**os.environ, "MZC": str(mzc), "IN": str(inputs), "OUT": str(out), "EXT": extension}
    wall, cpu, _ = timed_run(["bash", "-c", LOOP, "bash", *ENCODE], env=env)
    return {"wall_s": wall, "cpu_s": cpu}


def differing(batch_out, loop_out):
    """The names of the loop's outputs that the batch did not write with the same bytes."""
    return [p.name for p in sorted(loop_out.iterdir())
            if not (batch_out / p.name).is_file() or (batch_out / p.name).read_bytes() != p.read_bytes()]


def stage_seconds(rows):
    """(items, stages) array of each manifest row's seconds per stage (0 for a stage it lacks)."""
    parsed = [dict(zip(words[::2], map(float, words[1::2]))) for words in (r["timings"].split() for r in rows)]
    return np.array([[timings.get(stage, 0.0) for stage in STAGES] for timings in parsed])


def start_up(mzc, face, scratch):
    """Fixed cost of one batch command: the wall time of a batch of one face less that face's seconds."""
    (scratch / "one").mkdir()
    (scratch / "one" / face.name).symlink_to(face)
    run = run_batch(mzc, scratch / "one", scratch / "one-out")
    return {"face": face.name, "wall_s": run["wall_s"], "item_s": float(run["rows"][0]["seconds"]),
            "fixed_s": run["wall_s"] - float(run["rows"][0]["seconds"])}


def measure(mzc, sources, count, repeats, scratch):
    """Every run: per repeat a batch of one (start-up), then the batch and the loop, in alternating order."""
    from mzc.codecs import get_codec

    extension = get_codec("dwt2d").extension
    inputs = scratch / "in"
    input_bytes = link_faces(sources, count, inputs)
    runs = []
    for r in range(repeats):
        here = scratch / f"run{r}"
        here.mkdir()
        run = {"startup": start_up(mzc, sources[0], here)}
        order = ("batch", "loop") if r % 2 == 0 else ("loop", "batch")
        for what in order:
            print(f"repeat {r + 1}/{repeats}: {what} of {count} faces", file=sys.stderr, flush=True)
            run[what] = (run_batch(mzc, inputs, here / "batch") if what == "batch"
                         else run_loop(mzc, inputs, here / "loop", extension))
        run["order"] = list(order)
        run["failed"] = [row["input"] for row in run["batch"]["rows"] if row["status"] != "ok"]
        run["differing"] = differing(here / "batch", here / "loop")
        runs.append(run)
        shutil.rmtree(here)
    return runs, input_bytes


def analyse(runs, count, workers):
    """The figures of the report from the runs: rates, ratio, verdicts, the per-face cost split."""
    batch_wall = np.array([run["batch"]["wall_s"] for run in runs])
    loop_wall = np.array([run["loop"]["wall_s"] for run in runs])
    stages = np.concatenate([stage_seconds(run["batch"]["rows"]) for run in runs]).mean(axis=0)
    core = workers * batch_wall.sum() / (count * len(runs))     # core seconds per face in the batch
    item = np.mean([float(row["seconds"]) for run in runs for row in run["batch"]["rows"]])
    split = {**dict(zip(STAGES, stages)), "overhead": core - stages.sum(),
             "in the items, outside the stages": item - stages.sum(), "outside the items": core - item}
    batch_cpu = sum(run["batch"]["cpu_s"] for run in runs) / (count * len(runs))
    rate, loop_rate = count / np.median(batch_wall), count / np.median(loop_wall)
    compute = stages[STAGES.index("slice")] + stages[STAGES.index("encode")]
    return {
        "batch_items_per_s": rate, "loop_items_per_s": loop_rate, "ratio": rate / loop_rate,
        "ratio_met": bool(rate / loop_rate >= TARGET_RATIO), "rate_met": bool(rate >= TARGET_RATE),
        "identical": all(not run["differing"] and not run["failed"] for run in runs),
        "core_s_per_face": core, "split_s": split,
        "bound_slice_encode": workers / compute, "bound_all_stages": workers / stages.sum(),
        "startup_s": float(np.median([run["startup"]["fixed_s"] for run in runs])),
        "batch_cores_busy": sum(run["batch"]["cpu_s"] for run in runs) / batch_wall.sum(),
        "loop_cores_busy": sum(run["loop"]["cpu_s"] for run in runs) / loop_wall.sum(),
        "batch_cpu_s_per_face": batch_cpu, "bound_cpu": workers / batch_cpu,
    }


def versions():
    """{package: version} of what the rate depends on: the numerics and Dask."""
    return {name: metadata.version(name) for name in PACKAGES}


def markdown(args, figures, runs, workers, input_bytes, sources, load):
    """The report text."""
    f, count = figures, args.faces
    verdict = {True: "met", False: "NOT met"}
    lines = [
        "# mzc batch encode against a shell loop of the filters",
        "",
        f"Generated {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z} by `python benchmarks/batch.py"
        f"{''.join(' ' + a for a in sys.argv[1:])}` on {machine()}; "
        + ", ".join(f"{k} {v}" for k, v in versions().items())
        + f". Load average {load[0]:.2f} before and {load[1]:.2f} after: the machine is shared, so other "
        "processes may have run meanwhile.",
        "",
        "## Method",
        "",
        f"- Inputs: {count} files `face000{sources[0].suffix}` ... in one temporary folder, symlinks cycling "
        f"through the {len(sources)} faces of `shared/data/faces` ({', '.join(p.name for p in sources)}); "
        f"{input_bytes / 1e6:.0f} MB in all.",
        f"- batch: `mzc batch encode DIR -o OUT {' '.join(ENCODE)}`, the default local cluster ({workers} "
        "worker processes, one thread each), into a fresh OUT each run.",
        f"- loop: `for f in DIR/*; do mzc slice \"$f\" | mzc encode {' '.join(ENCODE)} > OUT/...; done` under bash.",
        "- Both run as subprocesses of this venv's `mzc`; wall time is the whole command (Python start-up, "
        "the cluster's start and stop included); CPU time is user + system of the command and all its "
        f"processes. {args.repeats} repeat(s), each: a batch of one face (start-up), then the batch and the "
        "loop, which goes first alternating between repeats.",
        "",
        "## Throughput",
        "",
        "| repeat | first | batch s | batch items/s | batch CPU s/face | loop s | loop items/s | loop CPU s/face | "
        "ratio | outputs |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r, run in enumerate(runs, 1):
        batch, loop = run["batch"], run["loop"]
        same = "identical" if not run["differing"] else f"{len(run['differing'])} differ"
        lines.append(f"| {r} | {run['order'][0]} | {batch['wall_s']:.1f} | {count / batch['wall_s']:.2f} | "
                     f"{batch['cpu_s'] / count:.2f} | {loop['wall_s']:.1f} | {count / loop['wall_s']:.2f} | "
                     f"{loop['cpu_s'] / count:.2f} | {loop['wall_s'] / batch['wall_s']:.2f} | {same} |")
    lines += [
        "",
        f"- Medians over repeats: batch {f['batch_items_per_s']:.2f} items/s, loop {f['loop_items_per_s']:.2f} "
        f"items/s; their ratio {f['ratio']:.2f}.",
        f"- Target batch >= {TARGET_RATIO:g}x the loop: {verdict[f['ratio_met']]}. "
        f"Target >= {TARGET_RATE:g} faces/s: {verdict[f['rate_met']]}.",
        "- Outputs: " + ("every batch output is byte-identical to the loop's output of the same face, in every "
                         "repeat, and every manifest row is ok." if f["identical"] else
                         "NOT all identical: " + "; ".join(
                             f"repeat {r}: {len(run['differing'])} differ ({', '.join(run['differing'][:5])}), "
                             f"{len(run['failed'])} failed" for r, run in enumerate(runs, 1))),
        "",
        *split_section(f, runs, count, workers),
    ]
    return "\n".join(lines) + "\n"


def split_section(f, runs, count, workers):
    """Where a face's time goes in the batch, the start-up, and what bounds the rate."""
    core = f["core_s_per_face"]
    startup = runs[0]["startup"]
    lines = [
        "## Where a face's time goes in the batch",
        "",
        f"Mean over the {count * len(runs)} manifest rows of the stages' seconds (the timings column); a face's "
        f"core time is workers x wall / items = {workers} x the batch's wall time / {count}; overhead is that "
        "less the stages. Its part in the items (the manifest's seconds less the stages) is hashing the input, "
        "the node errors and each worker's first imports; its part outside them is the cluster's start-up and "
        "shut-down, scheduling, workers idle at the end, and the cores other processes of the shared machine took.",
        "",
        "| stage | ms per face | % of core time |",
        "|---|---|---|",
        *(f"| {'- of which ' * (k > len(STAGES))}{name} | {1000 * s:.1f} | {100 * s / core:.1f}% |"
          for k, (name, s) in enumerate(f["split_s"].items())),
        f"| core time per face | {1000 * core:.1f} | 100% |",
        "",
        f"Start-up: a batch of one face ({startup['face']}) took "
        f"{startup['wall_s']:.2f} s wall, {startup['item_s']:.2f} s of it the face, so a batch command costs about "
        f"{f['startup_s']:.1f} s (median over repeats) whatever its size: Python and imports, the cluster's start "
        f"and stop. Over {count} faces that is {1000 * f['startup_s'] / count:.0f} ms of wall, "
        f"{1000 * workers * f['startup_s'] / count:.0f} ms of core time per face.",
        "",
        "## What bounds the rate",
        "",
        f"The work is slicing and encoding, {1000 * (f['split_s']['slice'] + f['split_s']['encode']):.0f} ms a face "
        f"on a worker, so {workers} cores busy all the time would do {f['bound_slice_encode']:.2f} items/s "
        f"({f['bound_all_stages']:.2f} with reading and writing). The batch did {f['batch_items_per_s']:.2f}, "
        f"{100 * f['batch_items_per_s'] / f['bound_slice_encode']:.0f}% of the former, "
        f"{100 * f['batch_items_per_s'] / f['bound_all_stages']:.0f}% of the latter; the rest is the overhead "
        f"above. The batch's processes kept {f['batch_cores_busy']:.2f} of the {workers} cores busy (CPU time / "
        "wall time; the stages are wall times, and stretch when other processes take a core). In CPU time, which "
        f"they do not stretch, the batch cost {f['batch_cpu_s_per_face']:.2f} s a face, all its processes "
        f"together: {workers} cores to itself would do {f['bound_cpu']:.2f} items/s. The loop runs one "
        "face at a time in two fresh processes, each starting Python and importing mzc, "
        f"{f['loop_cores_busy']:.2f} cores busy (the second process's start-up overlaps the first's work): "
        f"{1000 / f['loop_items_per_s']:.0f} ms a face.",
    ]
    return lines


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--faces", type=int, default=200, help="number of face files (default 200)")
    parser.add_argument("--repeats", type=int, default=1, help="runs of the batch and the loop each (default 1)")
    parser.add_argument("--out", type=Path, default=HERE / "batch-results.md",
                        help="the markdown report; the JSON goes beside it (default benchmarks/batch-results.md)")
    args = parser.parse_args(argv)
    sources = face_sources()
    if not sources:
        print(f"batch.py: skipped: no faces in {FACES}", file=sys.stderr)
        return
    mzc = Path(sys.executable).parent / "mzc"
    if not mzc.is_file():
        sys.exit(f"batch.py: no mzc beside {sys.executable}: run this with the venv's python")
    workers = os.cpu_count() or 1   # the local cluster's default
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory(prefix="bench-batch-", dir="/tmp") as scratch:
        runs, input_bytes = measure(mzc, sources, args.faces, args.repeats, Path(scratch))
    load.append(os.getloadavg()[0])
    figures = analyse(runs, args.faces, workers)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    document = {"settings": {"faces": args.faces, "repeats": args.repeats, "workers": workers, "encode": ENCODE},
                "machine": machine(), "versions": versions(), "load_average": load, "input_bytes": input_bytes,
                "figures": figures, "runs": runs}
    args.out.with_suffix(".json").write_text(json.dumps(document, indent=1, default=float) + "\n")
    args.out.write_text(markdown(args, figures, runs, workers, input_bytes, sources, load))
    print(f"batch {figures['batch_items_per_s']:.2f} items/s, loop {figures['loop_items_per_s']:.2f} items/s, "
          f"ratio {figures['ratio']:.2f} (target {TARGET_RATIO:g}x: {'met' if figures['ratio_met'] else 'NOT met'}; "
          f"{TARGET_RATE:g} faces/s: {'met' if figures['rate_met'] else 'NOT met'}); outputs "
          f"{'identical' if figures['identical'] else 'NOT identical'}; wrote {args.out}")


if __name__ == "__main__":
    main()
