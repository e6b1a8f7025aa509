"""Rate-distortion benchmark of mzc against its peers (issue 5).

    python benchmarks/rd.py [--quick] [--faces N] [--out DIR] [--workers N]

Every contender of ``contenders.py`` codes each corpus item at every setting of its
ladder; each file is decoded, turned into a mesh and measured against the original mesh
with mzc's own symmetric point-to-surface distance (``mzc.measure.metrics.surface_distance_parts``,
the code behind ``mzc diff --surface --heightfield``): over the whole surface (every
triangle; the primary figure) and over its height-field part (the secondary one). Writes
rd-results.md, rd-results.json and one rd-<corpus>.png per corpus into --out (default:
this directory). Progress goes to stderr only when it is a terminal.
"""

import functools
import time
from dataclasses import replace

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from contenders import THESIS_GRID, NotApplicable, all_contenders, mask_bytes, mesh_pair
from corpora import FACES, mesh_files

GRID_STEP = 0.5            # mm, the grid of the grid contenders
SAMPLES = 8_000           # per direction and item; see the sample-count check in the report
QUICK_SAMPLES = 5_000
SEED = 0
REPEATS = 5                # timing runs per contender and item (median)
QUICK_REPEATS = 1          # the speed table of a quick run is indicative only
# The summary ratios' measures ("part statistic" of the distance), primary first, and their
# target errors in units. A 0.5 mm face grid cannot get below about 0.85 mm whole-surface
# Hausdorff (the floor section of the report), hence its coarser targets.
TARGETS = {"whole rms": (0.05, 0.1, 0.2), "whole hausdorff": (1.0, 1.5, 2.0), "heightfield rms": (0.05, 0.1, 0.2)}


# --------------------------------------------------------------------------- corpus


def corpus_specs(quick, faces):
    """(corpus, name, loader argument) of every item: the faces, then the two DEMs."""
    paths = mesh_files(FACES)
    count = faces if faces is not None else (1 if quick else len(paths))
    specs = [("faces", p.stem, str(p)) for p in paths[:count]]
    dems = ["topobathy"] if quick else ["jacksboro", "topobathy"]
    return specs + [(name, name, name) for name in dems]


def load_item(corpus, source):
    """Inputs of one item: the original mesh, its grid(s), the error unit and vertex count."""
    from mzc import samples
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    if corpus == "faces":
        mesh = read_mesh(source)
        inputs = {"mesh": (mesh.points, mesh.triangles),
                  "grid": slice_surface(mesh, d1=GRID_STEP, d2=GRID_STEP),
                  "thesis": slice_surface(mesh, projection="planar", **THESIS_GRID)}
        return inputs, 1.0, "mm"
    grid = getattr(samples, source)()
    valid_z = grid.z[grid.valid]
    unit = 10.0 ** round(np.log10(np.ptp(valid_z) / 100))
    return {"mesh": mesh_pair(grid), "grid": grid}, unit, grid.units or "m"


# --------------------------------------------------------------------------- measuring


def without_degenerate(mesh):
    """The mesh without zero-area triangles (quantisers collapse some; they add no surface)."""
    from mzc.measure.metrics import triangle_areas

    points, triangles = mesh
    return points, triangles[triangle_areas(points, triangles) > 0]


def measure(original, decoded, filters, samples):
    """Whole-surface and height-field distances of ``decoded`` to ``original``."""
    from mzc.measure.metrics import surface_distance_parts

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


def time_contender(contender, data_in, unit, repeats, first):
    """Median encode and decode seconds over ``repeats`` runs at ``first``'s setting, ``first``
    (that setting's rate-distortion point) being the first run."""
    encode, decode = [first["encode_s"]], [first["decode_s"]]
    for _ in range(repeats - 1):
        start = time.perf_counter()
        data = contender.encode(data_in, first["setting"], unit)
        middle = time.perf_counter()
        contender.decode(data)
        encode.append(middle - start)
        decode.append(time.perf_counter() - middle)
    return {"setting": first["setting"], "bytes": first["bytes"], "encode_s": float(np.median(encode)),
            "decode_s": float(np.median(decode))}


def thinned(contender):
    """The contender with every other setting of its ladder (and its finest), for --quick."""
    ladder = contender.ladder[::2] + (contender.ladder[-1:] if len(contender.ladder) % 2 == 0 else ())
    return replace(contender, ladder=ladder)


@functools.lru_cache(maxsize=1)
def prepared_item(corpus, name, source):
    """(inputs, unit, height-field filters, the item's fields of the result) of one item.

    Kept for the worker's next job: jobs go out item by item, so each worker loads each
    item at most once.
    """
    from mzc.measure.metrics import heightfield_filters
    from mzc.meshes import Mesh

    inputs, unit, units = load_item(corpus, source)
    grid = inputs["grid"]
    fields = {"corpus": corpus, "item": name, "unit": unit, "units": units, "vertices": len(inputs["mesh"][0]),
              "grid_shape": list(grid.shape), "grid_projection": grid.projection,
              "mask_bytes": len(mask_bytes(grid.valid))}
    if corpus == "faces":
        fields["slice_cpu_s"] = slice_seconds(Mesh(*inputs["mesh"]))
    return inputs, unit, heightfield_filters(*inputs["mesh"]), fields


