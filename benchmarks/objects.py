"""Whole-object benchmark (issue 28): mzc beside Draco over the whole surface of closed and
multi-part objects, and of the faces.

    python benchmarks/objects.py [--quick] [--out DIR] [--workers N]

mzc is measured through its public API only: ``mzc.slice(mesh)`` with its defaults, the grid
rebuilt uncoded (``mzc.triangulate``, the lossless floor) and coded by ``mzc.encode(grid,
"dwt2d", rmse=...)`` at a ladder of RMS targets in % of D (the original's bounding-box
diagonal), each decoded by ``mzc.decode`` and ``mzc.triangulate``. Whatever ``mzc.slice``
makes by default (one grid today, several charts when issue 28 lands) is measured as it
is, with no change here. Draco codes the original mesh (the armadillo as a point cloud) at
6..14 quantisation bits in the same run.

Every rebuild is measured against the original over the whole surface (``errors``):
symmetric point-to-surface distance of area-weighted samples each way, RMS, mean and
Hausdorff in % of D, and the coverage, the share of the original's area within NEAR % D of
the rebuild. Writes objects-results.md, objects-results.json and objects-rd.png into --out
(default: this directory). Progress goes to stderr only when it is a terminal.
"""

import datetime
import functools
import json
import os
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import startup  # noqa: F401 - first: one thread per process, set before numpy loads

# isort: split
import numpy as np
from contenders import Contender, draco_contender, load
from corpora import DATA, FACES, OBJECTS, mesh_files
from rd import TARGETS
from report import (
    benchmark_parser,
    bytes_at,
    curves_of,
    draw_curves,
    fmt,
    git_commit,
    item_ratios,
    machine,
    measure_ratios,
    pareto,
    terminal_progress,
    versions,
)

from mzc.ops.slicing import FLOOR_COVERAGE as COVERAGE
from mzc.ops.slicing import FLOOR_HAUSDORFF, FLOOR_RMS
from mzc.ops.slicing import FLOOR_NEAR as NEAR

GROUPS = {"armadillo": "scanned", "dragon": "scanned", "hand": "scanned", "ogre": "modelled",
          "cycloidal": "CAD", "featuretype": "CAD"}   # an object not named here is "other"
QUICK_OBJECTS = ("armadillo", "hand")   # the cloud and the smallest closed scan
QUICK_FACE = "f18"
# dwt2d's rmse targets, % of D: dense where the faces cross 0.05 mm (about 0.017% D) and the objects' range
RMSE_LADDER = (0.003, 0.005, 0.0075, 0.01, 0.015, 0.02, 0.025, 0.035, 0.05, 0.07, 0.1, 0.15, 0.25, 0.5)
DRACO_BITS = tuple(range(6, 15))   # the issue's 7..14, and 6, which reaches above 0.1% D
PERCENT_TARGETS = (0.02, 0.05, 0.1)   # whole-surface RMS, % of D, of the ratio tables
ISSUE_RANGE = (0.05, 0.1)   # % of D: where Draco must need >= 4x mzc's bytes on the scanned objects
MM_TARGETS = TARGETS["whole rms"]   # the faces' targets of rd.py, mm
MISSED = 1.0   # % of D: original area this far from the rebuild is surface the rebuild does not have
SAMPLES, QUICK_SAMPLES = 100_000, 20_000   # per direction; see the sample-count check of a full run
SEED, CHECK_SEEDS = 0, 5
REPEATS, QUICK_REPEATS = 3, 1   # timing runs (median)
TIMING_RMSE, TIMING_BITS = 0.05, 10   # the settings of the speed table: % of D, Draco's bits
DISC_NEIGHBOUR = 3    # a cloud point's disc reaches to its 3rd nearest neighbour
DISC_CANDIDATES = 8   # a sample's nearest disc is sought among the discs of its 8 nearest points
SPEED_OBJECT, SPEED_VERTICES = "ogre", 100_000
EDGE_NODES = 4   # a node within this many 4-neighbour steps of an invalid one stands at a chart's edge
CALIBRATION_OBJECT = "hand"   # a closed mesh whose own vertices, as a cloud, calibrate the cloud measure
# Issue 28's figures
# the floors (% of D, % of D, and the share of the area within NEAR % of D) are the ones mzc.slice
# refines a low-poly mesh's charts to meet: one home, mzc.ops.slicing
SCANNED_RATIO, FACE_RATIO = 4.0, 13.0   # Draco bytes / mzc bytes
ENCODE_SECONDS, DECODE_SECONDS = 3.0, 1.0   # slice + encode, decode + triangulate, 100k vertices
MZC, DRACO = "mzc dwt2d --rmse", "Draco"
MZC_SURFACE = "mzc encode SURFACE --rmse"   # the surface given to encode: its spacing chosen by the target
SURFACE_LADDER = (0.015, 0.025, 0.035, 0.05, 0.07, 0.1, 0.15, 0.25)   # whole-surface RMS targets, % of D


# --------------------------------------------------------------------------- surfaces and distances


@dataclass
class Surface:
    """A surface to measure: a mesh (triangles), an oriented cloud (normals given: each point a
    small disc, ``disc_distances``) or bare points (a point codec's decoded cloud)."""

    points: np.ndarray
    triangles: np.ndarray   # (0, 3) for a cloud
    normals: np.ndarray | None = None

    @classmethod
    def of(cls, mesh):
        """The Surface of an mzc Mesh (a cloud's normals kept, made unit) or a (points, triangles) pair."""
        points, triangles = (mesh.points, mesh.triangles) if hasattr(mesh, "points") else mesh
        normals = getattr(mesh, "normals", None)
        if normals is not None and len(triangles) == 0:
            normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        return cls(np.asarray(points, dtype=float), np.asarray(triangles, dtype=np.int64).reshape(-1, 3),
                   normals if len(triangles) == 0 else None)

    @functools.cached_property
    def diagonal(self):
        """D, the length of the bounding box's diagonal: the unit of every error."""
        return float(np.linalg.norm(np.ptp(self.points, axis=0)))

    @functools.cached_property
    def tree(self):
        from scipy.spatial import cKDTree

        return cKDTree(self.points)

    @functools.cached_property
    def radius(self):
        """Each point's disc radius: the distance to its DISC_NEIGHBOUR-th nearest neighbour,
        so that the discs of an evenly spread cloud overlap and cover its surface."""
        return self.tree.query(self.points, k=DISC_NEIGHBOUR + 1)[0][:, -1]


def samples_on(surface, count, rng):
    """``count`` points standing for equal shares of ``surface``'s area: drawn by area on a mesh
    (``sample_surface``, as ``surface_distance_parts`` draws them), uniformly among a cloud's
    points (a scan's points are about evenly spread over its area)."""
    from mzc.measure.metrics import sample_surface

    if len(surface.triangles):
        return sample_surface(surface.points, surface.triangles, count, rng)[0]
    return surface.points[rng.integers(0, len(surface.points), count)]


