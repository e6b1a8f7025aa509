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

from mzc import projections
from mzc.errors import MzcError
from mzc.meshes import Mesh

if TYPE_CHECKING:
    from mzc.grid import ZGrid

JUMP_ANGLE = 3.0   # degrees between an edge and the node line below which the edge is a jump
JUMP_STRIP_NODES = 1 << 20   # nodes whose points jump_edges makes at a time when it is given none


@dataclass
class Jumps:
    """Which edges of a grid are depth jumps: ``across`` rows (rows-1, cols; cols+1 on a
    periodic grid, column 0 repeated after the last), ``along`` rows
    (rows, cols-1; cols on a periodic grid, the last joining column cols-1 to 0) and the
    cells' ``diagonal`` from corner 2 to corner 3 (rows-1, cells per row; None when not
    asked for: the lean of the surface at the nodes needs only the other two)."""

    across: np.ndarray
    along: np.ndarray
    diagonal: np.ndarray | None


def jump_edges(grid, angle=None, points=None, diagonal=True):
    """The Jumps of a ZGrid: edges between valid nodes within ``angle`` degrees (default
    JUMP_ANGLE) of the node line through their midpoint (none when ``angle`` is 0); edges
    along a pole row join nodes of one ray, which are one vertex, and are never jumps.
    ``points``: the grid's ``node_points()`` when the caller has them already; without, they
    are made a strip of rows at a time (each edge's test sees only its two nodes, so the
    jumps are the same), which keeps the memory a strip's (several times 24 bytes a node in
    passing), not the grid's. ``diagonal=False`` leaves the diagonals out (None)."""
    angle = JUMP_ANGLE if angle is None else angle
    if points is not None:
        jumps = jumps_between(points, grid.projection, grid.periodic, angle, diagonal)
    else:
        rows, step = grid.shape[0], max(1, JUMP_STRIP_NODES // grid.shape[1])
        starts = range(0, max(rows - 1, 1), step)
        parts = [jumps_between(grid.node_points(slice(low, min(low + step, rows - 1) + 1)), grid.projection,
                               grid.periodic, angle, diagonal) for low in starts]
        last = len(parts) - 1
        jumps = Jumps(across=np.concatenate([part.across for part in parts]),
                      along=np.concatenate([part.along[: None if i == last else -1] for i, part in enumerate(parts)]),
                      diagonal=np.concatenate([part.diagonal for part in parts]) if diagonal else None)
    jumps.along[grid.pole_rows()] = False
    return jumps


def jumps_between(points, projection, periodic, angle, diagonal=True):
    """The Jumps of the edges between grid-frame node ``points`` (rows, cols, 3), pole rows
    aside; the diagonals only with ``diagonal``."""
    if periodic:
        points = np.concatenate([points, points[:, :1]], axis=1)
    planes = [np.ascontiguousarray(points[..., i]) for i in range(3)]   # x, y, z
    return Jumps(across=is_jump(planes, (1, 0, 0), projection, angle),
                 along=is_jump(planes, (0, 0, 1), projection, angle),
                 diagonal=is_jump(planes, (1, 1, 0), projection, angle) if diagonal else None)


def is_jump(planes, kind, projection, angle):
    """Per edge of one ``kind`` (dr, start_dc, end_dc: from node (r, c + start_dc) to node
    (r + dr, c + end_dc)) between the grid-frame points whose x, y and z are ``planes`` (NaN
    where invalid): True where it lies within ``angle`` degrees of the node line through its
    midpoint (the compiled loop of mzc.ops._jumps)."""
    from mzc.ops import _jumps

    dr, start_dc, end_dc = kind
    rows, cols = planes[0].shape
    out = np.zeros((max(rows - dr, 0), max(cols - max(start_dc, end_dc), 0)), dtype=bool)
    if angle <= 0:
        return out
    if _jumps.jumps(out.view(np.uint8), *planes, rows, cols, dr, start_dc, end_dc,
                    projections.PROJECTIONS.index(projection), float(np.cos(np.radians(angle)))):
        raise MzcError("the depth-jump test was given planes of different shapes (an internal error)")
    return out


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
    triangles = grid_triangles(valid, grid.periodic, jump_edges(grid, jump_angle, nodes))
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
