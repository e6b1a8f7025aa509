"""web/'s JavaScript decoder beside Draco's WebAssembly decoder on the same face (issue 34).

    python benchmarks/web_decode.py [--runs N] [--warmups N] [--modules DIR] [--web DIR] [--out DIR]

The issue's goal: web/'s ``decode`` of f18's file (``mzc slice f18.ply | mzc encode --dwt2d
--rmse 0.05``) within 2x the time of Draco's WebAssembly decoder (draco3d from npm) on Draco's
file of the same face (DracoPy: the original mesh, 11 quantisation bits, compression level 10,
as benchmarks/contenders.py codes it), decoded as three.js's DRACOLoader does (float32
positions and uint32 triangles). Both decode in one node process (web_decode.mjs), alternated,
the order swapped every round: warm-ups, then medians of N runs of wall time (performance.now)
and CPU time (the process's user + system time, which a loaded machine stretches least). Also
the decoder's size: web/mzc.mjs bundled and minified by esbuild, gzip -9, beside Draco's
decoder (its wasm and its node glue, gzip -9), and the load average before and after.

Needs node and draco3d (``npm install --prefix DIR esbuild draco3d``, then ``--modules
DIR/node_modules``; default: $MZC_NODE_MODULES, else npm's global folder); esbuild is optional
(no sizes without it). Skips with a message on stderr, writing nothing, when node, draco3d,
DracoPy or f18 is missing. Writes web-decode-results.md and web-decode-results.json into --out
(default: this directory).
"""

import argparse
import datetime
import gzip
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import contenders  # noqa: E402 - after the path to this folder
from corpora import FACES  # noqa: E402
from report import git_commit, machine  # noqa: E402

FACE = FACES / "f18.ply"
WEB = HERE.parent / "web"
RMSE = 0.05
DRACO_BITS = 11
GOAL = 2.0   # issue 34: web/'s decode within 2x Draco's


def main(argv=None):
    """Measure, then write the report; a missing tool or input is a message and exit status 0."""
    args = parser().parse_args(argv)
    missing = missing_requirement(args)
    if missing:
        print(f"web_decode: skipped: {missing}", file=sys.stderr)
        return 0
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as scratch:
        mzc_file, draco_file = coded_files(Path(scratch))
        timing = node_timing(args, mzc_file, draco_file)
        files = {"mzc": mzc_file.stat().st_size, "draco": draco_file.stat().st_size}
    result = {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "commit": git_commit(), "machine": machine(), "load_before": load_before, "load_after": os.getloadavg(),
        "web": str(args.web), "runs": args.runs, "warmups": args.warmups, "files": files,
        **summary(timing), "sizes": sizes(Path(args.modules), Path(args.web)),
    }
    write_outputs(Path(args.out), result)
    print(f"web {result['mzc']['wall_median_ms']:.2f} ms, Draco {result['draco']['wall_median_ms']:.2f} ms: "
          f"{result['ratio_wall']:.2f}x (CPU {result['ratio_cpu']:.2f}x)")
    return 0


def parser():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=25, help="timed runs of each decoder (default 25)")
    p.add_argument("--warmups", type=int, default=3, help="untimed runs first (default 3)")
    p.add_argument("--modules", default=os.environ.get("MZC_NODE_MODULES") or npm_global_root(),
                   help="a node_modules folder with draco3d (and esbuild for the sizes)")
    p.add_argument("--web", default=str(WEB), help="the web/ folder to time (default: this checkout's)")
    p.add_argument("--out", default=str(HERE), help="output directory (default: benchmarks/)")
    return p


def npm_global_root():
    """npm's global node_modules folder, or "" without npm."""
    npm = shutil.which("npm")
    if npm is None:
        return ""
    return subprocess.run([npm, "root", "-g"], capture_output=True, text=True).stdout.strip()