def distance_to(surface, samples):
    """Each sample's distance to ``surface``: exact to a mesh's triangles, to the nearest disc of
    an oriented cloud, to the nearest point of bare points."""
    from mzc.measure.metrics import distance_to_mesh

    if len(surface.triangles):
        return distance_to_mesh(samples, surface.points, surface.triangles)
    if surface.normals is not None:
        return disc_distances(surface, samples)
    return surface.tree.query(samples)[0]


def disc_distances(cloud, samples):
    """Distance from each sample to the nearest disc of an oriented cloud (through each point,
    across its normal, of its ``radius``), sought among the discs of the DISC_CANDIDATES nearest
    points: the distance to the cloud's surface, which the distance to its nearest point
    overstates by up to half the point spacing."""
    _, nearest = cloud.tree.query(samples, k=DISC_CANDIDATES)
    offset = samples[:, None, :] - cloud.points[nearest]
    along = np.einsum("skj,skj->sk", offset, cloud.normals[nearest])
    across = np.sqrt(np.maximum(np.einsum("skj,skj->sk", offset, offset) - along**2, 0.0))
    beyond = np.maximum(across - cloud.radius[nearest], 0.0)
    return np.sqrt(along**2 + beyond**2).min(axis=1)


def directed(original, rebuild, samples, seed):
    """(original -> rebuild, rebuild -> original) distances of ``samples`` points each way, drawn
    from one generator, the original's first: on two meshes the draws and distances of
    ``surface_distance_parts``, so the same figures."""
    rng = np.random.default_rng(seed)
    there = samples_on(original, samples, rng)
    back = samples_on(rebuild, samples, rng)
    return distance_to(rebuild, there), distance_to(original, back)


def errors(original, rebuild, samples, seed=SEED):
    """The whole-surface error of ``rebuild``: RMS, mean and Hausdorff each way and together
    (``distance_summary``) in % of D; the coverage (% of the original's area within NEAR % D of
    the rebuild), the missed share (% of it beyond MISSED % D), the spurious share (% of the
    rebuild's area beyond NEAR % D of the original) and the far share (% of the squared
    distance carried by samples beyond NEAR % D)."""
    from mzc.measure.metrics import distance_summary

    there, back = directed(original, rebuild, samples, seed)
    there, back = (d * (100 / original.diagonal) for d in (there, back))   # in % of D from here on
    squares = np.concatenate([there, back]) ** 2
    far = squares[squares > NEAR**2].sum() / squares.sum() if squares.sum() > 0 else 0.0
    return {"whole": distance_summary(there, back), "coverage": 100 * float(np.mean(there <= NEAR)),
            "missed": 100 * float(np.mean(there > MISSED)), "spurious": 100 * float(np.mean(back > NEAR)),
            "far_share": 100 * float(far)}


# --------------------------------------------------------------------------- inputs


def item_specs(quick):
    """(group, name, path) of every item: the objects, then the faces; [] for a missing folder."""
    objects = mesh_files(OBJECTS)
    faces = mesh_files(FACES)
    if quick:
        objects = [p for p in objects if p.stem in QUICK_OBJECTS]
        faces = [p for p in faces if p.stem == QUICK_FACE]
    return [(GROUPS.get(p.stem, "other"), p.stem, str(p)) for p in objects] + \
        [("faces", p.stem, str(p)) for p in faces]


def input_facts(surface):
    """What the slicer meets in an input: its box, vertices and distinct positions; for a cloud
    the 5th, 50th and 95th percentiles of its point spacing (% of D); for a mesh the zero-area
    triangles and, with equal positions welded, the edges on one triangle (boundary), on more
    than two (non-manifold) and the connected parts."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from mzc.measure.metrics import triangle_areas

    distinct, inverse = np.unique(surface.points, axis=0, return_inverse=True)
    facts = {"box": np.ptp(surface.points, axis=0).tolist(), "vertices": len(surface.points),
             "distinct_positions": len(distinct), "triangles": len(surface.triangles),
             "cloud": not len(surface.triangles), "normals": surface.normals is not None}
    if facts["cloud"]:
        spacing = surface.tree.query(surface.points, k=2)[0][:, 1] * (100 / surface.diagonal)
        return {**facts, "spacing": np.percentile(spacing, [5, 50, 95]).tolist()}
    welded = inverse.reshape(-1)[surface.triangles]
    edges = np.sort(welded[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(distinct),) * 2)
    labels = connected_components(graph, directed=False)[1]
    return {**facts, "zero_area_triangles": int(np.sum(triangle_areas(surface.points, surface.triangles) == 0)),
            "boundary_edges": int(np.sum(counts == 1)), "non_manifold_edges": int(np.sum(counts > 2)),
            "parts": len(np.unique(labels[np.unique(welded)]))}


def grid_fields(grid):
    """What the default slice made, as far as its type says: its type, and the projection, shape,
    spacings and valid nodes of a ZGrid (another kind of grid keeps the fields it has)."""
    fields = {"type": type(grid).__name__}
    for name in ("projection", "d1", "d2"):
        if hasattr(grid, name):
            fields[name] = getattr(grid, name)
    if hasattr(grid, "shape"):
        fields["shape"] = list(grid.shape)
    if getattr(grid, "valid", None) is not None:
        fields["nodes"] = int(np.sum(grid.valid))
    return fields


def vertex_normals(points, triangles):
    """Unit vertex normals of a mesh: the sum of its triangles' area-weighted normals at each vertex."""
    corners = points[triangles]
    faces = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals = np.column_stack([np.bincount(triangles.ravel(), weights=np.repeat(faces[:, k], 3),
                                           minlength=len(points)) for k in range(3)])
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def with_vertices(surface, count):
    """``surface`` with its largest triangles split in three at their centroids until it has
    ``count`` vertices: the same surface (each centroid lies on its triangle), more vertices."""
    from mzc.measure.metrics import triangle_areas

    extra = count - len(surface.points)
    split = np.argsort(-triangle_areas(surface.points, surface.triangles), kind="stable")[:extra]
    a, b, c = surface.triangles[split].T
    centre = len(surface.points) + np.arange(len(split))
    triangles = np.vstack([np.delete(surface.triangles, split, axis=0), np.column_stack([a, b, centre]),
                           np.column_stack([b, c, centre]), np.column_stack([c, a, centre])])
    return Surface(np.vstack([surface.points, surface.points[surface.triangles[split]].mean(axis=1)]), triangles)


# --------------------------------------------------------------------------- one item


