"""Multi-chart grids of a mesh, for the zipper's tests (the real segmentation, issue 28, will replace this).

Each triangle is labelled with the axis direction of PLANAR_VIEWS closest to its normal, the
labels are smoothed a little (a triangle takes the label most of it and its edge neighbours
have), and each connected piece of one label is a chart: its own triangles (no other
chart's) are rasterized on the planar grid looking along its direction, nodes at i h, j h in
that grid's frame (the lattice of the input frame's origin), and the grid is triangulated
as ``mzc.ops.triangulation`` triangulates every grid. A piece that hides part of itself
along its direction (a fold, a spiral) keeps the triangles in front, and those behind
become pieces of their own, until every chart is a single layer.
"""

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from mzc.ops.raster import heights_on_triangles, rasterize
from mzc.ops.triangulation import grid_triangles
from mzc.ops.views import PLANAR_VIEWS
from mzc.vectors import dotted, rotated

FRAMES = [np.array(axes, dtype=float).T for axes in PLANAR_VIEWS.values()]   # input = frame @ grid point
SMOOTHING = 2   # rounds of the neighbours' vote
MERGING = 3     # rounds of small pieces taking a neighbour's label
SMALL_PIECE = 16.0   # cells: the area of a piece too small for a chart of its own
HIDDEN = 0.5    # spacings behind the front at which a triangle is another layer
STEEP = 75.0    # degrees from the view beyond which a grid triangle is not the chart's surface
FEWEST = 2      # triangles: a grid of fewer is a crumb (a body or a hidden layer under the spacing), no chart


def chart_meshes(points, triangles, spacing):
    """(points (n, 3), triangles (m, 3), chart (n,)): the union of the chart meshes of a mesh at ``spacing``."""
    points, triangles = np.asarray(points, dtype=float), np.asarray(triangles, dtype=np.int64)
    pairs = neighbour_pairs(triangles)
    label = triangle_labels(points, triangles, pairs, spacing)
    graph = same_label_graph(pairs, label)
    queue = pieces(graph, np.arange(len(triangles)))
    parts = []
    while queue:
        members = queue.pop(0)
        part, hidden = chart_grid(points, triangles[members], FRAMES[label[members[0]]], spacing)
        queue += pieces(graph, members[hidden])
        if part is not None:
            parts.append((*part, np.full(len(part[0]), len(parts))))
    offsets = np.cumsum([0] + [len(p[0]) for p in parts])
    return (np.concatenate([np.empty((0, 3))] + [p[0] for p in parts]),
            np.concatenate([np.empty((0, 3), dtype=np.int64)] + [p[1] + o for p, o in zip(parts, offsets)]),
            np.concatenate([np.empty(0, dtype=np.int64)] + [p[2] for p in parts]))


def same_label_graph(pairs, label):
    """The graph (sparse, triangles by triangles) of neighbour pairs with the same label."""
    same = pairs[label[pairs[:, 0]] == label[pairs[:, 1]]]
    return coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(len(label),) * 2).tocsr()


def pieces(graph, members):
    """The connected pieces (arrays of triangle indices) of the triangles ``members`` in ``graph``."""
    _count, piece = connected_components(graph[members][:, members], directed=False)
    return [members[piece == index] for index in np.unique(piece)]


