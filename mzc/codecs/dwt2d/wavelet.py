"""Numerics of the dwt2d codec: hole filling, the 2D wavelet pyramid, quantisation, rate control.

The encoder fills invalid nodes smoothly (so the transform spends no bits on a jump at
the mask edge), takes a multi-level 2D DWT with exactly as many coefficients as nodes,
and quantises each subband with its own step. Coefficients whose synthesis support
misses every valid node cannot change the decoded surface and are not coded at all. The
decoder's own inverse runs in the encoder too, so it sees exactly what the decoder will
produce and can add the correction layer that makes a max-error bound hold.

The transform is a property of the format's major version (``TRANSFORMS``): dwt2d 3.0
lifts with symmetric extension (``mzc.codecs.dwt2d.lifting``), 2.0 files are read with PyWavelets'
periodization, which joined a grid's opposite edges.
"""

import functools
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mzc import elementary, projections
from mzc.codecs.dwt2d import lifting
from mzc.errors import MzcError
from mzc.vectors import inner, unit_scaled

WAVELETS = ("bior4.4", "bior2.2", "bior3.3", "db2", "db4", "sym4", "coif1", "haar")   # of dwt2d 2.0
MODE = "periodization"
MAX_LEVELS = 12
MAX_QUANTUM = 1 << 45       # largest |quantised value|; keeps every class below entropy.MAX_CLASSES


# --------------------------------------------------------------------------- fill

FILL_TOLERANCE = 1e-6       # relative residual: the fill moves < 1e-4 of the height range, files not at all
SMOOTH_ITERATIONS = 16      # smooth_fill's steps at most (armadillo at 0.05% D: 12 steps 11,308 B, 16 11,228, 20
                            # 11,180; each about 10 ms on its 241,596 invalid nodes)...
SMOOTH_TOLERANCE = 1e-2     # ...or fewer, once the residual is this share of the harmonic fill's, which starts it
SMOOTH_START = 1e-2         # to this relative residual (3 steps where FILL_TOLERANCE takes 8; the same files)
SMOOTH_W_CYCLE = 1 << 62    # its preconditioner visits every level once (W-cycles: 0.2-0.6% smaller files,
                            # a third more of the fill's time)
FILL_OVERCORRECTION = 1.5   # coarse corrections of aggregates undershoot; 1.5 halved the iterations
FILL_W_CYCLE = 2000         # levels with more nodes are visited twice per cycle (iterations stay ~8 at any size)
NEIGHBOURS = ((0, 1), (0, -1), (1, 0), (-1, 0))
FILL_BLOCK = 1 << 14        # nodes a half-sweep updates at a time (the numpy sweeps' blocks, kept for their numbers)


def laplace_fill(z, valid, periodic=False):
    """``z`` with invalid nodes replaced by the discrete harmonic interpolant of the valid ones.

    The 5-point Laplace equation on the invalid nodes, the valid nodes as Dirichlet data
    and a free (Neumann) grid border: smooth across the mask edge, and it costs no bits
    because the decoder never needs it. With ``periodic`` the last column neighbours the
    first (a grid that makes a full turn). Solved by conjugate gradients preconditioned
    with an aggregation multigrid cycle (``FillLevel``): time and memory linear in the
    invalid nodes, where a sparse LU grew as n^1.3 and needed 317 MB per million nodes.
    The cycle's work is linear (9 iterations and 2.0 node visits per unknown per cycle at
    0.55-8.7 M unknowns), but its CPU time grew as n^1.36 from 0.55 to 2.2 M unknowns,
    most likely where the levels outgrew the 32 MB L3 cache: every sweep streamed eight
    temporaries a node through memory. Sweeps in cache-sized blocks, no weights on the
    finest level and int32 positions took 1.65x less CPU at 8.7 M unknowns, the same
    numbers bit for bit; the whole fill then grew as n^1.05 from 0.55 to 8.7 M unknowns
    (n^1.21 before), its last step (2.2 to 8.7 M) still n^1.18 on a loaded machine. The
    cycle is compiled (``Multigrid``), the same numbers again: the fill of f18 at 0.5 mm
    takes 2.1x less CPU.
    """
    filled = np.where(valid, z, 0.0)
    if valid.all() or not valid.any():
        return filled
    return harmonic_solve(filled, valid, periodic)[0]


def harmonic_solve(filled, valid, periodic, tolerance=FILL_TOLERANCE):
    """(``filled`` with its invalid nodes set to the harmonic fill, to ``tolerance``, in place; the
    multigrid of those nodes)."""
    fine, rhs = FillLevel.of_mask(filled, valid, periodic)
    levels = [fine]
    while levels[-1].size > 1:
        levels.append(levels[-1].coarser())
    multigrid = Multigrid(levels)
    filled[fine.rows, fine.cols] = conjugate_gradients(multigrid, rhs, tolerance=tolerance)
    return filled, multigrid


