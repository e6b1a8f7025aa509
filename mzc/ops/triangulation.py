"""Connectivity derived from the grid (thesis §4.3): it is never stored.

Between rows r, r+1 and columns c, c+1 the corners 1=(r,c), 2=(r,c+1), 3=(r+1,c),
4=(r+1,c+1) give the thesis's triangles 1-2-3 and 2-3-4, each wherever its three corners
are valid. The second is written 2-4-3 so both face the node lines' outward direction
(+z in a planar grid frame). A grid whose columns make a full turn also joins its last
column to its first, so a closed surface has no seam; the nodes of a pole row of a
spherical grid are one point, so its cells become a fan of triangles about the pole.

Depth discontinuities (spec/zgrid.md, Connectivity). Neighbouring nodes on either side of
a depth jump (a person in front of a wall, the layers of a part, the rim of a fold the
outermost hit cannot see) are far apart along the node lines and close across them: the
edge joining them runs nearly along the lines. Such an edge is a *jump* when it makes an
angle of less than JUMP_ANGLE with the node line through its midpoint (the "shadow" test
of range-image meshing, as in PCL's OrganizedFastMesh, which uses 12.5 degrees), and the
triangles with a jump edge are not surface: they are dropped. 3 degrees (a rise of more
than 19 node spacings across one cell) drops nothing of the default 0.5 mm grids of the
13 faces; 4 degrees dropped 3-38 triangles of two of them and 5 degrees 110 of
``example.obj``, raising its whole-surface RMS by 14%: grazing surface, not jumps.
"""

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mzc import elementary, projections

if TYPE_CHECKING:
    from mzc.grid import ZGrid
    from mzc.meshes import Mesh

JUMP_ANGLE = 3.0   # degrees between an edge and the node line below which the edge is a jump
CHART_JUMP_ANGLE = 30.0   # a chart's: its surface faces its lines within 60 degrees, so a steeper edge is a step
STRIP_NODES = 1 << 16   # nodes whose edges, triangles or points are made at a time (half a MB a value)


@dataclass
class Jumps:
    """Which edges of a grid are depth jumps: ``across`` rows (rows-1, cols; cols+1 on a
    periodic grid, column 0 repeated after the last), ``along`` rows
    (rows, cols-1; cols on a periodic grid, the last joining column cols-1 to 0) and the
    cells' ``diagonal`` from corner 2 to corner 3 (rows-1, cells per row)."""

    across: np.ndarray
    along: np.ndarray
    diagonal: np.ndarray


def jump_edges(grid, angle=None):
    """The Jumps of a ZGrid: edges between valid nodes within ``angle`` degrees (default
    JUMP_ANGLE) of the node line through their midpoint (none when ``angle`` is 0); edges
    along a pole row join nodes of one ray, which are one vertex, and are never jumps.

    Each edge's test reads its two nodes' values and where the grid puts their lines
    (``is_jump``), so the grid is tested a strip of rows at a time (``row_strips``): the
    temporaries are a strip's (several times 8 bytes a node), not the grid's."""
    parts = [jumps_between(grid, low, high, angle) for low, high in row_strips(grid.shape)]
    last = len(parts) - 1
    return Jumps(across=np.concatenate([part.across for part in parts]),
                 along=np.concatenate([part.along[: None if i == last else -1] for i, part in enumerate(parts)]),
                 diagonal=np.concatenate([part.diagonal for part in parts]))


