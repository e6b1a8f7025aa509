"""Cutting surfaces: where the node (u, v, value) of a z-grid lies in the grid frame.

The thesis cuts with two families of parallel planes, so every node's line is parallel
to z. Its cutting planes generalise to any two families of surfaces whose intersections
are lines; a node's value is then the distance along its line (spec/zgrid.md). In the grid
frame (the rigid ``transform`` of the header maps it to the input frame), with the axis
along y and azimuth 0 along +z:

``planar``
    u = x, v = y, value = z: the thesis's planes; node lines parallel to z.
``cylindrical``
    rows are planes across the axis, columns half-planes through it. u = R0 * azimuth,
    v = y, value = the distance from the axis; the node's line is a ray from the axis,
    perpendicular to it.
``spherical``
    columns are half-planes through the axis, rows cones of constant elevation about it.
    u = R0 * azimuth, v = R0 * elevation, value = the distance from the centre (the grid
    frame's origin); the node's line is a ray from the centre.

Azimuth is atan2(x, z), elevation atan2(y, sqrt(x^2 + z^2)). R0 (the grid's ``radius``)
scales the angles so that u, v and the spacings d1, d2 stay lengths in model units: at the
distance R0 from the centre or axis, nodes are d2 apart along a row and d1 across rows.
"""

import numpy as np

from mzc import elementary

PROJECTIONS = ("planar", "cylindrical", "spherical")
PLANAR_VIEWS = {   # the axes of a planar grid frame looking along each axis of a frame, in that frame
    "+z": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "-z": ((-1, 0, 0), (0, 1, 0), (0, 0, -1)),
    "+x": ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
    "-x": ((0, 0, 1), (0, 1, 0), (-1, 0, 0)),
    "+y": ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    "-y": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
}
FULL_TURN_TOLERANCE = 1e-9   # relative: columns spanning 2 pi R0 this closely make a full turn


def view_rotation(view):
    """The rotation (3x3, columns the grid frame's axes) from a planar grid frame looking along
    ``view`` (a key of PLANAR_VIEWS) to the frame it looks along an axis of."""
    return np.array(PLANAR_VIEWS[view], dtype=float).T


def to_points(projection, radius, u, v, value):
    """Grid-frame points (..., 3) of nodes at (u, v) holding ``value`` (NaN stays NaN); the
    arrays broadcast, so a row of u and a column of v give a grid's nodes."""
    return stacked(point_components(projection, radius, u, v, value))


def point_components(projection, radius, u, v, value):
    """(x, y, z): the grid-frame coordinates of ``to_points``, each as an array that broadcasts
    to the shape of u, v and value together."""
    u, v, value = (np.asarray(a, dtype=float) for a in (u, v, value))
    if projection == "planar":
        return u, v, value
    dx, dy, dz = ray_components(projection, radius, u, v)
    return value * dx, v if projection == "cylindrical" else value * dy, value * dz


def stacked(components, shape=()):
    """(..., 3) from three arrays that broadcast together (and to ``shape``)."""
    shape = np.broadcast_shapes(shape, *(np.shape(component) for component in components))
    return np.stack([np.broadcast_to(component, shape) for component in components], axis=-1)


def to_nodes(projection, radius, points):
    """(u, v, value) (..., 3) of grid-frame points: the inverse of ``to_points``."""
    points = np.asarray(points, dtype=float)
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    if projection == "planar":
        return points.copy()
    across = np.sqrt(x * x + z * z)
    u = radius * elementary.atan2(x, z)
    if projection == "cylindrical":
        return np.stack([u, y, across], axis=-1)
    return np.stack([u, radius * elementary.atan2(y, across), np.sqrt(x * x + y * y + z * z)], axis=-1)


def ray_directions(projection, radius, u, v):
    """Unit directions (..., 3) of the node lines at (u, v): +z for planar grids."""
    u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    return stacked(ray_components(projection, radius, u, v), np.broadcast_shapes(u.shape, v.shape))


def ray_components(projection, radius, u, v):
    """(dx, dy, dz): the components of ``ray_directions``, each as an array that broadcasts to
    the shape of u and v. The angles' sines and cosines are taken before u and v broadcast (a
    row of u and a column of v: one of each per column and per row, not per node)."""
    if projection == "planar":
        return np.zeros(()), np.zeros(()), np.ones(())
    azimuth = u / radius
    if projection == "cylindrical":
        return elementary.sin(azimuth), np.zeros(()), elementary.cos(azimuth)
    elevation = v / radius
    ring = elementary.cos(elevation)
    return ring * elementary.sin(azimuth), elementary.sin(elevation), ring * elementary.cos(azimuth)


def ray_origins(projection, v):
    """Grid-frame origins (..., 3) of the rays of central projections at row coordinate v:
    the centre for spherical grids, the point of the axis at height v for cylindrical ones."""
    v = np.asarray(v, dtype=float)
    origins = np.zeros(v.shape + (3,))
    if projection == "cylindrical":
        origins[..., 1] = v
    return origins


def metric(projection, radius, v, value):
    """(h_u, h_v): surface length per unit of u and of v along a surface of constant value.

    1 and 1 for planar grids; value/R0 and 1 for cylindrical ones; value cos(elevation)/R0
    and value/R0 for spherical ones. A surface whose value changes by (du, dv) at a node
    leans from the node's line by t with tan^2 t = (dvalue/du / h_u)^2 + (dvalue/dv / h_v)^2,
    and the node stands for the surface area h_u h_v d1 d2 / cos t.
    """
    value = np.asarray(value, dtype=float)
    if projection == "planar":
        return np.ones(value.shape), np.ones(value.shape)
    scale = value / radius
    if projection == "cylindrical":
        return scale, np.ones(value.shape)
    return scale * elementary.cos(np.asarray(v, dtype=float) / radius), scale


def full_turn(projection, radius, cols, d2):
    """True when the columns of a central grid make a full turn (cols * d2 = 2 pi R0)."""
    if projection == "planar":
        return False
    turn = 2 * np.pi * radius
    return abs(cols * d2 - turn) <= FULL_TURN_TOLERANCE * turn


def pole_rows(projection, radius, ys):
    """Per row, True where a spherical grid's row lies on a pole (elevation +-90 degrees):
    every node of such a row stands for the same ray, along the axis."""
    ys = np.asarray(ys, dtype=float)
    if projection != "spherical":
        return np.zeros(ys.shape, dtype=bool)
    return np.abs(ys) >= 0.5 * np.pi * radius * (1 - FULL_TURN_TOLERANCE)


def extent_problem(projection, radius, rows, cols, d1, d2, v0):
    """Why a central grid of this extent cannot exist (its columns span more than a turn, or
    a spherical grid's rows pass a pole), as (field, message); None when it can."""
    if projection == "planar":
        return None
    slack = 1 + FULL_TURN_TOLERANCE
    if cols * d2 > 2 * np.pi * radius * slack:
        return "d2", f"{cols} columns of {d2:g} span more than a full turn at radius {radius:g}"
    if projection == "spherical" and max(abs(v0), abs(v0 + (rows - 1) * d1)) > 0.5 * np.pi * radius * slack:
        return "d1", "rows reach beyond the poles (elevation v / radius outside +-90 degrees)"
    return None