def smooth_fill(z, valid, periodic=False):
    """``z`` with invalid nodes replaced by the discrete biharmonic extension of the valid ones: the
    values that make the sum of the squared 5-point Laplacian over every node of the grid least,
    the valid nodes held (a thin plate's bending energy; the free grid border as in laplace_fill).

    The harmonic fill meets the surface at a crease: its height runs on across the mask's edge but
    not its slope, and the wavelet coefficients whose support straddles the edge pay for the crease.
    This one carries the slope on too, so they shrink. Where the mask's edges are long, as between
    a multi-chart grid's charts, the file at equal whole-surface RMS is 11-22% smaller (armadillo and
    hand at 0.05 and 0.1% D, benchmarks/objects-results.md; a face's, whose invalid nodes lie outside
    one outline, 1-2%). Only the
    encoder fills: files are read as before. Solved by conjugate gradients from the harmonic fill,
    preconditioned by one V-cycle of that fill's multigrid (the harmonic operator is most of this
    one's square root; ThinPlate), for SMOOTH_ITERATIONS steps at most: the far corners of the fill
    converge slowly, but the nodes near the mask, which the coefficients see, do not need them (the
    armadillo's file at 16 steps is within 2.5% of the exact solution's, solved by a sparse LU in
    4 times the time; the fill takes 0.36 s there, the harmonic one 0.21 s). The same numbers on
    every CPU: the stencils are compiled and numpy's elementwise arithmetic, the sums ``inner``'s and
    ``np.bincount``'s, in a fixed order."""
    filled = np.where(valid, z, 0.0)
    if valid.all() or not valid.any():
        return filled
    known = filled.copy()
    filled, multigrid = harmonic_solve(filled, valid, periodic, SMOOTH_START)
    fine = multigrid.finest
    plate = ThinPlate(multigrid, valid, periodic)
    b = -plate.squared(known)[fine.rows, fine.cols]
    filled[fine.rows, fine.cols] = conjugate_gradients(plate, b, filled[fine.rows, fine.cols], SMOOTH_TOLERANCE,
                                                             SMOOTH_ITERATIONS)
    return filled