def slice_seconds(mesh, repeats=3):
    """CPU seconds (the fastest of ``repeats``: this process's own time, whatever the other
    workers do) of slicing ``mesh`` at the grid step in the default projection and in planes."""
    from mzc.ops.slicing import slice_surface

    def fastest(projection):
        runs = []
        for _ in range(repeats):
            start = time.process_time()
            slice_surface(mesh, d1=GRID_STEP, d2=GRID_STEP, projection=projection)
            runs.append(time.process_time() - start)
        return min(runs)

    return {"default": fastest("auto"), "planar": fastest("planar")}


@functools.lru_cache(maxsize=2)
def contender_table(faces):
    """{name: contender} of ``all_contenders(faces)``, built once per worker."""
    return {contender.name: contender for contender in all_contenders(faces=faces)[0]}


def run_job(job):
    """One contender at every setting of its ladder on one item, and its timing runs.

    Failures are recorded, not raised. Returns the item's fields and this contender's
    points, timing, failures, skipped settings and clock.
    """
    spec, contender_name, samples, repeats, quick = job
    clock = {"load": -time.perf_counter()}
    inputs, unit, filters, fields = prepared_item(*spec)
    clock["load"] += time.perf_counter()
    clock.update(encode=0.0, decode=0.0, metric=0.0, timing=0.0)
    contender = contender_table(spec[0] == "faces")[contender_name]
    if quick:
        contender = thinned(contender)
    original = inputs["mesh"]
    part = {"fields": fields, "points": [], "timing": {}, "failures": [], "skipped": [], "clock": clock}
    for setting in contender.ladder:
        try:
            point = run_point(contender, inputs[contender.source], setting, unit, original, filters,
                              samples, len(original[0]))
        except NotApplicable as why:
            part["skipped"].append({"contender": contender.name, "setting": setting, "why": str(why)})
            continue
        except Exception as error:  # noqa: BLE001 - one broken codec must not stop the run
            part["failures"].append({"contender": contender.name, "setting": setting,
                                     "error": f"{type(error).__name__}: {error}"})
            continue
        for phase in ("encode", "decode", "metric"):
            clock[phase] += point[f"{phase}_s"]
        part["points"].append({"contender": contender.name, "family": contender.family,
                               "source": contender.source, "knob": contender.knob, **point})
    start = time.perf_counter()
    middle = contender.ladder[len(contender.ladder) // 2]
    first = next((p for p in part["points"] if p["setting"] == middle), None)
    if first:   # else that setting failed or does not apply, as recorded above
        part["timing"][contender.name] = time_contender(contender, inputs[contender.source], unit, repeats, first)
    clock["timing"] += time.perf_counter() - start
    return part


def add_part(results, part):
    """Join one job's part into the result of its item (created at the item's first part)."""
    fields = part["fields"]
    result = results.setdefault(fields["item"], {**fields, "points": [], "timing": {}, "failures": [],
                                                 "skipped": [], "clock": dict.fromkeys(part["clock"], 0.0)})
    for key in ("points", "failures", "skipped"):
        result[key] += part[key]
    result["timing"].update(part["timing"])
    for phase, seconds in part["clock"].items():
        result["clock"][phase] += seconds
    return result


def sample_check(spec, samples, factor=5):
    """Every summary measure of a few contenders at ``samples`` and ``factor`` times as many.

    Shows whether the chosen sample count resolves the differences the report draws.
    """
    from report import error_of

    inputs, unit, filters, _fields = prepared_item(*spec)
    table = contender_table(spec[0] == "faces")
    rows = []
    for contender in [table[name] for name in ("mzc dwt2d", "SPERR", "Draco", "mzc dct") if name in table]:
        setting = contender.ladder[len(contender.ladder) // 2]
        decoded = contender.decode(contender.encode(inputs[contender.source], setting, unit))
        distances = [measure(inputs["mesh"], decoded, filters, n) for n in (samples, factor * samples)]
        rows.append({"item": spec[1], "contender": contender.name, "setting": setting,
                     "samples": [samples, factor * samples],
                     "errors": {m: [error_of(d, m) for d in distances] for m in TARGETS}})
    return rows


# --------------------------------------------------------------------------- running


def run_all(specs, samples, repeats, quick, workers, progress):
    """run_job over every (item, contender) in a process pool, so that one large item spreads
    over every worker; the item results in corpus order, points in table order."""
    import multiprocessing

    jobs = [(spec, contender.name, samples, repeats, quick)
            for spec in specs for contender in all_contenders(faces=spec[0] == "faces")[0]]
    results = {}
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        for done, part in enumerate(pool.imap(run_job, jobs), 1):
            result = add_part(results, part)
            progress(f"[{done}/{len(jobs)}] {result['corpus']} {result['item']}: "
                     f"{len(result['points'])} points, {len(result['failures'])} failures")
    return list(results.values())


def parse_args(argv):
    from report import benchmark_parser

    parser = benchmark_parser(__doc__, "one face and the small DEM, fewer samples", workers=True)
    parser.add_argument("--faces", type=int, help="number of faces (default: all, or 1 with --quick)")
    return parser.parse_args(argv)


def main(argv=None):
    from report import pipeline_timings, terminal_progress, write_outputs

    args = parse_args(argv)
    progress = terminal_progress()
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
