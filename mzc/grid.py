"""The z-grid: a regular grid of values on cutting surfaces, the one data model every mzc step shares.

Node (r, c) sits at u = x0 + c*d2, v = y0 + r*d1 and holds a value, or NaN where the
node's line misses the surface. With the thesis's planar cutting planes (u, v) are the
grid frame's (x, y) and the value is z; central projections (``mzc.projections``) cut with
planes and half-planes or cones through an axis, the value being the distance along the
node's ray. Row r is one "horizontal" cutting surface of the thesis; a rigid transform maps
the grid frame back to the frame of the input surface.

A multi-chart grid (``charts``) holds several planar grids, each a block of the values
looking along one axis of the grid's frame, so that a closed or many-part surface is seen
whole: every chart is a piece of the surface that its own node lines meet within 60
degrees (``mzc.ops.charts``), and triangulation zips the charts together.
"""

import math
import re
from dataclasses import dataclass, field, replace

import numpy as np

from mzc import projections
from mzc.colours import colour_array
from mzc.errors import MzcError
from mzc.limits import check_grid_size, length_problem
from mzc.numbers import real_array
from mzc.vectors import matrix_product, rotated

IDENTITY_TRANSFORM = np.hstack([np.eye(3), np.zeros((3, 1))])
TOKEN = re.compile(r"[^\s\x00-\x1f\x7f]{1,64}")   # one header token: no space, no control character
MAX_CRS = 16384            # characters of a crs line's WKT (a WKT2 of a projected CRS takes about 2,000)
CELLS = ("area", "point")  # what a raster's value stands for: its cell, or a sample at its node
ROW_ORDERS = ("down", "up")   # a raster's first row: the grid's last (north-up images) or its first
SAMPLES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")   # a raster's type
MAX_CHARTS = 65536         # charts of one grid
MAX_SOURCE_VERTICES = 2 ** 53   # a source's vertex count (any count a float64 array of points can have)


@dataclass(frozen=True)
class Raster:
    """How a planar grid lies in the raster it was read from (or is written to): ``cells``
    ``area`` (each node is the centre of a d2 x d1 cell, GeoTIFF's PixelIsArea, ESRI's
    ``xllcorner``) or ``point`` (a sample at the node: PixelIsPoint, ``xllcenter``); ``rows``
    ``down`` (the raster's first row is the grid's last: a north-up image) or ``up``; and
    ``sample``, the raster's value type. The node positions are the grid's own (origin, d1,
    d2): this only says how to write the same grid back as that raster (spec/zgrid.md)."""

    cells: str = "area"
    rows: str = "down"
    sample: str = "float64"

    def __post_init__(self) -> None:
        for name, choices in (("cells", CELLS), ("rows", ROW_ORDERS), ("sample", SAMPLES)):
            if getattr(self, name) not in choices:
                raise MzcError(f"raster {name} {getattr(self, name)!r} is not one of {', '.join(choices)}",
                               field="raster")

    def words(self) -> str:
        """The values of the header's ``raster`` line."""
        return f"{self.cells} {self.rows} {self.sample}"