def rebuilt_grid(data):
    """The mesh of the grid an mzc file holds, one vertex at every node: what the file holds."""
    import mzc

    rebuilt = mzc.triangulate(mzc.decode(data), vertices="all")
    return rebuilt.points, rebuilt.triangles


def mzc_contender(ladder):
    """mzc through its API: the default slice's grid coded by dwt2d at RMS targets in % of D
    (unit = D / 100), decoded and triangulated."""
    import mzc

    return Contender(MZC, "mzc", "grid", "rmse % D", ladder, lambda grid, s, u: mzc.encode(grid, "dwt2d", rmse=s * u),
                     rebuilt_grid, scaled=True)


def mzc_surface_contender(ladder):
    """mzc given the surface itself: ``mzc.encode(mesh, rmse=...)`` cuts it at the spacing that
    codes it within that RMS over its whole surface in the fewest bytes (mzc.targets), % of D."""
    import mzc

    return Contender(MZC_SURFACE, "mzc", "surface", "whole rmse % D", ladder,
                     lambda mesh, s, u: mzc.encode(mesh, "dwt2d", rmse=s * u), rebuilt_grid, scaled=True)


def contenders_for(quick):
    """(mzc's and Draco's contenders, {missing: why}), ladders thinned to every other setting with --quick."""
    missing = {}
    ladders = (RMSE_LADDER, SURFACE_LADDER, DRACO_BITS)
    ladders = [ladder[::2] for ladder in ladders] if quick else ladders
    table = [mzc_contender(ladders[0]), mzc_surface_contender(ladders[1])]
    draco = load("DracoPy", missing, "Draco (DracoPy)")
    if draco:
        table.append(draco_contender(draco, ladders[2]))
    return table, missing


def run_point(contender, source, setting, unit, original, samples):
    """One rate-distortion point: encode, decode, measure; and the rebuild, for the sample check."""
    start = time.perf_counter()
    data = contender.encode(source, setting, unit)
    encoded = time.perf_counter()
    rebuild = Surface.of(contender.decode(data))
    done = time.perf_counter()
    point = {"contender": contender.name, "family": contender.family, "setting": setting, "bytes": len(data),
             "bits_per_vertex": 8 * len(data) / len(original.points), "encode_s": encoded - start,
             "decode_s": done - encoded, **errors(original, rebuild, samples)}
    return point, rebuild


def run_item(job):
    """Every point of one item: the lossless floor (the default grid triangulated uncoded), the
    dwt2d ladder and Draco's, and with ``check`` the sample-count check. Failures are recorded,
    not raised; warnings (the slicer's own about what its grid meets) are kept."""
    import mzc

    (group, name, path), samples, quick, check = job
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = mzc.read(path)
        original = Surface.of(mesh)
        grid = mzc.slice(mesh)
        floor_rebuild = Surface.of(mzc.triangulate(grid, vertices="all"))
        result = {"corpus": group, "group": group, "item": name, "path": str(Path(path).relative_to(DATA)),
                  "diagonal": original.diagonal, "unit": 1.0, "facts": input_facts(original),
                  "grid": grid_fields(grid), "samples": samples,
                  "floor": errors(original, floor_rebuild, samples), "points": [], "failures": [], "check": []}
        table, result["missing"] = contenders_for(quick)
        sources = {"grid": grid, "surface": mesh, "mesh": (original.points, original.triangles)}
        kept = {"floor": floor_rebuild}
        for contender in table:
            for setting in contender.ladder:
                try:
                    point, rebuild = run_point(contender, sources[contender.source], setting,
                                               original.diagonal / 100, original, samples)
                except Exception as error:  # noqa: BLE001 - one failed setting must not stop the run
                    result["failures"].append({"contender": contender.name, "setting": setting,
                                               "error": f"{type(error).__name__}: {error}"})
                    continue
                result["points"].append(point)
                if setting == {MZC: TIMING_RMSE, DRACO: TIMING_BITS}.get(contender.name):
                    kept[f"{contender.name} at {setting} {'% D' if contender.family == 'mzc' else 'bits'}"] = rebuild
        if group != "faces":
            result["sites"] = error_sites(grid, original.diagonal)
        if check:
            result["check"] = sample_check(original, kept, samples)
    result["warnings"] = sorted({str(w.message) for w in caught})
    result["wall_s"] = time.perf_counter() - started
    return result


def error_sites(grid, diagonal):
    """Where the bytes and the error of the grid's file at TIMING_RMSE % D go: its bytes and its
    mask's (``anatomy.parts``), the valid nodes, the share of them within EDGE_NODES of a chart's
    edge and the share of the squared surface error they carry. The error is the encoder's own
    estimate at the nodes (``Prepared.surface_terms``: each value error weighted by its node's
    lean and area, as ``--rmse`` aims at it), which places it on the grid."""
    from scipy import ndimage

    import mzc
    from mzc.codecs.dwt2d import DEFAULT_WAVELET, SLOPE_LIMIT, Prepared
    from mzc.codecs.dwt2d.anatomy import parts

    data = mzc.encode(grid, "dwt2d", rmse=TIMING_RMSE * diagonal / 100)
    valid = grid.valid
    heights, weight, _ = Prepared(grid, DEFAULT_WAVELET, None, SLOPE_LIMIT).surface_terms
    squared = (mzc.decode(data).z[valid] - heights) ** 2 * weight
    steps = ndimage.distance_transform_cdt(np.pad(valid, 1), metric="taxicab")[1:-1, 1:-1][valid]
    edge = steps <= EDGE_NODES
    return {"rmse": TIMING_RMSE, "bytes": len(data), "mask_bytes": parts(data)["mask"], "nodes": int(valid.sum()),
            "edge_nodes": float(np.mean(edge)), "edge_error": float(squared[edge].sum() / max(squared.sum(), 1e-300))}


def sample_check(original, rebuilds, samples):
    """RMS, Hausdorff and coverage of each rebuild at CHECK_SEEDS seeds: how much the figures move
    with the draw of the samples at this count."""
    rows = []
    for what, rebuild in rebuilds.items():
        runs = [errors(original, rebuild, samples, seed) for seed in range(CHECK_SEEDS)]
        rows.append({"what": what, "samples": samples, "rms": [r["whole"]["rms"] for r in runs],
                     "hausdorff": [r["whole"]["hausdorff"] for r in runs], "coverage": [r["coverage"] for r in runs]})
    return rows


# --------------------------------------------------------------------------- speed


def timed(work, repeats):
    """({"wall_s", "cpu_s"} medians over ``repeats`` calls of ``work``, its last result). CPU time
    is the process's, every thread included."""
    walls, cpus = [], []
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        result = work()
        walls.append(time.perf_counter() - wall)
        cpus.append(time.process_time() - cpu)
    return {"wall_s": float(np.median(walls)), "cpu_s": float(np.median(cpus))}, result


