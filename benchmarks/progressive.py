"""What progressive files (mzc-dwt2d 9.0, issue 33) cost and what their prefixes give, on the faces.

    python benchmarks/progressive.py [--quick] [--out DIR]

Every face is sliced (the default grid) and coded at ``--rmse`` 0.05, 0.1 and 0.2 mm twice: as the
default file (mzc-dwt2d 10.x: one section) and with ``--progressive`` as 9.0, whose levels come in
sections coarsest first, so that a prefix of whole sections decodes to band 0 and the coarsest
levels. For each file: its bytes (9.0's overhead over the default's), how many of its level sections
keep the tables of the section before whole, and the median encode and decode times of each version
in the same run (one thread). For f18 and the median face (by the default's bytes at 0.05 mm), at
0.05 mm, every prefix of whole sections (K = 0: the header and base section, band 0 alone, up to K =
L: the whole file): its bytes and the whole-surface RMS of its rebuild against the whole file's
(benchmarks/objects.py's ``errors``: area-weighted samples each way, point to surface; both rebuilt
by ``triangulate --vertices all``), in mm. Writes progressive-results.md and .json.
"""

import sys
import time
import warnings

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from corpora import faces_measured
from objects import QUICK_SAMPLES, Surface, errors
from report import benchmark_parser, stamped, write_report

TARGETS = (0.05, 0.1, 0.2)   # mm, --rmse
PREFIX_TARGET = 0.05
PACKAGES = ("numpy", "constriction")
SAMPLES = 30000   # per direction, as prior_study.py
TIMING_REPEATS = 3


def median_seconds(repeats, work, *args, **options):
    """(the median wall seconds of ``work(*args, **options)`` over ``repeats`` runs, its result)."""
    times, result = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        result = work(*args, **options)
        times.append(time.perf_counter() - started)
    return float(np.median(times)), result


def kept_sections(data):
    """How many level sections of a 9.0 file keep the tables of the section before whole (table count 0)."""
    from mzc.codecs.dwt2d import compact

    return sum(body[0] == 0 for body in compact.read_progressive(data, "bench").bodies[1:])


def face_files(grid):
    """Per target: the default and 9.0 files' bytes, encode and decode seconds, and 9.0's kept sections."""
    import mzc

    rows = []
    for target in TARGETS:
        row = {"target": target}
        for version, options in (("default", {}), ("9.0", {"progressive": True})):
            encode_s, data = median_seconds(1, mzc.encode, grid, "dwt2d", rmse=target, **options)
            decode_s, _grid = median_seconds(TIMING_REPEATS, mzc.decode, data)
            assert options or not data.startswith(b"mzc-dwt2d 9.0\n")
            row[version] = {"bytes": len(data), "encode_s": encode_s, "decode_s": decode_s}
            if version == "9.0":
                row["kept_sections"] = kept_sections(data)
                row["level_sections"] = len(prefix_ends(data)) - 1
        rows.append(row)
    return rows


def prefix_ends(data):
    """The lengths of a 9.0 file's prefixes of whole sections: up to its base section, then each level's."""
    from mzc.codecs.dwt2d import compact

    return compact.read_progressive(data, "bench").ends


