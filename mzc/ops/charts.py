"""Multi-chart grids: a closed or many-part surface cut into charts, each a planar grid of its own.

One grid keeps one hit per node line, the outermost: on a whole object (a statue, a body,
a machined part) the back of a far ear, inner legs, mouths and bores are simply missing.
Here the surface is cut into pieces, each sampled along the one of the six axis directions
of the slicing frame (PLANAR_VIEWS) that its normals face within 60 degrees (the nearest
axis is always within 54.7 degrees), as MPEG V-PCC projects patches onto the faces of a
box and multi-chart geometry images sample charts of any shape:

1. each triangle takes the direction nearest its normal, then the direction its
   neighbours hold where that stays within 60 degrees (SMOOTHING rounds: compact charts,
   fewer seams);
2. a chart is a connected piece of one direction; a piece smaller than SMALL_CHART cells
   (where a coarse or jagged mesh turns faster than the directions can follow) joins the
   neighbouring piece whose direction its elements face best, within 80 degrees (a planar
   triangle is sampled exactly however steeply; what the limit saves is the sampling
   density of smooth scanned surfaces, which never form such pieces); a piece that hides
   part of itself along its lines (a curl, a fold) is peeled into layers, each a chart, and
   a peeled piece under MERGE_CELLS cells joins a neighbouring chart whose view sees all of it
   within 60 degrees, in one layer with it; a piece left on its own that its view sees beyond
   60 degrees takes the view that sees all of it within 60 degrees best;
3. each chart is rasterized alone (``mzc.ops.raster``: its own triangles only, so other
   charts never hide it) on the lattice of spacing h in its direction's frame (a piece too
   thin for its hits to make a cell takes its planes at the nodes within h of it), and the
   charts' blocks are packed in shelves into one strip of values (``ZGrid.charts``).

The grid is then coded as any other (``--dwt2d`` codes the packed values as one grid, so
an error target holds over the whole object) and triangulation zips the charts together.
A point cloud with normals (an oriented scan of a whole object) is cut the same way, its
points taking the place of triangles and each chart's points triangulated in its plane.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.grid import Chart, ZGrid
from mzc.ops.raster import rasterize
from mzc.projections import PLANAR_VIEWS, view_rotation
from mzc.vectors import dotted, lengths, of_each_row, rotated

VIEWS = tuple(PLANAR_VIEWS)
FACING = 0.5            # a surface element belongs only to a direction within 60 degrees of its normal
SMOOTHING = 4           # rounds in which each element leans to its neighbours' direction...
NEIGHBOUR_WEIGHT = 0.6  # ...by this much (a cosine's worth) for all its neighbours holding it
SMALL_CHART = 64        # cells (h^2 of area): a smaller piece joins a neighbouring piece...
JOINING = 0.17          # ...whose direction its elements face within 80 degrees
JOIN_ROUNDS = 6         # rings of a small piece's elements joined to their neighbours, at most
MIN_CHART_CELLS = 4     # a piece left smaller than this is dropped: the seams' zipping covers it
MERGE_CELLS = 256       # cells: a peeled piece smaller than this joins a neighbouring piece...
SAME_SURFACE = 1.0      # ...whose grid, where both meet a node line, meets it within this many spacings
LAYER_TOLERANCE = 3.0   # spacings: a triangle this far behind its chart's surface is hidden by it
MAX_LAYERS = 8          # layers peeled off one direction's pieces
CLOUD_NEIGHBOURS = 8    # a cloud point's neighbours, for its chart's smoothing and connection
WIDENED_RISE = 2.0      # a thin piece's plane carried a spacing off it rises at most this many spacings (a
                        # triangle facing its view within 60 degrees: tan 60 = 1.73)


def directions():
    """(6, 3): the direction each view looks along, in the slicing frame."""
    return np.array([view_rotation(view)[:, 2] for view in VIEWS])


def chart_surface(mesh, rotation, shift, spacing, units=None, max_charts=None):
    """The multi-chart ZGrid of ``mesh`` (triangles, or a point cloud with normals) in the frame
    where input = rotation @ p + shift, at ``spacing``; at most ``max_charts`` charts (the
    largest; the others' pieces join their neighbours) when given."""
    local = rotated(np.asarray(mesh.points, dtype=float) - shift, rotation.T)
    if mesh.is_point_cloud:
        if mesh.normals is None:
            raise MzcError("a point cloud needs normals to be cut into charts (slice it with --charts 1)",
                           field="charts")
        pieces = cloud_pieces(local, rotated(mesh.normals, rotation.T), spacing)
    else:
        pieces = mesh_pieces(local, np.asarray(mesh.triangles, dtype=np.int64), spacing)
    if max_charts is not None:
        pieces = sorted(pieces, key=lambda piece: -piece.area)[:max_charts]
    blocks = [block for block in (piece.block(spacing) for piece in pieces) if block is not None]
    if not blocks:
        raise MzcError("no chart meets the surface at this spacing")
    return packed(blocks, spacing, np.column_stack([rotation, shift]), units)


class Piece:
    """A chart to be: the view (index into VIEWS) it is seen along, the points in that view's
    frame (``view_frames``) and the triangles of one connected, single layer piece of the surface."""

    def __init__(self, view, local, triangles):
        self.view, self.local, self.triangles = view, local, triangles
        corners = local[triangles]
        self.area = float(lengths(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])).sum()) / 2

    def block(self, spacing):
        """(Chart without its place, its values) rasterized on the lattice, or None when no node meets it.
        A piece too thin for its nodes to make a cell (``makes_cells``: a fin, a spike narrower than a
        cell) takes its triangles' planes at the nodes within a spacing of it (``widened``): else its
        chart holds no triangle and the rebuild lacks it (the dragon's fins, 1.35% D away)."""
        used = self.local[np.unique(self.triangles)]
        low = np.floor(used[:, :2].min(axis=0) / spacing).astype(np.int64) - 1
        high = np.ceil(used[:, :2].max(axis=0) / spacing).astype(np.int64) + 1
        xs, ys = ((start + np.arange(end - start + 1)) * spacing for start, end in zip(low, high))
        z = rasterize(self.local, self.triangles, xs, ys)
        if not makes_cells(~np.isnan(z)):
            z = np.where(np.isnan(z), widened(self.local[self.triangles], xs, ys, spacing), z)
        valid = ~np.isnan(z)
        if not valid.any():
            return None
        rows, cols = np.flatnonzero(valid.any(axis=1)), np.flatnonzero(valid.any(axis=0))
        z = z[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1]
        return VIEWS[self.view], int(low[0] + cols[0]), int(low[1] + rows[0]), z


