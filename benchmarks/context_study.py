"""What richer contexts and adaptive models could save on dwt2d's detail magnitudes (issue 33).

    python benchmarks/context_study.py [--quick] [--out DIR]

Issue 33 asks for coding gains measured one by one, context modelling across subbands and
neighbours among them, before any is put in a format. This study measures their room on the
files of mzc-dwt2d 10.0 (``mzc.encode(grid, rmse=...)`` of the 13 faces' default grids at 0.05, 0.1 and
0.2 mm and of the two DEMs at the rd benchmark's targets, jacksboro 0.5, 1 and 2 m, topobathy 5, 10 and
20 m; the encoder held to 10.0's shared models, which 10.1 came from this study to vary): each file is decoded and its
detail bands' integers (``decode_bands``'s, exactly what the file holds) are re-costed under other
models. The figure is the ideal code length of the detail magnitude classes (what rANS spends to
within a few bytes), in bytes, and its change as a share of the whole file:

- **static** models, as 10.0 codes them: one table per context chosen by ``choose_short_records``
  (10.0's cheapest of a one-byte parametric table, 7.0's parametric table, weight codes or a
  repeat), the symbols' bits under it plus the table records' bytes. The first row, the 11
  contexts of 10.0, is what the file spends now.
- **adaptive** models: the table learnt while decoding, counts starting at ``alpha`` per class and
  growing by one per symbol (a Dirichlet estimator: an adaptive rANS coder adding 1/alpha per symbol
  to counts that start at 1). Its code length depends on the final counts alone, so no symbol loop;
  nothing is stored. alpha is one constant for every file (the best of a few, given in the report).

Context sets (every one computable by a decoder before a pass, as 10.0's are):

- **10.0's 11**: the activity (|parent| in this band's steps, |q| of the level's earlier bands at the
  same place), the rows above and the coded neighbours beside, summed, in 11 bins;
- **x orientation**: the same per band orientation (H, V, D): 33;
- **x level**: the same per level (finest, next, the coarser ones): 33;
- **x orientation x level**: 99;
- **x band (10.1)**: the same per detail band (orientation and every level): 11 x 3L, what 10.1's
  ``band_models`` codes;
- **2-D**: the neighbours' part (rows above, beside) and the activity part binned apart (6 x 5 = 30),
  so a coefficient with quiet neighbours and a busy parent is told from one with busy neighbours.

Besides, **first mantissa bit**: the raw bit below each magnitude's leading one (a raw bit today)
coded adaptively per (context, class) instead: its saving. Writes context-study-results.md and .json.
"""

import sys
import time
import warnings

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import FACES, mesh_files
from report import benchmark_parser, fmt, stamped, write_report
from scipy.special import gammaln

FACE_TARGETS = (0.05, 0.1, 0.2)   # mm, rmse
DEM_TARGETS = {"jacksboro": (0.5, 1.0, 2.0), "topobathy": (5.0, 10.0, 20.0)}   # m, rmse: rd.py's
DEMS = tuple(DEM_TARGETS)
ALPHAS = (1 / 32, 1 / 8, 1 / 2)
NEIGHBOUR_BINS = (0.5, 1.5, 3.0, 6.0, 12.0)   # 2-D contexts: the rows above and beside...
ACTIVITY_BINS = (0.5, 2.0, 6.0, 20.0)         # ...and the parent and siblings, apart
PACKAGES = ("numpy", "scipy", "PyWavelets", "constriction")
STATIC, ADAPTIVE = "static", "adaptive"
TODAY = "static|10.0's 11"   # the key of what a 10.0 file spends now


def file_bands(data):
    """(qflat, relevant, steps) of a dwt2d file: the integer bands ``decode_bands`` returns for it."""
    import mzc
    from mzc.codecs import dwt2d

    seen = []
    original = dwt2d.decode_bands

    def capture(decoders, relevant, steps, band_models=False):
        qflat = original(decoders, relevant, steps, band_models)
        seen.append((qflat, relevant, steps))
        return qflat

    dwt2d.decode_bands = capture
    try:
        mzc.decode(data)
    finally:
        dwt2d.decode_bands = original
    return seen[0]