@dataclass(frozen=True)
class Chart:
    """One chart of a multi-chart grid: the block of values at rows row0..row0+rows-1 and columns
    col0..col0+cols-1, a planar grid looking along ``view`` (a key of projections.PLANAR_VIEWS) of
    the grid's frame, whose node (0, 0) lies on the lattice of the grid's spacings at (i0, j0):
    u = i0 d2, v = j0 d1 in the view's frame (spec/zgrid.md, Charts)."""

    view: str
    row0: int
    col0: int
    rows: int
    cols: int
    i0: int
    j0: int

    def __post_init__(self) -> None:
        if self.view not in projections.PLANAR_VIEWS:
            raise MzcError(f"chart view {self.view!r} is not one of {', '.join(projections.PLANAR_VIEWS)}",
                           field="charts")
        for name in ("row0", "col0", "rows", "cols", "i0", "j0"):
            value = getattr(self, name)
            if not isinstance(value, int) or abs(value) > 1 << 40:
                raise MzcError(f"chart {name} {value!r} is not a whole number of nodes", field="charts")
        if min(self.row0, self.col0) < 0 or min(self.rows, self.cols) < 1:
            raise MzcError("a chart's block starts at row and column 0 or later and has a row and a column",
                           field="charts")

    def block(self, scale: int = 1) -> tuple[slice, slice]:
        """The chart's (rows, columns) of the grid's values, or with ``scale`` K of its colours K
        times finer than the nodes (``ZGrid.fine_colors``): the samples from its first node to its last."""
        return (slice(self.row0 * scale, (self.row0 + self.rows - 1) * scale + 1),
                slice(self.col0 * scale, (self.col0 + self.cols - 1) * scale + 1))

    def words(self) -> list[str]:
        """The chart's seven values on the header's ``charts`` line."""
        return [self.view, *(str(getattr(self, name)) for name in ("row0", "col0", "rows", "cols", "i0", "j0"))]

    def with_rows_inserted(self, n: int) -> "Chart":
        """The chart after ``n`` rows are inserted between each pair of the grid's rows (densify)."""
        return replace(self, row0=self.row0 * (n + 1), rows=(self.rows - 1) * (n + 1) + 1, j0=self.j0 * (n + 1))


def check_charts(charts, shape):
    """Refuse charts that leave the grid, overlap, or are too many; the nodes they cover."""
    if len(charts) > MAX_CHARTS:
        raise MzcError(f"{len(charts)} charts: at most {MAX_CHARTS}", field="charts")
    return chart_labels(shape, charts) >= 0


def node_colours(values, valid):
    """A grid's ``colors``: ``values`` as (rows, cols, 3) uint8 (``mzc.colours.colour_array``) for
    the ``valid`` mask's nodes, 0 at invalid ones (a copy where one was not), so that equal grids
    are equal whatever colour a hole was given."""
    colours = colour_array(values, (*valid.shape, 3))
    if colours[~valid].any():
        colours = colours.copy()
        colours[~valid] = 0
    return colours


def fine_shape(shape, scale):
    """(rows, cols) of a colour image ``scale`` times finer than a grid of ``shape`` nodes."""
    return tuple((n - 1) * scale + 1 for n in shape[:2])


def fine_lattice(count, scale):
    """(low, high, t) of the ``(count - 1) scale + 1`` samples of a node line ``scale`` times finer:
    sample a lies at node position a / scale, between nodes low and high (the same node when a is
    a multiple of scale) at the fraction t of the step (0 on a node)."""
    low, rest = np.divmod(np.arange((count - 1) * scale + 1), scale)
    return low, low + (rest > 0), rest / scale


def chart_labels(shape, charts):
    """(rows, cols): the number of the chart each node of a multi-chart grid of ``shape`` lies in,
    -1 outside them, refusing charts that leave the grid or overlap."""
    label = np.full(shape, -1, dtype=np.int64)
    for number, chart in enumerate(charts):
        if chart.row0 + chart.rows > shape[0] or chart.col0 + chart.cols > shape[1]:
            raise MzcError(f"a chart's block (rows {chart.row0}.., columns {chart.col0}..) leaves the "
                           f"{shape[0]} x {shape[1]} grid", field="charts")
        block = label[chart.block()]
        if (block >= 0).any():
            raise MzcError(f"the charts at row {chart.row0}, column {chart.col0} overlap another", field="charts")
        block[...] = number
    return label


def fine_mask(valid, scale, charts=None):
    """The validity of the colour samples of a grid ``scale`` times finer than its ``valid`` nodes:
    a sample is valid where every node of the cell (edge, node) it lies in is, and of a multi-chart
    grid's ``charts`` lies in one chart (spec/zgrid.md, Colours finer than the nodes), so that
    nothing beside the node mask and the charts need be stored."""
    (row_low, row_high, _), (col_low, col_high, _) = (fine_lattice(n, scale) for n in valid.shape)
    cells = [np.ix_(rows, cols) for rows in (row_low, row_high) for cols in (col_low, col_high)]
    mask = valid[cells[0]] & valid[cells[1]] & valid[cells[2]] & valid[cells[3]]
    if charts is None:
        return mask
    label = chart_labels(valid.shape, charts)
    first = label[cells[0]]
    return mask & (label[cells[1]] == first) & (label[cells[2]] == first) & (label[cells[3]] == first)