def triangle_labels(points, triangles, pairs, spacing):
    """Per triangle, the index in PLANAR_VIEWS of the direction nearest its normal, smoothed by
    its neighbours' votes, and pieces smaller than SMALL_PIECE cells taken into a neighbour's
    label; never a direction that sees a triangle at more than STEEP degrees."""
    corners = points[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = np.sqrt(dotted(normal, normal))
    cosine = np.stack([dotted(normal, frame[:, 2]) for frame in FRAMES], axis=1)
    label = np.argmax(cosine, axis=1)
    allowed = cosine > np.cos(np.radians(STEEP)) * area[:, None]
    for round_ in range(SMOOTHING + MERGING):
        votes = np.zeros((len(triangles), len(FRAMES)))
        for a, b in (pairs.T, pairs.T[::-1]):
            np.add.at(votes, (a, label[b]), 1.0)
        if round_ < SMOOTHING:
            votes[np.arange(len(label)), label] += 1.5   # its own label wins ties
            change = np.ones(len(label), dtype=bool)
        else:
            _count, piece = connected_components(same_label_graph(pairs, label), directed=False)
            change = np.bincount(piece, weights=area / 2)[piece] < SMALL_PIECE * spacing * spacing
            votes[np.arange(len(label)), label] = 0.0
        votes[~allowed] = -1.0
        best = np.argmax(votes, axis=1)
        label = np.where(change & (votes[np.arange(len(label)), best] > 0), best, label)
    return label


def neighbour_pairs(triangles):
    """(k, 2) pairs of triangles that share an edge."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(triangles)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, owner = edges[order], owner[order]
    same = (edges[1:] == edges[:-1]).all(axis=1)
    return np.stack([owner[:-1][same], owner[1:][same]], axis=1)


def chart_grid(points, triangles, frame, spacing):
    """((points, triangles) of the grid mesh of ``triangles`` seen along the frame's z, or None
    with fewer than FEWEST triangles; which triangles lie behind others, HIDDEN spacings or
    more, left out of it)."""
    used = np.unique(triangles)
    local = np.zeros((len(points), 3))
    local[used] = rotated(points[used], frame.T)
    low, high = local[used].min(axis=0), local[used].max(axis=0)
    xs = spacing * np.arange(np.ceil(low[0] / spacing), np.floor(high[0] / spacing) + 1)
    ys = spacing * np.arange(np.ceil(low[1] / spacing), np.floor(high[1] / spacing) + 1)
    hidden = np.zeros(len(triangles), dtype=bool)
    if len(xs) < 2 or len(ys) < 2:
        return None, hidden
    z = rasterize(local, triangles, xs, ys)
    hidden = behind(local[triangles], xs, ys, z, HIDDEN * spacing)
    if hidden.any():
        z = rasterize(local, triangles[~hidden], xs, ys)
    grid = grid_triangles(~np.isnan(z))
    nodes = np.stack([np.broadcast_to(xs, z.shape), np.broadcast_to(ys[:, None], z.shape), z], axis=-1).reshape(-1, 3)
    grid = grid[~steep(nodes[grid])]
    if len(grid) < FEWEST:
        return None, hidden
    used, grid = np.unique(grid, return_inverse=True)
    return (rotated(nodes[used], frame), grid.reshape(-1, 3)), hidden


def steep(corners):
    """Which grid triangles (corners (m, 3, 3) in the grid frame) turn more than STEEP degrees from
    the grid's z: cells that join parts of the surface the grid sees side by side at other heights."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return normal[:, 2] < np.cos(np.radians(STEEP)) * np.sqrt(dotted(normal, normal))


def behind(corners, xs, ys, z, depth):
    """Which triangles (corners (m, 3, 3) in the grid frame) lie more than ``depth`` below the
    front-most heights ``z`` at a node they cover."""
    step = xs[1] - xs[0]
    first = np.ceil((corners[:, :, :2].min(axis=1) - [xs[0], ys[0]]) / step).astype(np.int64)
    last = np.floor((corners[:, :, :2].max(axis=1) - [xs[0], ys[0]]) / step).astype(np.int64)
    first, last = np.maximum(first, 0), np.minimum(last, [len(xs) - 1, len(ys) - 1])
    span = np.maximum(last - first + 1, 0)
    owner = np.repeat(np.arange(len(corners)), span[:, 0] * span[:, 1])
    within = np.arange(len(owner)) - np.repeat(np.cumsum(span[:, 0] * span[:, 1]) - span[:, 0] * span[:, 1],
                                               span[:, 0] * span[:, 1])
    col = first[owner, 0] + within % span[owner, 0]
    row = first[owner, 1] + within // span[owner, 0]
    height, hit = heights_on_triangles(corners, owner, xs[col], ys[row])
    deep = hit & (height < z[row, col] - depth)
    return np.bincount(owner[deep], minlength=len(corners)) > 0