def makes_cells(valid):
    """True when some cell of the ``valid`` mask has three or more valid corners: a triangle to show."""
    corners = valid[:-1, :-1].astype(np.int8) + valid[1:, :-1] + valid[:-1, 1:] + valid[1:, 1:]
    return bool(np.any(corners >= 3))


def widened(corners, xs, ys, spacing):
    """(len(ys), len(xs)): at each node within a spacing of the triangles ``corners`` (t, 3, 3) seen
    along z, the height of the plane of the nearest of them there (the first of equally near ones;
    NaN elsewhere, for a triangle seen edge-on, and where the plane rises more than WIDENED_RISE
    spacings beyond the triangle's own heights, as a sliver nearly edge-on does: a cloud's armadillo
    at 3 times its spacing had three nodes at 10^12): a thin piece's surface carried to the nodes
    about it, off it by at most a spacing. Only the nodes in each triangle's box grown by a spacing
    are measured against it (``box_pairs``): a long thin piece's box may hold many nodes."""
    triangle, row, col = box_pairs(corners[..., :2], xs, ys, spacing)
    point, flat = np.column_stack([xs[col], ys[row]]), corners[triangle, :, :2]
    reach = np.min([segment_distances(point, flat[:, k], flat[:, (k + 1) % 3]) for k in range(3)], axis=0)
    node = row * len(xs) + col
    order = np.lexsort((triangle, reach, node))
    first = order[np.flatnonzero(np.diff(node[order], prepend=-1) != 0)]   # each node's nearest triangle
    first = first[reach[first] <= spacing]
    chosen = corners[triangle[first]]
    normal = np.cross(chosen[:, 1] - chosen[:, 0], chosen[:, 2] - chosen[:, 0])
    seen = normal[:, 2] > 0
    first, chosen, normal = first[seen], chosen[seen], normal[seen]
    across = normal[:, 0] * (point[first, 0] - chosen[:, 0, 0]) + normal[:, 1] * (point[first, 1] - chosen[:, 0, 1])
    carried = chosen[:, 0, 2] - across / normal[:, 2]
    lowest, highest = chosen[..., 2].min(axis=1), chosen[..., 2].max(axis=1)
    near = (carried >= lowest - WIDENED_RISE * spacing) & (carried <= highest + WIDENED_RISE * spacing)
    height = np.full(len(ys) * len(xs), np.nan)
    height[node[first][near]] = carried[near]
    return height.reshape(len(ys), len(xs))


