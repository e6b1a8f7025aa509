"""Sample two surfaces on one common grid, as ``mzc diff`` compares them.

The common grid lies in A's frame (a z-grid's own frame and projection, or a mesh's
coordinates as they are, cut with planes) and covers A's extent. A z-grid compared
without new spacings is compared at its own nodes; otherwise the spacing defaults to a
fine one, 1/1000 of A's longest side. B is sampled along the common grid's node lines
(vertical lines, or the rays of a central grid), so the error is measured along them. A
multi-chart grid's nodes are measured by their distance to B's surface instead: along a
chart's line B's outermost hit may be another part of the object, in front of the chart.
"""

import numpy as np

from mzc.grid import IDENTITY_TRANSFORM

DEFAULT_DIVISIONS = 1000


def common_grid(a, d1=None, d2=None):
    """The comparison grid (a ZGrid of A's values) for the Mesh ``a`` (``read_surface``)."""
    from mzc.meshes import Mesh
    from mzc.ops.slicing import slice_in_frame
    from mzc.projections import to_nodes
    from mzc.vectors import rotated

    if a.grid is not None and d1 is None and d2 is None:
        return a.grid
    grid = a.grid
    transform = grid.transform if grid is not None else IDENTITY_TRANSFORM
    rotation, shift = transform[:, :3], transform[:, 3]
    projection, radius = (grid.projection, grid.radius) if grid is not None else ("planar", None)
    extent = np.ptp(to_nodes(projection, radius, rotated(a.points - shift, rotation.T)), axis=0)[:2]
    d1 = d1 or d2 or extent.max() / DEFAULT_DIVISIONS
    return slice_in_frame(Mesh(a.points, a.triangles), rotation, shift, d1=d1, d2=d2 or d1,
                          units=grid.units if grid is not None else None, projection=projection, radius=radius,
                          full_turn=grid is not None and grid.periodic)


def sample_like(grid, surface):
    """Values of ``surface`` along the node lines of ``grid``, in grid's frame (outermost hit); for
    a multi-chart grid, each node's value plus its distance to ``surface``."""
    from mzc.ops.slicing import values_along

    if grid.charts is not None:
        return grid.z + node_distances(grid, surface)
    local = grid.to_grid_frame(surface.points)
    return values_along(grid.projection, grid.radius, local, surface.triangles, grid.xs(), grid.ys())


def node_distances(grid, surface):
    """The distance of every valid node of a multi-chart ``grid`` to ``surface``'s triangles (NaN
    at invalid nodes), each chart's nodes placed in the input frame."""
    from mzc.measure.metrics import distance_to_mesh

    distances = np.full(grid.shape, np.nan)
    for chart, part in zip(grid.charts, grid.chart_grids()):
        valid = part.valid
        points = part.to_input_frame(part.node_points()[valid])
        block = distances[chart.block()]
        block[valid] = distance_to_mesh(points, surface.points, surface.triangles)
    return distances


def error_grid(a, b, d1=None, d2=None):
    """(A sampled on the common grid, the error surface B - A on the same grid) as ZGrids."""
    reference = common_grid(a, d1, d2)
    other = sample_like(reference, b)
    return reference, reference.with_z(other - reference.z)
