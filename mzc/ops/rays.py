"""Outermost hits of the node rays of a central grid (cylindrical or spherical) on a triangle mesh.

The generalisation of the planar slicer's front-most height (``mzc.ops.raster.rasterize``):
every node's ray (``mzc.projections``) is intersected exactly with the triangles, and the
node takes the largest distance along its ray at which it meets the surface, NaN where
it meets none. Each triangle's candidate nodes come from a box in (u, v) that bounds its
image: the azimuths of its corners (an edge not crossing the axis sweeps its azimuth
monotonically), its heights (cylindrical) or a bound of its elevations (spherical: a
chord can rise above both its ends towards a pole), all columns for a triangle that the
axis passes through, and a second copy one turn over for a triangle across the seam of
the grid's azimuth window. The boxes are numpy's work (a few operations per triangle); the loop
over their candidate nodes, each with an exact ray-triangle test, is the C kernel of the
planar rasterizer (``_raster.c``'s ``farthest``), which finds a box's nodes as it finds a
triangle's block there.
"""

import numpy as np

from mzc import elementary
from mzc.ops.raster import BARYCENTRIC_TOLERANCE, checked

TURN = 2 * np.pi


def cast(points, triangles, projection, radius, xs, ys):
    """Values (len(ys), len(xs)) of the outermost hits of the rays of nodes (u in xs, v in ys).

    ``points`` are grid-frame coordinates (centre at the origin, axis along y); ``xs`` and
    ``ys`` are uniform and increasing. Triangles seen edge-on by a ray never count as hits.
    """
    from mzc.ops import _raster

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    xs, ys = np.ascontiguousarray(xs, dtype=np.float64), np.ascontiguousarray(ys, dtype=np.float64)
    best = np.full(len(ys) * len(xs), -np.inf)
    boxes, owners = candidate_boxes(points, triangles, projection, radius, xs[0])
    checked(_raster.farthest(points, triangles, owners, boxes, xs, ys, *direction_factors(projection, radius, xs, ys),
                             projection == "cylindrical", BARYCENTRIC_TOLERANCE, best))
    best[best == -np.inf] = np.nan
    return best.reshape(len(ys), len(xs))


def candidate_boxes(points, triangles, projection, radius, u_start):
    """((k, 2, 2) boxes [[u_low, u_high], [v_low, v_high]], (k,) triangle of each box).

    Azimuths are taken in the window [u_start, u_start + 2 pi R0) of the grid; a triangle
    whose corners straddle the window's seam is unwrapped past its end and gets a second
    box one turn lower, so each side of the seam sees it. A triangle around the axis gets
    every azimuth. Each coordinate is a (3, m) array, a row per corner, so that every step
    works on whole rows and reduces over three of them.
    """
    coordinates = np.ascontiguousarray(points.T)
    x, y, z = coordinates.take(triangles.T, axis=1)
    turn = TURN * radius
    azimuth = radius * elementary.atan2(coordinates[0], coordinates[2])   # once a point, not once a corner
    u = u_start + np.mod(azimuth.take(triangles.T) - u_start, turn)
    around = around_axis(x, z)
    straddles = ~around & (u.max(axis=0) - u.min(axis=0) > 0.5 * turn)
    u = np.where(straddles & (u < u_start + 0.5 * turn), u + turn, u)
    u_box = np.stack([u.min(axis=0), u.max(axis=0)], axis=1)
    v_box = v_bounds(x, y, z, projection, radius, around, u_box)
    u_box[around] = [-np.inf, np.inf]
    boxes = np.stack([u_box, v_box], axis=1)
    again = np.flatnonzero(straddles)
    shifted = boxes[again]
    shifted[:, 0] -= turn
    owners = np.concatenate([np.arange(len(triangles), dtype=np.int64), again])
    return np.concatenate([boxes, shifted]), owners


def around_axis(x, z):
    """True for triangles (columns of the corners' x and z, (3, m)) whose projection onto the xz
    plane contains the axis (x = z = 0)."""
    cross = x * np.roll(z, -1, axis=0) - z * np.roll(x, -1, axis=0)
    return ((cross >= 0).all(axis=0) | (cross <= 0).all(axis=0)) & (np.abs(cross.sum(axis=0)) > 0)


def v_bounds(x, y, z, projection, radius, around, u_box):
    """(m, 2) low and high v over each triangle: its heights along a cylindrical axis, or a
    bound of its elevations (from its heights and its distances from the axis) for spherical grids.

    A triangle's nearest point to the axis may lie inside an edge, nearer than its corners
    are: for corners at distances r and azimuths within an angle A < pi of each other it is no
    nearer than min r cos(A / 2) (the chord of two points r apart at angle A passes r cos(A/2)
    from the axis, and moving a corner outwards moves the chord out).
    """
    low, high = y.min(axis=0), y.max(axis=0)
    if projection == "cylindrical":
        return np.stack([low, high], axis=1)
    distance = np.sqrt(x * x + z * z)
    spread = np.minimum((u_box[:, 1] - u_box[:, 0]) / radius, np.pi)
    near = np.where(around, 0.0, distance.min(axis=0) * elementary.cos(spread / 2))
    far = distance.max(axis=0)
    top = elementary.atan2(high, np.where(high >= 0, near, far))
    bottom = elementary.atan2(low, np.where(low <= 0, near, far))
    return radius * np.stack([bottom, top], axis=1)


def direction_factors(projection, radius, xs, ys):
    """(2, len(xs)) sine and cosine of each column's azimuth, and (2, len(ys)) cosine and sine of
    each row's elevation (1 and 0 on cylindrical rays): node (row, column)'s ray runs along
    (ring sin, rise, ring cos), ring and rise the row's factors (``mzc.projections``)."""
    azimuth = xs / radius
    columns = np.stack([elementary.sin(azimuth), elementary.cos(azimuth)])
    if projection == "spherical":
        elevation = ys / radius
        return columns, np.stack([elementary.cos(elevation), elementary.sin(elevation)])
    return columns, np.stack([np.ones(len(ys)), np.zeros(len(ys))])
