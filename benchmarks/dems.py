"""mzc dwt2d beside LERC and SPERR on public DEMs at equal max error and equal vertical RMSE (issue 30).

    python benchmarks/dems.py [--quick] [--out DIR]

Every DEM (the rasters of tests/data/public that are elevation models, and matplotlib's two
sample DEMs as mzc.samples reads them) is coded by each contender in the same run:

- mzc dwt2d: ``mzc.encode(grid, "dwt2d", max_error=E)`` and ``rmse=R``; bytes = the file.
- LERC in a GeoTIFF: GDAL's ``COMPRESS=LERC`` with ``MAX_Z_ERROR`` through rasterio, written to
  memory in the DEM's sample type with its no-data value; bytes = the GeoTIFF file. The raw
  blob of the ``lerc`` package (``lerc.encode``, its own mask inside) is reported beside it.
- SPERR (imagecodecs): point-wise error mode on the float64 heights, no-data cells filled by
  mzc's encoder's biharmonic fill, in the container of benchmarks/contenders.py (grid header, the mask
  coded by mzc's mask coder, SPERR's payload without its own header).

At equal max error E every contender is asked for E; at an RMSE target R the peers' knob
(LERC's MAX_Z_ERROR, SPERR's point-wise bound) is searched by bisection in log space, and
their bytes at R are interpolated log-log on the points probed (report.bytes_at). Every
error is measured here, from the decoded arrays against the input over its valid cells.
Writes dems-results.md and dems-results.json into --out (default: this directory).
"""

import datetime
import json
import math
import time
from dataclasses import replace

from startup import HERE  # first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from contenders import GRID_HEADER, filled, grid_file, read_grid_file
from report import benchmark_parser, bytes_at, fmt, git_commit, machine, pareto, terminal_progress, versions

PUBLIC = HERE.parent / "tests" / "data" / "public"
PACKAGES = ("numpy", "PyWavelets", "constriction", "imagecodecs", "lerc", "rasterio")
INTEGER_MAX_ERRORS = (0.5, 1.0, 2.0, 5.0)     # m; 0.5 is lossless for an integer coder
INTEGER_RMSES = (0.5, 1.0, 2.0)               # m
FLOAT_MAX_ERRORS = (0.01, 0.02, 0.05, 0.1)    # m, kootenai: 0.01 m heights, 6.5 m of relief
FLOAT_RMSES = (0.005, 0.01, 0.025)            # m
TOLERANCE = 0.02                              # an RMSE search stops within 2% of its target
SEARCH_STEPS = 24
REPEATS = 3                                   # timing runs at equal max error (the fastest kept)
MZC, LERC_TIF, SPERR = "mzc dwt2d", "LERC GeoTIFF", "SPERR"
PEERS = (LERC_TIF, SPERR)


# --------------------------------------------------------------------------- corpus


def public_dem(name):
    """A raster of tests/data/public as mzc reads it (NaN at no-data)."""
    import mzc

    return mzc.read(PUBLIC / name)


def sample_dem(name, sample):
    """matplotlib's sample DEM ``name`` as mzc.samples reads it, with the sample type its file
    stores (jacksboro int16, topobathy float32), so every contender codes the same type."""
    from mzc import samples
    from mzc.grid import Raster

    return replace(getattr(samples, name)(), raster=Raster(sample=sample))


# (name, loader, why included). rasterio_float.tif (2 x 3 values) and rasterio_float_nodata.tif
# (12 x 13 cells of 0 and 0.25 only) are GDAL test rasters, not elevation models: left out.
DEMS = [
    ("srtm_blurred_res", lambda: public_dem("srtm_blurred_res.tif"), "SRTM tile, int16, EPSG:4326"),
    ("hugo_site", lambda: public_dem("hugo_site.asc"), "ESRI grid, whole metres (int32), half no-data"),
    ("west_bijou", lambda: public_dem("west_bijou_escarpment_snippet.asc"), "ESRI grid, 1\", whole metres"),
    ("kootenai", lambda: public_dem("dem_kootenai_37x50_1x1.asc"), "ESRI grid, 1 m river reach, float heights"),
    ("jacksboro", lambda: sample_dem("jacksboro", "int16"), "matplotlib sample, int16 in its .npz"),
    ("topobathy", lambda: sample_dem("topobathy", "float32"), "matplotlib sample, float32 in its .npz"),
]
QUICK_DEMS = ("srtm_blurred_res", "kootenai")