def missing_requirement(args):
    """What the benchmark lacks, as a sentence, or None."""
    if shutil.which("node") is None:
        return "node is not installed"
    if not args.modules or not (Path(args.modules) / "draco3d" / "package.json").is_file():
        return (f"draco3d is not in {args.modules or 'any node_modules folder'} "
                "(npm install --prefix DIR esbuild draco3d; then --modules DIR/node_modules)")
    if not FACE.is_file():
        return f"{FACE} is absent"
    try:
        import DracoPy  # noqa: F401 - only whether it imports
    except ImportError:
        return "DracoPy is not installed"
    return None


def coded_files(scratch):
    """(mzc's file, Draco's file) of f18 in ``scratch``: the command line's `slice | encode
    --dwt2d --rmse 0.05`, and DracoPy on the original mesh at DRACO_BITS."""
    import DracoPy

    from mzc.meshes import read_mesh

    sliced = mzc_command(["slice", str(FACE)])
    mzc_file = scratch / "f18.mzw2"
    mzc_file.write_bytes(mzc_command(["encode", "--dwt2d", "--rmse", str(RMSE)], sliced))
    mesh = read_mesh(FACE)
    draco_file = scratch / "f18.drc"
    draco_file.write_bytes(contenders.draco_encode(DracoPy, (mesh.points, mesh.triangles), DRACO_BITS))
    return mzc_file, draco_file


def mzc_command(words, stdin=b""):
    """The standard output of `python -m mzc WORDS` given ``stdin``."""
    return subprocess.run([sys.executable, "-m", "mzc", *words], input=stdin, capture_output=True,
                          check=True).stdout


def node_timing(args, mzc_file, draco_file):
    """The node helper's JSON: every run's wall and CPU milliseconds of both decoders."""
    command = ["node", str(HERE / "web_decode.mjs"), str(args.web), str(mzc_file), str(draco_file),
               str(args.modules), str(args.warmups), str(args.runs)]
    return json.loads(subprocess.run(command, capture_output=True, check=True, text=True).stdout)


def summary(timing):
    """Medians and minima of each decoder's runs, and the ratios of the medians (web / Draco)."""
    out = {key: timing[key] for key in ("node", "draco_instantiate_ms", "grid", "draco_mesh")}
    for name, times in timing["times"].items():
        out[name] = {f"{kind}_{stat}_ms": fn(times[kind]) for kind in ("wall", "cpu")
                     for stat, fn in (("median", statistics.median), ("min", min))}
    out["ratio_wall"] = out["mzc"]["wall_median_ms"] / out["draco"]["wall_median_ms"]
    out["ratio_cpu"] = out["mzc"]["cpu_median_ms"] / out["draco"]["cpu_median_ms"]
    return out


def sizes(modules, web):
    """Bytes of the decoder as written, bundled and minified (esbuild), and gzip -9, beside
    Draco's decoder gzip -9; the bundle's entries None without esbuild."""
    written = sum((web / name).stat().st_size for name in imported_modules(web, "mzc.mjs"))
    draco = modules / "draco3d"
    out = {"written": written, "minified": None, "gzip": None, "esbuild": None,
           "draco_wasm_gzip": gzipped((draco / "draco_decoder.wasm").read_bytes()),
           "draco_js_gzip": gzipped((draco / "draco_decoder_nodejs.js").read_bytes()),
           "draco3d": json.loads((draco / "package.json").read_text())["version"]}
    esbuild = modules / ".bin" / "esbuild"
    if esbuild.exists():
        bundle = subprocess.run([str(esbuild), "--bundle", "--minify", "--format=esm", str(web / "mzc.mjs")],
                                capture_output=True, check=True).stdout
        version = subprocess.run([str(esbuild), "--version"], capture_output=True, text=True).stdout.strip()
        out.update(minified=len(bundle), gzip=gzipped(bundle), esbuild=version)
    return out


def imported_modules(web, name, seen=None):
    """The module ``name`` of ``web`` and every module of ``web`` it imports, directly or not."""
    seen = set() if seen is None else seen
    seen.add(name)
    for imported in re.findall(r'from "\./([\w.]+\.mjs)"', (web / name).read_text()):
        if imported not in seen:
            imported_modules(web, imported, seen)
    return seen