def fine_scale(shape, node_shape):
    """The colour scale K of a colour image of ``shape`` (rows, cols[, 3]) on a grid of ``node_shape``:
    ((rows - 1) K + 1, (cols - 1) K + 1) samples, K in 1..MAX_COLOUR_SCALE (1 for a 1 x 1 grid), or
    an MzcError."""
    from mzc.limits import MAX_COLOUR_SCALE

    spans = [(n - 1, m - 1) for n, m in zip(node_shape, shape[:2]) if n > 1]
    scale = spans[0][1] // spans[0][0] if spans else 1
    if len(shape) != 3 or shape[2] != 3 or not 1 <= scale <= MAX_COLOUR_SCALE or any(
            m != n * scale for n, m in spans) or (not spans and tuple(shape[:2]) != (1, 1)):
        raise MzcError(f"a colour image of shape {tuple(shape)} is no grid of {node_shape[0]} x {node_shape[1]} "
                       f"nodes sampled 1..{MAX_COLOUR_SCALE} times finer", field="fine_colors")
    return scale


def check_shape(shape):
    """Refuse the shape of heights that make no z-grid: 2D, within mzc.limits' sizes (a file
    has at least one row and column), checked before they are converted."""
    if len(shape) != 2:
        raise MzcError(f"a z-grid's heights are a 2D array, not one of shape {shape}", field="z")
    check_grid_size(*shape, field="z")


def finite(values, name, count):
    """``count`` finite real numbers of the field ``name`` as a flat float64 array."""
    def check_count(shape):
        if math.prod(shape) != count:
            raise MzcError(f"must be {count} number{'s' if count > 1 else ''}, not an array of shape {shape}",
                           field=name)

    array = real_array(values, name, check_count).reshape(-1)
    if not np.isfinite(array).all():
        raise MzcError("must be finite", field=name)
    return array


def check_crs(value):
    """Refuse a ``crs`` that the header cannot hold as its one line of WKT."""
    if value is None:
        return
    if not isinstance(value, str) or not value or len(value) > MAX_CRS or value != " ".join(value.split()):
        raise MzcError(f"a CRS is one line of WKT of 1 to {MAX_CRS} characters, single spaces between words",
                       field="crs")
    if not value.isprintable():
        raise MzcError("the CRS holds a control character", field="crs")