def targets(grid, quick):
    """(max errors, RMSE targets) for a DEM: whole metres for integer samples, centimetres for
    the float DEM of 0.01 m heights; the quick run takes two and one."""
    integer = np.dtype(grid.raster.sample).kind in "iu" or np.array_equal(grid.z[grid.valid],
                                                                           np.round(grid.z[grid.valid]))
    errors, rmses = (INTEGER_MAX_ERRORS, INTEGER_RMSES) if integer else (FLOAT_MAX_ERRORS, FLOAT_RMSES)
    return (errors[1:3], rmses[1:2]) if quick else (errors, rmses)


# --------------------------------------------------------------------------- measuring


def timed(function, repeats=1):
    """(result, fastest wall seconds of ``repeats`` calls)."""
    best, result = math.inf, None
    for _ in range(repeats):
        started = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - started)
    return result, best


def errors(grid, decoded_z, decoded_valid):
    """{max, rms, integers, mask}: |decoded - input| over the input's valid cells, whether every
    decoded valid value is an integer, and whether the decoded mask is the input's."""
    valid = grid.valid
    difference = np.abs(decoded_z[valid] - grid.z[valid])
    values = decoded_z[valid]
    return {"max": float(difference.max()), "rms": float(np.sqrt(np.mean(difference**2))),
            "integers": bool(np.array_equal(values, np.round(values))),
            "mask": bool(np.array_equal(decoded_valid, valid))}


def point(grid, contender, setting, codec, repeats=1):
    """One coded file of ``codec`` (encode, decode, payload): bytes, the codec's payload bytes
    (the file without its container's header), encode and decode seconds, the measured errors."""
    encode, decode, payload = codec
    data, encode_s = timed(encode, repeats)
    (z, valid), decode_s = timed(lambda: decode(data), repeats)
    return {"contender": contender, "setting": setting, "bytes": len(data), "payload": payload(data),
            "encode_s": encode_s, "decode_s": decode_s, "valid": errors(grid, z, valid)}


# --------------------------------------------------------------------------- contenders


def mzc_codec(grid, **options):
    """(encode, decode, payload) of mzc dwt2d with ``options`` (max_error or rmse); the payload
    is the binary part after the text header (mask and coefficients)."""
    import mzc

    def decode(data):
        back = mzc.decode(data)
        return back.z, back.valid

    return lambda: mzc.encode(grid, "dwt2d", **options), decode, lambda data: len(data) - header_bytes(data)


def header_bytes(data):
    """The size of an mzc file's header (3.x: its text through the ``data`` line; 7.0: its binary
    fields and the sections' framing): the CRS's WKT is in it."""
    from mzc.codecs.dwt2d import anatomy

    return anatomy.parts(data)["header"]


def geotiff_profile(grid):
    """A one-band GeoTIFF profile of ``grid``: its sample type, CRS, no-data and cell size."""
    from rasterio.transform import from_origin

    rows, cols = grid.shape
    sample = np.dtype(grid.raster.sample)
    nodata = None
    if not grid.valid.all():
        nodata = float(grid.nodata) if grid.nodata not in (None, "nan") else np.nan
    x0, y0 = grid.origin
    return {"driver": "GTiff", "width": cols, "height": rows, "count": 1, "dtype": sample.name,
            "crs": grid.crs, "nodata": nodata,
            "transform": from_origin(x0 - grid.d2 / 2, y0 + (rows - 0.5) * grid.d1, grid.d2, grid.d1)}


