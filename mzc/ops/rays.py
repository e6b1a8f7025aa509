"""Outermost hits of the node rays of a central grid (cylindrical or spherical) on a triangle mesh.

The generalisation of the planar slicer's front-most height (``mzc.ops.raster.rasterize``):
every node's ray (``mzc.projections``) is intersected exactly with the triangles, and the
node takes the largest distance along its ray at which it meets the surface, NaN where
it meets none. Each triangle's candidate nodes come from a box in (u, v) that bounds its
image: the azimuths of its corners (an edge not crossing the axis sweeps its azimuth
monotonically), its heights (cylindrical) or a bound of its elevations (spherical: a
chord can rise above both its ends towards a pole), all columns for a triangle that the
axis passes through, and a second copy one turn over for a triangle across the seam of
the grid's azimuth window. Each candidate gets an exact ray-triangle test.
"""

import numpy as np

from mzc.ops.raster import BARYCENTRIC_TOLERANCE, candidate_chunks, candidate_nodes, index_range
from mzc.vectors import of_each_row

TURN = 2 * np.pi


def cast(points, triangles, projection, radius, xs, ys):
    """Values (len(ys), len(xs)) of the outermost hits of the rays of nodes (u in xs, v in ys).

    ``points`` are grid-frame coordinates (centre at the origin, axis along y); ``xs`` and
    ``ys`` are uniform and increasing. Triangles seen edge-on by a ray never count as hits.
    """
    points = np.asarray(points, dtype=np.float64)
    corners = points[np.asarray(triangles, dtype=np.int64).reshape(-1, 3)]
    xs, ys = np.asarray(xs, dtype=np.float64), np.asarray(ys, dtype=np.float64)
    best = np.full(len(ys) * len(xs), -np.inf)
    boxes, owners = candidate_boxes(corners, projection, radius, xs[0])
    if len(owners):
        col_range = index_range(boxes[:, 0], xs)
        row_range = index_range(boxes[:, 1], ys)
        planes = TrianglePlanes(corners[owners])
        rays = RayTable(projection, radius, xs, ys)
        for chunk in candidate_chunks(col_range, row_range):
            cast_chunk(planes, chunk, col_range[:, chunk], row_range[:, chunk], rays, len(xs), best)
    best[best == -np.inf] = np.nan
    return best.reshape(len(ys), len(xs))


def candidate_boxes(corners, projection, radius, u_start):
    """((k, 2, 2) boxes [[u_low, u_high], [v_low, v_high]], (k,) triangle of each box).

    Azimuths are taken in the window [u_start, u_start + 2 pi R0) of the grid; a triangle
    whose corners straddle the window's seam is unwrapped past its end and gets a second
    box one turn lower, so each side of the seam sees it. A triangle around the axis gets
    every azimuth.
    """
    x, z = corners[..., 0], corners[..., 2]
    turn = TURN * radius
    u = u_start + np.mod(radius * np.arctan2(x, z) - u_start, turn)
    around = around_axis(x, z)
    straddles = ~around & (of_each_row(np.ptp, u) > 0.5 * turn)
    u = np.where(straddles[:, None] & (u < u_start + 0.5 * turn), u + turn, u)
    u_box = np.stack([of_each_row(np.min, u), of_each_row(np.max, u)], axis=1)
    v_box = v_bounds(corners, projection, radius, around, u_box)
    u_box[around] = [-np.inf, np.inf]
    boxes = np.stack([u_box, v_box], axis=1)
    again = np.flatnonzero(straddles)
    shifted = boxes[again].copy()
    shifted[:, 0] -= turn
    owners = np.concatenate([np.arange(len(corners)), again])
    return np.concatenate([boxes, shifted]), owners


def around_axis(x, z):
    """True for triangles whose projection onto the xz plane contains the axis (x = z = 0)."""
    cross = [x[:, i] * z[:, (i + 1) % 3] - z[:, i] * x[:, (i + 1) % 3] for i in range(3)]
    return (np.all([c >= 0 for c in cross], axis=0) | np.all([c <= 0 for c in cross], axis=0)) \
        & (np.abs(sum(cross)) > 0)