def speed_of(mesh, repeats):
    """Slice + encode (dwt2d at TIMING_RMSE % D) and decode + triangulate of an mzc Mesh through
    the API, and Draco's encode and decode at TIMING_BITS of the same surface, in this process alone."""
    import mzc

    surface = Surface.of(mesh)
    rmse = TIMING_RMSE * surface.diagonal / 100
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        encode, (grid, data) = timed(lambda: sliced_and_encoded(mesh, rmse), repeats)
        decode, _ = timed(lambda: mzc.triangulate(mzc.decode(data)), repeats)
    row = {"vertices": len(surface.points), "triangles": len(surface.triangles), "grid": grid_fields(grid),
           "bytes": len(data), "slice_encode": encode, "decode_triangulate": decode}
    draco = load("DracoPy", {}, "Draco")
    if draco:
        contender = draco_contender(draco)
        pair = (surface.points, surface.triangles)
        row["draco_encode"], packed = timed(lambda: contender.encode(pair, TIMING_BITS, 1.0), repeats)
        row["draco_decode"], _ = timed(lambda: contender.decode(packed), repeats)
        row["draco_bytes"] = len(packed)
    return row


def sliced_and_encoded(mesh, rmse):
    """(the default grid of ``mesh``, its dwt2d bytes at ``rmse``): the work timed as slice + encode."""
    import mzc

    grid = mzc.slice(mesh)
    return grid, mzc.encode(grid, "dwt2d", rmse=rmse)


def speeds(specs, repeats):
    """{object: speed_of} for every object of the run, and the SPEED_OBJECT brought to
    SPEED_VERTICES vertices (``with_vertices``) when it is there."""
    import mzc

    rows = {}
    for group, name, path in specs:
        if group == "faces":
            continue
        mesh = mzc.read(path)
        rows[name] = speed_of(mesh, repeats)
        if name == SPEED_OBJECT and len(mesh.points) < SPEED_VERTICES:
            bigger = with_vertices(Surface.of(mesh), SPEED_VERTICES)
            rows[f"{name} at {SPEED_VERTICES:,} vertices"] = speed_of(mzc.Mesh(bigger.points, bigger.triangles),
                                                                       repeats)
    return rows


def cloud_calibration(specs, samples):
    """The cloud measure's own floor: the CALIBRATION_OBJECT's mesh measured against its own
    vertices as an oriented cloud (area-weighted vertex normals), by disc and by nearest point,
    in % of D; None when that object is not in the run."""
    import mzc

    path = next((p for _, name, p in specs if name == CALIBRATION_OBJECT), None)
    if path is None:
        return None
    mesh = Surface.of(mzc.read(path))
    cloud = Surface(mesh.points, np.zeros((0, 3), dtype=np.int64), vertex_normals(mesh.points, mesh.triangles))
    there = samples_on(mesh, samples, np.random.default_rng(SEED))
    scale = 100 / mesh.diagonal
    by_disc, by_point = disc_distances(cloud, there) * scale, cloud.tree.query(there)[0] * scale
    return {"object": CALIBRATION_OBJECT, "samples": samples,
            "disc_rms": float(np.sqrt(np.mean(by_disc**2))), "disc_hausdorff": float(by_disc.max()),
            "point_rms": float(np.sqrt(np.mean(by_point**2))), "point_hausdorff": float(by_point.max()),
            "spacing": float(np.median(cloud.tree.query(cloud.points, k=2)[0][:, 1]) * scale)}


# --------------------------------------------------------------------------- figures


def errors_of(item, family):
    """Whole-surface RMS (% of D) of the item's points of one family (mzc or peer)."""
    return [p["whole"]["rms"] for p in item["points"] if p["family"] == family]


def front_bytes(item, family, target):
    """Bytes of the family's Pareto front at ``target`` % D (mzc's cheapest setting when it is
    already better; None outside the front)."""
    front = pareto([p for p in item["points"] if p["family"] == family], "whole rms")
    return bytes_at(front, target, below_cheapest=family == "mzc")


def draco_ratios(item, targets, unit=1.0):
    """[Draco bytes / mzc bytes, or None, per target] at equal whole-surface RMS (``item_ratios``);
    ``unit`` turns the targets into % of D (100 / D for targets in mm)."""
    return item_ratios({**item, "unit": unit}, targets, "whole rms").get(DRACO, [None] * len(targets))


def ratio_note(item, target):
    """Why there is no ratio at ``target`` % D: which front stops short of it ('' when both reach it)."""
    mzc, draco = errors_of(item, "mzc"), errors_of(item, "peer")
    if not mzc or min(mzc) > target:
        best = f"{min(mzc):.3g}% D" if mzc else "none"
        return f"mzc's lowest whole-surface RMS is {best} (uncoded floor {item['floor']['whole']['rms']:.3g}% D)"
    if not draco:
        return "no Draco point"
    if not min(draco) <= target <= max(draco):
        return f"Draco spans {min(draco):.3g}-{max(draco):.3g}% D"
    return ""


def smallest_ratio(item):
    """(the smallest Draco / mzc ratio over ISSUE_RANGE, or None, and why None): whether mzc is
    ever larger than Draco there, on 11 log-spaced errors."""
    targets = np.geomspace(*ISSUE_RANGE, 11)
    ratios = draco_ratios(item, targets)
    if any(r is None for r in ratios):
        target = next(t for t, r in zip(targets, ratios) if r is None)
        return None, ratio_note(item, target)
    return float(min(ratios)), ""


def site_words(item):
    """Where an object's file at TIMING_RMSE goes (``error_sites``), in words: the measured reason
    behind its ratio to Draco."""
    sites = item.get("sites")
    if not sites:
        return ""
    nodes, draco = sites["nodes"], front_bytes(item, "peer", sites["rmse"])
    beside = f", Draco's whole file {draco:,.0f} B at {sites['rmse']}% D" if draco else ""
    return (f"{item['item']} at --rmse {sites['rmse']}% D: mask {sites['mask_bytes']:,} of {sites['bytes']:,} B"
            f"{beside}; {nodes:,} valid nodes, {nodes / item['facts']['distinct_positions']:.1f} a distinct "
            f"vertex; the {100 * sites['edge_nodes']:.0f}% within {EDGE_NODES} nodes of a chart's edge carry "
            f"{100 * sites['edge_error']:.0f}% of the squared error")


def face_unit(item):
    """% of D per mm of a face (faces are in mm)."""
    return 100 / item["diagonal"]


def summaries(results):
    """{"% D": {group: {peer: [(geometric mean, items)]}}, "mm": the faces' at MM_TARGETS}."""
    faces = [{**r, "unit": face_unit(r)} for r in results if r["group"] == "faces"]
    return {"% D": measure_ratios(results, PERCENT_TARGETS, "whole rms"),
            "mm": measure_ratios(faces, MM_TARGETS, "whole rms")}