def gzipped(data):
    """The length of ``data`` under `gzip -9 -n` (GNU gzip, as web/README.md's sizes are
    measured), or under zlib's level 9 (Python's gzip, some tenths of a percent larger) without it."""
    if shutil.which("gzip") is None:
        return len(gzip.compress(data, compresslevel=9, mtime=0))
    return len(subprocess.run(["gzip", "-9", "-n", "-c"], input=data, capture_output=True, check=True).stdout)


def write_outputs(out, result):
    """web-decode-results.json and .md in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "web-decode-results.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "web-decode-results.md").write_text(markdown(result))


def markdown(r):
    """The report: the goal's check, the times, the sizes, how it was measured."""
    s = r["sizes"]
    verdict = "met" if r["ratio_wall"] <= GOAL else "NOT met"
    lines = [
        "# web/'s decoder beside Draco's WebAssembly decoder (issue 34)", "",
        f"{r['date']}, commit {r['commit']}, node {r['node']}, {r['machine']}; load average "
        f"{fmt_load(r['load_before'])} before, {fmt_load(r['load_after'])} after. "
        f"Written by `python benchmarks/web_decode.py --runs {r['runs']} --warmups {r['warmups']}`"
        + ("." if Path(r["web"]) == WEB else f", timing the web/ of `{r['web']}`."), "",
        f"**Goal (web/'s decode within {GOAL:g}x Draco's): {verdict}**: {r['ratio_wall']:.2f}x in wall time, "
        f"{r['ratio_cpu']:.2f}x in CPU time (medians).", "",
        "| f18 | file bytes | decoded to | wall median / min, ms | CPU median / min, ms |",
        "|---|---|---|---|---|",
        f"| web/ `decode`, `mzc-dwt2d {r['grid']['version']}` (`--dwt2d --rmse {RMSE}`) | {r['files']['mzc']:,} | "
        f"{r['grid']['rows']} x {r['grid']['cols']} grid, {r['grid']['valid']:,} valid nodes (float64) | "
        f"{times(r['mzc'], 'wall')} | {times(r['mzc'], 'cpu')} |",
        f"| Draco (draco3d {s['draco3d']}, WebAssembly; DracoPy, {DRACO_BITS} bits, level 10) | "
        f"{r['files']['draco']:,} | "
        f"{r['draco_mesh']['vertices']:,} vertices (float32), {r['draco_mesh']['triangles']:,} triangles (uint32) | "
        f"{times(r['draco'], 'wall')} | {times(r['draco'], 'cpu')} |", "",
        f"Draco's module takes {r['draco_instantiate_ms']:.1f} ms more to instantiate, once. "
        f"Medians of {r['runs']} runs after {r['warmups']} warm-ups, the two decoders alternated in one node "
        "process (the order swapped every round); CPU is the process's user + system time over the call "
        "(node's garbage collector's threads included).", "",
        "| decoder | bytes |", "|---|---|",
        f"| web/'s decoder as written (`mzc.mjs` and the modules it imports) | {s['written']:,} |",
    ]
    if s["esbuild"]:
        lines += [f"| `web/mzc.mjs` bundled and minified (esbuild {s['esbuild']}: `--bundle --minify --format=esm`) "
                  f"| {s['minified']:,} |",
                  f"| the same, gzip -9 | **{s['gzip']:,}** |"]
    else:
        lines.append("| bundled and minified | not measured: esbuild is not in the node_modules folder |")
    lines += [f"| Draco's decoder: `draco_decoder.wasm` + `draco_decoder_nodejs.js`, gzip -9 | "
              f"{s['draco_wasm_gzip']:,} + {s['draco_js_gzip']:,} |", ""]
    return "\n".join(lines)


def times(entry, kind):
    return f"{entry[f'{kind}_median_ms']:.2f} / {entry[f'{kind}_min_ms']:.2f}"


def fmt_load(load):
    return " ".join(f"{x:.2f}" for x in load)


if __name__ == "__main__":
    sys.exit(main())
