"""The zipper (issue 28): the triangles that close the seams between the charts of a multi-chart grid.

A whole object is cut into charts, each sampled on a planar grid of its own and triangulated
from it. The chart meshes tile the surface but leave a gap of up to about a cell along every
seam, and a hole where three or more charts meet. ``zip_charts`` closes them from the chart
meshes alone (points, triangles and each vertex's chart: a file stores no connectivity, so a
decoder derives the same triangles), so that the rebuild of a watertight surface is
watertight, every edge in two triangles and run once each way, without laying triangles
back over the charts. Nothing near a boundary (the rim of an open scan, a hole of the
surface) leaves it open.

1. The boundary edges are those in one triangle only, each as its triangle runs it: its
   chart on its left. Boundary vertices of two charts that coincide (a lattice line
   through a sharp edge) are welded into one.
2. The gap lies right of them: reversed, they are its half-edges. At each boundary vertex
   it fills a wedge (two or more where a chart touches itself at a corner), turning
   clockwise about the vertex's normal from the chart's outgoing boundary edge to the
   incoming one (the chart's own edges, seen along its own normal: a chart is a height
   field there).
3. Rungs cross it. Each boundary vertex's partner is the nearest boundary vertex of another
   chart within REACH spacings such that the rung between them leaves each end within one
   of its wedges, seen about the sum of their normals (a wall standing on a floor meets it
   between the two); not two surfaces that face each other across air (opposed normals,
   each ahead of the other: two fingers, not the two sides of a fin thinner than a cell).
   Vertices that are each other's partner are joined: nearest pairs do not cross, so the
   rungs cut the gap into small faces, a quad or so between rungs along a seam and a loop
   at each junction. A boundary loop left without a rung (a chart of a cell or two) is
   joined by its vertex nearest its partner.
4. Each face runs on from a half-edge arriving in a wedge to the next rung leaving in that
   wedge (clockwise), or to the gap's half-edge leaving it: the faces of a planar map.
5. Each closed face is filled, but for its cycles that run around one chart's boundary
   alone (no rung): such a cycle is filled only as a hole in the chart (its area facing as
   the chart does), never over the chart.
6. The faces are filled by ear clipping (``_zipper.c``): shortest well-shaped cuts first,
   none that folds back over the surface beside it or adds an edge that exists. A face more
   than RIM_SHARE of whose vertices have no other chart's boundary near lies on a rim (of
   an open scan, a hole of the surface): if its filling would need a cut longer than
   LONGEST spacings it stays open. Other faces are gaps between charts, however wide
   (where many small charts meet), and are closed, with no cut longer than LONGEST spacings
   either (across a wide gap on a curved surface such a cut lies far inside it: 0.5% of the
   ogre's diagonal, 2.6 spacings): an ear that would make one is not taken, and what is left
   without another ear is closed by fans about new points (rare).
7. The creases are put back (``creased``). Charts part where the surface turns (each element
   goes with the direction its normal faces), so a seam lies on a bend, and a stitch that
   runs straight from one chart's last node to the other's, up to a cell or two away, cuts
   the bend's corner: on the edges of a box, by up to half a cell or more. Each edge between
   two stitches whose ends' tangent planes (their charts' normals) bend by 20 to 160 degrees
   (SHARP) is split at the point of the planes' crease nearest its middle (within
   CREASE_REACH of its length and a spacing), and its triangles with it.

Everything is elementwise numpy and the C kernels (``_zipper.c``), with IEEE operations in a fixed
order: the same triangles on every machine (spec/arithmetic.md).
"""

import numpy as np

from mzc.vectors import dotted, lengths