def lerc_geotiff(grid, max_z_error):
    """(encode, decode, payload) of a north-up GeoTIFF with COMPRESS=LERC, MAX_Z_ERROR, one strip (LERC's
    whole raster as one blob: its best case on a small DEM), written and read in memory. The
    payload is the lerc package's blob of the same values at the same bound."""
    from rasterio.io import MemoryFile

    profile = geotiff_profile(grid)
    nodata = profile["nodata"]
    raster = np.flipud(np.where(grid.valid, grid.z, 0 if nodata is None else nodata)).astype(profile["dtype"])

    def encode():
        with MemoryFile() as memory:
            with memory.open(**profile, compress="LERC", max_z_error=max_z_error, blockysize=grid.shape[0]) as out:
                out.write(raster, 1)
            return memory.read()

    def decode(data):
        with MemoryFile(data) as memory, memory.open() as dataset:
            band = dataset.read(1, masked=True)
        z = np.flipud(band.astype(np.float64).filled(np.nan))
        return z, np.flipud(~np.ma.getmaskarray(band))

    return encode, decode, lambda data: lerc_blob_bytes(grid, max_z_error)


def lerc_blob_bytes(grid, max_z_error):
    """Bytes of the lerc package's own blob (its mask inside) in the DEM's sample type."""
    import lerc

    z = np.where(grid.valid, grid.z, 0).astype(grid.raster.sample)
    code, size, _blob = lerc.encode(z, 1, True, grid.valid, max_z_error, 1)
    if code:
        raise RuntimeError(f"lerc.encode failed with code {code}")
    return int(size)


def sperr(grid, bound):
    """(encode, decode, payload) of SPERR's point-wise bound on the filled float64 heights, in
    contenders.py's container (grid header, mzc's mask coder, SPERR's payload); the payload is
    the mask and SPERR's stream, without the binary grid header and the mask's length."""
    import imagecodecs

    heights = np.ascontiguousarray(filled(grid))

    def encode():
        return grid_file(grid, bytes(imagecodecs.sperr_encode(heights, bound, "pwe", header=False, numthreads=1)))

    def decode(data):
        shell, _, valid, payload = read_grid_file(data)
        z = imagecodecs.sperr_decode(payload, shape=shell.shape, dtype=np.float64, header=False, numthreads=1)
        return np.where(valid, z, np.nan), valid

    return encode, decode, lambda data: len(data) - GRID_HEADER.size - 4


PEER_CODECS = {LERC_TIF: lerc_geotiff, SPERR: sperr}


# --------------------------------------------------------------------------- targets


def at_max_error(grid, error):
    """Every contender asked for max error ``error``."""
    rows = [point(grid, MZC, error, mzc_codec(grid, max_error=error), repeats=REPEATS)]
    return rows + [point(grid, name, error, codec(grid, error), repeats=REPEATS) for name, codec in PEER_CODECS.items()]


def search(grid, name, target):
    """The points probed while bisecting a peer's knob (log scale) for RMSE ``target``: it stops
    within TOLERANCE of the target, or after SEARCH_STEPS probes (an integer raster's LERC moves
    in whole steps of its bound, so it may never land there)."""
    low, high = target / 100, target * 100   # the knobs are bounds: RMSE is below them
    probes = []
    for _ in range(SEARCH_STEPS):
        knob = math.sqrt(low * high)
        probe = point(grid, name, knob, PEER_CODECS[name](grid, knob))
        probes.append(probe)
        rms = probe["valid"]["rms"]
        if abs(rms / target - 1) <= TOLERANCE:
            break
        low, high = (knob, high) if rms < target else (low, knob)
    return probes


def at_rmse(grid, target):
    """mzc at ``rmse=target``, then each peer searched for the RMSE mzc measured (so all compare at
    one measured RMSE, whether mzc landed a little above or below ``target``); each peer's bytes
    there interpolated on the Pareto front of its lossy probes (None outside their range)."""
    mzc_point = point(grid, MZC, target, mzc_codec(grid, rmse=target))
    measured = mzc_point["valid"]["rms"]
    peers = {}
    for name in PEER_CODECS:
        probes = search(grid, name, measured)
        nearest = min(probes, key=lambda p: abs(math.log(max(p["valid"]["rms"], 1e-12) / measured)))
        lossy = [p for p in probes if p["valid"]["rms"] > 0]
        peers[name] = {"nearest": nearest, "bytes_at_target": bytes_at(pareto(lossy, "valid rms"), measured),
                       "payload_at_target": bytes_at(pareto(payloads(lossy), "valid rms"), measured),
                       "probes": len(probes)}
    return {"target": target, "measured": measured, "mzc": mzc_point, "peers": peers}