def detail_symbols(qflat, relevant, steps):
    """Per coded detail magnitude: its class, 10.0's context, its orientation, its level rank (0 the
    finest), the neighbours' and the activity's parts of its context, its first mantissa bit (-1 where
    it has none) and its band (1..3L)."""
    from mzc.codecs.dwt2d import THRESHOLDS, activity, beside, neighbours, parent_map, shifted_down
    from mzc.codecs.dwt2d.entropy import classes

    levels = (len(qflat) - 1) // 3
    parts = []
    for index in range(1, len(qflat)):
        band = qflat[index]
        active = activity(qflat, index, steps, parent_map(qflat, index, band.shape))
        near = neighbours(shifted_down(band, 1), shifted_down(band, 2)) + beside(np.abs(band))
        where = relevant[index]
        magnitude = np.abs(band[where])
        cls = classes(magnitude)
        first = np.where(cls >= 2, (magnitude >> np.maximum(cls - 2, 0)) & 1, -1)
        level = (index + 2) // 3
        parts.append(np.stack([cls, np.digitize(active[where] + near[where], THRESHOLDS),
                               np.full(cls.shape, (index - 1) % 3), np.full(cls.shape, min(levels - level, 2)),
                               np.digitize(near[where], NEIGHBOUR_BINS), np.digitize(active[where], ACTIVITY_BINS),
                               first, np.full(cls.shape, index)]))
    return np.concatenate(parts, axis=1)


def context_sets(symbols):
    """{name: context id of every symbol} for the study's context sets."""
    from mzc.codecs.dwt2d import CONTEXTS

    _cls, k, orientation, rank, near, active, _first, band = symbols
    return {"10.0's 11": k,
            "x band (10.1)": k + CONTEXTS * (band - 1),
            "x orientation": k * 3 + orientation,
            "x level": k * 3 + rank,
            "x orientation x level": (k * 3 + orientation) * 3 + rank,
            "2-D (6 x 5)": near * (len(ACTIVITY_BINS) + 1) + active}


def counts_of(context, values, classes=None):
    """(contexts x classes) counts of ``values`` by ``context``."""
    size = int(values.max(initial=0)) + 1 if classes is None else classes
    flat = np.bincount(context * size + values, minlength=(int(context.max(initial=0)) + 1) * size)
    return flat.reshape(-1, size)


def static_bytes(counts):
    """Bytes of ``counts`` coded with 10.0's short table records, one table per context (records
    counted), as the encoder chooses them."""
    from mzc.codecs.dwt2d.entropy import choose_short_records, ideal_bits

    used = counts[counts.sum(axis=1) > 0]
    size = max(2, used.shape[1])   # the detail models share one class count
    tables, records = choose_short_records(used, np.full(len(used), size))
    return (sum(ideal_bits(t, c) for t, c in zip(tables, used)) + 8 * len(records)) / 8


def adaptive_bytes(counts, alpha):
    """Bytes of ``counts`` coded with adaptive tables learnt from counts starting at ``alpha`` per class
    (the Dirichlet estimator's code length, which depends on the final counts alone)."""
    size = counts.shape[1]
    n = counts.sum(axis=1)
    nats = (gammaln(n + size * alpha) - gammaln(size * alpha)
            - (gammaln(counts + alpha) - gammaln(alpha)).sum(axis=1))
    return float(nats.sum() / np.log(2) / 8)


def costs(symbols):
    """{(kind, context set or 'first bit'): bytes} of one file's detail magnitudes."""
    cls, k, first = symbols[0], symbols[1], symbols[6]
    out = {}
    for name, context in context_sets(symbols).items():
        counts = counts_of(context, cls, int(cls.max(initial=0)) + 1)
        out[(STATIC, name)] = static_bytes(counts)
        for alpha in ALPHAS:
            out[(f"{ADAPTIVE} {alpha:g}", name)] = adaptive_bytes(counts, alpha)
    has = first >= 0
    out[("raw", "first bit")] = has.sum() / 8
    bit_context = k[has] * 64 + cls[has]
    for alpha in ALPHAS:
        out[(f"{ADAPTIVE} {alpha:g}", "first bit")] = adaptive_bytes(counts_of(bit_context, first[has], 2), alpha)
    return out


