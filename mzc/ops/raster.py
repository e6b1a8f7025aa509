"""The planar rasterizer: the front-most hit of every node's vertical line (METHOD.md §1, in ../shared/reference).

Node (r, c) of a planar grid stands for the vertical line where a "horizontal" plane
(constant y, one grid row) meets a "vertical" plane (constant x, one column); its height
is the exact front-most intersection of that line with the surface, not the nearest
vertex the thesis takes, so a piecewise-linear surface is reproduced exactly at the
nodes. The blocks of candidate nodes per triangle, in chunks of bounded size, serve the
rays of central grids too (``mzc.ops.rays``).
"""

import numpy as np

from mzc.vectors import of_each_row

BARYCENTRIC_TOLERANCE = 1e-9  # nodes on shared edges belong to both triangles
CANDIDATES_PER_CHUNK = 1 << 15   # (triangle, node) pairs tested at a time: a few MB of temporaries


def rasterize(points, triangles, xs, ys):
    """Heights (len(ys), len(xs)) of the front-most (largest z) hit of each node's vertical line.

    ``xs`` and ``ys`` are uniform, increasing node coordinates. Each triangle's xy bounding
    box maps to a block of candidate nodes in O(1); every candidate gets an inclusive
    barycentric test and the plane's height, and the largest height per node wins. Nodes
    that no triangle covers are NaN. Triangles with no xy area (seen edge-on) are skipped.
    """
    points = np.asarray(points, dtype=np.float64)
    xs, ys = np.asarray(xs, dtype=np.float64), np.asarray(ys, dtype=np.float64)
    corners = points[non_degenerate(points, np.asarray(triangles, dtype=np.int64))]
    best = np.full(len(ys) * len(xs), -np.inf)
    if len(corners):
        col_range = index_range(corners[:, :, 0], xs)
        row_range = index_range(corners[:, :, 1], ys)
        for chunk in candidate_chunks(col_range, row_range):
            rasterize_chunk(corners[chunk], col_range[:, chunk], row_range[:, chunk], xs, ys, best)
    best[best == -np.inf] = np.nan
    return best.reshape(len(ys), len(xs))


def non_degenerate(points, triangles):
    """The triangles whose xy projection has an area (tested relative to their own size)."""
    a, b, c = (points[triangles[:, i], :2] for i in range(3))
    doubled_area = np.abs(cross2(b - a, c - a))
    scale = np.maximum(of_each_row(np.max, np.abs(b - a)), of_each_row(np.max, np.abs(c - a))) ** 2
    return triangles[doubled_area > 1e-12 * scale]


def cross2(u, v):
    """z component of the cross product of rows of 2D vectors."""
    return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]


def index_range(coordinate, nodes):
    """(2, m) first and last node index inside each triangle's [min, max] of ``coordinate``."""
    step = nodes[1] - nodes[0] if len(nodes) > 1 else 1.0
    slack = 1e-7  # in node steps: a node exactly on the box edge is always a candidate
    low = np.ceil((of_each_row(np.min, coordinate) - nodes[0]) / step - slack)
    high = np.floor((of_each_row(np.max, coordinate) - nodes[0]) / step + slack)
    return np.stack([np.clip(low, 0, len(nodes)), np.clip(high, -1, len(nodes) - 1)]).astype(np.int64)


def candidate_chunks(col_range, row_range):
    """Slices of triangles whose candidate (triangle, node) pairs fit in one chunk each."""
    counts = block_sizes(col_range) * block_sizes(row_range)
    ends = np.cumsum(counts)
    start = 0
    while start < len(counts):
        before = ends[start - 1] if start else 0
        stop = max(int(np.searchsorted(ends, before + CANDIDATES_PER_CHUNK, side="right")), start + 1)
        yield slice(start, stop)
        start = stop


def block_sizes(index_range_):
    """Number of node indices in each (first, last) range; 0 when empty."""
    return np.maximum(index_range_[1] - index_range_[0] + 1, 0)


def rasterize_chunk(corners, col_range, row_range, xs, ys, best):
    """Test every candidate node of these triangles and raise ``best`` to the heights that hit."""
    owner, rows, cols = candidate_nodes(col_range, row_range)
    z, hit = heights_on_triangles(corners, owner, xs[cols], ys[rows])
    np.maximum.at(best, rows[hit] * len(xs) + cols[hit], z[hit])


def candidate_nodes(col_range, row_range):
    """(triangle, row, column) of every node in the triangles' blocks of candidate nodes."""
    width, height = block_sizes(col_range), block_sizes(row_range)
    counts = width * height
    owner = np.repeat(np.arange(len(counts)), counts)
    down, across = np.divmod(np.arange(len(owner)) - np.repeat(np.cumsum(counts) - counts, counts), width[owner])
    return owner, row_range[0, owner] + down, col_range[0, owner] + across


def heights_on_triangles(corners, owner, x, y):
    """Barycentric test of points (x, y) against triangle ``owner``, and the height there."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ab, ac = b - a, c - a
    inverse_area = (1.0 / cross2(ab[:, :2], ac[:, :2]))[owner]
    at = lambda vectors, i: np.ascontiguousarray(vectors[:, i])[owner]  # noqa: E731 - a gather from a contiguous copy
    px, py = x - at(a, 0), y - at(a, 1)
    u = (px * at(ac, 1) - py * at(ac, 0)) * inverse_area
    v = (py * at(ab, 0) - px * at(ab, 1)) * inverse_area
    tolerance = -BARYCENTRIC_TOLERANCE
    hit = (u >= tolerance) & (v >= tolerance) & (1.0 - u - v >= tolerance)
    z = at(a, 2) + u * at(ab, 2) + v * at(ac, 2)
    return z, hit
