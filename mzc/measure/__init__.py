"""Measuring how far one surface is from another, as ``mzc diff`` and ``mzc.compare`` do.

The symmetric point-to-surface distance over every triangle (``metrics``) comes first: it is
what a user means by "how far", honest on steep walls and folds. Both surfaces are also
sampled on one common grid over A's extent (``sampling``) and compared along its node lines:
the grid statistics, named ``grid_*``. A point cloud on either side is measured by the
distances of its points to the other surface.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mzc.errors import MzcError
from mzc.limits import MAX_SAMPLES, check_magnitude

if TYPE_CHECKING:
    import numpy as np

    from mzc.grid import ZGrid
    from mzc.meshes import Mesh

STATISTICS = ("rmse", "max", "mean", "r2", "percentiles", "count")
KEYS = {"rmse": ["rmse"], "max": ["max"], "mean": ["mean", "bias"], "r2": ["r2"],
        "percentiles": ["p50", "p95", "p99"], "count": ["count"]}
GRID_PREFIX = "grid_"   # a two-surface report's statistics along the common grid's node lines


@dataclass
class Comparison:
    """The report (statistic name -> value) and, for two surfaces, the common grid of A's values,
    the error surface B - A on it and all its statistics, and the whole surface's sampled
    distances when they were measured (A's samples to B, B's to A)."""

    report: dict[str, Any]
    reference: ZGrid | None = None
    errors: ZGrid | None = None
    stats: dict[str, Any] = field(default_factory=dict)
    distances: tuple[np.ndarray, np.ndarray] | None = None


def compare_surfaces(first: Mesh, second: Mesh, chosen: tuple[str, ...] | list[str] = (),
                     surface: bool | None = None, heightfield: bool = False, samples: int = 100_000, seed: int = 0,
                     d1: float | None = None, d2: float | None = None,
                     names: tuple[str, str] = ("A", "B")) -> Comparison:
    """Compare Meshes ``first`` (A) and ``second`` (B): the point-to-surface distances first
    (``surface``; None: unless only some grid statistics are ``chosen``; always for central and
    multi-chart grids, which are compared in space; and with ``heightfield``), then the ``chosen``
    statistics (all when none) of B - A along the common grid's node lines, each named
    ``grid_*``; the length ``units`` when a side is a grid that knows them. ``names`` name the
    sides in a point cloud's direction line.
    Coordinates beyond mzc.limits' are refused, as ``slice`` refuses them: their squared
    distances overflow (the nearest-triangle search had no bound left to prune with)."""
    from mzc.measure.metrics import grid_error_stats
    from mzc.measure.sampling import error_grid

    if not 100 <= samples <= MAX_SAMPLES:
        raise MzcError(f"must be 100..{MAX_SAMPLES}, not {samples}", field="samples")
    for side, name in zip((first, second), names):
        check_magnitude(side.points, "coordinates", source=name)
    if first.is_point_cloud or second.is_point_cloud:
        return Comparison(cloud_report(first, second, names, chosen))
    reference, errors = error_grid(first, second, d1, d2)
    stats = grid_error_stats(reference.z, reference.z + errors.z)
    if stats["count"] == 0 and list(chosen) != ["count"]:
        raise MzcError(f"no node of the common grid is valid in both {names[0]} and {names[1]}: the surfaces do not "
                       "overlap, so there is nothing to compare", field="diff")
    in_space = any(side.grid is not None and (side.grid.projection != "planar" or side.grid.charts is not None)
                   for side in (first, second))
    report, distances = {}, None
    if (not chosen if surface is None else surface) or heightfield or in_space:
        report, distances = surface_report(first, second, heightfield, samples, seed)
    units = next((side.grid.units for side in (first, second) if side.grid is not None and side.grid.units), None)
    if units:
        report["units"] = units
    report.update({GRID_PREFIX + key: value for key, value in select(stats, chosen or STATISTICS).items()})
    return Comparison(report, reference, errors, stats, distances)


def cloud_report(first, second, names, chosen):
    """The distances of a point cloud's points to the other side's surface, direction stated."""
    from mzc.measure.metrics import distance_stats, distance_to_mesh

    if first.is_point_cloud and second.is_point_cloud:
        raise MzcError("both sides are point clouds: give a mesh or an mzc file on one side", field="diff")
    (cloud, cloud_name), (mesh, mesh_name) = ((first, names[0]), (second, names[1])) if first.is_point_cloud \
        else ((second, names[1]), (first, names[0]))
    stats = distance_stats(distance_to_mesh(cloud.points, mesh.points, mesh.triangles))
    return {"direction": f"points of {cloud_name} to the surface of {mesh_name}",
            **select(stats, chosen or STATISTICS)}


def surface_report(first, second, heightfield, samples, seed):
    """(surface_* entries, and surface_heightfield_* ones, of the point-to-surface distance; the
    whole surface's sampled distances, A's samples to B then B's to A)."""
    from mzc.measure.metrics import distance_summary, heightfield_filters, surface_distance_samples

    parts = {"surface_": (None, None)}
    if heightfield:
        parts["surface_heightfield_"] = heightfield_filters(first.points, first.triangles)
    distances = surface_distance_samples((first.points, first.triangles), (second.points, second.triangles),
                                         parts, samples=samples, seed=seed)
    # the distances lead and the sample count follows them: a reader's first line is the RMS
    report = {f"{prefix}{k}": v for prefix, pair in distances.items()
              for k, v in sorted(distance_summary(*pair).items(), key=lambda item: item[0] == "samples")}
    return report, distances["surface_"]


def select(stats, chosen):
    """The entries of ``stats`` that the chosen statistic names stand for."""
    unknown = sorted(set(chosen) - set(KEYS))
    if unknown:
        raise MzcError(f"unknown statistic {unknown[0]!r} (known: {', '.join(STATISTICS)})", field="statistics")
    return {key: stats[key] for name in chosen for key in KEYS[name] if key in stats}
