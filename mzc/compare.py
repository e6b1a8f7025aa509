"""Sample two surfaces on one common grid, as ``mzc diff`` compares them.

The common grid lies in A's frame (a z-grid's own frame, or a mesh's coordinates as
they are) and covers A's extent. A z-grid compared without new spacings is compared at
its own nodes; otherwise the spacing defaults to a fine one, 1/1000 of A's longest side.
"""

import numpy as np

from mzc.grid import IDENTITY_TRANSFORM

DEFAULT_DIVISIONS = 1000


def common_grid(a, d1=None, d2=None):
    """The comparison grid (a ZGrid of A's heights) for Surface ``a``."""
    from mzc.meshes import Mesh
    from mzc.slicing import slice_in_frame

    if a.grid is not None and d1 is None and d2 is None:
        return a.grid
    transform = a.grid.transform if a.grid is not None else IDENTITY_TRANSFORM
    rotation, shift = transform[:, :3], transform[:, 3]
    extent = np.ptp((a.points - shift) @ rotation, axis=0)[:2]
    d1 = d1 or d2 or extent.max() / DEFAULT_DIVISIONS
    return slice_in_frame(Mesh(a.points, a.triangles), rotation, shift, d1=d1, d2=d2 or d1,
                          units=a.grid.units if a.grid is not None else None)


def sample_like(grid, surface):
    """Heights of ``surface`` at the nodes of ``grid``, in grid's frame (front-most hit)."""
    from mzc.slicing import rasterize

    local = grid.to_grid_frame(surface.points)
    return rasterize(local, surface.triangles, grid.xs(), grid.ys())


def error_grid(a, b, d1=None, d2=None):
    """(A sampled on the common grid, the error surface B - A on the same grid) as ZGrids."""
    reference = common_grid(a, d1, d2)
    other = sample_like(reference, b)
    return reference, reference.with_z(other - reference.z)
