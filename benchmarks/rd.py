"""Rate-distortion benchmark of mzc against its peers (issue 5).

    python benchmarks/rd.py [--quick] [--faces N] [--out DIR] [--workers N]

Every contender of ``contenders.py`` codes each corpus item at every setting of its
ladder; each file is decoded, turned into a mesh and measured against the original mesh
with mzc's own symmetric point-to-surface distance (``mzc.metrics.surface_distance_parts``,
the code behind ``mzc diff --surface --heightfield``), over the whole surface and over its
height-field part. Writes rd-results.md, rd-results.json and one rd-<corpus>.png per corpus
into --out (default: this directory). Progress goes to stderr only when it is a terminal.
"""

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one core per worker: timings are single-threaded

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from contenders import THESIS_GRID, NotApplicable, all_contenders  # noqa: E402

FACES = HERE.parent.parent / "shared" / "data" / "faces"
GRID_STEP = 0.5            # mm, the grid of the grid contenders
SAMPLES = 8_000           # per direction and item; see the sample-count check in the report
QUICK_SAMPLES = 5_000
SEED = 0
REPEATS = 5                # timing runs per contender and item (median)
QUICK_REPEATS = 2
TARGETS = (0.05, 0.1, 0.2)  # height-field RMS errors of the summary ratio, in units


# --------------------------------------------------------------------------- corpus


def corpus_specs(quick, faces):
    """(corpus, name, loader argument) of every item: the faces, then the two DEMs."""
    paths = sorted(FACES.glob("*.ply")) + sorted(FACES.glob("*.obj")) if FACES.is_dir() else []
    count = faces if faces is not None else (1 if quick else len(paths))
    specs = [("faces", p.stem, str(p)) for p in paths[:count]]
    dems = ["topobathy"] if quick else ["jacksboro", "topobathy"]
    return specs + [(name, name, name) for name in dems]


def load_item(corpus, source):
    """Inputs of one item: the original mesh, its grid(s), the error unit and vertex count."""
    from mzc import samples
    from mzc.meshes import read_mesh
    from mzc.slicing import slice_surface
    from mzc.triangulation import grid_to_mesh

    if corpus == "faces":
        mesh = read_mesh(source)
        inputs = {"mesh": (mesh.points, mesh.triangles),
                  "grid": slice_surface(mesh, d1=GRID_STEP, d2=GRID_STEP),
                  "thesis": slice_surface(mesh, projection="planar", **THESIS_GRID)}
        return inputs, 1.0, "mm"
    grid = getattr(samples, source)()
    valid_z = grid.z[grid.valid]
    unit = 10.0 ** round(np.log10(np.ptp(valid_z) / 100))
    return {"mesh": grid_to_mesh(grid), "grid": grid}, unit, grid.units or "m"


# --------------------------------------------------------------------------- measuring


def without_degenerate(mesh):
    """The mesh without zero-area triangles (quantisers collapse some; they add no surface)."""
    from mzc.metrics import triangle_areas

    points, triangles = mesh
    return points, triangles[triangle_areas(points, triangles) > 0]


def measure(original, decoded, filters, samples):
    """Whole-surface and height-field distances of ``decoded`` to ``original``."""
    from mzc.metrics import surface_distance_parts

    return surface_distance_parts(original, without_degenerate(decoded),
                                  {"whole": (None, None), "heightfield": filters}, samples=samples, seed=SEED)


def run_point(contender, data_in, setting, unit, original, filters, samples, vertices):
    """One rate-distortion point: encode, decode, measure."""
    start = time.perf_counter()
    data = contender.encode(data_in, setting, unit)
    encoded = time.perf_counter()
    decoded = contender.decode(data)
    done = time.perf_counter()
    distances = measure(original, decoded, filters, samples)
    return {"setting": setting, "bound": setting * unit if contender.scaled else None,
            "bytes": len(data), "bits_per_vertex": 8 * len(data) / vertices,
            "encode_s": encoded - start, "decode_s": done - encoded,
            "metric_s": time.perf_counter() - done, **distances}


