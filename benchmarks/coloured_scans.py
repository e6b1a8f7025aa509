"""Coloured scans, whole files (issue 32): mzc's dwt2d file with its colour section beside Draco
with its 8-bit colour attribute, shape and colour measured in the same run.

    python benchmarks/coloured_scans.py [--quick] [--out DIR]

Scans (tests/data/public; no face of shared/data is coloured: the 12 PLY faces have no colour
and example.obj names no material, so none is measured):

- ``fuze``: trimesh's fuze bottle, a textured OBJ (``map_Kd`` JPEG); ``mzc.read`` gives each
  vertex its texture colour and ``mzc.slice`` samples the surface's colour at every node.
- ``fran``: VTK's Cyberware scan of a woman's face (``fran_cut``), converted to a textured OBJ
  (benchmarks/fran_obj.py): a real face scan whose colour is a photographic texture.
- ``milk``: PCL's Kinect RGB-D cloud of a milk carton (``rgba``), sliced by ``mzc.slice``.
- ``tum``: a whole RGB-D frame of the TUM RGB-D benchmark (an office desk, 640 x 480, depth
  1.5-9.3 m), made a coloured cloud (``rgbd_cloud``: the camera's default intrinsics, 248,250
  points) and sliced on a spherical grid about the camera (``SLICING``): a frame is one view, and
  its central projection sees every point of it, where planes across a room would not.

mzc through its API only: ``mzc.slice(scan)`` with its defaults but SLICING's (and at COARSER times its
spacing, ``d1``/``d2``: the sampling is a rate setting as Draco's bits are), ``mzc.encode(grid, "dwt2d",
rmse=..., colour_psnr=...)`` at a ladder of RMS targets in % of D (the scan's bounding-box
diagonal), ``mzc.decode`` and ``mzc.triangulate`` (its default: a mesh near the scan's vertex
count, issue 31, whose vertices carry the colours measured): the whole file, shape and colour. Draco
(DracoPy, compression level 10) codes the scan itself (the cloud as a point cloud) with its
colours as an 8-bit attribute at a ladder of position bits, in the same run.

Shape error: the whole-surface RMS distance of benchmarks/objects.py (``errors``: area-weighted
samples each way, point-to-surface; a cloud's points as discs), % of D. Colour error: each
rebuilt vertex's colour against the source colour at the nearest source point (on the
surface of the fuze or fran, its texture at the point's texture coordinates; a point of the milk cloud), RMS
over the three channels in 8-bit levels, and PSNR. Draco's bytes at mzc's shape error are
interpolated log-log on its Pareto front (report.bytes_at).
Writes coloured-scans-results.md and coloured-scans-results.json into --out.
"""

import time
import warnings

from startup import HERE  # first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from contenders import load
from objects import QUICK_SAMPLES, SAMPLES, Surface, errors
from report import benchmark_parser, bytes_at, fmt, pareto, stamped, write_report

PUBLIC = HERE.parent / "tests" / "data" / "public"
SCANS = {"fuze": PUBLIC / "fuze" / "fuze.obj", "fran": PUBLIC / "fran" / "fran.obj",
         "milk": PUBLIC / "pcl-milk" / "milk_color.pcd", "tum": PUBLIC / "tum-rgbd" / "TUM_depth.png"}
SLICING = {"tum": {"projection": "spherical", "center": (0.0, 0.0, 0.0)}}   # the camera's view of its frame
RGBD_CAMERA = (525.0, 525.0, 319.5, 239.5)   # fx, fy, cx, cy in pixels: Open3D's default (PrimeSense) intrinsics
TUM_DEPTH_SCALE = 5000.0                      # the TUM format's depth units a metre
RMSE_LADDER = (0.01, 0.02, 0.035, 0.05, 0.1, 0.2)   # % of D
DRACO_BITS = tuple(range(4, 15))   # 4-6 reach the milk cloud's grid, 0.3% D from its noisy points
COLOUR_PSNRS = (30.0, 36.0)   # dB: the colour section's targets tried at every shape target
COARSER = (2, 4)   # mzc also at these multiples of the default spacing (slice --d1), colour at 30 dB
RATIO_GOAL, COLOUR_RMS_GOAL = 0.25, 12.0   # issue 32: mzc's whole file / Draco's; levels
PACKAGES = ("numpy", "scipy", "constriction", "DracoPy", "Pillow", "trimesh")