REACH = 3.0        # spacings: the longest rung
CANDIDATES = 8     # the nearest boundary vertices looked at for a partner
FACING = -0.5      # cosine of normals that face each other
AHEAD = 0.5        # cosine within which a point lies ahead of a surface, not beside it
WELD = 1e-9        # spacings: boundary vertices of two charts this close are one
LONGEST = 6.0      # spacings: the longest edge a filling may add (a face on a rim that needs more stays open)
RIM_SHARE = 0.25   # a face more of whose vertices have no other chart near lies on a rim
SHARP = 0.94       # cosine of 20 degrees: tangent planes of two ends that bend by 20-160 degrees meet in a crease
CREASE_REACH = 0.5   # the crease point lies at most this share of its edge's length from the edge's middle


def zip_charts(points, triangles, chart, spacing):
    """(points, triangles): the chart meshes (``points`` (n, 3), ``triangles`` (m, 3), ``chart``
    (n,) the chart of each vertex, charts sampled at ``spacing``) with their seams closed.

    The points are the given ones, then any added (a face that only a fan about a new point
    can close, rare), then the creases' (``creased``); the triangles the given ones (over
    welded vertices), then the stitches."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    chart = np.asarray(chart).reshape(len(points))
    boundary = boundary_edges(triangles, len(points))
    if not len(boundary):
        return points, triangles
    near = Neighbours(points, boundary, spacing)
    welding = welded(points, triangles, chart, boundary, near, spacing)
    if welding is not None:
        triangles, boundary = welding
        if not len(boundary):
            return points, triangles
        near = Neighbours(points, boundary, spacing)
    gap = Gap(points, triangles, chart, boundary, near, spacing)
    added, stitches = gap.filled()
    return creased(np.concatenate([points, added]), triangles, stitches, boundary, (gap.vertex, gap.normal), spacing)


def creased(points, charted, stitches, boundary, normals, spacing):
    """(points, triangles): the ``charted`` triangles, then the ``stitches`` with the bends of the
    seams put back: each edge of the stitches that is not a chart's (``boundary``, the charts'
    boundary edges), where the tangent planes at its two ends (``normals``: the boundary
    vertices and the sums of their charts' normals, Gap's) bend by 20 to 160 degrees
    (SHARP; the two sides of a fin thinner than a cell face apart, with no crease between), is
    split at the point of their crease nearest its middle when that lies within CREASE_REACH
    of its length of it and within a ``spacing`` (a bend between the ends, as far from their
    stitch as a seam's gap is wide, not planes that meet far off), its
    triangles split with it (``split``). The edges of a stitch that this would turn over (a
    crease past a third plane where three charts meet) are split at their middles instead,
    round by round until none is (a stitch split at its edges' middles stays as it was). The
    new points come after the given ones; the charts' triangles stay first (spec/zgrid.md,
    Zipping the charts, step 10, the rule web/zipper.mjs follows to the same bits)."""
    size = len(points)
    key = edge_keys(stitches, stitches[:, [1, 2, 0]], size).ravel()   # edge k of a stitch: corners k, k + 1
    edges, which = np.unique(key, return_inverse=True)
    which = which.reshape(-1, 3)
    a, b = np.divmod(edges, size)
    vertex, normal = normals
    length = lengths(normal)
    unit = np.zeros((size, 3))   # zero at a point the filling added, or where the charts' normals cancel: no bend
    unit[vertex] = normal / np.where(length > 0, length, np.inf)[:, None]
    na, nb = unit[a], unit[b]
    middle = (points[a] + points[b]) / 2
    cosine = dotted(na, nb)
    across = 1.0 - cosine * cosine
    along_a, along_b = dotted(na, points[a] - middle), dotted(nb, points[b] - middle)
    bent = (across > 1.0 - SHARP * SHARP) & (dotted(na, na) > 0) & (dotted(nb, nb) > 0)   # neither flat nor folded flat
    divisor = np.where(bent, across, 1.0)
    alpha, beta = (along_a - cosine * along_b) / divisor, (along_b - cosine * along_a) / divisor
    crease = middle + alpha[:, None] * na + beta[:, None] * nb
    bent &= (lengths(crease - middle) <= np.minimum(CREASE_REACH * lengths(points[b] - points[a]), spacing)) & \
        ~among(edges, np.sort(edge_keys(boundary[:, 0], boundary[:, 1], size)))
    new = np.full(len(edges), -1, dtype=np.int64)
    new[bent] = size + np.arange(np.count_nonzero(bent))
    middles = new[which]
    pieces, parent = split(stitches, middles)
    cut = np.flatnonzero((middles >= 0).any(axis=1))
    place = np.full(len(stitches), -1)
    place[cut] = np.arange(len(cut))
    tested = place[parent] >= 0
    kept, owner = pieces[tested], place[parent[tested]]
    corners = np.concatenate([stitches[cut], kept]).ravel()
    present = np.zeros(size + len(new), dtype=bool)   # np.unique(return_inverse=True)'s, without its sort
    present[corners] = True
    used, local = np.flatnonzero(present), (np.cumsum(present) - 1)[corners]
    parents, kept = local[:3 * len(cut)].reshape(-1, 3), local[3 * len(cut):].reshape(-1, 3)
    at = points[np.minimum(used, size - 1)]
    added = used >= size
    while True:
        at[added] = crease[bent][used[added] - size]
        facing = triangle_normals(at, parents)
        turned = (dotted(facing, facing)[owner] > 0) & (dotted(triangle_normals(at, kept), facing[owner]) <= 0)
        back = which[cut[owner[turned]]].ravel()
        back = back[(crease[back] != middle[back]).any(axis=1)]   # at its middles, a sliver may still turn
        if not len(back):
            return np.concatenate([points, crease[bent]]), np.concatenate([charted, pieces])
        crease[back] = middle[back]


def split(triangles, middle):
    """(triangles, parent): ``triangles`` with each edge k (corners k, k + 1) whose ``middle`` (per
    triangle and edge) is not -1 split there, a triangle with one split edge into two, with
    two into three (the quad left cut from the corner between the whole edge and a split
    one), with three into four, those with none first as they were; and the index of the
    triangle each comes from."""
    cut = middle >= 0
    count = cut.sum(axis=1)
    parts = [np.flatnonzero(count == 0)]
    pieces = [triangles[parts[0]]]
    for k in range(3):
        one = np.flatnonzero((count == 1) & cut[:, k])
        t, m = np.roll(triangles[one], -k, axis=1), middle[one, k]
        pieces += [np.stack([t[:, 0], m, t[:, 2]], axis=1), np.stack([m, t[:, 1], t[:, 2]], axis=1)]
        two = np.flatnonzero((count == 2) & ~cut[:, (k + 2) % 3])
        t, m = np.roll(triangles[two], -k, axis=1), np.roll(middle[two], -k, axis=1)
        pieces += [np.stack([m[:, 0], t[:, 1], m[:, 1]], axis=1), np.stack([t[:, 0], m[:, 0], m[:, 1]], axis=1),
                   np.stack([t[:, 0], m[:, 1], t[:, 2]], axis=1)]
        parts += [one, one, two, two, two]
    three = np.flatnonzero(count == 3)
    t, m = triangles[three], middle[three]
    pieces += [np.stack([t[:, 0], m[:, 0], m[:, 2]], axis=1), np.stack([m[:, 0], t[:, 1], m[:, 1]], axis=1),
               np.stack([m[:, 2], m[:, 1], t[:, 2]], axis=1), m]
    parts += [three] * 4
    return np.concatenate(pieces), np.concatenate(parts)


def boundary_edges(triangles, count):
    """(k, 3) rows (tail, head, triangle): the edges of ``triangles`` (over ``count`` vertices)
    that are in one triangle only, each as it runs them."""
    from mzc.ops import _zipper

    edges = np.empty((triangles.size, 3), dtype=np.int64)
    return edges[:_zipper.boundary(np.ascontiguousarray(triangles), count, edges)]


class Neighbours:
    """The boundary vertices (``vertex``, the indices of the boundary edges' ends in order) and,
    for each, the CANDIDATES nearest closer than REACH spacings (``candidate``, numbered as
    ``vertex``; its own count where there are fewer) and how far (``distance``; inf).

    Nearest by squared distance (dx dx + dy dy + dz dz < (REACH spacing)^2), a tie by the lower
    number (spec/zgrid.md, Zipping the charts): a KD-tree's k nearest would keep whichever of
    equally far vertices its tree visits first (lattice points on a flat face are equally far),
    so ``_zipper.nearest`` finds them in cells of the space and keeps each vertex's in order
    (a KD-tree's pairs within reach sorted all at once took half the zipper's time)."""

    def __init__(self, points, boundary, spacing):
        from mzc.ops import _zipper

        self.vertex = np.unique(boundary[:, :2])
        size = len(self.vertex)
        count = min(CANDIDATES, size)
        self.candidate, squares = np.full((size, count), size), np.full((size, count), np.inf)
        if count:
            _zipper.nearest(points[self.vertex], REACH * spacing, self.candidate, squares)
        self.distance = np.sqrt(squares)


def welded(points, triangles, chart, boundary, near, spacing):
    """(triangles, boundary) with the boundary vertices of different charts within WELD
    spacings of each other made one (the lowest index) and the boundary edges (rows of
    ``boundary_edges``) this joins dropped, None if there are none; ``near``: the Neighbours
    of the boundary. Vertices whose welding would run an edge twice the same way (so put an
    edge in three triangles) or collapse a triangle (charts that overlap, a triangle across
    charts) stay apart."""
    row, column = np.nonzero(near.distance <= WELD * spacing)
    pairs = near.vertex[np.stack([row, near.candidate[row, column]], axis=1)]
    pairs = np.sort(pairs[chart[pairs[:, 0]] != chart[pairs[:, 1]]], axis=1)
    while len(pairs):
        one = np.arange(len(points))
        for _ in range(3):   # chains of three charts meeting at a corner
            np.minimum.at(one, pairs[:, 1], one[pairs[:, 0]])
            one = one[one]
        corners = one[triangles]
        blamed = np.concatenate([clashes(triangles, corners, np.unique(one[one != np.arange(len(one))])),
                                 triangles[(corners == np.roll(corners, 1, axis=1)).any(axis=1)
                                           & (triangles != np.roll(triangles, 1, axis=1)).all(axis=1)].ravel()])
        if not len(blamed):
            tail, head = one[boundary[:, 0]], one[boundary[:, 1]]
            joined = np.isin(head * len(points) + tail, tail * len(points) + head)
            return corners, np.stack([tail, head, boundary[:, 2]], axis=1)[~joined]
        apart = np.isin(one[pairs], one[blamed]).any(axis=1)
        if not apart.any():
            return None
        pairs = pairs[~apart]
    return None


def clashes(triangles, corners, welds):
    """The vertices (of ``triangles``) of the edges that ``corners`` (the triangles over welded
    vertices) run twice the same way, where one of them runs over a vertex welded into one of
    ``welds``."""
    at = np.isin(corners, welds).any(axis=1)
    before, after = triangles[at], corners[at]
    key = (after * (triangles.max() + 1) + after[:, [1, 2, 0]]).ravel()
    changed = ((before != after) | (before[:, [1, 2, 0]] != after[:, [1, 2, 0]])).ravel()
    unique, index, count = np.unique(key, return_inverse=True, return_counts=True)
    twice = (count[index] > 1) & (np.bincount(index, weights=changed, minlength=len(unique))[index] > 0)
    return np.concatenate([before.ravel()[twice], before[:, [1, 2, 0]].ravel()[twice]])


class Gap:
    """The gap between the charts: its half-edges (the boundary edges reversed, then the rungs
    one way, then the other) over the boundary vertices, numbered 0.. (``vertex`` their
    indices in the mesh), and each one's ``next`` around its face."""

    def __init__(self, points, triangles, chart, boundary, near, spacing):
        self.vertex, self.near = near.vertex, near
        self.p, self.point_count, self.spacing = points[self.vertex], len(points), spacing
        rank = np.full(len(points), -1, dtype=np.int64)
        rank[self.vertex] = np.arange(len(self.vertex))
        ranked = rank[triangles]
        at = (ranked[:, 0] >= 0) | (ranked[:, 1] >= 0) | (ranked[:, 2] >= 0)   # the triangles with a boundary vertex
        facing = triangle_normals(points, triangles[at])
        self.normal = vertex_normals(facing, ranked[at], len(self.vertex))
        self.frame = tangent_frames(self.normal)
        self.edges = existing_edges(ranked[at])
        self.chart = chart[self.vertex]
        self.source, self.target = rank[boundary[:, 1]], rank[boundary[:, 0]]
        self.beside = facing[(np.cumsum(at) - 1)[boundary[:, 2]]]   # the chart's across each, one of those
        self.gap_count = len(self.source)
        wedge_next = self.turns(self.source, self.target)
        rungs = self.rungs(wedge_next)
        self.next = self.threaded(wedge_next, rungs)
        self.source = np.concatenate([self.source, rungs[:, 0], rungs[:, 1]])
        self.target = np.concatenate([self.target, rungs[:, 1], rungs[:, 0]])

    def angles(self, source, target, frame=None):
        """The pseudo-angle (``pseudo_angle``) of each direction source -> target about the
        source's normal, or in the frames (first, second) given, one per direction."""
        d = self.p[target] - self.p[source]
        first, second = (self.frame[0][source], self.frame[1][source]) if frame is None else frame[:2]
        return pseudo_angle(dotted(d, first), dotted(d, second))

    def turns(self, source, target):
        """Each half-edge's next around its face (-1 for none): at each vertex, clockwise from
        the reverse of each half-edge arriving, the next half-edge leaving. Arriving and
        leaving alternate about a vertex; where rounding or a degenerate surface upsets that
        order, the k-th arriving from the first still takes the k-th leaving after it, so that
        no half-edge follows two."""
        count = len(source)
        at = np.concatenate([source, target])
        arriving = np.repeat([False, True], count)
        angle = np.concatenate([self.angles(source, target), self.angles(target, source)])
        order = np.lexsort((arriving, -angle, at))   # clockwise about each vertex, leaving first at a tie
        at, arriving = at[order], arriving[order]
        new = starts(at)
        group = np.cumsum(new) - 1
        start = np.flatnonzero(new)
        position = np.arange(len(at)) - start[group]
        first = np.zeros(len(start), dtype=np.int64)
        with_arriving, where = np.unique(group[arriving], return_index=True)
        first[with_arriving] = position[arriving][where]
        size = np.diff(np.r_[start, len(at)])
        rotated = np.lexsort(((position - first[group]) % size[group], group))   # each vertex's from its first arriving
        order, arriving, group = order[rotated], arriving[rotated], group[rotated]
        arrive, leave = np.flatnonzero(arriving), np.flatnonzero(~arriving)
        key_arrive, key_leave = (group[k] * (len(at) + 1) + np.arange(len(k)) - np.searchsorted(group[k], group[k])
                                 for k in (arrive, leave))
        match = np.minimum(np.searchsorted(key_leave, key_arrive), max(len(leave) - 1, 0))
        found = key_leave[match] == key_arrive if len(leave) else np.zeros(len(arrive), dtype=bool)
        next_ = np.full(count, -1, dtype=np.int64)
        next_[order[arrive] - count] = np.where(found, order[leave[match]] if len(leave) else -1, -1)
        return next_

    def rungs(self, wedge_next):
        """(k, 4) rows (a, b, wedge at a, wedge at b): the rungs, joining each vertex and its
        partner where they are each other's; and on a boundary loop that this leaves without
        one (a chart of a cell or two, whose neighbours' nearest lie elsewhere), its vertex
        nearest its partner and that partner (or, if none of its vertices has one, its nearest
        other chart's vertex), so that no loop is left apart. A wedge is named by the gap's
        half-edge that arrives at its start."""
        partner, distance, wedge, far_wedge, loose = self.partners(wedge_next)
        loop = np.zeros(len(self.p), dtype=np.int64)
        loop[self.source] = walks(wedge_next)
        here = np.arange(len(partner))
        mutual = (partner >= 0) & ~loose & (partner[np.maximum(partner, 0)] == here) & ~loose[np.maximum(partner, 0)]
        first = np.flatnonzero(mutual & (here < partner))
        alone = np.ones(loop.max(initial=-1) + 1, dtype=bool)
        alone[loop[mutual]] = False
        lonely = np.flatnonzero(alone[loop] & (partner >= 0))
        lonely = lonely[np.lexsort((lonely, distance[lonely], loose[lonely], loop[lonely]))]
        lonely = lonely[starts(loop[lonely])]
        lonely = lonely[~(mutual[partner[lonely]] & (partner[partner[lonely]] == lonely))]
        ends = np.concatenate([first, lonely])
        rungs = np.stack([ends, partner[ends], wedge[ends], far_wedge[ends]], axis=1)
        rungs = rungs[(rungs[:, 2] >= 0) & (rungs[:, 3] >= 0)]   # a vertex with no wedge: the charts are not oriented
        key = edge_keys(rungs[:, 0], rungs[:, 1], len(self.p))
        _unique, once = np.unique(key, return_index=True)
        once = np.sort(once)
        return rungs[once][~among(key[once], edge_keys(self.edges[:, 0], self.edges[:, 1], len(self.p)))]

    def partners(self, wedge_next):
        """(partner, distance, wedge, far wedge, loose): per boundary vertex, its partner (-1 for
        none), how far, and the wedges at it and at the partner that the rung between them lies
        in; a vertex with no partner whose wedges see it takes the nearest other chart's vertex,
        ``loose``, in its own first wedge and that vertex's (a last resort for a loop that has
        no rung). Sets ``seam``: whether another chart's boundary lies within REACH of each, not
        across air (a vertex without is on a rim)."""
        size = len(self.p)
        wedges = wedge_table(self.target, size)
        distance, candidate = self.near.distance, self.near.candidate
        partner, gap = np.full(size, -1), np.full(size, np.inf)
        wedge, far_wedge, loose = np.full(size, -1), np.full(size, -1), np.ones(size, dtype=bool)
        self.seam = np.zeros(size, dtype=bool)
        for column in range(candidate.shape[1]):
            here = np.flatnonzero((candidate[:, column] < size) & loose)
            other = candidate[here, column]
            apart = self.chart[other] != self.chart[here]   # first: across_air only for the pairs it may drop
            here, other = here[apart], other[apart]
            keep = ~self.across_air(here, other)
            here, other = here[keep], other[keep]
            nearest, self.seam[here] = here[~self.seam[here]], True
            partner[nearest], gap[nearest] = candidate[nearest, column], distance[nearest, column]
            wedge[nearest], far_wedge[nearest] = wedges[nearest, 0], wedges[partner[nearest], 0]
            frame = tangent_frames(self.frame[2][here] + self.frame[2][other])
            at_here = self.wedge_of(wedges, wedge_next, here, other, frame)
            at_other = self.wedge_of(wedges, wedge_next, other, here, frame)
            found = (at_here >= 0) & (at_other >= 0)
            here = here[found]
            partner[here], gap[here] = other[found], distance[here, column]
            wedge[here], far_wedge[here], loose[here] = at_here[found], at_other[found], False
        return partner, gap, wedge, far_wedge, loose

    def across_air(self, a, b):
        """Whether boundary vertices a and b face each other across air: normals opposed, and b
        in front of a more than beside it (not round the rim of a fin thinner than the gap)."""
        unit, offset = self.frame[2], self.p[b] - self.p[a]
        return (dotted(unit[a], unit[b]) < FACING) & (dotted(offset, unit[a]) > AHEAD * lengths(offset))

    def wedge_of(self, wedges, wedge_next, at, towards, frame):
        """The first of the gap's wedges at ``at`` (``wedge_table``) that the direction at ->
        towards lies in, seen in ``frame`` (about the normals of both ends: a rung from a wall
        to the floor it stands on lies in the wall's wedge only seen between the two); -1 for
        none. A wedge turns clockwise from the reverse of the gap's half-edge that arrives at
        the vertex to the one that leaves it next."""
        found, heading = np.full(len(at), -1), self.angles(at, towards, frame)
        for column in range(wedges.shape[1]):   # each vertex's wedges until one holds the direction
            open_ = np.flatnonzero((wedges[at, column] >= 0) & (found < 0))
            arrive, part = wedges[at[open_], column], (frame[0][open_], frame[1][open_])
            leave = wedge_next[arrive]
            start = self.angles(at[open_], self.source[arrive], part)
            span = np.mod(start - self.angles(at[open_], self.target[np.maximum(leave, 0)], part), 4.0)
            turn = np.mod(start - heading[open_], 4.0)
            inside = (leave >= 0) & (turn > 0) & ((turn < span) | (span == 0))
            found[open_[inside]] = arrive[inside]
        return found

    def threaded(self, wedge_next, rungs):
        """The next of each half-edge (gap's, then rungs' a -> b, then b -> a): in each wedge,
        the gap's arriving half-edge, the rungs leaving in it (clockwise, about the vertex's
        normal) and the gap's leaving one follow each other; a rung's arriving half-edge
        goes on as its leaving twin would."""
        count, size = len(wedge_next), len(rungs)
        leaving = np.concatenate([rungs[:, 0], rungs[:, 1]])
        towards = np.concatenate([rungs[:, 1], rungs[:, 0]])
        wedge = np.concatenate([rungs[:, 2], rungs[:, 3]])
        turn = np.mod(self.angles(leaving, self.source[wedge]) - self.angles(leaving, towards), 4.0)
        order = np.lexsort((turn, wedge))
        half = count + order   # rung half-edges in wedge order
        next_ = np.concatenate([wedge_next, np.full(2 * size, -1)])
        first = starts(wedge[order])
        last = np.r_[first[1:], True][:len(first)]
        next_[wedge[order][first]] = half[first]   # the gap's arriving half-edge: the first rung
        twin = np.where(half < count + size, half + size, half - size)
        next_[twin[~last]] = half[1:][~last[:-1]]
        next_[twin[last]] = wedge_next[wedge[order][last]]
        return next_

    def filled(self):
        """(points added, triangles): the stitches over the mesh's vertices, points added after them."""
        from mzc.ops import _zipper

        source, target, rung = self.source, self.target, slice(self.gap_count, None)
        reference = np.concatenate([self.beside, self.frame[2][source[rung]] + self.frame[2][target[rung]]])
        triangles, added = np.empty((len(source), 3), dtype=np.int64), np.empty((len(source), 3))
        made, points = _zipper.fill(self.p, source, target, self.next, self.gap_count, np.ascontiguousarray(reference),
                                    self.edges, LONGEST * self.spacing, self.rims(), triangles, added)
        triangles, size = triangles[:made], len(self.p)
        triangles = np.where(triangles < size, self.vertex[np.minimum(triangles, size - 1)],
                             triangles - size + self.point_count)
        return added[:points], triangles

    def rims(self):
        """Whether each half-edge's face lies on a rim: more than RIM_SHARE of its vertices on one
        (not ``seam``). Its filling stays open where it would need a cut longer than LONGEST
        spacings (which would close a rim or a hole of the surface); a gap between charts,
        however wide (where many small charts meet), is closed, by fans where it must."""
        face = walks(self.next)
        return (np.bincount(face, weights=~self.seam[self.source]) > RIM_SHARE * np.bincount(face))[face]


def edge_keys(a, b, size):
    """One number for each undirected edge a-b between ``size`` vertices."""
    return np.minimum(a, b) * size + np.maximum(a, b)


def among(values, keys):
    """Whether each of ``values`` is one of the ascending ``keys``: np.isin's answer by binary
    search, without its sort of both (the edges' keys come sorted, from np.unique)."""
    at = np.minimum(np.searchsorted(keys, values), max(len(keys) - 1, 0))
    return keys[at] == values if len(keys) else np.zeros(len(values), dtype=bool)


def starts(values):
    """Where each run of equal ``values`` starts (a boolean per value)."""
    new = np.ones(len(values), dtype=bool)
    new[1:] = values[1:] != values[:-1]
    return new


def wedge_table(arriving, size):
    """(size, most): per vertex, the gap's half-edges that arrive at it (each names the wedge
    that starts there), -1 after them."""
    count = np.bincount(arriving, minlength=size)
    order = np.argsort(arriving, kind="stable")
    slot = np.arange(len(order)) - (np.cumsum(count) - count)[arriving[order]]
    table = np.full((size, max(int(count.max(initial=0)), 1)), -1, dtype=np.int64)
    table[arriving[order], slot] = order
    return table


def walks(next_):
    """The walk of each half-edge along ``next_`` (-1: none), numbered from 0 in the order of
    their first half-edges: the weakly connected components of the graph of the nexts."""
    from mzc.ops import _zipper

    walk = np.empty(len(next_), dtype=np.int64)
    _zipper.walks(np.ascontiguousarray(next_, dtype=np.int64), walk)
    return walk


def triangle_normals(points, triangles):
    """The normal of each triangle, its length twice the area: the cross product of its edges
    from corner 0, each component as np.cross computes it (a fourth of its time, without its
    (m, 3, 3) gather and moved axes)."""
    x, y, z = points.T
    a, b, c = triangles.T
    ux, uy, uz = x[b] - x[a], y[b] - y[a], z[b] - z[a]
    vx, vy, vz = x[c] - x[a], y[c] - y[a], z[c] - z[a]
    return np.stack([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx], axis=-1)


def vertex_normals(normal, corners, size):
    """The normal at each of ``size`` vertices: the sum of the ``normal``s (area-weighted) of the
    triangles whose ``corners`` (k, 3) it is; corners -1 are left out."""
    owner = np.where(corners >= 0, corners, size).ravel()
    return np.stack([np.bincount(owner, weights=np.repeat(normal[:, k], 3), minlength=size + 1)[:size]
                     for k in range(3)], axis=1)


def tangent_frames(normal):
    """(first, second, unit normal): a right-handed frame about each normal (a zero normal: any)."""
    size = lengths(normal)
    unit = normal / np.where(size > 0, size, 1.0)[:, None]
    unit[size == 0] = (0.0, 0.0, 1.0)
    axis = np.zeros_like(unit)
    axis[np.arange(len(unit)), np.argmin(np.abs(unit), axis=1)] = 1.0
    first = axis - dotted(axis, unit)[:, None] * unit
    first /= lengths(first)[:, None]
    return first, np.cross(unit, first), unit


def pseudo_angle(x, y):
    """A stand-in for the angle of (x, y) that orders directions as atan2 does, counterclockwise
    in [0, 4) from +x, in additions and one division (no elementary function)."""
    size = np.abs(x) + np.abs(y)
    along = np.divide(x, size, out=np.zeros_like(size), where=size > 0)
    return np.where(y >= 0, 1.0 - along, np.mod(3.0 + along, 4.0))


def existing_edges(corners):
    """(k, 2), each row low, high, the rows ascending: the edges between the vertices that are
    not -1 of triangles whose ``corners`` (m, 3) they are."""
    a, b = corners, corners[:, [1, 2, 0]]
    both = (a >= 0) & (b >= 0)
    size = corners.max(initial=0) + 1
    return np.stack(np.divmod(np.unique(edge_keys(a[both], b[both], size)), size), axis=1)