def vertex_count(value):
    """A source's vertex count as an int in 1..MAX_SOURCE_VERTICES, or None; anything else refused."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= MAX_SOURCE_VERTICES:
        raise MzcError(f"must be an integer in 1..{MAX_SOURCE_VERTICES}, not {value!r}", field="source_vertices")
    return int(value)


def check_token(value, name):
    """Refuse a ``units`` or ``nodata`` value that the header cannot hold as the one token it
    reads back (spaces or a newline would add header lines; bytes that are not UTF-8 would
    make the file unreadable)."""
    if value is None:
        return
    if not isinstance(value, str) or not TOKEN.fullmatch(value):
        raise MzcError(f"{value!r} is not one word of at most 64 printable characters", field=name)
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise MzcError(f"{value!r} is not valid UTF-8 text", field=name) from None
    if name == "nodata" and value.lower().lstrip("+-") in ("inf", "infinity"):
        raise MzcError("the no-data marker cannot be infinite", field=name)


@dataclass
class ZGrid:
    """Values ``z`` (rows x cols, NaN = invalid) with row step ``d1`` and column step ``d2``.

    ``origin`` is (u0, v0) of node (0, 0); ``transform`` is the 3x4 matrix [R | t] taking
    grid-frame points p to the input frame as R p + t (for central projections t is the
    centre and R's second column the axis); ``projection`` names the cutting surfaces and
    ``radius`` the reference radius R0 that scales their angles into lengths (None for
    planar grids); ``units`` names the length unit when known; ``nodata`` is the token
    written for invalid nodes. ``colors`` (rows, cols, 3) uint8 is each node's colour, sampled
    from the surface where it has one (``mzc.ops.colouring``), 0 at invalid nodes; None when
    the surface has none. ``fine_colors`` is the colour image sampled ``colour_scale`` K (2..8)
    times finer than the nodes, ((rows - 1) K + 1, (cols - 1) K + 1, 3) uint8, sample (a, b) at
    node position (a / K, b / K), 0 where invalid (``fine_mask``); ``colors`` are then its
    samples at the nodes. None when the colours are the nodes' alone (K = 1).
    A planar grid read from a raster (or to be written as one) has
    ``crs``, the coordinate reference system of the input frame as one line of WKT, and
    ``raster`` (a Raster): both None otherwise. ``source_vertices`` is the vertex (or point)
    count of the mesh or cloud the grid was sliced from, which the rebuild comes back near
    (``mzc.triangulate``); None when the grid did not come from one, or no longer has its density
    (densified, windowed).
    """

    z: np.ndarray
    d1: float
    d2: float
    origin: tuple = (0.0, 0.0)
    transform: np.ndarray = field(default_factory=lambda: IDENTITY_TRANSFORM.copy())
    units: str | None = None
    nodata: str = "nan"
    projection: str = "planar"
    radius: float | None = None
    crs: str | None = None
    raster: Raster | None = None
    charts: tuple[Chart, ...] | None = None
    colors: np.ndarray | None = None
    source_vertices: int | None = None
    fine_colors: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.z = real_array(self.z, "heights", check_shape)
        self.transform = finite(self.transform, "transform", 12).reshape(3, 4)
        self.origin = tuple(finite(self.origin, "origin", 2).tolist())
        self.d1, self.d2 = (float(finite(getattr(self, name), name, 1)[0]) for name in ("d1", "d2"))
        for name in ("units", "nodata"):
            check_token(getattr(self, name), name)
        for name in ("d1", "d2"):
            problem = length_problem(getattr(self, name))
            if problem:
                raise MzcError(problem, field=name)
        if self.projection not in projections.PROJECTIONS:
            raise MzcError(f"unknown projection {self.projection!r}")
        if self.projection == "planar":
            self.radius = None
        elif self.radius is None or not finite(self.radius, "radius", 1)[0] > 0:
            raise MzcError(f"a {self.projection} grid needs a positive radius")
        else:
            self.radius = float(finite(self.radius, "radius", 1)[0])
            rows, cols = self.z.shape
            problem = projections.extent_problem(self.projection, self.radius, rows, cols, self.d1, self.d2,
                                                 self.origin[1])
            if problem:
                raise MzcError(f"{problem[0]}: {problem[1]}")
        check_crs(self.crs)
        self.source_vertices = vertex_count(self.source_vertices)
        if self.raster is not None and not isinstance(self.raster, Raster):
            raise MzcError(f"must be a mzc.grid.Raster, not a {type(self.raster).__name__}", field="raster")
        if self.projection != "planar" and self.georeferenced:
            raise MzcError(f"a {self.projection} grid has no raster or CRS: they belong to planar grids",
                           field="crs" if self.crs else "raster")
        if self.charts is not None:
            self.check_charts()
        if self.fine_colors is not None:
            self.take_fine_colours()
        if self.colors is not None:
            self.colors = node_colours(self.colors, self.valid)

    def take_fine_colours(self) -> None:
        """Check ``fine_colors`` and make ``colors`` its node samples: the one image holds both, so
        they cannot disagree; at scale 1 it is the nodes' colours alone."""
        values = np.asarray(self.fine_colors)
        fine = colour_array(values, values.shape, "fine_colors")
        scale = fine_scale(fine.shape, self.z.shape)
        if scale == 1:
            self.colors, self.fine_colors = fine, None
            return
        mask = fine_mask(self.valid, scale, self.charts)
        if fine[~mask].any():
            fine = fine.copy()
            fine[~mask] = 0
        self.fine_colors, self.colors = fine, fine[::scale, ::scale]

    @property
    def colour_scale(self) -> int:
        """K: the colour samples a node spacing (``fine_colors``), 1 for colours at the nodes alone."""
        return 1 if self.fine_colors is None else fine_scale(self.fine_colors.shape, self.z.shape)

    def check_charts(self) -> None:
        """Refuse charts that a multi-chart grid cannot hold: they are planar blocks of its values,
        without a raster's georeferencing, and no value lies outside them."""
        self.charts = tuple(self.charts or ())
        if not self.charts:
            raise MzcError("a multi-chart grid has at least one chart", field="charts")
        if self.projection != "planar" or self.georeferenced or self.origin != (0.0, 0.0):
            raise MzcError("a multi-chart grid is planar, at origin 0 0, without a CRS or raster layout",
                           field="charts")
        covered = check_charts(self.charts, self.z.shape)
        if (self.valid & ~covered).any():
            raise MzcError("a value lies outside every chart", field="charts")

    @property
    def georeferenced(self) -> bool:
        """True when the grid carries a CRS or a raster layout (the header lines of spec/zgrid.md's
        newer minor versions)."""
        return self.crs is not None or self.raster is not None

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        return self.z.shape

    @property
    def valid(self) -> np.ndarray:
        """Boolean mask of the nodes that hold a value."""
        return ~np.isnan(self.z)

    @property
    def periodic(self) -> bool:
        """True when the columns make a full turn about the axis: column cols-1 neighbours column 0."""
        return projections.full_turn(self.projection, self.radius, self.z.shape[1], self.d2)

    def pole_rows(self) -> np.ndarray:
        """Per row, True where the row lies on a pole of a spherical grid (all its nodes on one ray)."""
        return projections.pole_rows(self.projection, self.radius, self.ys())

    def xs(self) -> np.ndarray:
        """u of every column (grid-frame x for planar grids)."""
        return self.origin[0] + self.d2 * np.arange(self.z.shape[1])

    def ys(self) -> np.ndarray:
        """v of every row (grid-frame y for planar grids)."""
        return self.origin[1] + self.d1 * np.arange(self.z.shape[0])

    def node_points(self) -> np.ndarray:
        """(rows, cols, 3) grid-frame coordinates of every node (NaN where invalid)."""
        return projections.to_points(self.projection, self.radius, self.xs()[None, :], self.ys()[:, None], self.z)

    def to_input_frame(self, points: np.ndarray) -> np.ndarray:
        """Map (..., 3) grid-frame points to the input surface's frame."""
        rotation, shift = self.transform[:, :3], self.transform[:, 3]
        return rotated(points, rotation) + shift

    def to_grid_frame(self, points: np.ndarray) -> np.ndarray:
        """Map (..., 3) input-frame points to the grid frame (inverse of to_input_frame)."""
        rotation, shift = self.transform[:, :3], self.transform[:, 3]
        return rotated(points - shift, rotation.T)

    def chart_grids(self) -> list["ZGrid"]:
        """Each chart as a planar grid of its own: its block of values, its origin on the lattice and
        its frame (the grid's, turned to look along the chart's view); [self] without charts."""
        if self.charts is None:
            return [self]
        rotation, shift, scale = self.transform[:, :3], self.transform[:, 3:], self.colour_scale
        return [ZGrid(z=self.z[chart.block()], d1=self.d1, d2=self.d2, origin=(chart.i0 * self.d2, chart.j0 * self.d1),
                      transform=np.hstack([matrix_product(rotation, projections.view_rotation(chart.view)), shift]),
                      units=self.units, nodata=self.nodata,
                      colors=None if self.colors is None else self.colors[chart.block()],
                      fine_colors=None if self.fine_colors is None else self.fine_colors[chart.block(scale)])
                for chart in self.charts]

    def with_z(self, z: np.ndarray, **changes) -> "ZGrid":
        """A copy with new values (and any other fields changed); values of another shape leave
        the copy without colours unless ``colors`` is among the changes (a strip of rows, a
        densified grid: the caller that has them for the new nodes gives them); values of another
        shape, or new colours, leave it without ``fine_colors`` unless they are among the changes."""
        z = np.asarray(z, dtype=float)
        if self.colors is not None and "colors" not in changes and z.shape != self.z.shape:
            changes["colors"] = None
        if self.fine_colors is not None and "fine_colors" not in changes and (
                "colors" in changes or z.shape != self.z.shape):
            changes["fine_colors"] = None
        return replace(self, z=z, **changes)
