"""Connectivity derived from the grid (thesis §4.3): it is never stored.

Between rows r, r+1 and columns c, c+1 the corners 1=(r,c), 2=(r,c+1), 3=(r+1,c),
4=(r+1,c+1) give the thesis's triangles 1-2-3 and 2-3-4, each wherever its three corners
are valid. The second is written 2-4-3 so both face the node lines' outward direction
(+z in a planar grid frame). A grid whose columns make a full turn also joins its last
column to its first, so a closed surface has no seam; the nodes of a pole row of a
spherical grid are one point, so its cells become a fan of triangles about the pole.
"""

import numpy as np


def grid_triangles(valid, periodic=False):
    """Triangles (m, 3) over the flat node indices of a (rows, cols) validity mask; with
    ``periodic`` the cells between the last column and the first too."""
    rows, cols = valid.shape
    index = np.arange(rows * cols).reshape(rows, cols)
    if periodic:
        index, valid = np.hstack([index, index[:, :1]]), np.hstack([valid, valid[:, :1]])
    corner1, corner2 = index[:-1, :-1], index[:-1, 1:]
    corner3, corner4 = index[1:, :-1], index[1:, 1:]
    ok1, ok2 = valid[:-1, :-1], valid[:-1, 1:]
    ok3, ok4 = valid[1:, :-1], valid[1:, 1:]
    first = np.stack([corner1, corner2, corner3], axis=-1)[ok1 & ok2 & ok3]
    second = np.stack([corner2, corner4, corner3], axis=-1)[ok2 & ok3 & ok4]
    return np.concatenate([first, second]).reshape(-1, 3)


def grid_to_mesh(grid):
    """(points, triangles) of a ZGrid: valid nodes in the input frame, unused nodes dropped."""
    valid = grid.valid
    points = grid.node_points().reshape(-1, 3)
    triangles = merge_poles(grid_triangles(valid, grid.periodic), points, valid, grid.pole_rows())
    used = np.zeros(valid.size, dtype=bool)
    used[triangles.ravel()] = True
    new_index = np.cumsum(used) - 1
    return grid.to_input_frame(points[used]), new_index[triangles]


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