def colour_errors(source, points, rebuilt_colours):
    """(RMS in 8-bit levels, PSNR dB) of ``rebuilt_colours`` at ``points`` against the colour of the
    source (an mzc Mesh) at its point nearest each (mzc.ops.colouring.surface_colours: on a mesh's
    surface its texture (or vertex colours mixed barycentrically), in a cloud the nearest point's)."""
    from mzc.ops.colouring import surface_colours

    error = rebuilt_colours.astype(np.float64) - surface_colours(points, source)
    mse = float(np.mean(error ** 2))
    return float(np.sqrt(mse)), (float("inf") if mse == 0 else float(10 * np.log10(255.0 ** 2 / mse)))


def mzc_point(grid, rmse, psnr, mesh, source, samples, coarser=1):
    """One mzc file of ``grid`` (sliced from the scan ``mesh``, ``source`` its Surface): bytes (and the
    colour section's), shape and colour errors, times."""
    import mzc
    from mzc.codecs.dwt2d import compact

    start = time.perf_counter()
    data = mzc.encode(grid, "dwt2d", rmse=rmse * source.diagonal / 100, colour_psnr=psnr)
    encoded = time.perf_counter()
    decoded_grid = mzc.decode(data)
    rebuilt = mzc.triangulate(decoded_grid)
    decoded = time.perf_counter()
    colour_bytes = len(compact.read(data, "mzc")[2])
    rms, peak = colour_errors(mesh, rebuilt.points, rebuilt.colors)
    every_node = mzc.triangulate(decoded_grid, vertices="all")
    return {"contender": "mzc", "setting": rmse, "colour_psnr": psnr, "coarser": coarser, "bytes": len(data),
            "colour_bytes": colour_bytes, "shape_bytes": len(data) - colour_bytes,
            "encode_s": encoded - start, "decode_s": decoded - encoded,
            **errors(source, Surface.of(rebuilt), samples), "colour_rms": rms, "colour_psnr_measured": peak,
            "node_colour_rms": colour_errors(mesh, every_node.points, every_node.colors)[0]}


def draco_point(draco, mesh, bits, source, samples):
    """One Draco file of the scan ``mesh`` (``source`` its Surface) with its colours (8 bits a channel) at
    ``bits`` position bits; its colour bytes are what it has more than the same file without colours."""
    faces = mesh.triangles.astype(np.uint32) if len(mesh.triangles) else None
    points = mesh.points.astype(np.float32)
    start = time.perf_counter()
    data = bytes(draco.encode(points, faces, quantization_bits=bits, compression_level=10, colors=mesh.colors))
    encoded = time.perf_counter()
    colourless = len(draco.encode(points, faces, quantization_bits=bits, compression_level=10))
    decoded = draco.decode(data)
    done = time.perf_counter()
    points = np.asarray(decoded.points, dtype=float)
    triangles = np.asarray([] if faces is None else decoded.faces, dtype=np.int64).reshape(-1, 3)
    rms, peak = colour_errors(mesh, points, np.asarray(decoded.colors, dtype=np.uint8)[:, :3])
    return {"contender": "Draco", "setting": bits, "bytes": len(data), "colour_bytes": len(data) - colourless,
            "encode_s": encoded - start,
            "decode_s": done - encoded, **errors(source, Surface(points, triangles), samples),
            "colour_rms": rms, "colour_psnr_measured": peak}


def rgbd_cloud(depth_path):
    """The coloured cloud (an mzc Mesh of points) of an RGB-D frame: the 16-bit TUM-format depth PNG
    at ``depth_path`` and the colour PNG beside it (``_depth`` named ``_color``), each pixel with a
    depth back-projected through RGBD_CAMERA: x = (u - cx) d / fx, y = -(v - cy) d / fy, z = -d (the
    camera at the origin, looking along -z, y up), its colour the colour image's pixel."""
    from PIL import Image

    from mzc.meshes import Mesh

    with Image.open(depth_path) as depth_image, Image.open(str(depth_path).replace("_depth", "_color")) as colour:
        depth = np.asarray(depth_image, dtype=np.float64) / TUM_DEPTH_SCALE
        rgb = np.asarray(colour.convert("RGB"))
    fx, fy, cx, cy = RGBD_CAMERA
    v, u = np.nonzero(depth > 0)
    d = depth[v, u]
    points = np.column_stack([(u - cx) * d / fx, -(v - cy) * d / fy, -d])
    return Mesh(points, np.empty((0, 3), dtype=np.int64), colors=rgb[v, u])