def box_pairs(flat, xs, ys, spacing):
    """(triangle, row, col) of every node (xs[col], ys[row]) in the box of each triangle ``flat``
    (t, 3, 2), grown by ``spacing`` on every side."""
    low, high = flat.min(axis=1) - spacing, flat.max(axis=1) + spacing
    col0, col1 = np.searchsorted(xs, low[:, 0], "left"), np.searchsorted(xs, high[:, 0], "right")
    row0, row1 = np.searchsorted(ys, low[:, 1], "left"), np.searchsorted(ys, high[:, 1], "right")
    cols, count = col1 - col0, (col1 - col0) * (row1 - row0)
    triangle = np.repeat(np.arange(len(flat)), count)
    within = np.arange(len(triangle)) - np.repeat(np.cumsum(count) - count, count)
    return triangle, row0[triangle] + within // cols[triangle], col0[triangle] + within % cols[triangle]


def segment_distances(point, a, b):
    """(n,): the distance from each 2D point (n, 2) to its segment a-b (n, 2 each)."""
    ab = b - a
    along = of_each_row(np.sum, (point - a) * ab) / np.maximum(of_each_row(np.sum, ab * ab), 1e-300)
    return lengths(point - (a + np.clip(along, 0, 1)[:, None] * ab))


# --------------------------------------------------------------------------- when one grid will do

SINGLE_COVER = 0.9      # one grid will do when it meets this share of the area (auto; the faces: 0.95-0.97)
COVER_SAMPLES = 4096    # surface elements sampled to measure it


def single_grid_cover(grid, mesh):
    """The share of the surface's area (a seeded sample of its triangles, or of a cloud's points
    with normals) that ``grid`` holds: its element lies within LAYER_TOLERANCE spacings of the
    grid's surface along its node line, facing the line within 60 degrees. None for a cloud
    without normals (nothing tells which side it faces)."""
    from mzc.projections import ray_directions, to_nodes

    sample = surface_sample(mesh)
    if sample is None:
        return None
    centre, normal, area = sample
    local = grid.to_grid_frame(centre)
    nodes = to_nodes(grid.projection, grid.radius, local)
    lines = ray_directions(grid.projection, grid.radius, nodes[:, 0], nodes[:, 1])
    normal = rotated(normal, grid.transform[:, :3].T)
    col = np.floor((nodes[:, 0] - grid.origin[0]) / grid.d2).astype(np.int64) + 1
    row = np.floor((nodes[:, 1] - grid.origin[1]) / grid.d1).astype(np.int64) + 1
    padded = np.pad(grid.z, 1, constant_values=np.nan)
    inside = (row >= 0) & (col >= 0) & (row < padded.shape[0] - 1) & (col < padded.shape[1] - 1)
    value = np.full(len(area), np.nan)
    value[inside] = nearest_front(padded, row[inside], col[inside])
    with np.errstate(invalid="ignore"):
        near = np.abs(value - nodes[:, 2]) <= LAYER_TOLERANCE * max(grid.d1, grid.d2)
    facing = np.abs(dotted(normal, lines)) >= FACING
    return float(area[near & facing].sum() / area.sum())


