"""Surfaces the tests generate: closed and open ones that go all the way round an axis."""

import numpy as np

from mzc.meshes import Mesh

ICOSAHEDRON_T = (1 + 5 ** 0.5) / 2


def icosphere(subdivisions):
    """(unit vertices, triangles) of a subdivided icosahedron, triangles facing outwards."""
    t = ICOSAHEDRON_T
    points = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
                       [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=float)
    faces = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                      [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                      [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middles = points[unique[:, 0]] + points[unique[:, 1]]
        middles /= np.linalg.norm(middles, axis=1, keepdims=True)
        ab, bc, ca = (len(points) + inverse.reshape(3, -1)).reshape(3, -1)
        points = np.vstack([points, middles])
        a, b, c = faces.T
        faces = np.concatenate([np.stack(f, axis=1) for f in ([a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca])])
    return points, faces


def star_radius(directions):
    """The radius of the star-shaped blob along unit ``directions``: 50 mm with lobes and a bulge."""
    x, y, z = directions.T
    return 50 * (1 + 0.15 * np.sin(3 * np.arctan2(x, z)) * (1 - y ** 2) + 0.1 * y ** 3)


STAR_CENTRE = np.array([5.0, -3.0, 2.0])


def star(subdivisions=5):
    """A closed star-shaped surface about STAR_CENTRE (about 20,000 triangles at 5 subdivisions)."""
    directions, faces = icosphere(subdivisions)
    return Mesh(directions * star_radius(directions)[:, None] + STAR_CENTRE, faces)


def tube_radius(azimuth, height):
    """The tube's distance from its axis (y): 30 mm, four flutes of 3 mm, widening along y."""
    return 30 + 3 * np.sin(4 * azimuth) + 0.05 * height


def tube(around=240, along=200):
    """An open tube 200 mm long about the y axis, its quads split into triangles facing outwards."""
    azimuth, height = np.meshgrid(np.linspace(0, 2 * np.pi, around, endpoint=False), np.linspace(-100, 100, along))
    radius = tube_radius(azimuth, height)
    points = np.stack([radius * np.sin(azimuth), height, radius * np.cos(azimuth)], axis=-1).reshape(-1, 3)
    index = np.arange(along * around).reshape(along, around)
    right = np.roll(index, -1, axis=1)
    a, b, c, d = index[:-1], right[:-1], index[1:], right[1:]
    faces = np.concatenate([np.stack([a, b, c], axis=-1).reshape(-1, 3), np.stack([b, d, c], axis=-1).reshape(-1, 3)])
    return Mesh(points, faces)


def edge_counts(triangles):
    """(edges used by one triangle, edges used by more than two): 0 and 0 for a closed manifold."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int((counts == 1).sum()), int((counts > 2).sum())
