"""A point cloud as a surface: the Delaunay triangles between its points in a plane, without
those that bridge gaps (``mzc.ops.slicing`` and ``mzc.ops.charts`` cut such surfaces)."""

import numpy as np

from mzc.errors import MzcError
from mzc.vectors import lengths, of_each_row

LONG_EDGE_FACTOR = 5.0


def triangulate_point_cloud(points_xy, long_edge_factor=LONG_EDGE_FACTOR):
    """Triangles of a Delaunay triangulation in xy, without those that bridge gaps.

    Delaunay fills the convex hull, so it spans holes and concave borders with long thin
    triangles a scanner never sampled. A triangle is dropped when any of its edges is
    longer than ``long_edge_factor`` times the median Delaunay edge length: the median is
    the sample spacing (robust to the few bridging edges). 5x keeps every interior
    triangle even of uniformly random samples, the most irregular sampling (their longest
    edges reach about 3.5x the median; scanner grids stay under 2x), while cutting every
    gap wider than about five samples.
    """
    from scipy.spatial import Delaunay, QhullError

    points_xy = np.asarray(points_xy, dtype=np.float64)
    if len(points_xy) < 3:
        raise MzcError(f"a point cloud needs at least 3 points to form a surface, not {len(points_xy)}")
    try:
        triangles = Delaunay(points_xy).simplices.astype(np.int64)
    except QhullError:
        raise MzcError("the point cloud is degenerate in xy (all points on a line?)") from None
    corners = points_xy[triangles]
    edges = lengths((corners - np.roll(corners, 1, axis=1)).reshape(-1, 2)).reshape(-1, 3)
    return triangles[of_each_row(np.max, edges) <= long_edge_factor * np.median(edges)]
