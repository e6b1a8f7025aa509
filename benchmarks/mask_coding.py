"""Bytes of a dwt2d file's validity mask under 7.0's span coding and candidate schemes (issue 33).

    python benchmarks/mask_coding.py [--quick] [--out DIR]

The masks: the default grids (``mzc.slice``) of the 13 faces, of whole objects of
/work/shared/data/objects (their multi-chart grids), and of DEMs (matplotlib's sample DEMs as
mzc.samples reads them, which have no invalid node, and hugo_site.asc of tests/data/public, half
no-data). Each mask is coded by every scheme in the same entropy coder, the payload's rANS with
24-bit probabilities (spec/dwt2d.md), and measured as its ideal cost (-log2 of each symbol's
probability, plus raw bits and table records where the scheme has them), in bytes:

- **7.0 spans**: 7.0's coding (mzc.codecs.dwt2d.encode_mask): span counts as change from the row
  above, each flip's move from the row above where the count did not change, gaps otherwise;
  classes through static tables (each model's cheapest 7.0 record, entropy.choose_records, counted),
  the bits below a class's leading one raw.
- **2nd-order spans**: the same, but a flip's move minus the same flip's move in the row above.
- **2nd-order + contexts**: and the move's model chosen by the flip's side (entering, leaving)
  and the row above's residual (0, 1, 2+): 6 static tables.
- **JBIG 10 px**, **template 14 px**: every mask bit through an adaptive binary model chosen by
  the 10 (JBIG's three-line template) or 14 bits before it (two rows above, two to the left), P(1) =
  (2 n1 + 1) / (2 n + 2) from the counts so far, as 24-bit integers.
- **predicted flips**: mzc.codecs.dwt2d.flips (the chosen scheme): each row's span count change,
  then its flips as second-order moves by context (side, the residual above, the predicted move's
  size) or, where the count changed, from the nearest flip above on the same side, every integer
  binarised through adaptive binary models (no tables, no raw bits). Its real bytes (a payload of
  it alone) and the C decoder's time are measured too.

The whole-file effect on f18 (at RMS 0.05, 0.1, 0.2 mm): the reference encoder's 7.0 and 8.0 files
(8.0: 7.0 with the predicted flips and the face's source_vertices, 5 bytes, which 7.0 has no field for), each
with its mask's share (mzc.codecs.dwt2d.anatomy.parts).
Writes mask-coding-results.md and mask-coding-results.json into --out (default: this directory).
"""

import datetime
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from corpora import FACES, OBJECTS, mesh_files  # noqa: E402
from report import benchmark_parser, git_commit, machine, versions  # noqa: E402

PUBLIC = HERE.parent / "tests" / "data" / "public"
OBJECT_NAMES = ("hand.ply", "armadillo.ply", "featuretype.ply", "dragon.ply", "ogre.obj", "cycloidal.ply")
QUICK = ("f18", "m56", "hand")
TARGETS = (0.05, 0.1, 0.2)
PACKAGES = ("numpy", "constriction")
JBIG10 = ((-2, -1), (-2, 0), (-2, 1), (-1, -2), (-1, -1), (-1, 0), (-1, 1), (-1, 2), (0, -2), (0, -1))
TEMPLATE14 = ((-2, -2), (-2, -1), (-2, 0), (-2, 1), (-2, 2), (-1, -3), (-1, -2), (-1, -1), (-1, 0), (-1, 1),
              (-1, 2), (-1, 3), (0, -2), (0, -1))


# --------------------------------------------------------------------------- schemes


def static_bytes(models, values):
    """Bytes of integers through static tables: each model's cheapest 7.0 record (counted), the
    classes' ideal bits under it, and the raw bits (sign and the bits below the leading one)."""
    from mzc.codecs.dwt2d import entropy as en

    models, values = np.asarray(models, dtype=np.int64), np.asarray(values, dtype=np.int64)
    if not len(values):
        return 0.0
    cls = en.classes(values)
    count = int(models.max()) + 1
    counts = np.bincount(models * en.MAX_CLASSES + cls, minlength=count * en.MAX_CLASSES).reshape(count, -1)
    tables, records = en.choose_records(counts, en.Encoder().table_sizes(counts))
    ideal = sum(en.ideal_bits(table, row[:len(table)]) for table, row in zip(tables, counts))
    return (ideal + 8 * len(records) + int(cls.sum())) / 8   # signed: a class k has k raw bits


def spans_7(valid):
    """7.0's span coding (encode_mask's own integers and models)."""
    from mzc.codecs.dwt2d import encode_mask
    from mzc.codecs.dwt2d import entropy as en

    encoder = en.Encoder()
    encode_mask(encoder, valid)
    return static_bytes(np.concatenate(encoder.models), np.concatenate(encoder.values))


