"""Load either kind of surface a command may be given: a mesh file or an mzc file.

``diff`` compares any mix of meshes and z-grids; both become triangle meshes (a z-grid
through its derived connectivity), and a z-grid also keeps its grid and frame.
"""

from dataclasses import dataclass

import numpy as np

from mzc.errors import MzcError
from mzc.streams import display_name, is_stdio, read_input


@dataclass
class Surface:
    """A triangle mesh in the input frame, and the z-grid it came from when it was one."""

    points: np.ndarray
    triangles: np.ndarray
    grid: object = None

    @property
    def is_point_cloud(self):
        """True for points without triangles (a cloud read from a file)."""
        return len(self.triangles) == 0 and self.grid is None


def starts_like_mzc(path):
    """True when the file at ``path`` begins with an mzc magic line."""
    try:
        with open(path, "rb") as handle:
            return handle.read(4) == b"mzc-"
    except OSError:
        return False  # read_mesh reports the problem with the file


def load_surface(path):
    """Read a mesh (OBJ, PLY, ...) or any mzc file (z-grid or compressed) as a Surface.

    stdin may carry an mzc file only; meshes are read from named files.
    """
    from mzc.formats import is_mzc, read_any

    if is_stdio(path) or starts_like_mzc(path):
        data = read_input(path)
        if not is_mzc(data):
            raise MzcError("stdin must carry an mzc file; give meshes as file names",
                           source=display_name(path))
        return surface_from_grid(read_any(data, display_name(path)))
    from mzc.meshes import read_mesh

    mesh = read_mesh(path)
    return Surface(mesh.points, mesh.triangles)


def surface_from_grid(grid):
    """The Surface of a z-grid: its derived triangle mesh in the input frame."""
    from mzc.ops.triangulation import grid_to_mesh

    points, triangles = grid_to_mesh(grid)
    return Surface(points, triangles, grid)