def items():
    """(name, grid, targets) of the faces and the DEMs."""
    import mzc

    for path in mesh_files(FACES):
        yield path.stem, mzc.slice(mzc.read(path)), FACE_TARGETS
    for name in DEMS:
        yield name, mzc.slice(mzc.sample(name)), DEM_TARGETS[name]


def run(quick):
    """One row per item and target: the size of its 10.0 file and each model's bytes."""
    import mzc
    from mzc.codecs.dwt2d import Prepared

    Prepared.prefers_band_models = lambda self, counts: False   # 10.0's shared models, the study's baseline
    rows = []
    for number, (name, grid, targets) in enumerate(items()):
        if quick and number >= 2 and name not in DEMS:
            continue
        for target in targets:
            data = mzc.encode(grid, rmse=target)
            cost = costs(detail_symbols(*file_bands(data)))
            rows.append({"item": name, "target": target, "bytes": len(data),
                         "costs": {f"{kind}|{name}": value for (kind, name), value in cost.items()}})
            print(f"context_study: {name} at {target}: {len(data)} B", file=sys.stderr)
    return rows


def saving(rows, key, target_index, dem):
    """Geometric mean over the items of (file - detail bytes now + ``key``'s bytes) / file at the
    ``target_index``-th target: the whole file's size with that model, over today's."""
    ratios = []
    for row in rows:
        targets = DEM_TARGETS.get(row["item"], FACE_TARGETS)
        if (row["item"] in DEMS) != dem or row["target"] != targets[target_index]:
            continue
        if key.endswith("first bit"):
            change = row["costs"][key] - row["costs"]["raw|first bit"]
        else:
            change = row["costs"][key] - row["costs"][TODAY]
        ratios.append((row["bytes"] + change) / row["bytes"])
    return float(np.exp(np.mean(np.log(ratios)))) if ratios else None


def markdown(document):
    """The report: whole-file size with each model over today's, faces and DEMs."""
    rows = document["rows"]
    keys = list(rows[0]["costs"]) if rows else []
    keys = [key for key in keys if not key.startswith("raw")]
    lines = ["# dwt2d context and adaptive-model study (issue 33)", "",
             f"Generated {document['date']} by `benchmarks/context_study.py` at commit {document['commit']}, "
             f"{document['seconds']:.0f} s on {document['machine']}.", "",
             __doc__.split("\n\n", 2)[2].split("Writes context-study")[0].strip(), "",
             "## Whole file with the model, over today's file (geometric mean)", "",
             "Below 1: smaller. Faces at rmse " + ", ".join(f"{t:g}" for t in FACE_TARGETS) + " mm; DEMs at their "
             "first, second and third target (" + "; ".join(f"{n} " + ", ".join(f"{t:g}" for t in ts) + " m"
                                                          for n, ts in DEM_TARGETS.items()) + ").", "",
             "| model | context set | " + " | ".join(f"faces {t:g} mm" for t in FACE_TARGETS)
             + " | DEMs 1st | DEMs 2nd | DEMs 3rd |",
             "|---" * (2 + len(FACE_TARGETS) + 3) + "|"]
    for key in keys:
        kind, name = key.split("|")
        values = [saving(rows, key, i, False) for i in range(len(FACE_TARGETS))]
        values += [saving(rows, key, i, True) for i in range(3)]
        lines.append(f"| {kind} | {name} | " + " | ".join("n/a" if v is None else fmt(v, 4) for v in values) + " |")
    lines += ["", "## Files", "", "| item | target | bytes | detail classes now, B | first bits raw, B |",
              "|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['item']} | {row['target']:g} | {row['bytes']:,} | "
                     f"{row['costs'][TODAY]:.0f} | "
                     f"{row['costs']['raw|first bit']:.0f} |")
    return "\n".join(lines) + "\n"


def main():
    args = benchmark_parser(__doc__, "two faces and the DEMs").parse_args()
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # example.obj's texture coordinates, named by every read
        rows = run(args.quick)
    document = stamped(PACKAGES, started, quick=args.quick, rows=rows)
    write_report(args.out, "context-study", document, markdown)


if __name__ == "__main__":
    main()