def slice_warnings(item):
    """The slicer's own warnings about the area its grid meets, without their advice."""
    return [w.split(";")[0] for w in item["warnings"] if "meets only" in w]


def floor_reasons(item):
    """{figure: the measured reason the floor misses it}: where the squared distance lies (the
    area the rebuild misses or adds), which direction the largest distance goes, and how far
    from the rebuild the uncovered area lies."""
    floor = item["floor"]
    whole, reached, missed = floor["whole"], floor["coverage"], floor["missed"]
    return {"rms": f"samples beyond {NEAR}% D carry {floor['far_share']:.0f}% of the squared distance: "
                   f"{100 - reached:.1f}% of the area is beyond {NEAR}% D of the rebuild ({missed:.1f}% beyond "
                   f"{MISSED}% D), {floor['spurious']:.1f}% of the rebuild's beyond {NEAR}% D of the original"
                   + "".join(f"; slice: {w}" for w in slice_warnings(item)),
            "hausdorff": f"largest distance original -> rebuild {whole['a_to_b_hausdorff']:.3g}% D, "
                         f"rebuild -> original {whole['b_to_a_hausdorff']:.3g}% D",
            "coverage": f"{100 - reached - missed:.1f}% of the area lies {NEAR}-{MISSED}% D from the rebuild "
                        f"(coarse), {missed:.1f}% beyond {MISSED}% D (not there)"}


def face_reason(faces):
    """Why the faces' ratio at MM_TARGETS[0] is what it is: its lowest face, and how much of the
    target the default grids' uncoded floors take."""
    ratios = {r["item"]: draco_ratios(r, MM_TARGETS[:1], face_unit(r))[0] for r in faces}
    lowest = min((name for name in ratios if ratios[name] is not None), key=ratios.get, default=None)
    floors = [r["floor"]["whole"]["rms"] / face_unit(r) for r in faces]
    spacing = np.median([r["grid"].get("d1", np.nan) for r in faces])
    low = f"lowest {lowest} {ratios[lowest]:.3g}x; " if lowest else "no face reaches it; "
    return (low + f"the default grids (median spacing {spacing:.2f} mm; rd.py slices at 0.5 mm) leave uncoded "
            f"floors of {min(floors):.3f}-{max(floors):.3f} mm RMS of the {MM_TARGETS[0]} mm")


def verdict(figure, item, measured, target, ok, reason=""):
    """One row of the verdict table; ``ok`` None for a figure that could not be measured."""
    return {"figure": figure, "item": item, "measured": measured, "target": target, "ok": ok,
            "reason": "" if ok else reason}


def verdicts(results, ratios, speed):
    """Every issue-28 figure against this run: floors and coverage per object, the scanned
    objects' ratios, the faces' 13x, and the 100k-vertex timings."""
    rows = []
    objects = [r for r in results if r["group"] != "faces"]
    for item in objects:
        floor, why = item["floor"], floor_reasons(item)
        rows += [verdict("floor RMS", item["item"], f"{floor['whole']['rms']:.3g}% D", f"<= {FLOOR_RMS}% D",
                         floor["whole"]["rms"] <= FLOOR_RMS, why["rms"]),
                 verdict("floor Hausdorff", item["item"], f"{floor['whole']['hausdorff']:.3g}% D",
                         f"<= {FLOOR_HAUSDORFF}% D", floor["whole"]["hausdorff"] <= FLOOR_HAUSDORFF, why["hausdorff"]),
                 verdict(f"area within {NEAR}% D", item["item"], f"{floor['coverage']:.1f}%", f">= {COVERAGE}%",
                         floor["coverage"] >= COVERAGE, why["coverage"])]
    scanned = [r for r in objects if r["group"] == "scanned"]
    for k, target in enumerate(PERCENT_TARGETS):
        if target not in ISSUE_RANGE or not scanned:
            continue
        mean, count = ratios["% D"].get("scanned", {}).get(DRACO, [(None, 0)] * len(PERCENT_TARGETS))[k]
        missing = [f"{r['item']}: {ratio_note(r, target)}" for r in scanned if draco_ratios(r, (target,))[0] is None]
        rows.append(verdict(f"Draco / mzc at {target}% D, scanned (geometric mean)", f"{count} of {len(scanned)}",
                            fmt(mean), f">= {SCANNED_RATIO:g}",
                            None if count < len(scanned) else mean >= SCANNED_RATIO,
                            "; ".join(missing) or "; ".join([f"{mean:.3g}x", *map(site_words, scanned)])))
    for item in scanned:
        smallest, why = smallest_ratio(item)
        rows.append(verdict(f"mzc never larger than Draco at {ISSUE_RANGE[0]}-{ISSUE_RANGE[1]}% D", item["item"],
                            fmt(smallest), ">= 1", None if smallest is None else smallest >= 1,
                            why or f"Draco / mzc falls to {fmt(smallest)}; {site_words(item)}"))
    faces = [r for r in results if r["group"] == "faces"]
    if faces:
        mean, count = ratios["mm"].get("faces", {}).get(DRACO, [(None, 0)])[0]
        rows.append(verdict(f"faces: Draco / mzc at {MM_TARGETS[0]} mm (geometric mean)", f"{count} faces",
                            fmt(mean), f">= {FACE_RATIO:g}", None if mean is None else mean >= FACE_RATIO,
                            face_reason(faces)))
    big = next((row for name, row in speed.items() if row["vertices"] >= SPEED_VERTICES), None)
    if big:
        for stage, limit in (("slice_encode", ENCODE_SECONDS), ("decode_triangulate", DECODE_SECONDS)):
            seconds = big[stage]["wall_s"]
            rows.append(verdict(f"{stage.replace('_', ' + ')}, {big['vertices']:,} vertices", "wall time",
                                f"{seconds:.2f} s", f"<= {limit:g} s", seconds <= limit,
                                f"{seconds:.2f} s of wall time ({big[stage]['cpu_s']:.2f} s CPU)"))
    return rows


# --------------------------------------------------------------------------- report


def pct(value, digits=3):
    return "n/a" if value is None else f"{value:.{digits}g}"


def kilobytes(value):
    return "n/a" if value is None else f"{value / 1000:.1f}"


