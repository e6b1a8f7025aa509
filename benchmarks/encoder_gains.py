"""Coding gains of the dwt2d encoder's quantisation and parameter choices, one by one (issue 33).

    python benchmarks/encoder_gains.py [--quick] [--out DIR]

Every face of the shared data is sliced on mzc's default grid (``mzc.slice``) and coded with
``mzc.encode(grid, "dwt2d", rmse=t)`` at a ladder of targets by each variant of the encoder: the
baseline (the encoder before issue 33's work), then each technique alone, then the kept ones
together. A variant is the encoder with some of its constants set (mzc.codecs.dwt2d: DEADZONE,
RDO_LAMBDA), an option (``wavelet``, ``level``), or a ``steps`` line of one step per band
(1 + 3L values, which every dwt2d 3.x decoder reads) at another level ratio. None changes the
bitstream: every file is decoded by the unchanged decoder, rebuilt by ``mzc.triangulate`` and
measured against the original mesh over its whole surface (symmetric point-to-surface RMS,
mzc.measure.metrics.surface_distance_parts, as rd.py measures) and on the grid (RMS of the height
error over the valid nodes). A variant's bytes at whole-surface RMS 0.05, 0.1 and 0.2 mm are
interpolated log-log on its own Pareto front (report.pareto, report.bytes_at) and divided by the
baseline's, face by face; the tables give the geometric mean, the range and the faces where it
is smaller. "Per-file best" takes, per face and target, the smallest of the wavelet and level
variants' interpolated bytes: what a per-file choice by trial could win at most. Encodes run
face by face with the variants in turn, so the machine's load falls on all alike; the encode
time is each variant's total CPU time over the ladder against the baseline's. Writes
encoder-gains-results.md and encoder-gains-results.json into --out (default: this directory).
"""

import contextlib
import datetime
import json
import time
from unittest import mock

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import faces_measured
from report import benchmark_parser, bytes_at, git_commit, machine, pareto, terminal_progress, versions

PACKAGES = ("numpy", "PyWavelets", "constriction")
TARGETS = (0.05, 0.1, 0.2)                             # mm of whole-surface RMS
LADDER = (0.035, 0.05, 0.07, 0.1, 0.14, 0.2, 0.28)     # the --rmse ladder (whole-surface RMS lies above the grid's)
QUICK_FACES = 3
SAMPLES = 20_000                                       # surface samples per direction
SEED = 0
MEASURE = "whole rms"
BASELINE = {"DEADZONE": 0.6, "RDO_LAMBDA": 0.0}        # the encoder before issue 33's work
# name: (what it is, constants of mzc.codecs.dwt2d, encode options, level ratio of a full steps line or None)
VARIANTS = {
    "baseline": ("rounding offset 0.4 (DEADZONE 0.6), no RDO, bior4.4, default levels, level ratio 0.9",
                 {}, {}, None),
    "deadzone 0.5": ("rounding to the nearest (DEADZONE 0.5)", {"DEADZONE": 0.5}, {}, None),
    "deadzone 0.55": ("rounding offset 0.45", {"DEADZONE": 0.55}, {}, None),
    "rdo 0.05": ("greedy RDO (lowered_toward_zero), lambda 0.05 squared steps per bit", {"RDO_LAMBDA": 0.05}, {},
                 None),
    "rdo 0.1": ("greedy RDO, lambda 0.1", {"RDO_LAMBDA": 0.1}, {}, None),
    "bior2.2": ("LeGall 5/3 wavelet", {}, {"wavelet": "bior2.2"}, None),
    "levels 4": ("one level fewer than the faces' default 5", {}, {"level": 4}, None),
    "levels 6": ("one level more", {}, {"level": 6}, None),
    "ratio 0.8": ("a step per band (16 values), each coarser level 0.8x the finer", {}, {}, 0.8),
}
PER_FILE = ("baseline", "bior2.2", "levels 4", "levels 6")   # the per-file choice's candidates
COMBINED = "combined"
BAR_RATIO, BAR_ENCODE = 0.99, 1.5   # a technique is kept when it saves 1% at every target, encoding within 1.5x


# --------------------------------------------------------------------------- variants