def time_contender(contender, data_in, unit, repeats):
    """Median encode and decode seconds over ``repeats`` runs at the middle of the ladder."""
    setting = contender.ladder[len(contender.ladder) // 2]
    encode, decode = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        data = contender.encode(data_in, setting, unit)
        middle = time.perf_counter()
        contender.decode(data)
        encode.append(middle - start)
        decode.append(time.perf_counter() - middle)
    return {"setting": setting, "bytes": len(data), "encode_s": float(np.median(encode)),
            "decode_s": float(np.median(decode))}


def thinned(contender):
    """The contender with every other setting of its ladder (and its finest), for --quick."""
    ladder = contender.ladder[::2] + (contender.ladder[-1:] if len(contender.ladder) % 2 == 0 else ())
    return replace(contender, ladder=ladder)


def run_item(job):
    """Every contender at every setting on one corpus item; failures are recorded, not raised."""
    from mzc.metrics import heightfield_filters

    (corpus, name, source), samples, repeats, quick = job
    clock = {"load": -time.perf_counter()}
    inputs, unit, units = load_item(corpus, source)
    original = inputs["mesh"]
    filters = heightfield_filters(*original)
    clock["load"] += time.perf_counter()
    table, _missing = all_contenders(faces=corpus == "faces")
    if quick:
        table = [thinned(contender) for contender in table]
    result = {"corpus": corpus, "item": name, "unit": unit, "units": units, "vertices": len(original[0]),
              "grid_shape": list(inputs["grid"].shape), "points": [], "timing": {}, "failures": [], "skipped": []}
    clock.update(encode=0.0, decode=0.0, metric=0.0, timing=0.0)
    for contender in table:
        for setting in contender.ladder:
            try:
                point = run_point(contender, inputs[contender.source], setting, unit, original, filters,
                                  samples, len(original[0]))
            except NotApplicable as why:
                result["skipped"].append({"contender": contender.name, "setting": setting, "why": str(why)})
                continue
            except Exception as error:  # noqa: BLE001 - one broken codec must not stop the run
                result["failures"].append({"contender": contender.name, "setting": setting,
                                           "error": f"{type(error).__name__}: {error}"})
                continue
            for phase in ("encode", "decode", "metric"):
                clock[phase] += point[f"{phase}_s"]
            result["points"].append({"contender": contender.name, "family": contender.family,
                                     "source": contender.source, "knob": contender.knob, **point})
        start = time.perf_counter()
        try:
            result["timing"][contender.name] = time_contender(contender, inputs[contender.source], unit, repeats)
        except Exception:  # noqa: BLE001 - already recorded as a failure above
            pass
        clock["timing"] += time.perf_counter() - start
    result["clock"] = clock
    return result


def sample_check(spec, samples, factor=5):
    """The height-field RMS of a few contenders at ``samples`` and ``factor`` times as many.

    Shows whether the chosen sample count resolves the differences the report draws.
    """
    from mzc.metrics import heightfield_filters

    inputs, unit, _units = load_item(spec[0], spec[2])
    filters = heightfield_filters(*inputs["mesh"])
    table, _missing = all_contenders()
    rows = []
    for contender in [c for c in table if c.name in ("mzc dwt2d", "SZ3", "Draco", "mzc dct")]:
        setting = contender.ladder[len(contender.ladder) // 2]
        decoded = contender.decode(contender.encode(inputs[contender.source], setting, unit))
        values = [measure(inputs["mesh"], decoded, filters, n)["heightfield"]["rms"]
                  for n in (samples, factor * samples)]
        rows.append({"item": spec[1], "contender": contender.name, "setting": setting,
                     "samples": [samples, factor * samples], "heightfield_rms": values})
    return rows


# --------------------------------------------------------------------------- running


def run_all(specs, samples, repeats, quick, workers, progress):
    """run_item over every spec in a process pool; results in corpus order."""
    import multiprocessing

    jobs = [(spec, samples, repeats, quick) for spec in specs]
    results = []
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        for done, result in enumerate(pool.imap_unordered(run_item, jobs), 1):
            results.append(result)
            progress(f"[{done}/{len(jobs)}] {result['corpus']} {result['item']}: "
                     f"{len(result['points'])} points, {len(result['failures'])} failures")
    order = {spec[1]: k for k, spec in enumerate(specs)}
    return sorted(results, key=lambda r: order[r["item"]])


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="one face and the small DEM, fewer samples")
    parser.add_argument("--faces", type=int, help="number of faces (default: all, or 1 with --quick)")
    parser.add_argument("--out", type=Path, default=HERE, help="output directory (default: benchmarks/)")
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1))
    return parser.parse_args(argv)


def main(argv=None):
    from report import pipeline_timings, write_outputs

    args = parse_args(argv)
    progress = (lambda text: print(text, file=sys.stderr, flush=True)) if sys.stderr.isatty() else (lambda text: None)
    samples = QUICK_SAMPLES if args.quick else SAMPLES
    repeats = QUICK_REPEATS if args.quick else REPEATS
    specs = corpus_specs(args.quick, args.faces)
    started = time.perf_counter()
    face_specs = [s for s in specs if s[0] == "faces"]
    progress("timing the CLI pipeline")  # first, while this process is small: children inherit its peak RSS
    pipeline = pipeline_timings(face_specs[0][2] if face_specs else None, 1 if args.quick else 3)
    results = run_all(specs, samples, repeats, args.quick, args.workers, progress)
    checks = sample_check(face_specs[0], samples) if face_specs and not args.quick else []
    _table, missing = all_contenders()
    settings = {"samples": samples, "seed": SEED, "repeats": repeats, "grid_step": GRID_STEP,
                "thesis_grid": THESIS_GRID, "targets": TARGETS, "workers": args.workers, "quick": args.quick,
                "wall_s": time.perf_counter() - started}
    args.out.mkdir(parents=True, exist_ok=True)
    write_outputs(args.out, results, missing, checks, pipeline, settings)
    progress(f"done in {settings['wall_s']:.0f} s; wrote {args.out}/rd-results.md")


if __name__ == "__main__":
    main()