def markdown(document):
    """The report text."""
    settings = document["settings"]
    results = document["items"]
    objects = [r for r in results if r["group"] != "faces"]
    faces = [r for r in results if r["group"] == "faces"]
    lines = [
        "# mzc whole-object benchmark (issue 28)", "",
        f"Generated {document['generated']} by `python benchmarks/objects.py{' --quick' if settings['quick'] else ''}` "
        f"on {document['machine']}, commit {document['commit']}; {settings['workers']} worker processes, one "
        f"thread each; total wall time {settings['wall_s']:.0f} s.", "",
        "Package versions: " + ", ".join(f"{k} {v}" for k, v in document["versions"].items()) + ".", "",
        *verdict_section(document["verdicts"]),
        *method_section(settings, document["calibration"]),
        *item_section("Objects", objects, PERCENT_TARGETS[1:]),
        *sites_section(objects),
        *ratio_section(document["summary"], list(dict.fromkeys(r["group"] for r in results))),
        *item_section("Faces", faces, PERCENT_TARGETS, mm=True),
        *speed_section(document["speed"], settings["load_average"]),
        *check_section(objects),
        *calibration_section(document["calibration"]),
        *facts_section(results),
        *problems_section(results, document["missing"]),
        "", "Every point (bytes, RMS, mean and Hausdorff each way and together, coverage, in % of D) is in "
        "`objects-results.json`; the curves are in `objects-rd.png`.",
    ]
    return "\n".join(lines) + "\n"


def verdict_section(rows):
    lines = ["## Issue 28's figures on this run", "",
             "| figure | item | measured | target | verdict | measured reason |", "|---|---|---|---|---|---|"]
    for r in rows:
        state = {True: "pass", False: "FAIL", None: "n/a"}[r["ok"]]
        lines.append(f"| {r['figure']} | {r['item']} | {r['measured']} | {r['target']} | {state} | {r['reason']} |")
    return lines + [""]


def method_section(settings, calibration):
    disc = (f" On {calibration['object']}'s mesh against its own vertices as such a cloud (area-weighted vertex "
            f"normals, median spacing {calibration['spacing']:.2f}% D) the disc distance is RMS "
            f"{calibration['disc_rms']:.4f}% D, Hausdorff {calibration['disc_hausdorff']:.3f}% D: the measure's own "
            "floor (below).") if calibration else ""
    return [
        "## Method", "",
        "- Items: every mesh and cloud of `shared/data/objects` and the faces of `shared/data/faces` (mm). "
        f"Groups for the ratios: {group_words()}, faces. D is the bounding-box diagonal of the original; every "
        "error is in % of D.",
        "- mzc, through its public API only: `grid = mzc.slice(original)` with its defaults; the lossless floor is "
        "`mzc.triangulate(grid, vertices=\"all\")` uncoded; the rate ladder is `mzc.encode(grid, \"dwt2d\", "
        f"rmse=r * D / 100)` for r in {', '.join(map(str, settings['rmse_ladder']))} (% of D), each rebuilt by "
        "`mzc.triangulate(mzc.decode(data), vertices=\"all\")`: a vertex at every valid node, what the file holds "
        "(the default rebuild, near the source's vertex count, adds the simplifier's error: issue 31). Whatever "
        "`mzc.slice` makes by default is measured as it is.",
        "- mzc given the surface (`mzc encode SURFACE --rmse`): `mzc.encode(original_mesh, \"dwt2d\", rmse=r * D / "
        f"100)` for r in {', '.join(map(str, settings['surface_ladder']))} (% of D), which cuts the surface at the "
        "spacing that holds r over its whole surface in the fewest bytes (`mzc.targets`: the coarsest of 1-8 times "
        "the default spacing whose floor is within 0.8 r, and the next finer; each coded at two budgets), rebuilt "
        "as above. mzc's bytes at a target are the smaller of its two fronts ('mzc' in the tables).",
        f"- Draco (DracoPy) codes the original at {settings['draco_bits'][0]}..{settings['draco_bits'][-1]} position "
        "quantisation bits, compression level 10 (`contenders.draco_encode`); the armadillo as Draco's point "
        "cloud (positions only: neither file keeps the normals).",
        f"- Whole-surface error: {settings['samples']:,} samples each way, seed {settings['seed']}: area-weighted "
        "samples on the original measured exactly to every triangle of the rebuild, and the rebuild's to the "
        "original (`mzc.measure.metrics.sample_surface` and `distance_to_mesh`, drawn as `surface_distance_parts` "
        "draws them: on two meshes its figures). RMS and mean over both directions together; Hausdorff the largest "
        "sampled distance (a lower bound). Coverage: the share of the original's samples within "
        f"{settings['near']}% D of the rebuild (original -> rebuild); spurious: the share of the rebuild's beyond "
        f"{settings['near']}% D of the original; far share: the share of the squared distance those samples carry; "
        f"missed: the share of the original's beyond {MISSED}% D of the rebuild (surface it does not have).",
        "- A cloud (the armadillo: oriented points, no triangles) is sampled by its points (drawn uniformly: a "
        "scan's points are about evenly spread), measured exactly to the rebuild. The other way, each rebuild "
        f"sample is measured to the cloud's surface taken as a disc at each point, across its normal, reaching to "
        f"its {DISC_NEIGHBOUR}rd nearest neighbour: the distance to the nearest of the discs of its "
        f"{DISC_CANDIDATES} nearest points (the distance to the nearest point would add up to half the point "
        "spacing). Draco's decoded cloud is measured point to point (each original point to its nearest decoded "
        f"point; each decoded point to the discs). So its coverage is the share of the cloud's points within "
        f"{settings['near']}% D of the rebuild." + disc,
        "- Ratios: each contender's Pareto front of (whole-surface RMS, bytes) is interpolated log-log at the "
        "target (`report.item_ratios`: mzc counts at its cheapest setting when that is already below the target, "
        "Draco is never extrapolated); Draco bytes / mzc bytes, above 1 when mzc is smaller; geometric means per "
        "group over the items where both reach the target. 'Never larger' takes the smallest ratio at 11 "
        f"log-spaced errors over {ISSUE_RANGE[0]}-{ISSUE_RANGE[1]}% D.",
        f"- Speed: in this process alone after the measuring, median of {settings['repeats']} runs, wall and CPU "
        f"(every thread): `mzc.slice` + `mzc.encode` at rmse {TIMING_RMSE}% D, and `mzc.decode` + "
        f"`mzc.triangulate`; Draco's encode and decode at {TIMING_BITS} bits beside them. The 100k-vertex check "
        f"uses {SPEED_OBJECT} (the largest object) with its largest triangles split in three at their centroids "
        f"until it has {SPEED_VERTICES:,} vertices: the same surface with the vertex count of the issue. The "
        "default spacing follows the median edge, which these splits lengthen: its default grid has fewer nodes "
        f"than the original {SPEED_OBJECT}'s (both rows are in the table).",
        "",
    ]


def group_words():
    """'scanned (armadillo, dragon, hand), modelled (ogre), ...' of GROUPS."""
    groups = dict.fromkeys(GROUPS.values())
    return ", ".join(f"{group} ({', '.join(n for n, g in GROUPS.items() if g == group)})" for group in groups)