def band_ratio_steps(ratio):
    """A ``header_steps`` writing one step per band (1 + 3L values): band 0's, then each level's
    detail step ``ratio`` times the next finer one's, coarsest level first (expand_steps' order)."""
    from mzc.codecs import dwt2d
    from mzc.codecs.dwt2d import wavelet as w2

    def header_steps(step, levels):
        if not levels:
            return [step]
        details = [w2.round_step(step * ratio ** (levels - 1 - level)) for level in range(levels) for _ in range(3)]
        return [w2.round_step(dwt2d.APPROXIMATION_GAIN * step), *details]

    return header_steps


@contextlib.contextmanager
def encoder_of(constants, ratio):
    """The dwt2d encoder with the baseline's constants, then ``constants``, and a full steps line
    at ``ratio`` when given; the decoder's constants are not touched (LEVEL_RATIO stays)."""
    from mzc.codecs import dwt2d

    patches = {**BASELINE, **constants}
    if ratio is not None:
        patches["header_steps"] = band_ratio_steps(ratio)
    with mock.patch.multiple(dwt2d, **patches):
        yield


# --------------------------------------------------------------------------- measuring


def load_face(path):
    """(original mesh as points and triangles, the default grid) of one face."""
    import mzc
    from mzc.meshes import read_mesh

    mesh = read_mesh(str(path))
    return (mesh.points, mesh.triangles), mzc.slice(str(path))


def point(mesh, grid, target, constants, options, ratio):
    """One file: its bytes, encode CPU seconds (this process's: other work on the machine counts
    less than in wall time), whole-surface and grid RMS errors."""
    import mzc
    from mzc.measure.metrics import surface_distance_parts

    with encoder_of(constants, ratio):
        start = time.process_time()
        data = mzc.encode(grid, "dwt2d", rmse=target, **options)
        seconds = time.process_time() - start
    decoded = mzc.decode(data)   # today's decoder, as it is
    rebuilt = mzc.triangulate(decoded, vertices="all")   # the grid's own mesh: the codec alone
    distances = surface_distance_parts(mesh, (rebuilt.points, rebuilt.triangles), {"whole": (None, None)},
                                       samples=SAMPLES, seed=SEED)
    grid_rms = float(np.sqrt(np.mean(np.square(decoded.z - grid.z)[grid.valid])))
    return {"target": target, "bytes": len(data), "encode_s": seconds, "whole": distances["whole"],
            "grid_rms": grid_rms}


def measure_face(path, variants, progress):
    """{variant: [point per ladder target]} of one face, the variants in turn at each target."""
    mesh, grid = load_face(path)
    points = {name: [] for name in variants}
    for target in LADDER:
        for name, (_, constants, options, ratio) in variants.items():
            progress(f"{path.stem}: {name} at {target} mm")
            points[name].append(point(mesh, grid, target, constants, options, ratio))
    return {"face": path.stem, "shape": list(grid.shape), "projection": grid.projection, "points": points}


def sizes_at(points):
    """Bytes at each of TARGETS on the front of ``points`` (None outside it)."""
    front = pareto(points, MEASURE)
    return [bytes_at(front, target) for target in TARGETS]


def summary(faces, names):
    """{variant: per target {ratio: geometric mean, low, high, smaller: faces, count}, encode: time ratio}."""
    base = {face["face"]: sizes_at(face["points"]["baseline"]) for face in faces}
    seconds = {name: sum(p["encode_s"] for face in faces for p in face["points"][name]) for name in names}
    result = {}
    for name in [*names, "per-file best"]:
        per_target = []
        for k in range(len(TARGETS)):
            ratios = []
            for face in faces:
                own = [sizes_at(face["points"][n])[k] for n in (PER_FILE if name == "per-file best" else [name])]
                own = [s for s in own if s is not None]
                if own and base[face["face"]][k] is not None:
                    ratios.append(min(own) / base[face["face"]][k])
            per_target.append({"ratio": float(np.exp(np.mean(np.log(ratios)))) if ratios else None,
                               "low": min(ratios, default=None), "high": max(ratios, default=None),
                               "smaller": sum(r < 1 for r in ratios), "count": len(ratios)})
        encode = (sum(seconds[n] for n in PER_FILE) if name == "per-file best" else seconds[name])
        result[name] = {"targets": per_target, "encode": encode / seconds["baseline"]}
    return result


# --------------------------------------------------------------------------- report