def payloads(points):
    """The points with their payloads as their bytes (for report.pareto and bytes_at)."""
    return [{**p, "bytes": p["payload"]} for p in points]


def measure_dem(name, loader, why, quick, progress):
    """Every figure of one DEM."""
    grid = loader()
    max_errors, rmses = targets(grid, quick)
    valid = grid.z[grid.valid]
    item = {"dem": name, "why": why, "shape": list(grid.shape), "valid": int(grid.valid.sum()),
            "sample": grid.raster.sample, "geographic": bool(grid.crs and grid.crs.startswith("GEOGCS")),
            "range": [float(valid.min()), float(valid.max())], "max_error": [], "rmse": []}
    for error in max_errors:
        progress(f"{name}: max error {error}")
        item["max_error"].append({"target": error, "points": at_max_error(grid, error)})
    for target in rmses:
        progress(f"{name}: RMSE {target}")
        item["rmse"].append(at_rmse(grid, target))
    return item


# --------------------------------------------------------------------------- summary


def ratios(items, size="bytes"):
    """{"max_error"|"rmse": {peer: [(geometric mean of peer / mzc ``size`` (bytes of the files, or
    payload), DEMs counted) per target rank]}}: the k-th target of each DEM (the same E for the
    integer DEMs) counted together."""
    summary = {}
    for kind in ("max_error", "rmse"):
        collected = {peer: {} for peer in PEERS}
        for item in items:
            for rank, row in enumerate(item[kind]):
                for peer in PEERS:
                    value = ratio_of(row, peer, kind, size)
                    if value is not None:
                        collected[peer].setdefault(rank, []).append(value)
        summary[kind] = {peer: [(float(np.exp(np.mean(np.log(v)))), len(v)) for _, v in sorted(ranks.items())]
                         for peer, ranks in collected.items()}
    return summary


def ratio_of(row, peer, kind, size="bytes"):
    """Peer / mzc ``size`` ("bytes" or "payload") at one target (None when the peer's is unknown)."""
    if kind == "max_error":
        sizes = {p["contender"]: p[size] for p in row["points"]}
        return sizes[peer] / sizes[MZC]
    peer_size = row["peers"][peer][f"{size}_at_target"]
    return None if peer_size is None else peer_size / row["mzc"][size]


# --------------------------------------------------------------------------- report


def markdown(items, summary, settings):
    """The report text."""
    import rasterio

    lines = [
        "# mzc dwt2d beside LERC and SPERR on public DEMs (issue 30)",
        "",
        f"`python benchmarks/dems.py{' --quick' if settings['quick'] else ''}` at commit {settings['commit']}, "
        f"{settings['started']} UTC, on {machine()} (shared with other work: times are wall seconds, the "
        f"fastest of {REPEATS} at equal max error, one run per probe at equal RMSE); total {settings['wall_s']:.0f} s.",
        "",
        "Package versions: " + ", ".join(f"{k} {v}" for k, v in versions(PACKAGES).items())
        + f", GDAL {rasterio.__gdal_version__}.",
        "",
        "Large rasters are in `benchmarks/tiles-results.md`, not measured again here: float32 GeoTIFFs of 1e6 to "
        "1.44e8 nodes at `--max-error 0.1`, tiled encode at 0.62-0.83 M nodes/s of CPU with a flat peak of "
        "320-347 MB, decode at 2.6-5.9 M nodes/s in 122-154 MB; growth exponents from 1e6 to 1.44e8 nodes: "
        "encode CPU 0.94, encode peak 0.02, decode CPU 0.84, decode peak 0.05.",
        "",
        *method_section(),
        *corpus_section(items),
        *summary_section(items, summary),
        *max_error_section(items),
        *rmse_section(items),
        *speed_section(items),
        *verdict_section(items, summary),
    ]
    return "\n".join(lines) + "\n"