def item_section(title, items, targets, mm=False):
    """One row per item: D, input, default grid, floor, bytes and Draco / mzc ratios at ``targets`` % D
    (and at MM_TARGETS for faces)."""
    if not items:
        return [f"## {title}", "", "None in this run.", ""]
    at = " / ".join(f"{t}" for t in targets)
    header = ["item", "group", "D", "vertices / triangles", "default grid", "floor RMS % D",
              "floor Hausdorff % D", f"area within {NEAR}% D", f"mzc KB at {at}% D", f"Draco KB at {at}% D",
              f"Draco / mzc at {at}% D", f"smallest Draco / mzc over {ISSUE_RANGE[0]}-{ISSUE_RANGE[1]}% D"]
    if mm:
        header.append(f"Draco / mzc at {' / '.join(map(str, MM_TARGETS))} mm")
    lines = [f"## {title}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for item in items:
        floor, facts = item["floor"], item["facts"]
        smallest, why = smallest_ratio(item)
        row = [item["item"], item["group"], f"{item['diagonal']:.4g}",
               f"{facts['vertices']:,} / {facts['triangles']:,}", grid_words(item["grid"]),
               pct(floor["whole"]["rms"]), pct(floor["whole"]["hausdorff"]),
               f"{floor['coverage']:.1f}%",
               " / ".join(kilobytes(front_bytes(item, "mzc", t)) for t in targets),
               " / ".join(kilobytes(front_bytes(item, "peer", t)) for t in targets),
               " / ".join(pct(r) for r in draco_ratios(item, targets)),
               pct(smallest) if smallest is not None else f"n/a ({why})"]
        if mm:
            row.append(" / ".join(pct(r) for r in draco_ratios(item, MM_TARGETS, face_unit(item))))
        lines.append("| " + " | ".join(row) + " |")
    notes = {f"{item['item']} at {t}% D: {note}" for item in items for t, r in zip(targets, draco_ratios(item, targets))
             if r is None and (note := ratio_note(item, t))}
    return lines + [""] + [f"- n/a: {note}" for note in sorted(notes)] + ([""] if notes else [])


def sites_section(items):
    """Where each object's file at TIMING_RMSE goes: the mask's share and the chart edges' share of the error."""
    rows = [r for r in items if r.get("sites")]
    if not rows:
        return []
    lines = [f"## Where mzc's bytes and errors go (the file at --rmse {rows[0]['sites']['rmse']}% D)", "",
             f"The mask's bytes are its ideal cost in the file's rANS words (`anatomy.parts`). The error is the "
             f"encoder's own estimate at the valid nodes (each value error weighted by its node's lean and area, "
             f"as `--rmse` aims at it); 'edge' nodes lie within {EDGE_NODES} steps of an invalid node, where a chart "
             f"ends and its surface leans furthest from the chart's node lines.", "",
             "| object | file B | mask B (share) | valid nodes | nodes a distinct vertex | edge nodes | their share of "
             "the squared error |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        s = r["sites"]
        mask = f"{s['mask_bytes']:,} ({100 * s['mask_bytes'] / s['bytes']:.0f}%)"
        per_vertex = s["nodes"] / r["facts"]["distinct_positions"]
        lines.append(f"| {r['item']} | {s['bytes']:,} | {mask} | {s['nodes']:,} | {per_vertex:.1f} | "
                     f"{100 * s['edge_nodes']:.0f}% | {100 * s['edge_error']:.0f}% |")
    return lines + [""]


def grid_words(fields):
    """'spherical 238 x 238, 47,738 nodes' of ``grid_fields``."""
    words = [str(fields.get("projection", fields["type"]))]
    if "shape" in fields:
        words.append(" x ".join(map(str, fields["shape"])))
    if "nodes" in fields:
        words.append(f"{fields['nodes']:,} nodes")
    return ", ".join(words)


def ratio_section(summary, groups):
    lines = ["## Draco bytes / mzc bytes by group (geometric mean; items counted in brackets)", "",
             "| group | " + " | ".join(f"{t}% D" for t in PERCENT_TARGETS) + " |",
             "|---|" + "---|" * len(PERCENT_TARGETS)]
    for group in groups:
        values = summary["% D"].get(group, {}).get(DRACO, [(None, 0)] * len(PERCENT_TARGETS))
        lines.append(f"| {group} | " + " | ".join(f"{fmt(r)} ({n})" for r, n in values) + " |")
    faces = summary["mm"].get("faces", {}).get(DRACO)
    if faces:
        lines += ["", "Faces at the mm targets of `rd.py`: " + ", ".join(
            f"{t} mm: {fmt(r)} ({n})" for t, (r, n) in zip(MM_TARGETS, faces)) + "."]
    return lines + [""]


def speed_section(speed, load):
    if not speed:
        return []
    lines = ["## Speed (in process, one process alone; median wall / CPU seconds)", "",
             f"The machine's load average was {load[0]:.1f} before the timing and {load[1]:.1f} after it (other "
             "work shares its 2 cores): wall time beyond CPU time is time spent waiting for a core.", "",
             "| object | vertices | default grid | mzc slice + encode | mzc decode + triangulate | mzc bytes | "
             "Draco encode | Draco decode | Draco bytes |", "|---|---|---|---|---|---|---|---|---|"]

    def both(row, key):
        return f"{row[key]['wall_s']:.3f} / {row[key]['cpu_s']:.3f}" if key in row else "n/a"

    for name, row in speed.items():
        lines.append(f"| {name} | {row['vertices']:,} | {grid_words(row['grid'])} | {both(row, 'slice_encode')} | "
                     f"{both(row, 'decode_triangulate')} | {row['bytes']:,} | {both(row, 'draco_encode')} | "
                     f"{both(row, 'draco_decode')} | {row.get('draco_bytes', 0):,} |")
    return lines + ["", f"Targets for {SPEED_VERTICES:,} vertices: slice + encode <= {ENCODE_SECONDS:g} s, "
                    f"decode + triangulate <= {DECODE_SECONDS:g} s.", ""]


def check_section(items):
    rows = [(item["item"], c) for item in items for c in item["check"]]
    if not rows:
        return []
    lines = [f"## Sample-count check ({CHECK_SEEDS} seeds at the run's sample count)", "",
             "| item | rebuild | RMS % D (mean) | RMS spread (std / mean) | Hausdorff % D (min-max) | "
             "coverage (min-max) |", "|---|---|---|---|---|---|"]
    for name, c in rows:
        rms = np.array(c["rms"])
        lines.append(f"| {name} | {c['what']} | {rms.mean():.4g} | {100 * rms.std() / rms.mean():.2f}% | "
                     f"{min(c['hausdorff']):.3g}-{max(c['hausdorff']):.3g} | "
                     f"{min(c['coverage']):.2f}-{max(c['coverage']):.2f}% |")
    return lines + [""]


def calibration_section(calibration):
    if not calibration:
        return []
    c = calibration
    return ["## The cloud measure's own floor", "",
            f"{c['object']}'s mesh ({c['samples']:,} area-weighted samples) against its own vertices as an oriented "
            f"cloud: by disc RMS {c['disc_rms']:.4f}% D, Hausdorff {c['disc_hausdorff']:.3f}% D; by nearest point "
            f"RMS {c['point_rms']:.4f}% D, Hausdorff {c['point_hausdorff']:.3f}% D (median point spacing "
            f"{c['spacing']:.3f}% D). A perfect rebuild of the armadillo would measure about the disc figures "
            "in the rebuild -> original direction; the nearest point alone would put a floor near the point "
            "spacing under every rebuild.", ""]


def facts_section(results):
    lines = ["## The inputs as the slicer meets them", "",
             "| item | box (x x y x z) | vertices | distinct positions | triangles | zero-area | boundary edges "
             "(welded) | non-manifold edges | parts | slicer's warning |", "|---|---|---|---|---|---|---|---|---|---|"]
    clouds = []
    for item in results:
        if item["group"] == "faces":
            continue
        f = item["facts"]
        mesh = [f.get(k, "-") for k in ("zero_area_triangles", "boundary_edges", "non_manifold_edges", "parts")]
        warned = "; ".join(slice_warnings(item)) or "-"
        box = " x ".join(f"{v:.3g}" for v in f["box"])
        lines.append(f"| {item['item']} | {box} | {f['vertices']:,} | {f['distinct_positions']:,} | "
                     f"{f['triangles']:,} | " + " | ".join(map(str, mesh)) + f" | {warned} |")
        if "spacing" in f:
            clouds.append(f"- {item['item']} is a cloud{' with normals' if f['normals'] else ''}: the distance from a "
                          "point to its nearest neighbour is " + ", ".join(f"{v:.3f}" for v in f["spacing"])
                          + "% D at the 5th, 50th and 95th percentiles.")
    return lines + [""] + clouds + ([""] if clouds else [])


def problems_section(results, missing):
    lines = ["## Missing contenders and failures", ""]
    lines += [f"- missing: {name}: {why}" for name, why in missing.items()] or ["- no contender missing"]
    failures = [f"- failed: {r['item']}, {f['contender']} at {f['setting']}: {f['error'][:200]}"
                for r in results for f in r["failures"]]
    return lines + (failures or ["- no failure"])


def plot(path, results):
    """Bytes against whole-surface RMS (% of D), one panel per object and one for the faces'
    geometric means; the uncoded floor dotted, the issue's range shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(r["item"], [r]) for r in results if r["group"] != "faces"]
    faces = [r for r in results if r["group"] == "faces"]
    if faces:
        panels.append((f"faces (geometric mean of {len(faces)})", faces))
    columns = min(4, len(panels))
    rows = -(-len(panels) // columns)
    figure, axes = plt.subplots(rows, columns, figsize=(4.6 * columns, 4.2 * rows), squeeze=False)
    for axis, (title, items) in zip(axes.ravel(), panels):
        draw_curves(axis, curves_of(items, items[0]["corpus"], "whole rms"), plt, "whole-surface RMS (% of D)", title)
        axis.axvline(float(np.exp(np.mean(np.log([r["floor"]["whole"]["rms"] for r in items])))), linestyle=":",
                     color="grey", label="mzc uncoded floor")
        axis.axvspan(*ISSUE_RANGE, color="gold", alpha=0.15, label=f"{ISSUE_RANGE[0]}-{ISSUE_RANGE[1]}% D")
    for axis in axes.ravel()[len(panels):]:
        axis.axis("off")
    figure.legend(*axes[0][0].get_legend_handles_labels(), loc="lower right", fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)


# --------------------------------------------------------------------------- running


def run_all(specs, samples, quick, workers, progress):
    """run_item over every item in a process pool, the largest files first; results in spec order."""
    import multiprocessing

    check = not quick
    jobs = [(spec, samples, quick, check and spec[0] != "faces") for spec in specs]
    jobs.sort(key=lambda job: -Path(job[0][2]).stat().st_size)
    results = {}
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        for done, result in enumerate(pool.imap_unordered(run_item, jobs), 1):
            results[result["item"], result["group"]] = result
            progress(f"[{done}/{len(jobs)}] {result['item']}: {len(result['points'])} points, "
                     f"{len(result['failures'])} failures, {result['wall_s']:.0f} s")
    return [results[name, group] for group, name, _ in specs]


def parse_args(argv):
    quick = f"{' and '.join(QUICK_OBJECTS)}, one face, every other setting, fewer samples"
    return benchmark_parser(__doc__, quick, workers=True).parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    progress = terminal_progress()
    specs = item_specs(args.quick)
    if not specs:
        print(f"objects.py: skipped: no objects in {OBJECTS} and no faces in {FACES}", file=sys.stderr)
        return
    if not OBJECTS.is_dir():
        print(f"objects.py: no objects in {OBJECTS}: measuring the faces only", file=sys.stderr)
    samples = QUICK_SAMPLES if args.quick else SAMPLES
    repeats = QUICK_REPEATS if args.quick else REPEATS
    started = time.perf_counter()
    results = run_all(specs, samples, args.quick, args.workers, progress)
    progress("timing")
    load = [os.getloadavg()[0]]
    speed = speeds(specs, repeats)
    load.append(os.getloadavg()[0])
    summary = summaries(results)
    settings = {"quick": args.quick, "workers": args.workers, "samples": samples, "seed": SEED, "repeats": repeats,
                "rmse_ladder": RMSE_LADDER[::2] if args.quick else RMSE_LADDER,
                "surface_ladder": SURFACE_LADDER[::2] if args.quick else SURFACE_LADDER,
                "draco_bits": DRACO_BITS[::2] if args.quick else DRACO_BITS, "near": NEAR,
                "percent_targets": PERCENT_TARGETS, "issue_range": ISSUE_RANGE, "mm_targets": MM_TARGETS,
                "groups": GROUPS, "errors_in": "% of D", "load_average": load}
    document = {"generated": f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}", "machine": machine(),
                "commit": git_commit(), "versions": versions(), "settings": settings,
                "missing": results[0]["missing"], "calibration": cloud_calibration(specs, samples),
                "summary": summary, "verdicts": verdicts(results, summary, speed), "speed": speed, "items": results}
    settings["wall_s"] = time.perf_counter() - started
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "objects-results.json").write_text(json.dumps(document, indent=1, default=float) + "\n")
    (args.out / "objects-results.md").write_text(markdown(document))
    plot(args.out / "objects-rd.png", results)
    progress(f"done in {settings['wall_s']:.0f} s; wrote {args.out}/objects-results.md")


if __name__ == "__main__":
    main()