def paying_row(row):
    """Whether a summary row pays: BAR_RATIO or fewer bytes at every target, within BAR_ENCODE of the encode time."""
    return row["encode"] <= BAR_ENCODE and all(c["ratio"] is not None and c["ratio"] <= BAR_RATIO
                                               for c in row["targets"])


def markdown(document):
    """The report: settings, the gains table, what each variant is."""
    settings, table = document["settings"], document["summary"]
    heads = " | ".join(f"bytes at {t} mm" for t in TARGETS)
    lines = [
        "# dwt2d encoder gains, one by one (issue 33)", "",
        f"Generated {settings['started']} UTC by `benchmarks/encoder_gains.py` at commit {settings['commit']}"
        f"{' (--quick)' if settings['quick'] else ''}, {settings['wall_s']:.0f} s on {document['machine']}.", "",
        f"{len(document['faces'])} faces on mzc's default grid, `--rmse` ladder {', '.join(map(str, LADDER))} mm; "
        f"each variant's bytes at equal whole-surface RMS over the baseline's (geometric mean over the faces; "
        f"in brackets the range, then the faces where it is smaller). Encode: total encode time over the "
        f"baseline's. Every file is decoded by the unchanged decoder. See the script's docstring for the method.",
        "", f"| variant | {heads} | encode |", "|---|" + "---|" * len(TARGETS) + "---|"]
    for name, row in table.items():
        cells = [f"{c['ratio']:.4f} [{c['low']:.3f}-{c['high']:.3f}] {c['smaller']}/{c['count']}"
                 if c["ratio"] is not None else "n/a" for c in row["targets"]]
        lines.append(f"| {name} | {' | '.join(cells)} | {row['encode']:.2f}x |")
    paying = [name for name, row in table.items() if paying_row(row)]
    lines += ["", f"Meets the bar (at least {1 - BAR_RATIO:.0%} fewer bytes at every target, encode at most "
                  f"{BAR_ENCODE}x the baseline's): {', '.join(paying) or 'none'}."]
    lines += ["", "## Variants", ""]
    lines += [f"- **{name}**: {what}" for name, (what, *_rest) in document["variants"].items()]
    lines += ["- **per-file best**: per face and target the smallest of " + ", ".join(PER_FILE)
              + " (encode: all of them)", ""]
    heads = " | ".join(f"rmse {t}: bytes, whole, grid RMS" for t in TARGETS)
    lines += ["## Baseline files", "", f"| face | grid | {heads} |", "|---|---|" + "---|" * len(TARGETS)]
    for face in document["faces"]:
        by_target = {p["target"]: p for p in face["points"]["baseline"]}
        cells = [f"{by_target[t]['bytes']:,}, {by_target[t]['whole']['rms']:.4f}, {by_target[t]['grid_rms']:.4f}"
                 for t in TARGETS]
        lines.append(f"| {face['face']} | {face['shape'][0]}x{face['shape'][1]} {face['projection']} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- main


def variants_run(combined):
    """VARIANTS, and the kept techniques together under COMBINED."""
    return {**VARIANTS, COMBINED: ("the kept techniques together", combined, {}, None)}


def main(argv=None):
    arguments = benchmark_parser(__doc__, f"the first {QUICK_FACES} faces").parse_args(argv)
    from mzc.codecs import dwt2d

    paths = faces_measured("encoder_gains", arguments.quick, quick_count=QUICK_FACES)
    progress = terminal_progress()
    started = time.perf_counter()
    settings = {"quick": arguments.quick, "commit": git_commit(), "samples": SAMPLES, "ladder": LADDER,
                "targets": TARGETS, "started": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"}
    variants = variants_run({"DEADZONE": dwt2d.DEADZONE, "RDO_LAMBDA": dwt2d.RDO_LAMBDA})
    faces = [measure_face(path, variants, progress) for path in paths]
    settings["wall_s"] = time.perf_counter() - started
    document = {"settings": settings, "machine": machine(), "versions": versions(PACKAGES),
                "variants": {name: [what, constants, options, ratio] for name, (what, constants, options, ratio)
                             in variants.items()},
                "summary": summary(faces, list(variants)), "faces": faces}
    arguments.out.mkdir(parents=True, exist_ok=True)
    (arguments.out / "encoder-gains-results.json").write_text(json.dumps(document, indent=1) + "\n")
    (arguments.out / "encoder-gains-results.md").write_text(markdown(document))


if __name__ == "__main__":
    main()
