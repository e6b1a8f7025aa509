"""Measuring how far one surface is from another, as ``mzc diff`` and ``mzc.compare`` do.

Both surfaces are sampled on one common grid over A's extent (``sampling``) and compared
along its node lines; the point-to-surface distances over every triangle (``metrics``) are
added when asked for, and always for central and multi-chart grids, which are compared in space. A point
cloud on either side is measured by the distances of its points to the other surface.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from mzc.errors import MzcError
from mzc.limits import MAX_SAMPLES, check_magnitude

if TYPE_CHECKING:
    from mzc.grid import ZGrid
    from mzc.meshes import Mesh

STATISTICS = ("rmse", "max", "mean", "r2", "percentiles", "count")
KEYS = {"rmse": ["rmse"], "max": ["max"], "mean": ["mean", "bias"], "r2": ["r2"],
        "percentiles": ["p50", "p95", "p99"], "count": ["count"]}


@dataclass
class Comparison:
    """The report (statistic name -> value) and, for two surfaces, the common grid of A's values,
    the error surface B - A on it and all its statistics."""

    report: dict[str, Any]
    reference: ZGrid | None = None
    errors: ZGrid | None = None
    stats: dict[str, Any] = field(default_factory=dict)


def compare_surfaces(first: Mesh, second: Mesh, chosen: tuple[str, ...] | list[str] = (), surface: bool = False,
                     heightfield: bool = False, samples: int = 100_000, seed: int = 0, d1: float | None = None,
                     d2: float | None = None, names: tuple[str, str] = ("A", "B")) -> Comparison:
    """Compare Meshes ``first`` (A) and ``second`` (B): the ``chosen`` statistics (all when none)
    of B - A along the common grid's node lines, and with ``surface`` or ``heightfield`` the
    point-to-surface distances; ``names`` name the sides in a point cloud's direction line.
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
    report = select(stats, chosen or STATISTICS)
    if surface or heightfield or any(side.grid is not None and (side.grid.projection != "planar"
                                                                or side.grid.charts is not None)
                                     for side in (first, second)):
        report.update(surface_report(first, second, heightfield, samples, seed))
    return Comparison(report, reference, errors, stats)


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
    """surface_* entries (and surface_heightfield_* ones) of the point-to-surface distance."""
    from mzc.measure.metrics import heightfield_filters, surface_distance_parts

    parts = {"surface_": (None, None)}
    if heightfield:
        parts["surface_heightfield_"] = heightfield_filters(first.points, first.triangles)
    distances = surface_distance_parts((first.points, first.triangles), (second.points, second.triangles),
                                       parts, samples=samples, seed=seed)
    return {f"{prefix}{k}": v for prefix, summary in distances.items() for k, v in summary.items()}


def select(stats, chosen):
    """The entries of ``stats`` that the chosen statistic names stand for."""
    unknown = sorted(set(chosen) - set(KEYS))
    if unknown:
        raise MzcError(f"unknown statistic {unknown[0]!r} (known: {', '.join(STATISTICS)})", field="statistics")
    return {key: stats[key] for name in chosen for key in KEYS[name] if key in stats}