def read_scan(path):
    """A scan as mzc reads it, or an RGB-D frame's depth PNG as its coloured cloud (``rgbd_cloud``)."""
    import mzc

    return rgbd_cloud(path) if path.suffix == ".png" else mzc.read(str(path))


def run_scan(name, path, samples, quick, missing):
    """Every point of one scan: the uncoded grid (the floor), mzc's ladder at each colour target,
    Draco's ladder."""
    import mzc

    slicing = SLICING.get(name, {})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = read_scan(path)
        source = Surface.of(mesh)
        grid = mzc.slice(mesh, **slicing)
        floor = mzc.triangulate(grid)
        every_node = mzc.triangulate(grid, vertices="all")
    result = {"scan": name, "path": str(path.relative_to(HERE.parent)), "points_in": len(mesh.points),
              "triangles_in": len(mesh.triangles), "diagonal": source.diagonal, "grid": list(grid.shape),
              "valid_nodes": int(grid.valid.sum()), "warnings": sorted({str(w.message) for w in caught}),
              "floor": {**errors(source, Surface.of(floor), samples),
                        **dict(zip(("colour_rms", "colour_psnr_measured"),
                                   colour_errors(mesh, floor.points, floor.colors))),
                        "node_colour_rms": colour_errors(mesh, every_node.points, every_node.colors)[0]},
              "points": []}
    ladder = RMSE_LADDER[1::2] if quick else RMSE_LADDER
    for psnr in COLOUR_PSNRS:
        result["points"] += [mzc_point(grid, rmse, psnr, mesh, source, samples) for rmse in ladder]
    for k in COARSER:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # the same warnings as the default slice's, kept above
            coarse = mzc.slice(mesh, d1=k * grid.d1, d2=k * grid.d2, **slicing)
        result["points"] += [mzc_point(coarse, rmse, COLOUR_PSNRS[0], mesh, source, samples, k) for rmse in ladder]
    draco = load("DracoPy", missing, "Draco (DracoPy)")
    if draco:
        bits = DRACO_BITS[::2] if quick else DRACO_BITS
        result["points"] += [draco_point(draco, mesh, b, source, samples) for b in bits]
    result["comparisons"] = comparisons(result["points"])
    return result


def comparisons(points):
    """Each mzc point beside Draco's bytes at its whole-surface RMS (None outside Draco's range)."""
    front = pareto([p for p in points if p["contender"] == "Draco"], "whole rms")
    rows = []
    for p in (p for p in points if p["contender"] == "mzc"):
        draco = bytes_at(front, p["whole"]["rms"])
        rows.append({"rmse_target": p["setting"], "colour_psnr": p["colour_psnr"], "coarser": p.get("coarser", 1),
                     "whole_rms": p["whole"]["rms"],
                     "mzc_bytes": p["bytes"], "colour_bytes": p["colour_bytes"], "draco_bytes": draco,
                     "ratio": None if draco is None else p["bytes"] / draco, "colour_rms": p["colour_rms"],
                     "goal_met": draco is not None and p["bytes"] / draco <= RATIO_GOAL
                     and p["colour_rms"] <= COLOUR_RMS_GOAL})
    return rows