def second_order(valid, contexts):
    """7.0's spans with each unchanged-count row's moves less the row above's moves (0 where the row
    above was not such a row); with ``contexts`` by side and the residual above (min 2)."""
    from mzc.codecs.dwt2d.flips import row_flips

    rows = row_flips(valid)
    counts = np.array([len(f) // 2 for f in rows])
    models, values = [np.zeros(len(rows), dtype=np.int64)], [np.diff(counts, prepend=0)]
    above = moves = residuals = np.zeros(0, dtype=np.int64)
    for flips in rows:
        if len(flips) == len(above):
            residual = flips - above - moves
            side = np.arange(len(flips)) % 2
            values.append(residual)
            models.append(1 + (side + 2 * np.minimum(np.abs(residuals), 2) if contexts else 0 * side))
            moves, residuals = flips - above, residual
        else:
            values.append(np.diff(flips, prepend=-1) - 1)
            models.append(np.full(len(flips), 7))
            moves = residuals = np.zeros(len(flips), dtype=np.int64)
        above = flips
    return static_bytes(np.concatenate(models), np.concatenate(values))


def template_bytes(valid, template):
    """Every mask bit through an adaptive binary model chosen by the ``template`` bits before it
    (row, column offsets; outside the grid counts as invalid), in raster order."""
    from mzc.codecs.dwt2d.flips import PRECISION, probabilities

    rows, cols = valid.shape
    padded = np.zeros((rows + 2, cols + 8), dtype=np.int64)
    padded[2:, 4:-4] = valid
    context = np.zeros(valid.shape, dtype=np.int64)
    for dr, dc in template:
        context = 2 * context + padded[2 + dr:2 + dr + rows, 4 + dc:4 + dc + cols]
    bits = valid.ravel().astype(np.int64)
    f1 = probabilities(bits, context.ravel()) / (1 << PRECISION)
    return float(-np.log2(np.where(bits == 1, f1, 1 - f1)).sum()) / 8


def predicted_flips(valid):
    """The chosen scheme's ideal bytes."""
    from mzc.codecs.dwt2d import flips

    return flips.ideal_bits(valid) / 8


SCHEMES = {
    "7.0 spans": spans_7,
    "2nd-order spans": lambda valid: second_order(valid, False),
    "2nd-order + contexts": lambda valid: second_order(valid, True),
    "JBIG 10 px": lambda valid: template_bytes(valid, JBIG10),
    "template 14 px": lambda valid: template_bytes(valid, TEMPLATE14),
    "predicted flips": predicted_flips,
}


# --------------------------------------------------------------------------- measures


def real_and_time(valid, repeats=5):
    """(bytes of the chosen scheme's payload alone (2 bytes of varints and its rANS words), best decode
    time in ms of the chosen scheme, of 7.0's decode_mask), each decoder reading a payload of the mask alone."""
    from mzc.codecs.dwt2d import decode_mask, encode_mask, flips
    from mzc.codecs.dwt2d import entropy as en

    payload = flips.alone(valid)
    encoder = en.Encoder(parametric=True)
    encode_mask(encoder, valid)
    old = encoder.finish()

    def best(decode):
        times = []
        for _ in range(repeats):
            started = time.perf_counter()
            decode()
            times.append(time.perf_counter() - started)
        return 1000 * min(times)

    new_ms = best(lambda: flips.decode(en.Decoder(payload, "<mask>"), *valid.shape))
    old_ms = best(lambda: decode_mask(en.Decoder(old, "<mask>", parametric=True), *valid.shape))
    assert (flips.decode(en.Decoder(payload, "<mask>"), *valid.shape) == valid).all()
    return len(payload), new_ms, old_ms


def masks(quick):
    """(corpus, name, valid) of every mask measured."""
    import mzc
    from mzc import samples

    for path in mesh_files(FACES):
        if not quick or path.stem in QUICK:
            yield "faces", path.stem, mzc.slice(str(path)).valid
    for name in OBJECT_NAMES:
        path = OBJECTS / name
        if path.exists() and (not quick or path.stem in QUICK):
            yield "objects", path.stem, mzc.slice(str(path)).valid
    for name in ("jacksboro", "topobathy"):
        yield "dems", name, getattr(samples, name)().valid
    if (PUBLIC / "hugo_site.asc").exists():
        yield "dems", "hugo_site", mzc.read(PUBLIC / "hugo_site.asc").valid


def measure(corpus, name, valid):
    """One mask's row of the report."""
    row = {"corpus": corpus, "name": name, "shape": list(valid.shape), "valid": float(valid.mean()),
           "bytes": {scheme: round(cost(valid), 1) for scheme, cost in SCHEMES.items()}}
    row["real"], row["decode_ms"], row["decode_7_ms"] = real_and_time(valid)
    return row


def whole_file(path):
    """f18 coded by the reference encoder at each target as 7.x and as 8.0 (the same search, each
    file its own steps), with each file's mask share (mzc.codecs.dwt2d.anatomy.parts)."""
    import mzc
    from mzc.codecs import dwt2d
    from mzc.codecs.dwt2d.anatomy import parts

    grid = mzc.slice(str(path))
    out = []
    for target in TARGETS:
        old = dwt2d.encode_whole(grid, rmse=target, compact=dwt2d.COMPACT_VERSION)[0]
        new = mzc.encode(grid, "dwt2d", rmse=target)
        out.append({"rmse": target, "bytes_7": len(old), "mask_7": parts(old)["mask"], "bytes_8": len(new),
                    "mask_8": parts(new)["mask"]})
    return out


# --------------------------------------------------------------------------- report


def summary(rows):
    """Per corpus and scheme: median, min, max bytes and the median ratio to 7.0 spans."""
    out = {}
    for corpus in dict.fromkeys(r["corpus"] for r in rows):
        group = [r for r in rows if r["corpus"] == corpus and r["bytes"]["7.0 spans"] > 0]
        if not group:
            continue
        out[corpus] = {}
        for scheme in SCHEMES:
            values = np.array([r["bytes"][scheme] for r in group])
            ratio = np.array([r["bytes"][scheme] / r["bytes"]["7.0 spans"] for r in group])
            out[corpus][scheme] = {"median": float(np.median(values)), "min": float(values.min()),
                                   "max": float(values.max()), "ratio": float(np.median(ratio))}
    return out


def markdown(document):
    """The report."""
    settings = document["settings"]
    lines = ["# Mask coding: 7.0's spans against candidates (issue 33)", "",
             f"Generated {settings['started']} UTC by `benchmarks/mask_coding.py` at commit {settings['commit']}"
             f"{' (--quick)' if settings['quick'] else ''}, {settings['wall_s']:.0f} s on {document['machine']}.", "",
             "Bytes of each mask (ideal cost in the payload's rANS, tables and raw bits included; see the "
             "script's docstring). *real*: the predicted flips alone in a payload (2 bytes of varints, then "
             "whole 32-bit words); "
             "*decode*: best of 5, the C decoder of the predicted flips and 7.0's decode_mask, each from a "
             "payload holding the mask alone.", "",
             "## Summary (median [min-max] bytes; ratio: median of each mask's bytes over 7.0's)", "",
             "| scheme | " + " | ".join(document["summary"]) + " |", "|---|" + "---|" * len(document["summary"])]
    for scheme in SCHEMES:
        cells = [f"{s[scheme]['median']:.0f} [{s[scheme]['min']:.0f}-{s[scheme]['max']:.0f}] "
                 f"{s[scheme]['ratio']:.2f}" for s in document["summary"].values()]
        lines.append(f"| {scheme} | " + " | ".join(cells) + " |")
    lines += ["", "## Every mask", "",
              "| mask | shape | valid | " + " | ".join(SCHEMES) + " | real | decode ms | 7.0 decode ms |",
              "|---" * (len(SCHEMES) + 6) + "|"]
    for r in document["masks"]:
        lines.append(f"| {r['corpus']}/{r['name']} | {r['shape'][0]}x{r['shape'][1]} | {r['valid']:.3f} | "
                     + " | ".join(f"{r['bytes'][s]:.0f}" for s in SCHEMES)
                     + f" | {r['real']} | {r['decode_ms']:.3f} | {r['decode_7_ms']:.3f} |")
    if document["f18"]:
        lines += ["", "## Whole file: f18", "",
                  "| rmse mm | 7.x file | its mask | 8.0 file | its mask | change |", "|---|---|---|---|---|---|"]
        for w in document["f18"]:
            lines.append(f"| {w['rmse']} | {w['bytes_7']} | {w['mask_7']} | {w['bytes_8']} | {w['mask_8']} "
                         f"| {w['bytes_8'] / w['bytes_7'] - 1:+.1%} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    arguments = benchmark_parser(__doc__, "f18, m56, hand and the DEMs").parse_args(argv)
    started = time.perf_counter()
    settings = {"quick": arguments.quick, "commit": git_commit(),
                "started": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"}
    rows = []
    for corpus, name, valid in masks(arguments.quick):
        rows.append(measure(corpus, name, valid))
        print(f"{corpus}/{name}: " + ", ".join(f"{k} {v:.0f}" for k, v in rows[-1]["bytes"].items()), flush=True)
    f18 = FACES / "f18.ply"
    document = {"settings": settings, "machine": machine(), "versions": versions(PACKAGES),
                "summary": summary(rows), "masks": rows, "f18": whole_file(f18) if f18.exists() else []}
    settings["wall_s"] = time.perf_counter() - started
    arguments.out.mkdir(parents=True, exist_ok=True)
    (arguments.out / "mask-coding-results.json").write_text(json.dumps(document, indent=1) + "\n")
    (arguments.out / "mask-coding-results.md").write_text(markdown(document))


if __name__ == "__main__":
    main()