def method_section():
    return [
        "## Method",
        "",
        "- mzc dwt2d: `mzc.encode(grid, \"dwt2d\", max_error=E)` or `rmse=R` on the grid `mzc.read` gives "
        "(NaN at no-data), decoded by `mzc.decode`; bytes = the whole file, whose text header (magic, shape, "
        "origin, the CRS's WKT, raster line, ...) is counted and shown apart. An integer raster at a max error "
        "is format 6.0: its values come back integers within floor(E). On a geographic grid `rmse` is the "
        "vertical RMSE in metres.",
        "- LERC GeoTIFF: rasterio (GDAL) writes a north-up GeoTIFF into a `MemoryFile` with `COMPRESS=LERC`, "
        "`MAX_Z_ERROR=E`, in the DEM's sample type (int16, int32, float32, or float64 for the ESRI float grid), "
        "its CRS, geotransform and no-data value (GDAL gives LERC the mask of valid cells), one strip of the "
        "whole raster (one LERC blob: on small rasters fewer bytes than 256 x 256 tiles, which would pad); "
        "bytes = the file as stored; read back through rasterio with its mask. `lerc blob` is the `lerc` "
        "package's own blob (`lerc.encode`, mask inside) of the same values: LERC without the TIFF.",
        "- SPERR: `imagecodecs.sperr_encode(z, E, 'pwe', header=False)` on the float64 heights with no-data "
        "cells filled by mzc's encoder's biharmonic fill (SPERR has no mask), in the container of "
        "`benchmarks/contenders.py` (`grid_file`: a 133-byte binary grid header, the validity mask coded by "
        "mzc's dwt2d mask coder, and the payload; SPERR's own 10-byte header left out). It decodes float64: "
        "never integers.",
        "- Equal max error: each contender asked for E (in metres). Equal RMSE: mzc takes `rmse=R` and its RMSE "
        "is measured (M, within a few % of R); each peer's knob (LERC's MAX_Z_ERROR, SPERR's point-wise bound) is "
        "bisected in log space between M/100 and 100 M until its measured RMSE is within "
        f"{TOLERANCE:.0%} of M (at most {SEARCH_STEPS} probes); its bytes at M are interpolated log-log on the "
        "Pareto front of its lossy probes (`report.bytes_at`), the nearest probe shown. So the ratios compare "
        "files of one measured RMSE. LERC on integer samples moves in whole steps of its bound, so its search "
        "may not land within 2%: its bytes at M are then interpolated between two real files.",
        "- Integer DEMs at E = 0.5: mzc and LERC are lossless (they code integers); SPERR's floats are within "
        "0.5, so rounding them would also give the integers back, which SPERR itself does not do. topobathy's "
        "heights are whole metres stored as float32: LERC notices integer-valued floats and codes them as "
        "integers (lossless at 0.5, integers at every E), mzc (float32 sample: no rounding) and SPERR do not. "
        "At RMSE 0.5 m LERC on integer samples has no file between lossless (RMSE 0) and bound 1 (RMSE about "
        "0.70): n/a there; its bound-1 file is the cheapest that is not lossless.",
        "- Every error is measured here: |decoded - input| over the input's valid cells (max and RMS), from "
        "the decoded arrays; `mask` checks the decoded validity equals the input's; `int` whether every decoded "
        "valid value is an integer.",
        "- Ratios: peer bytes / mzc bytes at the same target; geometric means over the DEMs at each target rank "
        "(the integer DEMs share their targets; kootenai's are in centimetres). Above 1: mzc is smaller.",
        "",
    ]


def corpus_section(items):
    lines = ["## DEMs", "", "| DEM | what | rows x cols | valid cells | sample | heights m | max errors | RMSEs |",
             "|---|---|---|---|---|---|---|---|"]
    for item in items:
        lines.append(f"| {item['dem']} | {item['why']} | {item['shape'][0]} x {item['shape'][1]} | {item['valid']:,} | "
                     f"{item['sample']} | {item['range'][0]:g} to {item['range'][1]:g} | "
                     f"{targets_text(item['max_error'])} | {targets_text(item['rmse'])} |")
    return lines + ["", "Left out: `rasterio_float.tif` (2 x 3 values) and `rasterio_float_nodata.tif` (12 x 13 "
                    "cells holding only 0 and 0.25): GDAL test rasters, not elevation models.", ""]


