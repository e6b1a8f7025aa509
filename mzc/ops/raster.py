"""The planar rasterizer: the front-most hit of every node's vertical line (METHOD.md §1, in ../shared/reference).

Node (r, c) of a planar grid stands for the vertical line where a "horizontal" plane
(constant y, one grid row) meets a "vertical" plane (constant x, one column); its height
is the exact front-most intersection of that line with the surface, not the nearest
vertex the thesis takes, so a piecewise-linear surface is reproduced exactly at the
nodes. It is a small C kernel (``_raster.c``), which also casts the rays of central grids
(``mzc.ops.rays``) and finds their candidate nodes as it finds a triangle's here.
"""

import numpy as np

from mzc.errors import MzcError

BARYCENTRIC_TOLERANCE = 1e-9  # nodes on shared edges belong to both triangles


def rasterize(points, triangles, xs, ys):
    """Heights (len(ys), len(xs)) of the front-most (largest z) hit of each node's vertical line.

    ``xs`` and ``ys`` are uniform, increasing node coordinates. Each triangle's xy bounding
    box maps to a block of candidate nodes in O(1); every candidate gets an inclusive
    barycentric test and the plane's height, and the largest height per node wins (in C,
    node by node: no candidate lists). Nodes that no triangle covers are NaN. Triangles with
    no xy area (seen edge-on) are skipped.
    """
    from mzc.ops import _raster

    xs, ys = np.ascontiguousarray(xs, dtype=np.float64), np.ascontiguousarray(ys, dtype=np.float64)
    best = np.full(len(ys) * len(xs), -np.inf)
    checked(_raster.front_most(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3),
                               np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3), xs, ys,
                               BARYCENTRIC_TOLERANCE, best))
    best[best == -np.inf] = np.nan
    return best.reshape(len(ys), len(xs))


def cross2(u, v):
    """z component of the cross product of rows of 2D vectors."""
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


def heights_on_triangles(corners, owner, x, y):
    """(height, hit) of points (x, y) on triangles ``owner`` of ``corners`` (m, 3, 3): the height
    of the triangle's plane there and the inclusive barycentric test (``_raster.c``)."""
    from mzc.ops import _raster

    z, hit = np.empty(len(owner)), np.empty(len(owner), dtype=bool)
    checked(_raster.heights(np.ascontiguousarray(corners, dtype=np.float64),
                            np.ascontiguousarray(owner, dtype=np.int64), np.ascontiguousarray(x, dtype=np.float64),
                            np.ascontiguousarray(y, dtype=np.float64), BARYCENTRIC_TOLERANCE, z, hit))
    return z, hit


def checked(status):
    """Turn a status of ``_raster`` into an error: sizes that do not fit, or an index out of range."""
    if status:
        raise MzcError("the rasterizer was given " + ("buffers whose sizes do not fit" if status == 1
                                                      else "a node or triangle index out of range"))
