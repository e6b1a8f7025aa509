"""Rasters of any size (issue 30): encode and decode of float32 GeoTIFFs from 1e6 to 1.44e8 nodes in tiles.

For each size, a square float32 GeoTIFF (a smooth terrain-like field of three scales of
sinusoids, 300 m of relief, plus 0.1 m of Gaussian noise; UTM metres, 1 m cells) is written
strip by strip into a temporary folder (never kept), then each stage runs as its own ``mzc``
subprocess under ``/usr/bin/time -v`` (its peak RSS is its own):

- ``mzc encode --dwt2d --max-error 0.1 dem.tif -o dem.mzw2`` (tiled above 1024 x 1024 nodes,
  the raster read window by window), and, up to MAX_WHOLE nodes, ``--tile 0`` (the whole grid
  as one stream, as before) for the file size and memory it costs;
- ``mzc decode dem.mzw2 -o back.tif --float32`` (tile by tile into a tiled GeoTIFF);
- ``mzc decode dem.mzw2 --window R C 512 512 -o w.zg`` (a window at the centre: its tiles alone).

The decoded raster is compared with the original strip by strip (maximum and RMS error over
the valid cells). Writes ``benchmarks/tiles-results.md`` and ``benchmarks/tiles-results.json``.

    python benchmarks/tiles.py                  # 1, 4, 16, 36, 144 M nodes (about 15 minutes)
    python benchmarks/tiles.py --sizes 1000,2000 --output /tmp/tiles   # a quick look
"""

import argparse
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SIDES = (1000, 2000, 4000, 6000, 12000)   # square rasters: 1e6 .. 1.44e8 nodes
MAX_WHOLE = 16_000_000                    # --tile 0 is run up to this many nodes (the 25 M-node one took 4 GB)
MAX_ERROR = 0.1                           # metres
NOISE = 0.1                               # metres, the field's Gaussian noise
STRIP = 512                               # rows written and compared at a time
WINDOW = 512


def write_terrain(path, side, seed=0):
    """A side x side float32 GeoTIFF of terrain-like values, written strip by strip (bounded memory)."""
    import rasterio
    from rasterio.transform import from_origin
    from rasterio.windows import Window

    rng = np.random.default_rng(seed)
    profile = {"driver": "GTiff", "width": side, "height": side, "count": 1, "dtype": "float32", "crs": "EPSG:32611",
               "transform": from_origin(440000, 3750000, 1, 1), "nodata": -9999, "compress": "deflate",
               "tiled": True, "blockxsize": 512, "blockysize": 512, "bigtiff": "IF_SAFER"}
    with rasterio.open(path, "w", **profile) as dataset:
        for r0 in range(0, side, STRIP):
            rows = min(STRIP, side - r0)
            y, x = np.mgrid[r0:r0 + rows, 0:side].astype(np.float64)
            z = (300 * np.sin(x / 2100) * np.cos(y / 1700) + 60 * np.sin((x + 0.6 * y) / 410)
                 + 8 * np.sin(x / 53) * np.cos(y / 71) + rng.normal(0, NOISE, (rows, side)))
            dataset.write(z.astype(np.float32), 1, window=Window(0, r0, side, rows))


def timed(*arguments, cwd):
    """(wall s, CPU s, peak MB) of ``python -m mzc ARGUMENTS`` under /usr/bin/time -v."""
    env = {**os.environ, "PYTHONPATH": str(HERE.parent)}
    started = time.perf_counter()
    result = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "mzc", *map(str, arguments)], cwd=cwd,
                            env=env, capture_output=True, text=True)
    wall = time.perf_counter() - started
    if result.returncode != 0:
        raise SystemExit(f"mzc {' '.join(map(str, arguments))} failed: {result.stderr[-2000:]}")
    found = {key: float(re.search(pattern, result.stderr)[1]) for key, pattern in
             (("user", r"User time \(seconds\): ([\d.]+)"), ("system", r"System time \(seconds\): ([\d.]+)"),
              ("rss", r"Maximum resident set size \(kbytes\): (\d+)"))}
    return {"wall": round(wall, 2), "cpu": round(found["user"] + found["system"], 2),
            "mb": round(found["rss"] / 1024, 1)}


def errors(original, decoded):
    """(max, RMS) of |decoded - original| over the original's valid cells, strip by strip."""
    import rasterio
    from rasterio.windows import Window

    largest, squares, count = 0.0, 0.0, 0
    with rasterio.open(original) as a, rasterio.open(decoded) as b:
        for r0 in range(0, a.height, STRIP):
            window = Window(0, r0, a.width, min(STRIP, a.height - r0))
            want, got = a.read(1, window=window).astype(np.float64), b.read(1, window=window).astype(np.float64)
            valid = want != a.nodata
            if not np.array_equal(got == b.nodata, ~valid):
                raise SystemExit("the decoded raster's no-data cells differ from the original's")
            difference = np.abs(got - want)[valid]
            largest = max(largest, float(difference.max(initial=0)))
            squares += float(np.sum(difference**2))
            count += int(valid.sum())
    return largest, math.sqrt(squares / count)