def markdown(document):
    """The report: method, the scans, each scan's comparison table and Draco's points."""
    lines = ["# Coloured scans: whole files (shape and colour), mzc beside Draco (issue 32)", "",
             f"`python benchmarks/coloured_scans.py{' --quick' if document['quick'] else ''}` at commit "
             f"{document['commit']}, {document['date']}, on {document['machine']}; {document['seconds']:.0f} s.",
             "Package versions: " + ", ".join(f"{k} {v}" for k, v in document["versions"].items()) + ".", "",
             "Shape error: whole-surface RMS distance (benchmarks/objects.py's `errors`, "
             f"{document['samples']} area-weighted samples each way), % of D (the scan's bounding-box diagonal). "
             "Colour error: each rebuilt vertex's colour against the source colour at the nearest source point "
             "(on a textured mesh's surface (fuze, fran), its texture at the point's texture coordinates; of "
             "the milk and tum clouds, the nearest point's), "
             "RMS in 8-bit levels over the three channels, and PSNR; node colour RMS: the same of every node of "
             "the decoded grid (what `triangulate --texture` or `--vertices all` shows: the texture's detail "
             "finer than the scan's triangles, which slice samples at each node). "
             "Draco codes the scan (the cloud as points) "
             "with its colours as an 8-bit attribute, compression level 10; its bytes at mzc's shape error are "
             "interpolated log-log on its Pareto front. mzc's mesh is `mzc.triangulate`'s default, near the "
             "scan's vertex count (issue 31): its vertices carry the colours measured, and the uncoded grid's "
             "row includes that rebuild. mzc's bytes are the whole `.mzw2` file (header, shape "
             f"payload, colour section). Goal: mzc / Draco <= {RATIO_GOAL} at equal shape error with colour RMS "
             f"<= {COLOUR_RMS_GOAL:g} levels.", "",
             "| scan | input | grid (valid nodes) | D | uncoded grid: shape RMS % D | colour RMS | PSNR | "
             "node colour RMS |", "|---|---|---|---|---|---|---|---|"]
    for s in document["scans"]:
        what = f"{s['points_in']} points" + (f", {s['triangles_in']} triangles" if s["triangles_in"] else "")
        lines.append(f"| {s['scan']} | {what} | {s['grid'][0]} x {s['grid'][1]} ({s['valid_nodes']}) | "
                     f"{fmt(s['diagonal'])} | {fmt(s['floor']['whole']['rms'])} | {fmt(s['floor']['colour_rms'])} | "
                     f"{fmt(s['floor']['colour_psnr_measured'])} | {fmt(s['floor']['node_colour_rms'])} |")
    for s in document["scans"]:
        lines += ["", f"## {s['scan']}", "",
                  "| spacing (x default) | rmse target % D | colour PSNR target | shape RMS % D | mzc bytes | "
                  "of them colour | colour RMS | colour PSNR | node colour RMS | Draco bytes at that RMS | "
                  "mzc / Draco | goal met |", "|---" * 12 + "|"]
        measured = {(p["setting"], p["colour_psnr"], p.get("coarser", 1)): p for p in s["points"]
                    if p["contender"] == "mzc"}
        for c in s["comparisons"]:
            p = measured[(c["rmse_target"], c["colour_psnr"], c["coarser"])]
            lines.append(f"| {c['coarser']} | {c['rmse_target']} | {c['colour_psnr']:g} | {fmt(c['whole_rms'])} | "
                         f"{c['mzc_bytes']} | "
                         f"{c['colour_bytes']} | {fmt(c['colour_rms'])} | {fmt(p['colour_psnr_measured'])} | "
                         f"{fmt(p['node_colour_rms'])} | "
                         f"{'n/a (outside Draco range)' if c['draco_bytes'] is None else round(c['draco_bytes'])} | "
                         f"{'n/a' if c['ratio'] is None else fmt(c['ratio'])} | {'yes' if c['goal_met'] else 'no'} |")
        for label, rows in (("default spacing", [c for c in s["comparisons"] if c["coarser"] == 1]),
                            ("coarser spacings", [c for c in s["comparisons"] if c["coarser"] != 1])):
            met = [c for c in rows if c["goal_met"]]
            where = f", from {fmt(min(c['whole_rms'] for c in met))} % D" if met else ""
            lines += ["", f"Goal (mzc / Draco <= {RATIO_GOAL} at equal shape RMS, colour RMS <= {COLOUR_RMS_GOAL:g}), "
                      f"{label}: met at {len(met)} of {len(rows)} points{where}."]
        lines += ["", "Draco's points (of them colour: its bytes beyond the same file without colours):", "",
                  "| bits | bytes | of them colour | shape RMS % D | colour RMS | colour PSNR |", "|---" * 6 + "|"]
        lines += [f"| {p['setting']} | {p['bytes']} | {p['colour_bytes']} | {fmt(p['whole']['rms'])} | "
                  f"{fmt(p['colour_rms'])} | "
                  f"{fmt(p['colour_psnr_measured'])} |" for p in s["points"] if p["contender"] == "Draco"]
        if s["warnings"]:
            lines += ["", "Warnings while reading and slicing: " + "; ".join(s["warnings"])]
    if document["missing"]:
        lines += ["", "Missing: " + "; ".join(f"{k} ({v})" for k, v in document["missing"].items())]
    return "\n".join(lines) + "\n"


def main():
    args = benchmark_parser(__doc__, "two rmse targets, every other Draco setting, fewer samples").parse_args()
    started = time.perf_counter()
    samples = QUICK_SAMPLES if args.quick else SAMPLES
    missing = {}
    scans = [run_scan(name, path, samples, args.quick, missing) for name, path in SCANS.items() if path.is_file()]
    document = stamped(PACKAGES, started, quick=args.quick, samples=samples, missing=missing, scans=scans)
    write_report(args.out, "coloured-scans", document, markdown)


if __name__ == "__main__":
    main()