def prefixes(grid):
    """Each prefix of whole sections of ``grid``'s 9.0 file at PREFIX_TARGET: its bytes and the
    whole-surface RMS (mm) of its rebuild against the whole file's."""
    import mzc

    data = mzc.encode(grid, "dwt2d", rmse=PREFIX_TARGET, progressive=True)
    whole = Surface.of(mzc.triangulate(mzc.decode(data), vertices="all"))
    out = []
    for k, end in enumerate(prefix_ends(data)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # "the file is cut short": what a prefix is
            coarse = mzc.decode(data[:end])
        rebuilt = Surface.of(mzc.triangulate(coarse, vertices="all"))
        rms = errors(whole, rebuilt, SAMPLES)["whole"]["rms"] * whole.diagonal / 100   # % of D -> mm
        out.append({"levels": k, "bytes": end, "rms_mm": 0.0 if end == len(data) else float(rms)})
    return out


def run(faces):
    """Every face's files at the targets, then the prefixes of f18 and the median face."""
    import mzc

    grids = {face.stem: mzc.slice(str(face)) for face in faces}
    files = {}
    for name, grid in grids.items():
        files[name] = face_files(grid)
        print(f"{name}: " + "; ".join(f"{r['target']} mm {r['default']['bytes']} -> {r['9.0']['bytes']} B"
                                      for r in files[name]), file=sys.stderr)
    by_size = sorted(grids, key=lambda n: files[n][0]["default"]["bytes"])
    median = by_size[len(by_size) // 2]
    shown = list(dict.fromkeys(n for n in ("f18", median) if n in grids))
    return files, median, {name: prefixes(grids[name]) for name in shown}


def medians(files, target_index, key):
    """The median over the faces of ``key``(row) at one target."""
    return float(np.median([key(rows[target_index]) for rows in files.values()]))


def markdown(document):
    """The report: overhead per target, times, each face's bytes, the prefixes."""
    files = document["files"]
    lines = ["# Progressive files (mzc-dwt2d 9.0) on the faces (issue 33)", "",
             f"`python benchmarks/progressive.py{' --quick' if document['quick'] else ''}` at commit "
             f"{document['commit']}, {document['date']}, on {document['machine']}; {document['seconds']:.0f} s. "
             "Package versions: " + ", ".join(f"{k} {v}" for k, v in document["versions"].items()) + ".", "",
             (__doc__ or "").split("\n\n", 2)[2].split("Writes")[0].strip(), "",
             "## 9.0's bytes over the default's, and the times (medians over the faces)", "",
             "| --rmse | default bytes | 9.0 bytes | overhead (min-max) | level sections keeping the tables whole "
             "| encode default / 9.0 s | decode default / 9.0 ms |", "|---|---|---|---|---|---|---|"]
    for i, target in enumerate(TARGETS):
        over = [rows[i]["9.0"]["bytes"] - rows[i]["default"]["bytes"] for rows in files.values()]
        kept = sum(rows[i]["kept_sections"] for rows in files.values())
        sections = sum(rows[i]["level_sections"] for rows in files.values())
        lines.append(
            f"| {target} | {medians(files, i, lambda r: r['default']['bytes']):.0f} "
            f"| {medians(files, i, lambda r: r['9.0']['bytes']):.0f} | +{np.median(over):.0f} B "
            f"({min(over)}-{max(over)}) | {kept} of {sections} "
            f"| {medians(files, i, lambda r: r['default']['encode_s']):.2f} / "
            f"{medians(files, i, lambda r: r['9.0']['encode_s']):.2f} "
            f"| {1000 * medians(files, i, lambda r: r['default']['decode_s']):.0f} / "
            f"{1000 * medians(files, i, lambda r: r['9.0']['decode_s']):.0f} |")
    lines += ["", "## Bytes by face (default -> 9.0)", "",
              "| face | " + " | ".join(f"{t} mm" for t in TARGETS) + " |", "|---" * (len(TARGETS) + 1) + "|"]
    for name, rows in files.items():
        pairs = (f"{r['default']['bytes']} -> {r['9.0']['bytes']}" for r in rows)
        lines.append(f"| {name} | " + " | ".join(pairs) + " |")
    for name, steps in document["prefixes"].items():
        label = " (the median face)" if name == document["median"] else ""
        lines += ["", f"## {name}{label} at --rmse {PREFIX_TARGET}: each prefix of whole sections", "",
                  "| detail levels K | bytes | whole-surface RMS against the whole file's rebuild, mm |",
                  "|---|---|---|"]
        lines += [f"| {s['levels']} | {s['bytes']} | {s['rms_mm']:.3f} |" for s in steps]
    return "\n".join(lines) + "\n"


def main():
    args = benchmark_parser(__doc__, "four faces, fewer samples").parse_args()
    global SAMPLES
    faces = faces_measured("progressive", args.quick)
    SAMPLES = QUICK_SAMPLES if args.quick else SAMPLES
    started = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)   # example.obj's texture coordinates, named by every read
        files, median, shown = run(faces)
    document = stamped(PACKAGES, started, quick=args.quick, samples=SAMPLES, files=files, median=median,
                       prefixes=shown)
    write_report(args.out, "progressive", document, markdown)


if __name__ == "__main__":
    main()