def row_strips(shape):
    """(low, high) per strip of about STRIP_NODES nodes: the cells between rows low and high
    (the last strip's high is the last row; a grid of one row is one strip of no cells)."""
    rows, step = shape[0], max(1, STRIP_NODES // shape[1])
    return [(low, min(low + step, rows - 1)) for low in range(0, max(rows - 1, 1), step)]


def jumps_between(grid, low, high, angle=None):
    """The Jumps of the edges between rows low..high of ``grid`` (``jump_edges``)."""
    angle = JUMP_ANGLE if angle is None else angle
    z = grid.z[low:high + 1]
    if grid.periodic:
        z = np.concatenate([z, z[:, :1]], axis=1)
    if angle <= 0:
        return Jumps(across=np.zeros((len(z) - 1, z.shape[1]), dtype=bool),
                     along=np.zeros((len(z), z.shape[1] - 1), dtype=bool),
                     diagonal=np.zeros((len(z) - 1, z.shape[1] - 1), dtype=bool))
    chords = EdgeChords.of(grid, grid.ys()[low:high + 1])
    cosine2 = squared_cosine(angle)
    jumps = Jumps(across=is_jump(z[:-1], z[1:], chords.across, cosine2),
                  along=is_jump(z[:, :-1], z[:, 1:], chords.along, cosine2),
                  diagonal=is_jump(z[:-1, 1:], z[1:, :-1], chords.diagonal, cosine2))
    jumps.along[grid.pole_rows()[low:high + 1]] = False
    return jumps


@dataclass
class EdgeChords:
    """The grid's geometry as each kind of edge sees it: (spread, rise) for edges ``across``
    rows, ``along`` them and along the cells' ``diagonal``s, each a number or a column of one
    per row (per row pair), such that the edge between nodes of values a and b has

        |e|^2 = (b - a)^2 + a b spread + rise   and   4 |m|^2 = (a + b)^2 - a b spread,

    m the part of its midpoint that fixes the node line through it (its projection on the xz
    plane for cylindrical grids, the point itself for spherical ones; None on planar grids,
    whose lines are all +z). For central grids spread = 2 - 2 cos(angle between the rays)
    and rise the squared step along the axis; for planar ones rise is the squared step
    across the lines."""

    across: tuple
    along: tuple
    diagonal: tuple

    @classmethod
    def of(cls, grid, ys):
        """The chords of ``grid``'s edges between the rows at ``ys``."""
        d1, d2 = grid.d1, grid.d2
        if grid.projection == "planar":
            return cls(across=(None, d1 * d1), along=(None, d2 * d2), diagonal=(None, d1 * d1 + d2 * d2))
        turn = 4 * squared_sine(d2 / grid.radius / 2)            # 2 - 2 cos of the columns' angle
        if grid.projection == "cylindrical":
            return cls(across=(0.0, d1 * d1), along=(turn, 0.0), diagonal=(turn, d1 * d1))
        ring = elementary.cos(ys / grid.radius)[:, None]         # spherical: rows are cones of elevation ys / R
        tilt = 4 * squared_sine(d1 / grid.radius / 2)
        return cls(across=(tilt, 0.0), along=(ring * ring * turn, 0.0),
                   diagonal=(tilt + ring[:-1] * ring[1:] * turn, 0.0))


def squared_sine(angle):
    """sin^2 of ``angle`` (radians)."""
    sine = elementary.sin(angle)
    return sine * sine


def squared_cosine(degrees):
    """cos^2 of an angle given in degrees (the jump angle)."""
    cosine = elementary.cos(np.radians(degrees))
    return cosine * cosine


def is_jump(start, end, chord, cosine2):
    """Per edge between nodes of values ``start`` and ``end`` (NaN where invalid), whose
    geometry is ``chord`` = (spread, rise) (``EdgeChords``): True where the edge e lies within
    the angle whose squared cosine is ``cosine2`` of the node line through its midpoint m.

    With a, b the values, e . m = (b^2 - a^2) / 2 (both points lie at their value's distance
    along their lines), so |e . d(m)| > cos(A) |e| (spec/zgrid.md) becomes
    (b^2 - a^2)^2 > cos^2(A) |e|^2 4 |m|^2, and on planar grids (b - a)^2 > cos^2(A) |e|^2:
    no points, square roots or divisions, and the same edges as the test on the points but
    for an edge within rounding of the angle."""
    spread, rise = chord
    delta = end - start
    if spread is None:
        return delta * delta > cosine2 * (delta * delta + rise)
    total = end + start
    product = start * end * spread
    return (delta * total) ** 2 > cosine2 * (delta * delta + product + rise) * (total * total - product)


def sight_jumps(points, angle=JUMP_ANGLE):
    """The Jumps of the edges between the (rows, cols, 3) ``points`` of an organised cloud,
    whose node lines are the lines of sight from the origin (a spherical grid's rays, but not
    on a regular grid of angles): the spec's test on the points themselves, with ``is_jump``'s
    algebra (2 e . m = |end|^2 - |start|^2, 2m = start + end). The test is of the fourth power
    of the coordinates on both sides, so points past 2^200 (whose fourth powers overflow) are
    scaled by a power of two first, exactly: the same answers."""
    cosine2 = squared_cosine(angle)
    largest = float(np.fmax.reduce(np.abs(points[np.isfinite(points)]), initial=0.0))
    if largest > 2.0 ** 200:
        points = np.ldexp(points, -np.frexp(largest)[1])

    def jump(start, end):
        squared = lambda vectors: np.sum(vectors * vectors, axis=-1)  # noqa: E731
        return (squared(end) - squared(start)) ** 2 > cosine2 * squared(end - start) * squared(end + start)

    with np.errstate(invalid="ignore"):
        return Jumps(across=jump(points[:-1], points[1:]), along=jump(points[:, :-1], points[:, 1:]),
                     diagonal=jump(points[:-1, 1:], points[1:, :-1]))


def grid_triangles(valid, periodic=False, jumps=None):
    """Triangles (m, 3) over the flat node indices of a (rows, cols) validity mask: those of
    ``kept_cells``, every 1-2-3 first, then every 2-4-3."""
    kept = kept_cells(valid, periodic, jumps)
    return np.concatenate([corners(kept, which, valid.shape[1], periodic) for which in (0, 1)])


def kept_cells(valid, periodic=False, jumps=None):
    """(rows-1, cells per row, 2): per cell, whether its triangles 1-2-3 and 2-4-3 are made over
    a (rows, cols) validity mask: where their corners are valid (with ``periodic`` the cells
    between the last column and the first too) and, with ``jumps`` (a Jumps), none of their
    edges is a jump."""
    if periodic:
        valid = np.hstack([valid, valid[:, :1]])
    kept = np.empty((len(valid) - 1, valid.shape[1] - 1, 2), dtype=bool)
    np.logical_and(valid[:-1, :-1] & valid[:-1, 1:], valid[1:, :-1], out=kept[..., 0])
    np.logical_and(valid[:-1, 1:] & valid[1:, 1:], valid[1:, :-1], out=kept[..., 1])
    if jumps is not None:
        kept[..., 0] &= ~(jumps.along[:-1] | jumps.across[:, :-1] | jumps.diagonal)
        kept[..., 1] &= ~(jumps.across[:, 1:] | jumps.along[1:] | jumps.diagonal)
    return kept


def corners(kept, which, cols, periodic):
    """(m, 3): the triangles 1-2-3 (``which`` 0) or 2-4-3 (1) of the ``kept`` cells (``kept_cells``),
    cell by cell, row by row, over the flat node indices of a grid of ``cols`` columns."""
    cell = np.flatnonzero(kept[..., which])
    row, col = np.divmod(cell, kept.shape[1])
    corner1 = row * cols + col
    corner2 = corner1 + 1 if not periodic else row * cols + (col + 1) % cols
    triangles = np.empty((len(cell), 3), dtype=np.int64)
    triangles[:, 0], triangles[:, 1], triangles[:, 2] = (corner1, corner2, corner1 + cols) if which == 0 else \
        (corner2, corner2 + cols, corner1 + cols)
    return triangles


def grid_to_mesh(grid: "ZGrid", jump_angle: float | None = None) -> "Mesh":
    """The Mesh of a ZGrid (its ``grid`` set to it): ``GridMesh``'s, whole, or ``charted_mesh``."""
    return GridMesh(grid, jump_angle).mesh() if grid.charts is None else charted_mesh(grid, jump_angle)


def mesh_of(grid, jump_angle=None):
    """What makes a ZGrid's mesh: a GridMesh (streamed a strip at a time), or for a multi-chart
    grid the Mesh of its charts (``charted_mesh``)."""
    return GridMesh(grid, jump_angle) if grid.charts is None else charted_mesh(grid, jump_angle)


def charted_mesh(grid, jump_angle=None):
    """The Mesh of a multi-chart grid (its ``grid`` set): its charts' meshes zipped into one
    surface (``zipped_charts``), each vertex with its node's colour."""
    from mzc.meshes import Mesh

    points, triangles, node = zipped_charts(grid, jump_angle)
    colors = None if grid.colors is None else grid.colors.reshape(-1, 3)[every_node(points, node)]
    return Mesh(points, triangles, grid=grid, colors=colors)


def zipped_charts(grid, jump_angle=None):
    """(points, triangles, node of each chart point) of a multi-chart grid: each chart's GridMesh,
    one after the other, its jumps those of CHART_JUMP_ANGLE unless ``jump_angle`` is given
    (spec/zgrid.md, Charts), zipped along their seams into one surface (``mzc.ops.zipper``); the
    charts' points come first, each with the flat number of its grid node in ``node``, then the
    points the zipper adds (``every_node`` gives them theirs)."""
    from mzc.ops.zipper import zip_charts

    angle = CHART_JUMP_ANGLE if jump_angle is None else jump_angle
    points, triangles, chart, node = chart_meshes(grid, angle)
    zipped, stitched = zip_charts(points, triangles, chart, max(grid.d1, grid.d2))
    return zipped, stitched, node


def every_node(points, node):
    """The grid node of each of ``points`` (``zipped_charts``'): the charts' own points have theirs in
    ``node``; a point the zipper added takes that of the charts' point nearest it (whose colour and
    texel it takes)."""
    if len(points) == len(node):
        return node
    from mzc.ops.colouring import nearest_sources

    return np.concatenate([node, node[nearest_sources(points[len(node):], points[:len(node)])]])


def node_mesh(grid, jump_angle=None):
    """(points, triangles, node of each point) of a grid's mesh, whole: a GridMesh's used nodes,
    or a multi-chart grid's ``zipped_charts`` (what a texture places in the grid's colour image)."""
    if grid.charts is not None:
        points, triangles, node = zipped_charts(grid, jump_angle)
        return points, triangles, every_node(points, node)
    mesh = GridMesh(grid, jump_angle)
    return mesh.points, mesh.triangles, np.flatnonzero(mesh.used)


def chart_meshes(grid, angle):
    """(points, triangles, chart and node of each point): the GridMeshes of a multi-chart grid's charts
    (``ZGrid.chart_grids``) at jump angle ``angle``, one after the other, made at once over the
    grid's values (393 charts one by one took a tenth of a second): each edge's jump test reads
    its two values and the spacings, which the charts share, so the cells kept are the chart
    grids', but for those across two charts; the triangles and points come in each chart's
    order (its 1-2-3s row by row, then its 2-4-3s; its used nodes row by row) and each point
    as its chart grid's ``to_input_frame`` makes it, operation for operation."""
    from mzc.grid import chart_labels

    label, cols = chart_labels(grid.shape, grid.charts), grid.shape[1]
    kept = kept_cells(grid.valid, False, jump_edges(grid, angle))
    kept[..., 0] &= (label[:-1, :-1] == label[:-1, 1:]) & (label[:-1, :-1] == label[1:, :-1])
    kept[..., 1] &= (label[:-1, 1:] == label[1:, 1:]) & (label[:-1, 1:] == label[1:, :-1])
    triangles = np.concatenate([corners(kept, which, cols, False) for which in (0, 1)])
    triangles = triangles[np.argsort(label.ravel()[triangles[:, 0]], kind="stable")]
    used = np.zeros(label.size, dtype=bool)
    used[triangles.ravel()] = True
    node = np.flatnonzero(used)
    node = node[np.argsort(label.ravel()[node], kind="stable")]
    number = np.zeros(label.size, dtype=np.int64)
    number[node] = np.arange(len(node))
    chart = label.ravel()[node]
    return chart_points(grid, node, chart), number[triangles], chart, node


def chart_points(grid, node, chart):
    """(k, 3) input-frame points of the grid's flat ``node``s, each in ``chart``: u = i0 d2 + d2 i
    and v = j0 d1 + d1 j at its column i and row j of its chart's block, its value, turned by its
    chart's rotation (the grid's, turned to the chart's view) and shifted."""
    from mzc.vectors import dotted, matrix_product

    at = np.array([(c.row0, c.col0, c.i0, c.j0) for c in grid.charts], dtype=np.int64).reshape(-1, 4)
    row, col = np.divmod(node, grid.shape[1])
    components = np.empty((3, len(node)))
    components[0] = (at[:, 2] * grid.d2)[chart] + grid.d2 * (col - at[chart, 1])
    components[1] = (at[:, 3] * grid.d1)[chart] + grid.d1 * (row - at[chart, 0])
    components[2] = grid.z.ravel()[node]
    rotation, shift = grid.transform[:, :3], grid.transform[:, 3]
    views = sorted({c.view for c in grid.charts})
    turns = np.stack([matrix_product(rotation, projections.view_rotation(view)) for view in views])
    view = np.searchsorted(views, [c.view for c in grid.charts])[chart]
    return np.stack([dotted(components.T, turns[:, k][view]) for k in range(3)], axis=-1) + shift


class GridMesh:
    """The mesh of a ZGrid, made a strip of rows at a time (``row_strips``), for writers that
    stream it (``parts``): its valid nodes in the input frame, unused nodes dropped; the
    triangles 1-2-3 of every cell first, row by row, then the triangles 2-4-3; none across a
    depth jump of ``jump_angle`` degrees (default JUMP_ANGLE; 0 keeps them all); the valid
    nodes of a pole row one vertex (the first, at their mean point) and the triangles this
    collapses to an edge dropped. A geographic grid (longitude and latitude in degrees) is
    placed in metres about its centre (``mzc.georef.metric_frame``): a mesh is lengths.

    Made when it is read: each strip's jumps (from the values) and kept cells first, the
    nodes their triangles use and the counts; then, a strip at a time, the points and the
    triangles. So the memory beside the grid is a strip's and two bytes a cell, and a file
    written from the parts holds no copy of the mesh (the points and triangles of ``mesh()``
    or of the attributes are its arrays, made on first use)."""

    def __init__(self, grid, jump_angle=None):
        from mzc.georef import metric_frame

        self.grid = grid = metric_frame(grid)
        self.valid, self.poles = grid.valid, grid.pole_rows()
        self.strips = row_strips(grid.shape)
        self.kept = [kept_cells(self.valid[low:high + 1], grid.periodic, jumps_between(grid, low, high, jump_angle))
                     for low, high in self.strips]
        self.used = np.zeros(self.valid.size, dtype=bool)
        self.triangle_count = 0
        for index in range(len(self.strips)):
            for which in (0, 1):
                triangles = self.strip_triangles(index, which)
                self.used[triangles.ravel()] = True
                self.triangle_count += len(triangles)
        self.vertex_count = int(np.count_nonzero(self.used))
        self.whole = None

    def strip_triangles(self, index, which):
        """The triangles 1-2-3 (``which`` 0) or 2-4-3 (1) of strip ``index`` over the grid's flat
        node indices, pole rows merged."""
        low, high = self.strips[index]
        cols = self.grid.shape[1]
        triangles = corners(self.kept[index], which, cols, self.grid.periodic) + low * cols
        merged = False
        for row in low + np.flatnonzero(self.poles[low:high + 1]):
            valid_columns = np.flatnonzero(self.valid[row])
            if len(valid_columns):
                on_row = (triangles >= row * cols) & (triangles < (row + 1) * cols)
                triangles[on_row] = row * cols + valid_columns[0]
                merged = True
        if merged or cols == 1:   # a periodic grid of one column joins each node to itself
            triangles = triangles[(triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2])
                                  & (triangles[:, 0] != triangles[:, 2])]
        return triangles

    def triangle_chunks(self):
        """The triangles over the used nodes' numbers, a strip at a time: 1-2-3, then 2-4-3."""
        rows, cols = self.grid.shape
        before = np.r_[0, np.cumsum(np.count_nonzero(self.used.reshape(rows, cols), axis=1))]   # used, by row
        for which in (0, 1):
            for index, (low, high) in enumerate(self.strips):
                number = before[low] - 1 + np.cumsum(self.used[low * cols:(high + 1) * cols])
                yield number[self.strip_triangles(index, which) - low * cols]

    def point_chunks(self):
        """(k, 3) input-frame points of the used nodes, in node order, a strip of rows at a
        time, coordinate by coordinate (the components of the points a strip chooses are
        gathered into the rows of one array, which the frame's rotation reads as it is)."""
        grid, (rows, cols) = self.grid, self.grid.shape
        step = max(1, STRIP_NODES // cols)
        for low in range(0, rows, step):
            strip = slice(low, min(low + step, rows))
            shape = grid.z[strip].shape
            coordinates = [np.broadcast_to(c, shape) for c in projections.point_components(
                grid.projection, grid.radius, grid.xs()[None, :], grid.ys()[strip, None], grid.z[strip])]
            chosen = self.used[strip.start * cols:strip.stop * cols].reshape(shape)
            components = np.empty((3, np.count_nonzero(chosen)))
            for component, coordinate in zip(components, coordinates):
                component[:] = coordinate[chosen]
            for row in np.flatnonzero(self.poles[strip]):
                on_row = np.flatnonzero(self.valid[low + row])
                if len(on_row) and chosen[row, on_row[0]]:
                    mean = np.stack([coordinate[row, on_row] for coordinate in coordinates], axis=-1).mean(axis=0)
                    components[:, np.count_nonzero(chosen.ravel()[:row * cols + on_row[0]])] = mean
            yield grid.to_input_frame(components.T)

    def parts(self):
        """(vertex count, triangle count, point chunks, triangle chunks), as ``Mesh.parts``."""
        return self.vertex_count, self.triangle_count, self.point_chunks(), self.triangle_chunks()

    @property
    def colors(self):
        """(n, 3) uint8 colours of the used nodes, in node order (a pole's vertex its first
        node's), or None for a grid without colours: 3 bytes a vertex, made when asked."""
        if self.grid.colors is None:
            return None
        return self.grid.colors.reshape(-1, 3)[self.used]

    def mesh(self):
        """The whole Mesh (its ``grid`` set, its colours the nodes'), made on first use."""
        from mzc.meshes import Mesh  # here: densify and encode find jumps without the mesh modules

        if self.whole is None:
            self.whole = Mesh(filled(self.point_chunks(), self.vertex_count, np.float64),
                              filled(self.triangle_chunks(), self.triangle_count, np.int64), grid=self.grid,
                              colors=self.colors)
        return self.whole

    @property
    def points(self):
        """The mesh's (n, 3) points (``mesh()``'s), for writers that take the whole arrays."""
        return self.mesh().points

    @property
    def triangles(self):
        """The mesh's (m, 3) triangles (``mesh()``'s)."""
        return self.mesh().triangles


def filled(chunks, count, dtype):
    """(count, 3) of ``dtype``: the (k, 3) ``chunks`` one after the other."""
    out = np.empty((count, 3), dtype=dtype)
    done = 0
    for chunk in chunks:
        out[done:done + len(chunk)] = chunk
        done += len(chunk)
    return out