class FillLevel:
    """One level of the fill's multigrid: a weighted 5-point graph Laplacian on the unknown
    nodes of a grid, plus a leak to the fixed (valid) nodes on the diagonal.

    Nodes are listed red ((row + column) even) first, so a Gauss-Seidel half-sweep is a
    slice. ``neighbours``/``weights`` (4 x size) point to each node's neighbours (``size``,
    a zero slot, where there is none); ``weights`` is None on the finest level, where every
    edge weighs 1 (it saves a third of the level's memory and traffic; a weight of 0 there
    meets the zero slot, so the products are the same numbers). A coarser level aggregates
    2x2 blocks: its weights are the sums of the fine edges between two blocks, its leak the
    sum of the block's (the Galerkin operator of piecewise-constant interpolation), so it
    stays a 5-point stencil. ``index`` holds each node's position in the level's grid padded
    by a border (``padded``; ``size`` where there is no node), ``at`` each node's place in it:
    a neighbour is one gather, with no test for the border.
    """

    def __init__(self, rows, cols, shape, periodic):
        odd = (rows + cols) % 2 == 1
        order = np.concatenate([np.flatnonzero(~odd), np.flatnonzero(odd)])   # a stable sort, in linear time
        self.rows, self.cols = rows[order].astype(np.int32), cols[order].astype(np.int32)   # half the traffic of int64
        self.shape, self.periodic = shape, periodic
        self.size, self.red = len(order), int(np.count_nonzero(~odd))
        index = np.full(shape, self.size, dtype=np.int32)
        index[self.rows, self.cols] = np.arange(self.size)
        self.index = self.padded(index, self.size)
        self.at = padded_place(self.rows, self.cols, shape)

    @classmethod
    def of_mask(cls, filled, valid, periodic):
        """(the finest level: the invalid nodes, unit weights, leak = count of valid
        neighbours; the right-hand side: the sum of the valid neighbours' heights)."""
        level = cls(*np.nonzero(~valid), valid.shape, periodic)
        known, heights = level.padded(valid, False), level.padded(filled, 0.0)
        neighbours, leak, rhs = [], np.zeros(level.size), np.zeros(level.size)
        for step in NEIGHBOURS:
            leak += level.beside(known, *step)
            rhs += level.beside(heights, *step)   # 0 beside an invalid node or the border, as the sum wants
            neighbours.append(level.beside(level.index, *step))
        neighbours = np.array(neighbours, dtype=np.int32)
        level.neighbours, level.weights = neighbours, None
        level.diagonal = leak + (neighbours < level.size).sum(axis=0)
        return level, rhs

    def padded(self, grid, outside):
        """``grid`` (of this level's shape) in ``padded``'s border."""
        return padded(grid, outside, self.periodic)

    def beside(self, grid, dr, dc):
        """Each node's neighbour (dr, dc) away in a ``padded`` grid."""
        return beside(grid, self.at, dr, dc)

    def connect(self, neighbours, weights, leak):
        """Set the stencil: the diagonal is the leak plus every edge's weight."""
        self.neighbours, self.weights, self.diagonal = neighbours, weights, leak + weights.sum(axis=0)

    def coarser(self):
        """The level of 2x2 aggregates of this one's nodes; sets ``parent``, each node's aggregate."""
        shape = ((self.shape[0] + 1) // 2, (self.shape[1] + 1) // 2)
        occupied = np.zeros(shape, dtype=bool)
        occupied[self.rows // 2, self.cols // 2] = True
        coarse = FillLevel(*np.nonzero(occupied), shape, self.periodic)
        self.parent = coarse.index[self.rows // 2 + 1, self.cols // 2 + 1]
        target = np.append(self.parent, -1)[self.neighbours]
        neighbours, weights = [], []
        for k, step in enumerate(NEIGHBOURS):
            crossing = (target[k] >= 0) & (target[k] != self.parent)
            weight = 1.0 if self.weights is None else self.weights[k]
            weights.append(np.bincount(self.parent, np.where(crossing, weight, 0.0), minlength=coarse.size))
            neighbours.append(np.where(weights[-1] > 0, coarse.beside(coarse.index, *step), coarse.size))
        coarse.connect(np.array(neighbours, dtype=np.int32), np.array(weights),
                       np.bincount(self.parent, self.leak_of(), minlength=coarse.size))
        return coarse

    def leak_of(self):
        """Each node's leak to fixed nodes: its diagonal less its edges."""
        edges = (self.neighbours < self.size).sum(axis=0) if self.weights is None else self.weights.sum(axis=0)
        return self.diagonal - edges


class Multigrid:
    """The fill's levels packed for the compiled kernels of ``mzc.codecs.dwt2d._fill``: the
    preconditioner's cycle (``cycle``) and the finest level's stencil (``times``).

    The cycle smooths each level with red-black Gauss-Seidel half-sweeps (red nodes neighbour
    only black ones, except across the seam of a periodic level with an odd column count),
    restricts the residual to the next level's aggregates, corrects with FILL_OVERCORRECTION
    times its solution, and is symmetric (red-black before, black-red after the coarse
    correction), as conjugate gradients needs; levels of more than FILL_W_CYCLE nodes are
    visited twice. Its numbers are those of the numpy cycle it replaced, so a half-sweep
    still updates FILL_BLOCK nodes at a time from the values before the block; it takes
    3.4x less CPU (f18 at 0.5 mm), most of the numpy cycle's time being Python's, on levels
    of a few nodes.
    """

    def __init__(self, levels):
        self.finest = levels[0]
        self.sizes = np.array([level.size for level in levels], dtype=np.int64)
        self.reds = np.array([level.red for level in levels], dtype=np.int64)
        self.neighbours = np.concatenate([level.neighbours.ravel() for level in levels])
        self.weights = np.concatenate([np.zeros(0)] + [level.weights.ravel() for level in levels[1:]])
        self.diagonals = np.concatenate([level.diagonal for level in levels])
        self.parents = np.concatenate([np.zeros(0, dtype=np.int32)] + [level.parent for level in levels[:-1]])
        self.space = np.empty(3 * int(self.sizes[1:].sum()) + FILL_BLOCK)   # the cycle's, lent at every call

    def cycle(self, b, out, w_cycle=FILL_W_CYCLE):
        """The preconditioner: approximately solve the finest level's system for ``b``, into ``out``
        (levels of more than ``w_cycle`` nodes visited twice)."""
        from mzc.codecs.dwt2d import _fill

        checked(_fill.cycle(out, b, self.sizes, self.reds, self.neighbours, self.weights, self.diagonals,
                            self.parents, self.space, FILL_BLOCK, w_cycle, FILL_OVERCORRECTION))

    def times(self, v, out):
        """The finest level's stencil applied to ``v`` (one value per node), into ``out``."""
        from mzc.codecs.dwt2d import _fill

        checked(_fill.apply(out, v, self.finest.neighbours, self.finest.diagonal))


class ThinPlate:
    """smooth_fill's system on the invalid nodes: ``times`` applies L_I^T L_I, L the 5-point graph
    Laplacian of the whole grid (as the harmonic fill's: free border, columns wrapping when
    ``periodic``) and _I its columns of the invalid nodes; ``cycle``, its preconditioner, is a V-cycle
    of the harmonic fill's multigrid (SMOOTH_W_CYCLE). L_I^T L_I = L_II^2 + L_VI^T L_VI: the harmonic
    stencil twice (compiled), and a correction through the *ring*, the valid nodes beside invalid
    ones: (L_VI v)_r is minus the sum of ring node r's invalid neighbours' values, and L_VI^T hands it
    back to them, negated."""

    def __init__(self, multigrid, valid, periodic):
        self.cycle = functools.partial(multigrid.cycle, w_cycle=SMOOTH_W_CYCLE)
        self.finest, self.periodic = multigrid.finest, periodic
        at = padded_place(*ring_of(valid, periodic), valid.shape)
        self.ring = np.stack([beside(self.finest.index, at, *step)
                              for step in NEIGHBOURS])   # 4 x ring: invalid neighbours, finest.size if none
        self.once = np.zeros(self.finest.size)

    def squared(self, grid):
        """L L ``grid``: the Laplacian of the Laplacian of a whole grid of values."""
        return grid_laplacian(grid_laplacian(grid, self.periodic), self.periodic)

    def times(self, v, out):
        """L_I^T L_I ``v`` (one value per invalid node) into ``out``."""
        from mzc.codecs.dwt2d import _fill

        fine = self.finest
        checked(_fill.apply(self.once, v, fine.neighbours, fine.diagonal))
        checked(_fill.apply(out, self.once, fine.neighbours, fine.diagonal))
        sums = np.append(v, 0.0)[self.ring].sum(axis=0)
        out += np.bincount(self.ring.ravel(), np.tile(sums, 4), minlength=fine.size + 1)[:-1]


def padded(grid, outside, periodic):
    """``grid`` in a border one node wide: ``outside`` beyond the rows and the ends of the rows,
    except that periodic columns wrap (never onto the node itself: a grid of one column has no
    neighbours along its rows). Every neighbour of a node is then one step away, with no test
    for the border or the seam."""
    out = np.full((grid.shape[0] + 2, grid.shape[1] + 2), outside, dtype=grid.dtype)
    out[1:-1, 1:-1] = grid
    if periodic and grid.shape[1] > 1:
        out[1:-1, 0], out[1:-1, -1] = grid[:, -1], grid[:, 0]
    return out


def padded_place(rows, cols, shape):
    """The flat places of the nodes (rows, cols) of a grid of ``shape`` in its ``padded`` grid."""
    return (rows + 1) * (shape[1] + 2) + (cols + 1)


def beside(grid, at, dr, dc):
    """The neighbour (dr, dc) away of the nodes at the flat places ``at`` of a ``padded`` grid."""
    return grid.ravel()[at + (dr * grid.shape[1] + dc)]


def neighbour_grids(grid, outside, periodic):
    """The four neighbours (NEIGHBOURS' order) of every node of ``grid``, each a grid of its shape:
    ``outside`` beyond the border, wrapping across the seam of periodic columns (``padded``)."""
    out = padded(grid, outside, periodic)
    rows, cols = grid.shape
    return [out[1 + dr:1 + dr + rows, 1 + dc:1 + dc + cols] for dr, dc in NEIGHBOURS]


def ring_of(valid, periodic):
    """(rows, cols) of the valid nodes beside an invalid one (across the seam of periodic columns)."""
    right, left, down, up = neighbour_grids(~valid, False, periodic)
    return np.nonzero(valid & (right | left | down | up))


def grid_laplacian(u, periodic=False):
    """The 5-point graph Laplacian of a grid of values: the sum over each node's neighbours of its
    value less theirs (no neighbours beyond the border, but across the seam of periodic columns;
    ``neighbour_grids``)."""
    out = np.zeros_like(u)
    present = neighbour_grids(np.ones(u.shape, dtype=bool), False, periodic)
    for here, neighbour in zip(present, neighbour_grids(u, 0.0, periodic)):
        out += np.where(here, u - neighbour, 0.0)
    return out


def checked(status):
    """Refuse a compiled fill kernel's error status (levels that disagree with their buffers)."""
    if status:
        raise MzcError("the hole fill's multigrid levels are inconsistent (an internal error)", field="fill")


def conjugate_gradients(multigrid, b, start=None, tolerance=FILL_TOLERANCE, iterations=100):
    """Solve the system of ``multigrid`` (its ``times``: the finest level's, or a ThinPlate's) for
    ``b`` to ``tolerance`` (the residual over the start's) by conjugate gradients preconditioned with the
    multigrid cycle, from ``start`` (None: 0). Every vector is updated in place (the same
    numbers: x += length * direction and so on), as fresh ones cost a big grid more in the
    kernel's page handling than in the arithmetic. Solved on ``b`` and ``start`` scaled by a power
    of two (``unit_scaled``: the same numbers, and heights of 1e-162 as any others)."""
    return unit_scaled(lambda rhs, first: conjugate_steps(multigrid, rhs, first, tolerance, iterations), b, start)


def conjugate_steps(multigrid, b, start, tolerance, iterations):
    """conjugate_gradients' steps, on ``b`` and ``start`` as they are."""
    preconditioned, image, change = (np.zeros_like(b) for _ in range(3))
    if start is None:
        x, residual = np.zeros_like(b), b.copy()
    else:
        x = start.copy()
        multigrid.times(x, image)
        residual = b - image
    multigrid.cycle(residual, preconditioned)
    direction = preconditioned.copy()
    product, limit = inner(residual, preconditioned), tolerance * np.sqrt(inner(residual, residual))
    for _ in range(iterations):
        if np.sqrt(inner(residual, residual)) <= limit:   # before the first step too: b = 0 is solved by 0
            break
        multigrid.times(direction, image)
        length = product / inner(direction, image)
        x += np.multiply(direction, length, out=change)
        residual -= np.multiply(image, length, out=change)
        multigrid.cycle(residual, preconditioned)
        product, previous = inner(residual, preconditioned), product
        direction *= product / previous
        direction += preconditioned
    return x


# --------------------------------------------------------------------------- transform


def default_levels(shape, coarsest):
    """Levels until the coarsest band is about ``coarsest`` nodes across (measured: deeper stops paying)."""
    return max(0, min(MAX_LEVELS, math.frexp(max(1, min(shape) / coarsest))[1] - 1))   # frexp: floor(log2) + 1


def forward(z, wavelet, levels):
    """dwt2d 2.0: [approximation, (H, V, D) coarse to fine, ...] of the filled heights."""
    import pywt

    if levels == 0:
        return [z.copy()]
    with warnings.catch_warnings():  # pywt warns when a level is deeper than the filter allows
        warnings.simplefilter("ignore")
        return pywt.wavedec2(z, wavelet, mode=MODE, level=levels)


def inverse(bands, shape, wavelet, levels):
    """dwt2d 2.0: heights from dequantised bands, cropped to ``shape``: the decoder's reconstruction."""
    import pywt

    if levels == 0:
        return bands[0].copy()
    return pywt.waverec2(bands, wavelet, mode=MODE)[: shape[0], : shape[1]]


def relevance(valid, wavelet, levels):
    """dwt2d 2.0: per band, True where the coefficient's synthesis support touches a valid node.

    Computed as the transform of the mask with every filter replaced by a box of the
    filter length (non-negative, so the test '> 0' is exact): a superset of the true
    support, identical in encoder and decoder because both see the same mask.
    """
    import pywt

    if levels == 0:
        return [valid.copy()]
    length = pywt.Wavelet(wavelet).dec_len
    box = [np.ones(length)] * 4
    boxes = forward(valid.astype(np.float64), pywt.Wavelet("box", filter_bank=box), levels)
    return [boxes[0] > 0] + [tuple(b > 0 for b in level) for level in boxes[1:]]


@dataclass(frozen=True)
class Transform:
    """The wavelet transform of one dwt2d major version: its wavelets and three functions,
    ``forward(z, wavelet, levels, periodic)``, ``inverse(bands, shape, wavelet, levels, periodic)``
    and ``relevance(valid, wavelet, levels, periodic)`` (``periodic``: the rows wrap round)."""

    wavelets: tuple
    forward: Callable
    inverse: Callable
    relevance: Callable
    coarsest: int       # the default levels stop when the coarsest band is about this many nodes across


TRANSFORMS = {
    2: Transform(WAVELETS, lambda z, wavelet, levels, periodic: forward(z, wavelet, levels),
                 lambda bands, shape, wavelet, levels, periodic: inverse(bands, shape, wavelet, levels),
                 lambda valid, wavelet, levels, periodic: relevance(valid, wavelet, levels), 16),
    3: Transform(tuple(lifting.LIFTINGS), lifting.forward,
                 lambda bands, shape, wavelet, levels, periodic: lifting.inverse(bands, wavelet, periodic),
                 lifting.relevance, 8),   # 5 levels on a face at 0.5 mm: 4-5% smaller than 4
}
# 4.0 adds charts side by side, 6.0 rounding, 7.0 a binary container, 8.0 another mask coding, 9.0 sections of
# levels, 10.0 a tighter container and table records: the same transform
TRANSFORMS[4] = TRANSFORMS[6] = TRANSFORMS[7] = TRANSFORMS[8] = TRANSFORMS[9] = TRANSFORMS[10] = TRANSFORMS[3]


# --------------------------------------------------------------------------- slope-scaled steps


@dataclass(frozen=True)
class Geometry:
    """What the slope factors need of a grid: spacings, projection and reference radius,
    the v of the first row and the row count (for elevations), and whether columns wrap."""

    d1: float
    d2: float
    projection: str = "planar"
    radius: float | None = None
    v0: float = 0.0
    rows: int = 1
    periodic: bool = False

    @classmethod
    def of(cls, d1, d2, origin, shape, projection="planar", radius=None):
        """The Geometry of a grid of ``shape`` with these header fields."""
        return cls(d1, d2, projection, radius, origin[1], shape[0],
                   projections.full_turn(projection, radius, shape[1], d2))


def slope_factors(approximation, levels, geometry, shapes, limit):
    """Step factor of every coefficient of the detail bands of ``shapes``: min(limit, 1/sqrt(w)).

    A value error d where the surface leans from the node's line by t moves it by d*cos(t)
    along its normal, and the node stands for a surface area a/cos(t) (a = h_u h_v, the
    projection's metric; 1 on planar grids); so the area-weighted squared normal error
    weighs d^2 by w = a*cos(t), and the steps that minimise it for a given rate grow as
    1/sqrt(w) (high-rate theory: step^2 inversely proportional to the weight). Measured on
    the faces at equal surface RMS, limit 2: 1-3% smaller files counting the whole grid,
    4-11% on the height-field part. The lean comes from the dequantised approximation band
    (values times 2**levels on a grid 2**levels times coarser), which the decoder has
    before any detail band, resampled linearly onto each band.
    """
    scale = 2.0 ** levels
    values = approximation / scale
    h_u, h_v = coarse_metric(values, scale, geometry)
    lean = area_factor(values, (scale * geometry.d1, scale * geometry.d2), (h_u, h_v), geometry.periodic)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.fmin(limit, np.sqrt(lean / (h_u * h_v)))
    down = {rows: resample(factor, rows, 0) for rows in {shape[0] for shape in shapes}}   # bands sharing a row count
    return [resample(down[shape[0]], shape[1], 1) for shape in shapes]


def coarse_metric(values, scale, geometry):
    """(h_u, h_v) at the nodes of the approximation band: coarse row i stands at fine row
    (i + 0.5) * scale - 0.5 (clamped to the grid), the band's values at the nodes' values."""
    if geometry.projection == "planar":
        return 1.0, 1.0
    position = np.clip((np.arange(values.shape[0]) + 0.5) * scale - 0.5, 0, geometry.rows - 1)
    v = (geometry.v0 + position * geometry.d1)[:, None]
    return projections.metric(geometry.projection, geometry.radius, v, values)


def area_factor(z, spacing, metric=(1.0, 1.0), periodic=False, jumps=None):
    """1/cos(t) at every node, t the lean of the surface from the node's line:
    sqrt(1 + (dz/dv / h_v)^2 + (dz/du / h_u)^2) with ``metric`` = (h_u, h_v); on planar
    grids the surface area per unit of grid area. ``periodic`` rows wrap around; the
    differences never span an edge of ``jumps`` (a triangulation.Jumps)."""
    h_u, h_v = metric
    with np.errstate(divide="ignore", invalid="ignore"):
        across = gradient(z, 0, spacing[0], breaks=None if jumps is None else jumps.across[:, :z.shape[1]]) / h_v
        along = gradient(z, 1, spacing[1], periodic, breaks=None if jumps is None else jumps.along) / h_u
        return np.sqrt(1.0 + across ** 2 + along ** 2)


def node_areas(z, geometry, jumps=None):
    """(1/cos(t), a): the lean factor and the metric area h_u h_v of every node of a grid
    of values ``z`` (filled, NaN-free); a node stands for the surface area a/cos(t) d1 d2.
    The lean at a node beside a depth jump (``jumps``) is that of the surface on its side."""
    if geometry.projection == "planar":
        return area_factor(z, (geometry.d1, geometry.d2), jumps=jumps), np.ones(z.shape)
    v = (geometry.v0 + geometry.d1 * np.arange(z.shape[0]))[:, None]
    h_u, h_v = projections.metric(geometry.projection, geometry.radius, v, z)
    return area_factor(z, (geometry.d1, geometry.d2), (h_u, h_v), geometry.periodic, jumps), h_u * h_v


def gradient(values, axis, spacing, periodic=False, breaks=None):
    """numpy.gradient along one axis (central inside, one-sided at the ends; 0 when the axis has
    one node); ``periodic``: central differences everywhere, the ends neighbouring each other.
    ``breaks`` (one per edge along the axis: n-1, or n when periodic) are edges the
    differences must not span: a node beside one takes the difference on its other side
    (0 between two)."""
    if values.shape[axis] < 2:
        return np.zeros(values.shape)
    if periodic and values.shape[axis] > 2:
        result = (np.roll(values, -1, axis=axis) - np.roll(values, 1, axis=axis)) / (2 * spacing)
    else:
        result = np.gradient(values, spacing, axis=axis)
    if breaks is None or not breaks.any():
        return result
    return np.moveaxis(avoiding_breaks(np.moveaxis(result, axis, -1), np.moveaxis(values, axis, -1),
                                       np.moveaxis(breaks, axis, -1), spacing), -1, axis)


def avoiding_breaks(result, values, breaks, spacing):
    """``result`` (differences along the last axis) with the nodes beside a break given the
    mean of their differences over the edges that are not breaks (0 when both are)."""
    n = values.shape[-1]
    edges = np.diff(values, axis=-1, append=values[..., :1])[..., :breaks.shape[-1]] / spacing
    before, after = np.full(values.shape, np.nan), np.full(values.shape, np.nan)
    before[..., 1:], after[..., :-1] = edges[..., :n - 1], edges[..., :n - 1]
    broken_before, broken_after = np.zeros(values.shape, dtype=bool), np.zeros(values.shape, dtype=bool)
    broken_before[..., 1:], broken_after[..., :-1] = breaks[..., :n - 1], breaks[..., :n - 1]
    if breaks.shape[-1] == n:   # periodic: the last edge joins node n-1 to node 0
        before[..., 0], after[..., -1] = edges[..., -1], edges[..., -1]
        broken_before[..., 0], broken_after[..., -1] = breaks[..., -1], breaks[..., -1]
    before[broken_before], after[broken_after] = np.nan, np.nan
    with np.errstate(invalid="ignore"):
        count = np.isfinite(before).astype(float) + np.isfinite(after)
        one_sided = (np.nan_to_num(before) + np.nan_to_num(after)) / np.maximum(count, 1)
    return np.where(broken_before | broken_after, one_sided, result)


def resample(values, size, axis):
    """``values`` linearly interpolated to ``size`` cells along ``axis``, cell centres aligned
    (position (i + 0.5) * n / size - 0.5 of the n input cells, clamped to the ends)."""
    n = values.shape[axis]
    if n == 1:
        return np.repeat(values, size, axis=axis)
    low, high, weight, complement = resampling(n, size, axis, values.ndim)
    out, upper = np.take(values, low, axis=axis), np.take(values, high, axis=axis)
    out *= complement   # in place: on big grids every new array is pages the kernel must hand out afresh
    upper *= weight
    out += upper
    return out


@functools.lru_cache(maxsize=256)
def resampling(n, size, axis, ndim):
    """(lower input cell, upper one, weight of the upper, 1 - weight) of each output cell of
    ``resample``: the same few shapes recur at every step the rate control tries."""
    position = np.clip((np.arange(size) + 0.5) * n / size - 0.5, 0, n - 1)
    low = np.minimum(position.astype(np.int64), n - 2)
    weight = (position - low).reshape([-1 if a == axis else 1 for a in range(ndim)])
    arrays = low, low + 1, weight, 1 - weight
    for array in arrays:   # shared by every call
        array.flags.writeable = False
    return arrays


def step_maps(steps, approximation_q, levels, geometry, shapes, limit):
    """Per band, its step (band 0) or its step times the slope factor of each coefficient."""
    if limit <= 1 or levels == 0:
        return list(steps)
    factors = slope_factors(approximation_q * steps[0], levels, geometry, shapes[1:], limit)
    for step, factor in zip(steps[1:], factors):
        factor *= step
    return [steps[0]] + factors


# --------------------------------------------------------------------------- quantisation


def round_step(step):
    """``step`` to 4 significant digits: a short header line, and no measurable change in size or error."""
    return float(f"{step:.4g}")


def quantise_band(magnitude, sign, step, deadzone=0.5):
    """Integers floor(|c|/step + 1 - deadzone) with c's sign (deadzone 0.5 = rounding), from
    ``magnitude`` |c| and ``sign`` sign(c) of a band (taken once: the rate control quantises
    the same bands at every step it tries); ``step`` is one number or one per coefficient."""
    scaled = magnitude / step
    if scaled.size and scaled.max() >= MAX_QUANTUM:
        raise MzcError(f"quantisation step {np.min(step):g} is too small for these heights")
    scaled += 1.0   # in place, the same numbers: (|c|/step + 1) - deadzone, floored, times the sign
    scaled -= deadzone
    np.floor(scaled, out=scaled)
    scaled *= sign
    return scaled.astype(np.int64)


def dequantise(qflat, steps):
    """Bands of step * q (steps: per band one number or one per coefficient), in the layout ``inverse`` takes."""
    return unflatten([q * s for q, s in zip(qflat, steps)], (len(qflat) - 1) // 3)


def flatten(bands):
    """[approximation, H, V, D, H, V, D, ...] from the pywt layout."""
    return [bands[0]] + [b for level in bands[1:] for b in level]


def unflatten(flat, levels):
    """The pywt layout from a flat band list."""
    return [flat[0]] + [tuple(flat[1 + 3 * i: 4 + 3 * i]) for i in range(levels)]


# --------------------------------------------------------------------------- correction


def correction_step(max_error):
    """Residual step 2E shrunk by one part in 1e9, so rounding error plus float noise stays <= E."""
    return 2.0 * max_error * (1.0 - 1e-9)


def corrections(z, decoded, valid, step):
    """Integer residuals k at the valid nodes (raster order) so |z - (decoded + k*step)| <= step/2."""
    return np.round((z[valid] - decoded[valid]) / step).astype(np.int64)


# --------------------------------------------------------------------------- rate control


SEARCH_TOLERANCE = 1.005   # the search ends with an x that meets the target and one within 0.5% above that does not
SEARCH_OVERSHOOT = 1.01    # a point aimed at the side of the target not yet seen lands this far past the crossing
SEARCH_LIMIT = 40          # costs taken at most (the rd corpus's --rmse encodes take 3-8, --size ones 4-7)
LEVER = elementary.log(1.02)   # two points fix the power law's slope when their x are 2% apart or more


def search_step(cost, target, low, high, guess, slope, snap=float):
    """The largest x found in [low, high] whose ``cost(x)`` <= target (``low`` when none is).

    ``cost`` grows with x, about as x**slope near the target, but neither exactly nor
    monotonically (a quantiser's error jitters from one step to the next): hence 'found'.
    The search starts at ``guess`` and ends when the smallest x found above the best one
    costs more than the target and lies within SEARCH_TOLERANCE of it. Each next x comes from
    the power law through two points: while they are all on one side of the target, the
    two nearest it (the given ``slope`` while there is one), aimed SEARCH_OVERSHOOT past the
    crossing and past every point taken, to reach the other side; then the best x and that
    smallest one above it (regula falsi on log x and log cost, with the Illinois rule: an
    end kept twice running counts half its distance from the target, so both ends close in),
    placed so that one more point can close the bracket where it is narrow enough. ``snap``
    maps x to the values it may take (the steps a header can write); an x snapped onto one
    already taken ends the search (the bracket as narrow as the tolerance and the snapping
    allow). On the 13 faces and 2 DEMs at 11 RMS targets it takes 5.3 costs (3-8) where a
    log bisection to 1% took 12, and its files were 0.07% smaller (geometric mean; the
    largest 1.0% larger: where the error jitters, the bisection can end on a step above the
    first one that fails).
    """
    points, sides = {}, []   # x: cost; whether each cost taken met the target
    x = snap(min(max(guess, low), high))
    best = None
    for _ in range(SEARCH_LIMIT):
        points[x] = cost(x)
        sides.append(points[x] <= target)
        met = [p for p in points if points[p] <= target]
        best = max(met) if met else None
        above = [p for p in points if points[p] > target and (best is None or p > best)]
        ceiling = min(above) if above else None
        if (best is not None and ceiling is not None and ceiling <= best * SEARCH_TOLERANCE) \
                or (best is None and x <= low) or (ceiling is None and x >= high):
            break
        if best is not None and ceiling is not None:
            x = closing_point(points, target, best, ceiling, sides)
        else:
            x = min(max(reaching_point(points, target, slope, best is not None), low), high)
        x = snap(x)
        if x in points:
            break
    return low if best is None else best


def log_cost(points, x, target):
    """log(cost(x) / target), -inf for a cost of 0."""
    return elementary.log(points[x] / target)


def reaching_point(points, target, slope, upwards):
    """The next x while every cost taken is on one side of the target (``upwards``: below it):
    the power law through the two points nearest the target (of x at least 2% apart; the
    default ``slope`` while there is one) solved for the target, then SEARCH_OVERSHOOT past
    that and past every point taken, towards the other side."""
    near = sorted(points, key=lambda p: abs(log_cost(points, p, target)))
    x0, f0 = near[0], log_cost(points, near[0], target)
    lever = [p for p in near[1:] if abs(elementary.log(p / x0)) > LEVER and np.isfinite(log_cost(points, p, target))]
    if lever and np.isfinite(f0):
        rise = (log_cost(points, lever[0], target) - f0) / elementary.log(lever[0] / x0)
        slope = float(np.clip(rise, slope / 4, slope * 4))   # a jitter between the two must not fling x far
    reach = elementary.log(1000.0)   # a jump moves x at most 1000x
    jump = np.clip(-f0 / slope, -reach, reach) if np.isfinite(f0) else reach
    if upwards:
        return max(x0 * elementary.exp(jump), max(points)) * SEARCH_OVERSHOOT
    return min(x0 * elementary.exp(jump), min(points)) / SEARCH_OVERSHOOT


def closing_point(points, target, best, ceiling, sides):
    """The next x between the best x and the smallest x above it that costs more (Illinois
    regula falsi on the logs), where one more point closes the bracket when it can (within
    SEARCH_TOLERANCE of both ends), else at least half the tolerance inside each end."""
    low, high = elementary.log(best), elementary.log(ceiling)
    f_low, f_high = log_cost(points, best, target), log_cost(points, ceiling, target)
    if len(sides) > 1 and sides[-1] == sides[-2]:
        if sides[-1]:
            f_high /= 2
        else:
            f_low /= 2
    middle = low + (high - low) * f_low / (f_low - f_high) if np.isfinite(f_low) else (low + high) / 2
    tolerance = elementary.log(SEARCH_TOLERANCE)
    if high - tolerance <= low + tolerance:
        return float(elementary.exp(np.clip(middle, high - tolerance, low + tolerance)))
    return float(elementary.exp(np.clip(middle, low + tolerance / 2, high - tolerance / 2)))
