"""Connectivity derived from the grid (thesis §4.3): it is never stored.

Between rows r, r+1 and columns c, c+1 the corners 1=(r,c), 2=(r,c+1), 3=(r+1,c),
4=(r+1,c+1) give the thesis's triangles 1-2-3 and 2-3-4, each wherever its three corners
are valid. The second is written 2-4-3 so both face the node lines' outward direction
(+z in a planar grid frame). A grid whose columns make a full turn also joins its last
column to its first, so a closed surface has no seam; the nodes of a pole row of a
spherical grid are one point, so its cells become a fan of triangles about the pole.

Depth discontinuities (spec/zgrid.md, Connectivity). Neighbouring nodes on either side of
a depth jump (a person in front of a wall, the layers of a part, the rim of a fold the
outermost hit cannot see) are far apart along the node lines and close across them: the
edge joining them runs nearly along the lines. Such an edge is a *jump* when it makes an
angle of less than JUMP_ANGLE with the node line through its midpoint (the "shadow" test
of range-image meshing, as in PCL's OrganizedFastMesh, which uses 12.5 degrees), and the
triangles with a jump edge are not surface: they are dropped. 3 degrees (a rise of more
than 19 node spacings across one cell) drops nothing of the default 0.5 mm grids of the
13 faces; 4 degrees dropped 3-38 triangles of two of them and 5 degrees 110 of
``example.obj``, raising its whole-surface RMS by 14%: grazing surface, not jumps.
"""

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mzc.meshes import Mesh

if TYPE_CHECKING:
    from mzc.grid import ZGrid

JUMP_ANGLE = 3.0   # degrees between an edge and the node line below which the edge is a jump
STRIP_NODES = 1 << 20   # nodes whose edges jump_edges tests at a time


@dataclass
class Jumps:
    """Which edges of a grid are depth jumps: ``across`` rows (rows-1, cols; cols+1 on a
    periodic grid, column 0 repeated after the last), ``along`` rows
    (rows, cols-1; cols on a periodic grid, the last joining column cols-1 to 0) and the
    cells' ``diagonal`` from corner 2 to corner 3 (rows-1, cells per row)."""

    across: np.ndarray
    along: np.ndarray
    diagonal: np.ndarray


def jump_edges(grid, angle=None):
    """The Jumps of a ZGrid: edges between valid nodes within ``angle`` degrees (default
    JUMP_ANGLE) of the node line through their midpoint (none when ``angle`` is 0); edges
    along a pole row join nodes of one ray, which are one vertex, and are never jumps.

    Each edge's test reads its two nodes' values and where the grid puts their lines
    (``is_jump``), so the grid is tested a strip of rows at a time (``row_strips``): the
    temporaries are a strip's (several times 8 bytes a node), not the grid's."""
    parts = [jumps_between(grid, low, high, angle) for low, high in row_strips(grid.shape)]
    last = len(parts) - 1
    return Jumps(across=np.concatenate([part.across for part in parts]),
                 along=np.concatenate([part.along[: None if i == last else -1] for i, part in enumerate(parts)]),
                 diagonal=np.concatenate([part.diagonal for part in parts]))


