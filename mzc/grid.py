"""The z-grid: a regular grid of heights, the one data model every mzc step shares.

Node (r, c) lies at x = x0 + c*d2, y = y0 + r*d1 in the grid frame and holds z, or NaN
where the node's line misses the surface. Row r is one "horizontal" cutting plane of the
thesis; a rigid transform maps the grid frame back to the frame of the input surface.
"""

from dataclasses import dataclass, field, replace

import numpy as np

IDENTITY_TRANSFORM = np.hstack([np.eye(3), np.zeros((3, 1))])


@dataclass
class ZGrid:
    """Heights ``z`` (rows x cols, NaN = invalid) on a grid with row step ``d1``, column step ``d2``.

    ``origin`` is (x0, y0) of node (0, 0) in the grid frame; ``transform`` is the 3x4
    matrix [R | t] taking grid-frame points p to the input frame as R p + t; ``units``
    names the length unit when known; ``nodata`` is the token written for invalid nodes.
    """

    z: np.ndarray
    d1: float
    d2: float
    origin: tuple = (0.0, 0.0)
    transform: np.ndarray = field(default_factory=lambda: IDENTITY_TRANSFORM.copy())
    units: str | None = None
    nodata: str = "nan"

    def __post_init__(self):
        self.z = np.asarray(self.z, dtype=float)
        if self.z.ndim != 2:
            raise ValueError("z must be a 2D array")
        self.transform = np.asarray(self.transform, dtype=float).reshape(3, 4)
        self.origin = (float(self.origin[0]), float(self.origin[1]))
        self.d1 = float(self.d1)
        self.d2 = float(self.d2)

    @property
    def shape(self):
        """(rows, cols)."""
        return self.z.shape

    @property
    def valid(self):
        """Boolean mask of the nodes that hold a height."""
        return ~np.isnan(self.z)

    def xs(self):
        """Grid-frame x of every column."""
        return self.origin[0] + self.d2 * np.arange(self.z.shape[1])

    def ys(self):
        """Grid-frame y of every row."""
        return self.origin[1] + self.d1 * np.arange(self.z.shape[0])

    def node_points(self):
        """(rows, cols, 3) grid-frame coordinates of every node (z is NaN where invalid)."""
        x, y = np.meshgrid(self.xs(), self.ys())
        return np.stack([x, y, self.z], axis=-1)

    def to_input_frame(self, points):
        """Map (..., 3) grid-frame points to the input surface's frame."""
        rotation, shift = self.transform[:, :3], self.transform[:, 3]
        return points @ rotation.T + shift

    def to_grid_frame(self, points):
        """Map (..., 3) input-frame points to the grid frame (inverse of to_input_frame)."""
        rotation, shift = self.transform[:, :3], self.transform[:, 3]
        return (points - shift) @ rotation

    def with_z(self, z, **changes):
        """A copy with new heights (and any other fields changed)."""
        return replace(self, z=np.asarray(z, dtype=float), **changes)