def measure(side, folder):
    """Every figure of one size."""
    nodes = side * side
    tif, coded, whole, back = (folder / name for name in ("dem.tif", "dem.mzw2", "whole.mzw2", "back.tif"))
    started = time.perf_counter()
    write_terrain(tif, side)
    row = {"side": side, "nodes": nodes, "tif_bytes": tif.stat().st_size,
           "generate_s": round(time.perf_counter() - started, 1)}
    row["encode"] = timed("encode", "--dwt2d", "--max-error", MAX_ERROR, tif, "-o", coded, cwd=folder)
    row["bytes"] = coded.stat().st_size
    row["magic"] = coded.read_bytes()[:13].decode()
    if nodes <= MAX_WHOLE:
        row["whole"] = timed("encode", "--dwt2d", "--max-error", MAX_ERROR, "--tile", 0, tif, "-o", whole, cwd=folder)
        row["whole_bytes"] = whole.stat().st_size
        whole.unlink()
    row["decode"] = timed("decode", coded, "-o", back, "--float32", cwd=folder)
    middle = max(0, side // 2 - WINDOW // 2)
    size = min(WINDOW, side)
    row["window"] = timed("decode", coded, "--window", middle, middle, size, size, "-o", folder / "w.zg", cwd=folder)
    row["max_error"], row["rms_error"] = errors(tif, back)
    for name in (tif, coded, back, folder / "w.zg"):
        name.unlink()
    return row


def rate(nodes, seconds):
    """Millions of nodes a second."""
    return nodes / seconds / 1e6


def report(rows, started):
    """The markdown report."""
    from report import git_commit

    commit = git_commit()
    lines = [
        "# Rasters of any size: tiled encode and decode (issue 30)",
        "",
        f"`python benchmarks/tiles.py` at commit {commit}, {started} UTC, on {platform.machine()} with "
        f"{os.cpu_count()} cores shared with other work (wall times carry that load; CPU times and peaks do not).",
        f"Each raster: a square float32 GeoTIFF (deflate, 512 x 512 blocks), a smooth terrain-like field (300 m of "
        f"relief in three scales of sinusoids) plus {NOISE} m of Gaussian noise, 1 m cells in UTM 11N, made in a "
        f"temporary folder and deleted. Encode: `mzc encode --dwt2d --max-error {MAX_ERROR} dem.tif -o dem.mzw2` "
        "(the default: tiles of 1024 x 1024 above that many nodes, read window by window); decode: `mzc decode "
        f"dem.mzw2 -o back.tif --float32` (tile by tile into a tiled GeoTIFF); window: `mzc decode dem.mzw2 --window "
        f"R C {WINDOW} {WINDOW}` at the centre. Each a subprocess under `/usr/bin/time -v`: peak = its maximum RSS. "
        "Errors: the decoded GeoTIFF against the original over every valid cell (the bound holds on the decoded "
        "float64 values; `--float32` rounds them, by up to half a float32 step, 7.6e-6 m at 128-256 m).",
        "",
        "| nodes | format | encode wall s | CPU s | M nodes/s (CPU) | peak MB | bytes | bits/node | decode wall s | "
        "CPU s | M nodes/s (CPU) | peak MB | window s | window MB | max error m | RMS error m |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        e, d, w = row["encode"], row["decode"], row["window"]
        lines.append(
            f"| {row['nodes'] / 1e6:.0f} M | {row['magic']} | {e['wall']:.1f} | {e['cpu']:.1f} | "
            f"{rate(row['nodes'], e['cpu']):.2f} | {e['mb']:.0f} | {row['bytes']:,} | "
            f"{8 * row['bytes'] / row['nodes']:.3f} | {d['wall']:.1f} | {d['cpu']:.1f} | "
            f"{rate(row['nodes'], d['cpu']):.2f} | {d['mb']:.0f} | {w['wall']:.2f} | {w['mb']:.0f} | "
            f"{row['max_error']:.6f} | {row['rms_error']:.4f} |")
    lines += ["", "Against the whole grid as one stream (`--tile 0`, dwt2d 3.2), where it fits:", "",
              "| nodes | whole bytes | tiled bytes | tiled / whole | whole encode CPU s | peak MB | tiled CPU s | "
              "peak MB |", "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        if "whole" in row:
            lines.append(f"| {row['nodes'] / 1e6:.0f} M | {row['whole_bytes']:,} | {row['bytes']:,} | "
                         f"{row['bytes'] / row['whole_bytes']:.4f} | {row['whole']['cpu']:.1f} | "
                         f"{row['whole']['mb']:.0f} | {row['encode']['cpu']:.1f} | {row['encode']['mb']:.0f} |")
    first, last = rows[0], rows[-1]
    if len(rows) > 1:
        growth = math.log(last["nodes"] / first["nodes"])
        lines += ["", f"Growth from {first['nodes'] / 1e6:.0f} M to {last['nodes'] / 1e6:.0f} M nodes (exponents of "
                  "log ratio over the log of the node ratio; 1 is linear, 0 flat):", "",
                  "| | encode CPU | encode peak | decode CPU | decode peak |", "|---|---|---|---|---|",
                  "| exponent | " + " | ".join(
                      f"{math.log(last[stage][key] / first[stage][key]) / growth:.2f}"
                      for stage, key in (("encode", "cpu"), ("encode", "mb"), ("decode", "cpu"), ("decode", "mb")))
                  + " |"]
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", help="sides of the square rasters, comma-separated (default: "
                                        + ",".join(map(str, SIDES)) + ")")
    parser.add_argument("--output", type=Path, default=HERE / "tiles-results",
                        help="where to write the report (.md) and figures (.json), without extension")
    arguments = parser.parse_args()
    sides = [int(s) for s in arguments.sizes.split(",")] if arguments.sizes else list(SIDES)
    started = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    rows = []
    with tempfile.TemporaryDirectory(prefix="mzc-tiles-") as folder:
        for side in sides:
            rows.append(measure(side, Path(folder)))
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    arguments.output.with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")
    arguments.output.with_suffix(".md").write_text(report(rows, started))
    print(report(rows, started))


if __name__ == "__main__":
    main()
