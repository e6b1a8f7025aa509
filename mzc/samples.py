"""Built-in sample surfaces, so mzc can be tried with no file to download.

Two real elevation models ship with matplotlib (a USGS DEM of the Jacksboro fault, and
a topography/bathymetry grid off the Pacific Northwest); their lat/lon steps are turned
into metres with a local equirectangular projection. The others are generated: ``bump``,
a smooth patch with a hole; ``blob``, a closed star-shaped surface (a head-sized lobed
ball, cut from its centre by a spherical grid); ``tube``, an open fluted tube (cut round
its axis by a cylindrical grid). The terrains come as grids, the generated surfaces
that go all the way round as meshes.
"""

import math

import numpy as np

from mzc import elementary
from mzc.grid import ZGrid
from mzc.meshes import Mesh
from mzc.vectors import lengths

BLOB_CENTRE = np.array([5.0, -3.0, 2.0])

METRES_PER_DEGREE = 111_320.0


def jacksboro():
    """The Jacksboro fault DEM (344 x 403, about 92 x 74 m cells), metres, north up."""
    from matplotlib import cbook

    data = cbook.get_sample_data("jacksboro_fault_dem.npz")
    latitude = (float(data["ymin"]) + float(data["ymax"])) / 2
    d1 = float(data["dy"]) * METRES_PER_DEGREE
    d2 = float(data["dx"]) * METRES_PER_DEGREE * elementary.cos(math.radians(latitude))
    z = np.flipud(data["elevation"].astype(float))  # the file's first row is the northern one
    return ZGrid(z, d1, d2, units="m")


def topobathy():
    """Topography and bathymetry (91 x 120, about 2.5 x 2.5 km cells), metres."""
    from matplotlib import cbook

    data = cbook.get_sample_data("topobathy.npz")
    latitude, longitude = data["latitude"].astype(float), data["longitude"].astype(float)
    d1 = np.diff(latitude).mean() * METRES_PER_DEGREE
    d2 = np.diff(longitude).mean() * METRES_PER_DEGREE * elementary.cos(math.radians(latitude.mean()))
    return ZGrid(data["topo"].astype(float), d1, d2, units="m")


def bump():
    """A generated 120 x 160 mm patch: two Gaussian bumps on a tilted plane, with a round hole."""
    y, x = np.mgrid[0:120:0.5, 0:160:0.5]
    z = (30 * elementary.exp(-((x - 60) ** 2 + (y - 60) ** 2) / 800)
         + 12 * elementary.exp(-((x - 115) ** 2 + (y - 50) ** 2) / 200) + 0.05 * x - 0.02 * y)
    z[(x - 120) ** 2 + (y - 95) ** 2 < 10**2] = np.nan
    return ZGrid(z, 0.5, 0.5, units="mm")


def icosphere(subdivisions):
    """(unit vertices, triangles) of a subdivided icosahedron, its triangles facing outwards."""
    t = (1 + math.sqrt(5)) / 2
    points = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
                       [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=float)
    faces = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                      [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                      [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    points /= lengths(points)[:, None]
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middles = points[unique[:, 0]] + points[unique[:, 1]]
        middles /= lengths(middles)[:, None]
        ab, bc, ca = (len(points) + inverse.reshape(3, -1)).reshape(3, -1)
        points = np.vstack([points, middles])
        a, b, c = faces.T
        faces = np.concatenate([np.stack(f, axis=1) for f in ([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca])])
    return points, faces


def blob_radius(directions):
    """The blob's radius along unit ``directions``: 50 mm with three lobes and a bulge upwards."""
    x, y, z = directions.T
    return 50 * (1 + 0.15 * elementary.sin(3 * elementary.atan2(x, z)) * (1 - y * y) + 0.1 * (y * y * y))


def blob(subdivisions=5):
    """A closed star-shaped surface about BLOB_CENTRE, mm (20,480 triangles at 5 subdivisions)."""
    directions, faces = icosphere(subdivisions)
    return Mesh(directions * blob_radius(directions)[:, None] + BLOB_CENTRE, faces)


def tube_radius(azimuth, height):
    """The tube's distance from its axis (y): 30 mm, four flutes of 3 mm, widening along y."""
    return 30 + 3 * elementary.sin(4 * azimuth) + 0.05 * height


def tube(around=240, along=200):
    """An open tube 200 mm long about the y axis, mm: a full turn's lattice, triangulated as a grid."""
    azimuth, height = np.meshgrid(np.linspace(0, 2 * np.pi, around, endpoint=False), np.linspace(-100, 100, along))
    radius = tube_radius(azimuth, height)
    from mzc.ops.triangulation import grid_triangles

    points = np.stack([radius * elementary.sin(azimuth), height, radius * elementary.cos(azimuth)],
                      axis=-1).reshape(-1, 3)
    return Mesh(points, grid_triangles(np.ones(azimuth.shape, dtype=bool), periodic=True))


SAMPLES = {"jacksboro": jacksboro, "topobathy": topobathy, "bump": bump, "blob": blob, "tube": tube}


def sample_mesh(name: str) -> Mesh:
    """The mesh of sample ``name``: a grid sample through its derived connectivity."""
    from mzc.ops.triangulation import grid_to_mesh

    surface = SAMPLES[name]()
    return surface if isinstance(surface, Mesh) else grid_to_mesh(surface)