def row_strips(shape):
    """(low, high) per strip of about STRIP_NODES nodes: the cells between rows low and high
    (the last strip's high is the last row; a grid of one row is one strip of no cells)."""
    rows, step = shape[0], max(1, STRIP_NODES // shape[1])
    return [(low, min(low + step, rows - 1)) for low in range(0, max(rows - 1, 1), step)]


def jumps_between(grid, low, high, angle=None):
    """The Jumps of the edges between rows low..high of ``grid`` (``jump_edges``)."""
    angle = JUMP_ANGLE if angle is None else angle
    z = grid.z[low:high + 1]
    if grid.periodic:
        z = np.concatenate([z, z[:, :1]], axis=1)
    if angle <= 0:
        return Jumps(across=np.zeros((len(z) - 1, z.shape[1]), dtype=bool),
                     along=np.zeros((len(z), z.shape[1] - 1), dtype=bool),
                     diagonal=np.zeros((len(z) - 1, z.shape[1] - 1), dtype=bool))
    chords = EdgeChords.of(grid, grid.ys()[low:high + 1])
    cosine2 = np.cos(np.radians(angle)) ** 2
    jumps = Jumps(across=is_jump(z[:-1], z[1:], chords.across, cosine2),
                  along=is_jump(z[:, :-1], z[:, 1:], chords.along, cosine2),
                  diagonal=is_jump(z[:-1, 1:], z[1:, :-1], chords.diagonal, cosine2))
    jumps.along[grid.pole_rows()[low:high + 1]] = False
    return jumps


@dataclass
class EdgeChords:
    """The grid's geometry as each kind of edge sees it: (spread, rise) for edges ``across``
    rows, ``along`` them and along the cells' ``diagonal``s, each a number or a column of one
    per row (per row pair), such that the edge between nodes of values a and b has

        |e|^2 = (b - a)^2 + a b spread + rise   and   4 |m|^2 = (a + b)^2 - a b spread,

    m the part of its midpoint that fixes the node line through it (its projection on the xz
    plane for cylindrical grids, the point itself for spherical ones; None on planar grids,
    whose lines are all +z). For central grids spread = 2 - 2 cos(angle between the rays)
    and rise the squared step along the axis; for planar ones rise is the squared step
    across the lines."""

    across: tuple
    along: tuple
    diagonal: tuple

    @classmethod
    def of(cls, grid, ys):
        """The chords of ``grid``'s edges between the rows at ``ys``."""
        d1, d2 = grid.d1, grid.d2
        if grid.projection == "planar":
            return cls(across=(None, d1 * d1), along=(None, d2 * d2), diagonal=(None, d1 * d1 + d2 * d2))
        turn = 4 * np.sin(d2 / grid.radius / 2) ** 2             # 2 - 2 cos of the columns' angle
        if grid.projection == "cylindrical":
            return cls(across=(0.0, d1 * d1), along=(turn, 0.0), diagonal=(turn, d1 * d1))
        ring = np.cos(ys / grid.radius)[:, None]                 # spherical: rows are cones of elevation ys / R
        tilt = 4 * np.sin(d1 / grid.radius / 2) ** 2
        return cls(across=(tilt, 0.0), along=(ring * ring * turn, 0.0),
                   diagonal=(tilt + ring[:-1] * ring[1:] * turn, 0.0))


def is_jump(start, end, chord, cosine2):
    """Per edge between nodes of values ``start`` and ``end`` (NaN where invalid), whose
    geometry is ``chord`` = (spread, rise) (``EdgeChords``): True where the edge e lies within
    the angle whose squared cosine is ``cosine2`` of the node line through its midpoint m.

    With a, b the values, e . m = (b^2 - a^2) / 2 (both points lie at their value's distance
    along their lines), so |e . d(m)| > cos(A) |e| (spec/zgrid.md) becomes
    (b^2 - a^2)^2 > cos^2(A) |e|^2 4 |m|^2, and on planar grids (b - a)^2 > cos^2(A) |e|^2:
    no points, square roots or divisions, and the same edges as the test on the points but
    for an edge within rounding of the angle."""
    spread, rise = chord
    delta = end - start
    if spread is None:
        return delta * delta > cosine2 * (delta * delta + rise)
    total = end + start
    product = start * end * spread
    return (delta * total) ** 2 > cosine2 * (delta * delta + product + rise) * (total * total - product)


def grid_triangles(valid, periodic=False, jumps=None):
    """Triangles (m, 3) over the flat node indices of a (rows, cols) validity mask; with
    ``periodic`` the cells between the last column and the first too; with ``jumps`` (a
    Jumps) only the triangles none of whose edges is a jump."""
    rows, cols = valid.shape
    index = np.arange(rows * cols).reshape(rows, cols)
    if periodic:
        index, valid = np.hstack([index, index[:, :1]]), np.hstack([valid, valid[:, :1]])
    corner1, corner2 = index[:-1, :-1], index[:-1, 1:]
    corner3, corner4 = index[1:, :-1], index[1:, 1:]
    keep_first = valid[:-1, :-1] & valid[:-1, 1:] & valid[1:, :-1]
    keep_second = valid[:-1, 1:] & valid[1:, 1:] & valid[1:, :-1]
    if jumps is not None:
        keep_first &= ~(jumps.along[:-1] | jumps.across[:, :-1] | jumps.diagonal)
        keep_second &= ~(jumps.across[:, 1:] | jumps.along[1:] | jumps.diagonal)
    first = np.stack([corner1, corner2, corner3], axis=-1)[keep_first]
    second = np.stack([corner2, corner4, corner3], axis=-1)[keep_second]
    return np.concatenate([first, second]).reshape(-1, 3)


def grid_to_mesh(grid: "ZGrid", jump_angle: float | None = None) -> Mesh:
    """The Mesh of a ZGrid (its ``grid`` set to it): valid nodes in the input frame, unused
    nodes dropped, no triangle across a depth jump of ``jump_angle`` degrees (default
    JUMP_ANGLE; 0 keeps them all)."""
    valid = grid.valid
    nodes = grid.node_points()
    triangles = grid_triangles(valid, grid.periodic, jump_edges(grid, jump_angle))
    points = nodes.reshape(-1, 3)
    triangles = merge_poles(triangles, points, valid, grid.pole_rows())
    used = np.zeros(valid.size, dtype=bool)
    used[triangles.ravel()] = True
    new_index = np.cumsum(used) - 1
    return Mesh(grid.to_input_frame(points[used]), new_index[triangles], grid=grid)


def merge_poles(triangles, points, valid, poles):
    """Triangles with the valid nodes of each pole row made one vertex (their mean point,
    written into ``points``) and the triangles that collapse to an edge dropped."""
    cols = valid.shape[1]
    for row in np.flatnonzero(poles):
        nodes = row * cols + np.flatnonzero(valid[row])
        if not len(nodes):
            continue
        points[nodes[0]] = points[nodes].mean(axis=0)
        triangles = np.where(np.isin(triangles, nodes), nodes[0], triangles)
    distinct = ((triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2])
                & (triangles[:, 0] != triangles[:, 2]))
    return triangles[distinct]