def targets_text(rows):
    return ", ".join(f"{row['target']:g}" for row in rows)


def summary_section(items, summary):
    lines = ["## Summary: peer size / mzc size, geometric means over the DEMs", "",
             "Files: the bytes as stored (mzc's file, the LERC GeoTIFF, SPERR in its container). Payloads: without "
             "the containers' headers (mzc's text header with the CRS's WKT, the TIFF's tags and GeoKeys, the "
             "133-byte grid header): mzc's binary part, the lerc package's blob, SPERR's stream plus mzc's mask "
             "coding. On these small DEMs the headers are a large share: mzc's 194-511 bytes, about 200 of keys and "
             "numbers plus the CRS's WKT where the DEM has one (west_bijou's 150 bytes, the SRTM tile's 307).",
             ""]
    for kind, label in (("max_error", "equal max error"), ("rmse", "equal measured vertical RMSE")):
        ranks = max(len(item[kind]) for item in items)
        heads = [" / ".join(sorted({f"{item[kind][k]['target']:g}" for item in items if k < len(item[kind])},
                                   key=float)) + " m" for k in range(ranks)]
        lines += [f"At {label}:", "", "| peer | size | " + " | ".join(heads) + " |", "|---" * (ranks + 2) + "|"]
        for peer in PEERS:
            for size, name in (("bytes", "files"), ("payload", "payloads")):
                lines.append(f"| {peer} | {name} | " + " | ".join(f"{fmt(g)} ({n} DEMs)"
                                                                  for g, n in summary[size][kind][peer]) + " |")
        lines.append("")
    return lines