def surface_sample(mesh):
    """(centres, unit normals, areas) of a seeded sample of COVER_SAMPLES triangles (a cloud:
    points with their normals, equal areas), or None for a cloud without normals."""
    rng = np.random.default_rng(0)
    points = np.asarray(mesh.points, dtype=float)
    if mesh.is_point_cloud:
        if mesh.normals is None:
            return None
        chosen = rng.choice(len(points), min(COVER_SAMPLES, len(points)), replace=False)
        normal = np.asarray(mesh.normals, dtype=float)[chosen]
        return points[chosen], normal / np.maximum(lengths(normal), 1e-300)[:, None], np.ones(len(chosen))
    triangles = np.asarray(mesh.triangles, dtype=np.int64)
    chosen = rng.choice(len(triangles), min(COVER_SAMPLES, len(triangles)), replace=False)
    corners = points[triangles[chosen]]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = lengths(normal)
    keep = doubled > 0
    return corners[keep].mean(axis=1), normal[keep] / doubled[keep, None], doubled[keep] / 2


# --------------------------------------------------------------------------- meshes


def mesh_pieces(points, triangles, spacing):
    """The Pieces of a triangle mesh (slicing-frame ``points``), its corners at one place welded
    (a triangle soup's neighbours share no vertex index)."""
    points, welded = np.unique(points, axis=0, return_inverse=True)
    triangles = welded.reshape(-1)[triangles]
    corners = points[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area = lengths(normal) / 2
    keep = area > 0
    triangles, normal, area = triangles[keep], normal[keep] / (2 * area[keep, None]), area[keep]
    pairs = neighbour_pairs(triangles)
    cosine = facing_cosines(normal)
    labels = joined_small(facing_labels(normal, pairs), cosine, pairs, area, spacing)
    frames = view_frames(points)
    groups = merged_into_neighbours(list(layers(frames, triangles, labels, pairs, spacing)), frames, triangles,
                                    cosine, pairs, area, spacing)
    groups = [refaced(view, members, frames, triangles, cosine, area, spacing) for view, members in groups]
    return merged_small([Piece(view, frames[view], triangles[members]) for view, members in groups], spacing)


def view_frames(points):
    """``points`` in the frame of each view, in VIEWS' order (the views' rotations permute the
    coordinates and turn their signs: exact)."""
    return [rotated(points, view_rotation(view).T) for view in VIEWS]


def neighbour_pairs(triangles):
    """(k, 2) indices of triangles sharing an edge (an edge of exactly two triangles)."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(triangles)), 3)
    key = edges[:, 0] * (int(triangles.max(initial=0)) + 1) + edges[:, 1]
    order = np.argsort(key, kind="stable")
    key, owner = key[order], owner[order]
    first = np.flatnonzero(np.diff(key, prepend=key[:1] - 1) != 0)
    count = np.diff(np.append(first, len(key)))
    two = first[count == 2]
    return np.column_stack([owner[two], owner[two + 1]])


def facing_cosines(normal):
    """(n, 6): the cosine of the angle between each unit normal and each view's direction."""
    return np.stack([dotted(normal, direction) for direction in directions()], axis=1)


def facing_labels(normal, pairs):
    """Per element, the index into VIEWS it is seen along: the direction nearest its normal, then,
    SMOOTHING times, the one maximising its cosine plus NEIGHBOUR_WEIGHT times the share of its
    neighbours holding it, among those within 60 degrees of the normal."""
    cosine = facing_cosines(normal)
    allowed = cosine >= FACING
    labels = np.argmax(cosine, axis=1)
    degree = np.bincount(pairs.ravel(), minlength=len(normal)).astype(float)
    element, neighbour = np.concatenate([pairs, pairs[:, ::-1]]).T
    for _ in range(SMOOTHING):
        votes = np.bincount(element * len(VIEWS) + labels[neighbour], minlength=cosine.size).reshape(cosine.shape)
        score = cosine + NEIGHBOUR_WEIGHT * votes / np.maximum(degree, 1)[:, None]
        labels = np.argmax(np.where(allowed, score, -np.inf), axis=1)
    return labels


def joined_small(labels, cosine, pairs, area, spacing):
    """``labels`` with the elements of pieces smaller than SMALL_CHART cells relabelled, ring by
    ring from their border, to the label of the neighbour in a larger piece that they face best,
    within 80 degrees (JOINING); JOIN_ROUNDS rings at most."""
    for _ in range(JOIN_ROUNDS):
        small = in_small_pieces(labels, pairs, area, SMALL_CHART * spacing * spacing)
        first, second = np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])
        reach = small[first] & ~small[second]
        element, offered = first[reach], labels[second[reach]]
        score = cosine[element, offered]
        order = np.lexsort((-score, element))   # each element's best offer first (ties: in pair order)
        element, offered, score = element[order], offered[order], score[order]
        best = np.flatnonzero(np.diff(element, prepend=-1) != 0)
        best = best[score[best] >= JOINING]
        if not len(best):
            break
        labels = labels.copy()
        labels[element[best]] = offered[best]
    return labels


