"""Connectivity derived from the grid (thesis §4.3): it is never stored.

Between rows r, r+1 and columns c, c+1 the corners 1=(r,c), 2=(r,c+1), 3=(r+1,c),
4=(r+1,c+1) give the thesis's triangles 1-2-3 and 2-3-4, each wherever its three corners
are valid. The second is written 2-4-3 so both face +z in the grid frame.
"""

import numpy as np


def grid_triangles(valid):
    """Triangles (m, 3) over the flat node indices of a (rows, cols) validity mask."""
    rows, cols = valid.shape
    index = np.arange(rows * cols).reshape(rows, cols)
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
    triangles = grid_triangles(valid)
    used = np.zeros(valid.size, dtype=bool)
    used[triangles.ravel()] = True
    new_index = np.cumsum(used) - 1
    points = grid.to_input_frame(grid.node_points().reshape(-1, 3)[used])
    return points, new_index[triangles]