def v_bounds(corners, projection, radius, around, u_box):
    """(k, 2) low and high v over each triangle: its heights along a cylindrical axis, or a
    bound of its elevations (from its heights and its distances from the axis) for spherical grids.

    A triangle's nearest point to the axis may lie inside an edge, nearer than its corners
    are: for corners at distances r and azimuths within an angle A < pi of each other it is no
    nearer than min r cos(A / 2) (the chord of two points r apart at angle A passes r cos(A/2)
    from the axis, and moving a corner outwards moves the chord out).
    """
    y = corners[..., 1]
    low, high = of_each_row(np.min, y), of_each_row(np.max, y)
    if projection == "cylindrical":
        return np.stack([low, high], axis=1)
    distance = np.hypot(corners[..., 0], corners[..., 2])
    spread = np.minimum((u_box[:, 1] - u_box[:, 0]) / radius, np.pi)
    near = np.where(around, 0.0, of_each_row(np.min, distance) * np.cos(spread / 2))
    far = of_each_row(np.max, distance)
    top = np.where(high >= 0, np.arctan2(high, near), np.arctan2(high, far))
    bottom = np.where(low <= 0, np.arctan2(low, near), np.arctan2(low, far))
    return radius * np.stack([bottom, top], axis=1)


class TrianglePlanes:
    """What the exact test needs of each triangle: its normal n, n . a, and the corner
    products whose dot with a ray's direction are the ray's barycentric weights.

    For a ray from O in direction D, the weights of corners a, b, c are D . ((b-O) x (c-O))
    and its cyclic shifts; (b-O) x (c-O) = b x c - v (y x (c - b)) when O = v y (the
    axis point of a cylindrical ray; v = 0 for the centre of a spherical one). The weights
    sum to D . n, and the ray meets the triangle's plane at t = (n . a - v n_y) / (D . n).
    """

    def __init__(self, corners):
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        self.normal = np.cross(b - a, c - a)
        self.offset = np.einsum("ij,ij->i", self.normal, a)
        self.products = [np.cross(b, c), np.cross(c, a), np.cross(a, b)]
        axis = np.array([0.0, 1.0, 0.0])
        self.shifts = [np.cross(axis, c - b), np.cross(axis, a - c), np.cross(axis, b - a)]


class RayTable:
    """Direction factors of every column and row, so a node's ray is two lookups away."""

    def __init__(self, projection, radius, xs, ys):
        self.projection = projection
        self.ys = ys
        azimuth = xs / radius
        self.sin_u, self.cos_u = np.sin(azimuth), np.cos(azimuth)
        if projection == "spherical":
            elevation = ys / radius
            self.ring, self.rise = np.cos(elevation), np.sin(elevation)
        else:
            self.ring, self.rise = np.ones(len(ys)), np.zeros(len(ys))

    def directions(self, rows, cols):
        """(n, 3) unit directions of the nodes (rows, cols)."""
        ring = self.ring[rows]
        return np.stack([ring * self.sin_u[cols], self.rise[rows], ring * self.cos_u[cols]], axis=1)


def cast_chunk(planes, chunk, col_range, row_range, rays, cols_count, best):
    """Test every candidate node of the triangles of ``chunk`` and raise ``best`` to their hits."""
    owner, rows, cols = candidate_nodes(col_range, row_range)
    t, hit = ray_hits(planes, np.arange(chunk.start, chunk.stop)[owner], rays, rows, cols)
    np.maximum.at(best, rows[hit] * cols_count + cols[hit], t[hit])


def ray_hits(planes, triangle, rays, rows, cols):
    """(distance along the ray, hit) of the rays of nodes (rows, cols) against ``triangle``s."""
    direction = rays.directions(rows, cols)
    of = lambda vectors: vectors.take(triangle, axis=0)  # noqa: E731 - take: 4x faster than [triangle] on rows of 3
    normal = of(planes.normal)
    facing = np.einsum("ij,ij->i", direction, normal)
    cylindrical = rays.projection == "cylindrical"
    v = rays.ys[rows] if cylindrical else 0.0
    weights = []
    for product, shift in zip(planes.products, planes.shifts):
        weight = np.einsum("ij,ij->i", direction, of(product))
        if cylindrical:
            weight -= v * np.einsum("ij,ij->i", direction, of(shift))
        weights.append(weight)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = 1.0 / facing
        tolerance = -BARYCENTRIC_TOLERANCE
        hit = np.isfinite(scale)
        for weight in weights:
            hit &= weight * scale >= tolerance
        t = (planes.offset[triangle] - (v * normal[:, 1] if cylindrical else 0.0)) * scale
    return t, hit & (t > 0)