def in_small_pieces(labels, pairs, area, smallest):
    """Per element, True when its piece (``piece_numbers``) has less area than ``smallest``."""
    piece = piece_numbers(labels, pairs, np.ones(len(labels), dtype=bool))
    return np.bincount(piece, weights=area)[piece] < smallest


def piece_numbers(labels, pairs, inside):
    """Per element, the number of its connected piece: elements ``inside`` joined by ``pairs`` of
    one label (scipy's connected components, numbered in order of their first element)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    same = pairs[inside[pairs[:, 0]] & inside[pairs[:, 1]] & (labels[pairs[:, 0]] == labels[pairs[:, 1]])]
    graph = coo_matrix((np.ones(len(same)), (same[:, 0], same[:, 1])), shape=(len(labels), len(labels)))
    return connected_components(graph, directed=False)[1]


def components(labels, pairs, members):
    """The connected groups of ``members`` (element indices) joined by ``pairs`` of one label."""
    inside = np.zeros(len(labels), dtype=bool)
    inside[members] = True
    group = piece_numbers(labels, pairs, inside)[members]
    order = np.argsort(group, kind="stable")
    return np.split(members[order], np.flatnonzero(np.diff(group[order])) + 1)


def layers(frames, triangles, labels, pairs, spacing):
    """(view, triangle indices) of the single-layer connected pieces: each connected piece of
    one label, less the triangles it hides behind its own surface, which are peeled off into
    the next layer (up to MAX_LAYERS)."""
    remaining = np.arange(len(triangles))
    for _ in range(MAX_LAYERS):
        hidden = []
        for group in components(labels, pairs, remaining):
            view = int(labels[group[0]])
            behind = hidden_triangles(frames[view], triangles[group], spacing)
            hidden.append(group[behind])
            yield view, group[~behind]
        remaining = np.concatenate(hidden) if hidden else remaining[:0]
        if not len(remaining):
            return


def hidden_triangles(local, triangles, spacing):
    """Per triangle of a piece (its points ``local`` in its view's frame), True when its centroid
    lies more than LAYER_TOLERANCE spacings behind the piece's front-most surface along the view
    (another part of the piece covers it)."""
    centroid = local[triangles].mean(axis=1)
    low = np.floor(centroid[:, :2].min(axis=0) / spacing).astype(np.int64) - 1
    cells = np.ceil(centroid[:, :2].max(axis=0) / spacing).astype(np.int64) - low + 2
    xs, ys = (low[0] + np.arange(cells[0])) * spacing, (low[1] + np.arange(cells[1])) * spacing
    front = rasterize(local, triangles, xs, ys)
    col = np.floor(centroid[:, 0] / spacing - low[0]).astype(np.int64)
    row = np.floor(centroid[:, 1] / spacing - low[1]).astype(np.int64)
    with np.errstate(invalid="ignore"):
        return nearest_front(front, row, col) > centroid[:, 2] + LAYER_TOLERANCE * spacing


def nearest_front(values, row, col):
    """The largest of the four nodes of ``values`` about each point in cell (row, col), NaN-blind."""
    above = np.fmax(values[row, col], values[row, col + 1])
    return np.fmax(above, np.fmax(values[row + 1, col], values[row + 1, col + 1]))


def merged_into_neighbours(groups, frames, triangles, cosine, pairs, area, spacing):
    """``groups`` (view, triangle indices) with each piece of less than MERGE_CELLS cells, smallest
    first, joined to the neighbouring piece it shares most edges with among those whose view sees
    all its triangles within 60 degrees (FACING) and whose own surface does not lie over or under
    it along that view (``one_layer``): a small chart costs its mask's boundary and its record
    whatever it holds, and one chart fewer leaves one seam fewer to zip."""
    piece = np.full(len(triangles), -1)
    for number, (_view, members) in enumerate(groups):
        piece[members] = number
    views, members = [view for view, _ in groups], [members for _, members in groups]
    sizes = np.array([area[group].sum() for group in members])
    ends = piece[pairs[piece[pairs[:, 0]] != piece[pairs[:, 1]]]]   # the pieces either side of each seam edge
    for small in np.argsort(sizes, kind="stable"):
        if sizes[small] >= MERGE_CELLS * spacing * spacing:
            break
        for other in neighbours_by_edges(ends, small):
            view = views[other]
            if cosine[members[small], view].min() >= FACING and \
                    one_layer(frames[view], triangles[members[small]], triangles[members[other]], spacing):
                members[other] = np.concatenate([members[other], members[small]])
                ends[ends == small], sizes[other] = other, sizes[other] + sizes[small]
                members[small], sizes[small] = members[small][:0], 0.0
                break
    return [(view, group) for view, group in zip(views, members) if len(group)]


def neighbours_by_edges(ends, number):
    """The pieces sharing an edge with piece ``number`` (``ends``: the pieces either side of each
    seam edge), most shared edges first."""
    across = np.concatenate([ends[ends[:, 0] == number, 1], ends[ends[:, 1] == number, 0]])
    across = across[(across != number) & (across >= 0)]
    found, count = np.unique(across, return_counts=True)
    return found[np.argsort(-count, kind="stable")]


def one_layer(local, small, other, spacing):
    """True when the triangles ``small`` and ``other`` (points ``local`` in a view's frame) seen
    along the view make one layer: over the lattice about ``small``, every node both meet they
    meet within SAME_SURFACE spacings of each other (along a shared edge), none one behind the other."""
    corners = local[small][..., :2].reshape(-1, 2)
    low = np.floor(corners.min(axis=0) / spacing).astype(np.int64)
    high = np.ceil(corners.max(axis=0) / spacing).astype(np.int64)
    theirs = local[other][..., :2]
    near = np.all((theirs.max(axis=1) >= low * spacing) & (theirs.min(axis=1) <= high * spacing), axis=1)
    xs, ys = ((start + np.arange(end - start + 1)) * spacing for start, end in zip(low, high))
    mine, theirs = rasterize(local, small, xs, ys), rasterize(local, other[near], xs, ys)
    both = ~np.isnan(mine) & ~np.isnan(theirs)
    return bool(np.all(np.abs(mine[both] - theirs[both]) <= SAME_SURFACE * spacing))


def refaced(view, members, frames, triangles, cosine, area, spacing):
    """(view, members) of a piece, its view turned to the one that sees all its triangles within 60
    degrees (FACING) best (by area), where they make one layer, when ``view`` sees one beyond that:
    a small piece takes a neighbour's view up to 80 degrees off (``joined_small``) to join its chart,
    but one left a chart of its own would be sampled edge-on (the dragon's, 76 degrees off, 0.6% D
    from its rebuild)."""
    facing = cosine[members]
    fits = facing.min(axis=0) >= FACING
    if facing[:, view].min() >= FACING or not fits.any():
        return view, members
    best = int(np.argmax(np.where(fits, area[members] @ facing, -np.inf)))
    if hidden_triangles(frames[best], triangles[members], spacing).any():
        return view, members
    return best, members


def merged_small(pieces, spacing):
    """The pieces, those too small to hold MIN_CHART_CELLS cells dropped (a chart of their own
    would hold no surface: they are left to the seams between their neighbours)."""
    return [piece for piece in pieces if piece.area >= MIN_CHART_CELLS * spacing * spacing]


# --------------------------------------------------------------------------- point clouds


def cloud_pieces(points, normals, spacing):
    """The Pieces of an oriented point cloud: points labelled as triangles are, joined to their
    CLOUD_NEIGHBOURS nearest points, each piece triangulated in its view's plane (Delaunay)."""
    from scipy.spatial import cKDTree

    from mzc.ops.delaunay import triangulate_point_cloud

    length = lengths(normals)
    keep = length > 0
    points, normals = points[keep], normals[keep] / length[keep, None]
    count = min(CLOUD_NEIGHBOURS + 1, len(points))
    distance, near = cKDTree(points).query(points, k=count)
    near = np.asarray(near).reshape(len(points), count)
    pairs = np.column_stack([np.repeat(np.arange(len(points)), count - 1), near[:, 1:].ravel()])
    nearest = np.asarray(distance).reshape(len(points), count)[:, min(1, count - 1)]
    area = np.full(len(points), float(np.median(nearest)) ** 2)   # a point stands for about its spacing squared
    labels = joined_small(facing_labels(normals, pairs), facing_cosines(normals), pairs, area, spacing)
    pieces = []
    for group in components(labels, pairs, np.arange(len(points))):
        view = int(labels[group[0]])
        local = rotated(points[group], view_rotation(VIEWS[view]).T)
        try:
            triangles = triangulate_point_cloud(local[:, :2])
        except MzcError:   # fewer than 3 points, or all on a line: no surface of its own
            continue
        if len(triangles):
            pieces.append(Piece(view, local, triangles))
    return merged_small(pieces, spacing)


# --------------------------------------------------------------------------- packing


def packed(blocks, spacing, transform, units):
    """One ZGrid holding ``blocks`` (view, i0, j0, values): shelves of blocks, tallest first, one
    invalid node apart, in a strip as wide as the widest block. The mask coder (spec/dwt2d.md)
    codes a row whose span count is the row above's as moves of its flips, any other row afresh:
    the fewer blocks share a row, the fewer rows one block's change of shape makes dear (the square
    array packed before took 14% more bytes on the dragon, 7% on the hand, at the same rmse)."""
    heights = np.array([z.shape[0] for *_, z in blocks])
    widths = np.array([z.shape[1] for *_, z in blocks])
    width = int(widths.max())
    places, row, col, shelf = [], 0, 0, 0
    for index in np.argsort(-heights, kind="stable"):
        if col + widths[index] > width:
            row, col, shelf = row + shelf + 1, 0, 0
        places.append((index, row, col))
        col += widths[index] + 1
        shelf = max(shelf, heights[index])
    z = np.full((row + shelf, width), np.nan)
    charts = []
    for index, row0, col0 in sorted(places, key=lambda place: (place[1], place[2])):
        view, i0, j0, values = blocks[index]
        z[row0:row0 + values.shape[0], col0:col0 + values.shape[1]] = values
        charts.append(Chart(view, int(row0), int(col0), values.shape[0], values.shape[1], i0, j0))
    return ZGrid(z, spacing, spacing, transform=transform, units=units, charts=tuple(charts))