def max_error_section(items):
    lines = ["## Equal max error (bytes; measured max and RMS error in m; encode / decode ms)", "",
             "| DEM | E m | contender | bytes | peer / mzc | payload | peer / mzc | max err | RMSE | int | mask | "
             "enc ms | dec ms |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for item in items:
        for row in item["max_error"]:
            mzc_point = row["points"][0]
            for p in row["points"]:
                ok = "" if p["valid"]["max"] <= row["target"] * (1 + 1e-9) else " (over E)"
                lines.append(f"| {item['dem']} | {row['target']:g} | {p['contender']} | {p['bytes']:,} | "
                             f"{p['bytes'] / mzc_point['bytes']:.2f} | {p['payload']:,} | "
                             f"{p['payload'] / mzc_point['payload']:.2f} | {p['valid']['max']:.4g}{ok} | "
                             f"{p['valid']['rms']:.4g} | "
                             f"{yes(p['valid']['integers'])} | {yes(p['valid']['mask'])} | "
                             f"{1e3 * p['encode_s']:.1f} | {1e3 * p['decode_s']:.1f} |")
    return lines + [""]


def rmse_section(items):
    lines = ["## Equal vertical RMSE (mzc at rmse=R measures M; each peer's nearest probe and its bytes at M)", "",
             "| DEM | R m | contender | bytes at M | peer / mzc | payload at M | peer / mzc | nearest probe: knob | "
             "bytes | RMSE | max err | enc ms | dec ms | probes |", "|---" * 14 + "|"]
    for item in items:
        for row in item["rmse"]:
            m = row["mzc"]
            lines.append(f"| {item['dem']} | {row['target']:g} | {MZC} | {m['bytes']:,} | 1 | {m['payload']:,} | 1 | "
                         f"rmse={row['target']:g} | "
                         f"{m['bytes']:,} | {m['valid']['rms']:.4g} | {m['valid']['max']:.4g} | "
                         f"{1e3 * m['encode_s']:.1f} | {1e3 * m['decode_s']:.1f} | 1 |")
            for peer, found in row["peers"].items():
                p, at, inner = found["nearest"], found["bytes_at_target"], found["payload_at_target"]
                lines.append(f"| {item['dem']} | {row['target']:g} | {peer} | {fmt_bytes(at)} | "
                             f"{fmt(None if at is None else at / m['bytes'])} | {fmt_bytes(inner)} | "
                             f"{fmt(None if inner is None else inner / m['payload'])} | {p['setting']:.4g} | "
                             f"{p['bytes']:,} | "
                             f"{p['valid']['rms']:.4g} | {p['valid']['max']:.4g} | {1e3 * p['encode_s']:.1f} | "
                             f"{1e3 * p['decode_s']:.1f} | {found['probes']} |")
    return lines + [""]


def speed_section(items):
    """Median encode and decode wall times per DEM and contender over its max-error targets."""
    lines = ["## Times at equal max error (median over the DEM's targets of the fastest of "
             f"{REPEATS} runs; wall ms, in-process, one thread)", "",
             "| DEM | valid cells | " + " | ".join(f"{name} encode | decode" for name in (MZC, *PEERS)) + " |",
             "|---" * (2 + 2 * (1 + len(PEERS))) + "|"]
    for item in items:
        cells = []
        for name in (MZC, *PEERS):
            points = [p for row in item["max_error"] for p in row["points"] if p["contender"] == name]
            cells += [f"{1e3 * np.median([p[key] for p in points]):.1f}" for key in ("encode_s", "decode_s")]
        lines.append(f"| {item['dem']} | {item['valid']:,} | " + " | ".join(cells) + " |")
    return lines + ["", "mzc dwt2d's encoder is the slowest here (tens of times LERC's, which is about a "
                    "millisecond on these rasters); its throughput on large rasters is in tiles-results.md.", ""]


def verdict_section(items, summary):
    """Where each peer is smaller than mzc (its file or its payload), said plainly."""
    wins = []
    for item in items:
        for kind, label in (("max_error", "max error"), ("rmse", "RMSE")):
            for row in item[kind]:
                for peer in PEERS:
                    files, inner = (ratio_of(row, peer, kind, size) for size in ("bytes", "payload"))
                    if min(v for v in (files, inner, 1.0) if v is not None) < 1:
                        wins.append(f"- {peer} on {item['dem']} at {label} {row['target']:g} m: file {fmt(files)}, "
                                    f"payload {fmt(inner)} of mzc's")
    return ["## Where a peer is smaller (peer / mzc below 1)", "",
            *(wins or ["- nowhere: mzc dwt2d is the smallest at every target"]), "",
            "SPERR's container carries no CRS; mzc's header carries the CRS's WKT (150 of west_bijou's 403 header "
            "bytes), so on the smallest files SPERR's file ratios favour it and its payload ratios are the "
            "codec-to-codec comparison.", ""]


def yes(flag):
    return "yes" if flag else "no"


def fmt_bytes(value):
    return "n/a" if value is None else f"{value:,.0f}"


# --------------------------------------------------------------------------- main


def parse_arguments(argv=None):
    return benchmark_parser(__doc__, f"{' and '.join(QUICK_DEMS)} at fewer targets").parse_args(argv)


def main(argv=None):
    arguments = parse_arguments(argv)
    progress = terminal_progress()
    started = time.perf_counter()
    settings = {"quick": arguments.quick, "commit": git_commit(),
                "started": f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}",
                "tolerance": TOLERANCE, "search_steps": SEARCH_STEPS, "repeats": REPEATS}
    items = [measure_dem(name, loader, why, arguments.quick, progress) for name, loader, why in DEMS
             if not arguments.quick or name in QUICK_DEMS]
    summary = {"bytes": ratios(items), "payload": ratios(items, "payload")}
    settings["wall_s"] = time.perf_counter() - started
    document = {"settings": settings, "machine": machine(), "versions": versions(PACKAGES), "summary": summary,
                "items": items}
    arguments.out.mkdir(parents=True, exist_ok=True)
    (arguments.out / "dems-results.json").write_text(json.dumps(document, indent=1) + "\n")
    (arguments.out / "dems-results.md").write_text(markdown(items, summary, settings))


if __name__ == "__main__":
    main()
