"""Restore the mesh density: insert rows between the cutting planes (METHOD.md §5, thesis §6.2.3).

A z-grid of k1 rows becomes (k1-1)(n+1)+1 rows with row step d1/(n+1); original row r
lands unchanged on dense row r*(n+1). Three ways to fill the inserted rows:

``thesis``
    The thesis exactly (§6.2.3, eq. 3.40): each pair of rows bounds its own rectangle,
    the left/right sides are straight lines between the corner values, the interior
    starts at 0 and is Jacobi-averaged over the 4 neighbours (equal steps assumed) a
    fixed number of times or until the update falls below a tolerance.
``laplace``
    The same boundary value problem solved to convergence with the true steps
    (d1/(n+1) across rows, d2 along them) by one sparse direct solve.
``biharmonic``
    The step the thesis names as future work (§8.2-8.3): the discrete thin-plate energy
    (u_xx² + 2u_xy² + u_yy², true steps) minimised over the whole dense grid at once with
    the original rows held fixed, so each inserted row feels the planes beyond its two
    neighbours and the surface stays smooth (C¹) across planes. Edges of the data get the
    natural boundary conditions of a free plate: only difference stencils whose nodes all
    hold data enter the energy.

Holes. Inserted nodes exist only in columns valid in both neighbouring rows; everything
else stays NaN, so no surface is invented outside the data and non-overlapping rows
insert nothing. (Columns valid in both rows always lie inside the thesis's domain
U_left = max of the first valid columns .. U_right = min of the last valid ones.) A row
with interior holes splits a gap into runs of such columns; for ``thesis`` and
``laplace`` every run is its own rectangle with the thesis's straight-line sides at its
two end columns (a run of one or two columns is just those lines), which is the thesis
itself when there are no holes. ``biharmonic`` treats run ends as free edges instead.

Depth jumps. Rows are never inserted across a depth jump (an edge between two nodes that
runs nearly along the node lines, ``mzc.ops.triangulation``): such a column is outside the
gap's domain, as if one of its rows were invalid there, and the inserted nodes are not
smoothed across a jump along a row (a jump in either row of the gap): for ``thesis`` and
``laplace`` its columns are run ends, for ``biharmonic`` no stencil spans it. So a person
in front of a wall gets no sheet of inserted nodes between them.

Big grids. The gaps are solved in strips of rows (``strips``): exactly for ``thesis`` and
``laplace``, whose gaps are independent, and with a halo of gaps for ``biharmonic``, whose
strips then equal the whole-grid solve within its tolerance; a grid within one strip (a
face) is solved whole. So the memory beyond the dense result is bounded and the time linear.

Central grids are densified in their own coordinates (rows inserted in v, values along
the rays). A grid whose columns make a full turn is periodic: it is padded with copies of
its own columns, wrapped round, on both sides, densified, and cut back, so every column,
the first and last included, sees its true neighbours. The padding is wide enough that
the result is the periodic one: one column more than the thesis's fixed Jacobi sweeps
reach, or, for the converged solves, WRAP_DECAY gap heights (d1), over which the influence
of the padding's far edge decays below 1e-12 (it decays as exp(-pi x / d1) along a gap).
"""

import numpy as np

from mzc.errors import MzcError
from mzc.limits import MAX_INSERTED, MAX_ITERATIONS, check_grid_size, length_problem
from mzc.vectors import inner, unit_scaled

METHODS = ("thesis", "laplace", "biharmonic")
DEFAULT_METHOD = "biharmonic"
DEFAULT_ITERATIONS = 100   # the thesis's fixed Jacobi count (§6.2.3)
WRAP_DECAY = 9.0           # periodic padding of the converged solves, in gap heights
STRIP_NODES = 1 << 21      # inserted nodes solved at a time, halo aside (biharmonic: ~300 bytes each)
BIHARMONIC_HALO = 24       # gaps solved beyond each side of a biharmonic strip (densify.strips)


def densify_grid(grid, n, method=DEFAULT_METHOD, iterations=DEFAULT_ITERATIONS, tol=None, jump_angle=None,
                 strip=STRIP_NODES):
    """``grid`` (a ZGrid) with ``n`` rows inserted between each pair of rows; row step d1/(n+1).

    No row is inserted across a depth jump of ``jump_angle`` degrees (default the
    triangulation's JUMP_ANGLE; 0 ignores jumps), and no row is smoothed across one (module
    docstring). A periodic grid (a full turn) is densified with its columns wrapped round.
    ``strip``: as ``densify``'s; the jumps are found strip by strip too. A geographic grid is
    solved with its steps and jumps in metres (``mzc.georef.metric_frame``) and keeps its degrees.
    A multi-chart grid is densified chart by chart (``densify_charts``). The densified grid drops the
    source's vertex count (``kept_count``): its rebuild keeps the density asked for.
    """
    from mzc.georef import metric_frame

    if grid.charts is not None:
        return densify_charts(grid, n, method, iterations, tol, jump_angle, strip)
    original, grid = grid, metric_frame(grid)
    cols = grid.shape[1]
    pad = wrap_width(grid, method, iterations, tol) if grid.periodic else 0
    z = np.pad(grid.z, ((0, 0), (pad, pad)), mode="wrap") if pad else grid.z
    breaks = lambda low, high: strip_jumps(grid, low, high, jump_angle, pad)  # noqa: E731
    dense = densify(z, n, grid.d1, grid.d2, method=method, iterations=iterations, tol=tol, breaks=breaks, strip=strip)
    dense = dense[:, pad:pad + cols]
    return original.with_z(dense, d1=original.d1 / (n + 1), colors=dense_colours(original, dense, n),
                           fine_colors=kept_fine_colours(original, n), source_vertices=kept_count(original, n))


def kept_fine_colours(grid, n):
    """The colours finer than the nodes (``ZGrid.fine_colors``) that a grid densified by ``n`` keeps:
    its own when no row was inserted; else none, named in one MzcWarning (the inserted rows cut its
    cells unevenly; the nodes keep their colours, mixed for the new rows)."""
    if grid.fine_colors is None or not n:
        return grid.fine_colors
    from mzc.colours import warn_not_kept

    warn_not_kept(f"the colours {grid.colour_scale} times finer than the nodes",
                  "densify keeps the nodes' colours, mixed for the rows it inserts")
    return None


def dense_colours(grid, dense, n):
    """The colours of ``grid`` densified to the values ``dense`` (``colouring.densified_colours``),
    or None for a grid without."""
    from mzc.ops.colouring import densified_colours

    return None if grid.colors is None else densified_colours(grid.colors, ~np.isnan(dense), n)


def densify_charts(grid, n, method, iterations, tol, jump_angle, strip):
    """A multi-chart ``grid`` densified chart by chart, each chart's rows and place scaled by n+1
    (``Chart.with_rows_inserted``): no chart is smoothed into the one beside it."""
    from mzc.ops.triangulation import CHART_JUMP_ANGLE

    check_request(grid.z, n, grid.d1, grid.d2, method, iterations, tol)   # the whole grid's request, first
    jump_angle = CHART_JUMP_ANGLE if jump_angle is None else jump_angle
    charts = tuple(chart.with_rows_inserted(n) for chart in grid.charts)
    z = np.full(((grid.shape[0] - 1) * (n + 1) + 1, grid.shape[1]), np.nan)
    for chart, part in zip(charts, grid.chart_grids()):
        z[chart.block()] = densify_grid(part, n, method, iterations, tol, jump_angle, strip).z
    return grid.with_z(z, d1=grid.d1 / (n + 1), charts=charts, colors=dense_colours(grid, z, n),
                       source_vertices=kept_count(grid, n))


def kept_count(grid, n):
    """The source's vertex count a grid densified by ``n`` keeps: none when rows were inserted (the
    rebuild keeps the density asked for), its own when none were."""
    return None if n else grid.source_vertices


def strip_jumps(grid, low, high, jump_angle, pad):
    """(across, along) depth jumps (``triangulation.jump_edges``) of original rows low..high
    of ``grid``, its columns padded by ``pad`` on each side, wrapped round.

    Each edge's test sees only its two nodes and the grid's own row positions: the same
    jumps as the whole grid's (only a spherical grid's pole rows, found with a tolerance
    from the strip's own row positions, could differ, for a row within rounding of that
    tolerance)."""
    from mzc.ops.triangulation import jump_edges

    cols, rows = grid.shape[1], slice(low, high + 1)
    jumps = jump_edges(grid.with_z(grid.z[rows], origin=(grid.origin[0], grid.ys()[low])), jump_angle)
    across, along = jumps.across[:, :cols], jumps.along
    if pad:
        across = np.pad(across, ((0, 0), (pad, pad)), mode="wrap")
        along = np.take(along, np.arange(-pad, cols + pad - 1), axis=1, mode="wrap")
    return across, along


def wrap_width(grid, method, iterations, tol):
    """Columns to pad a periodic grid with on each side so that densifying it is periodic."""
    cols = grid.shape[1]
    if method == "thesis" and tol is None:
        return min(cols, iterations + 1)
    if method == "thesis":
        return cols
    return min(cols, int(np.ceil(WRAP_DECAY * grid.d1 / grid.d2)) + 1)


def densify(z, n, d1, d2, method=DEFAULT_METHOD, iterations=DEFAULT_ITERATIONS, tol=None, breaks=None,
            strip=STRIP_NODES):
    """Heights ``z`` (rows x cols, NaN = invalid) with ``n`` rows inserted between each pair of rows.

    ``d1`` and ``d2`` are the row and column steps of ``z``. Returns (k1-1)(n+1)+1 rows
    (k1 rows when k1 < 2); original row r is dense row r*(n+1), bit for bit.
    ``iterations`` and ``tol`` drive the ``thesis`` Jacobi sweeps only. ``breaks`` =
    (across (rows-1, cols), along (rows, cols-1)) marks the edges between neighbouring
    nodes that nothing is inserted or smoothed across (depth jumps), or a function giving
    them for original rows low..high, ``breaks(low, high)``; none by default. The gaps are
    solved in strips of about ``strip`` inserted nodes (``strips``), so the memory beyond
    the dense result stays bounded and the time linear on big grids.
    """
    z = np.asarray(z, dtype=float)
    check_request(z, n, d1, d2, method, iterations, tol)
    if n == 0 or z.shape[0] < 2:
        return z.copy()
    step = d1 / (n + 1)
    dense = np.empty(((len(z) - 1) * (n + 1) + 1, z.shape[1]))
    dense[::n + 1] = z
    inserted_rows = dense[:-1].reshape(len(z) - 1, n + 1, -1)[:, 1:]   # a view: (gaps, n, cols)
    if breaks is not None and not callable(breaks):
        across, along = breaks
        breaks = lambda low, high: (across[low:high], along[low:high + 1])  # noqa: E731
    for first, last, low, high in strips(len(z) - 1, n * z.shape[1], strip, method, tol):
        part = z[low:high + 1]
        gaps = Gaps(part, None if breaks is None else breaks(low, high))
        if method == "thesis":
            inserted = thesis_inserted(part, n, gaps, iterations, tol)
        elif method == "laplace":
            inserted = laplace_inserted(part, n, gaps, step, d2)
        else:
            inserted = biharmonic_inserted(part, n, gaps, step, d2)
        inserted_rows[first:last] = inserted[first - low:last - low]
    return dense


def strips(gaps, per_gap, strip, method, tol):
    """(first, last, low, high) per strip: gaps first..last-1 are taken from a solve of gaps
    low..high-1 (original rows low..high), about ``strip`` inserted nodes (``per_gap`` a gap)
    plus a halo.

    ``thesis`` and ``laplace`` solve every gap on its own, so strips without a halo are
    exact, except that ``thesis`` with a ``tol`` stops all gaps at once (when no node of
    the grid moves by ``tol``) and is solved in one strip. ``biharmonic`` couples the gaps
    through the original rows; the influence of the plate beyond a strip falls by a
    factor of about 4-6 per gap (n = 1..7), so a halo of BIHARMONIC_HALO gaps on each side
    brings the strips to the whole-grid solve within that solve's own tolerance (its
    conjugate gradients stop at a relative residual of 1e-12): measured on grids with
    holes and jumps, strips of 1-10 gaps differ from it by at most 1e-12 of the largest
    height for n = 1 and 3, 5e-12 for n = 7, 3e-11 for n = 20 (3e-8 with a halo of 8).
    """
    if method == "thesis" and tol is not None:
        yield 0, gaps, 0, gaps
        return
    halo = BIHARMONIC_HALO if method == "biharmonic" else 0
    size = max(1, strip // max(1, per_gap))
    for first in range(0, gaps, size):
        last = min(gaps, first + size)
        yield first, last, max(0, first - halo), min(gaps, last + halo)


def check_request(z, n, d1, d2, method, iterations, tol):
    """Refuse impossible requests before allocating the dense grid."""
    if z.ndim != 2:
        raise MzcError("heights must be a 2D grid")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 0 <= n <= MAX_INSERTED:
        raise MzcError(f"must be a whole number 0..{MAX_INSERTED}, not {n!r}", field="n")
    if method not in METHODS:
        raise MzcError(f"unknown method {method!r} (choose {', '.join(METHODS)})", field="method")
    for name, value in (("d1", d1), ("d2", d2)):
        problem = length_problem(float(value))
        if problem:
            raise MzcError(f"spacing {problem}", field=name)
    if not 0 <= iterations <= MAX_ITERATIONS:
        raise MzcError(f"must be 0..{MAX_ITERATIONS}, not {iterations}", field="iterations")
    if tol is not None and not tol > 0:
        raise MzcError(f"must be a positive number, not {tol}", field="tol")
    check_grid_size((z.shape[0] - 1) * (n + 1) + 1, z.shape[1], "use a smaller n", field="n")


# --------------------------------------------------------------------------- domains


class Gaps:
    """Where rows are inserted between each pair of neighbouring rows (a gap) of ``z``.

    ``domain`` (gaps, cols): the columns valid in both rows of the gap, except where the
    edge between them is a break; ``rows_along`` (rows, cols-1): the breaks between
    neighbouring columns of each row; ``along`` (gaps, cols-1): those of a gap's inserted
    rows (a break in either of its rows); ``interior``: the domain columns whose
    left and right neighbours are in the domain too, with no break between (not run ends).
    """

    def __init__(self, z, breaks=None):
        valid = ~np.isnan(z)
        across, along = breaks if breaks is not None else (np.zeros((len(z) - 1, z.shape[1]), dtype=bool),
                                                           np.zeros((len(z), z.shape[1] - 1), dtype=bool))
        self.domain = valid[:-1] & valid[1:] & ~across
        self.rows_along = along
        self.along = along[:-1] | along[1:]
        self.interior = np.zeros_like(self.domain)
        self.interior[:, 1:-1] = (self.domain[:, :-2] & self.domain[:, 1:-1] & self.domain[:, 2:]
                                  & ~self.along[:, :-1] & ~self.along[:, 1:])


def straight_lines(z, n):
    """(gaps, n, cols) heights on the straight lines between each pair of rows (the thesis's sides)."""
    t = (np.arange(1, n + 1) / (n + 1))[None, :, None]
    return (1 - t) * z[:-1, None, :] + t * z[1:, None, :]


def gap_stack(z, n, inside):
    """(gaps, n+2, cols) rectangles: top row, ``inside`` rows, bottom row; NaN outside the data."""
    return np.concatenate([z[:-1, None, :], inside, z[1:, None, :]], axis=1)


# --------------------------------------------------------------------------- thesis


def thesis_inserted(z, n, gaps, iterations, tol):
    """Inserted rows by the thesis's Jacobi iteration (eq. 3.40), all gaps stacked and swept at once."""
    domain = gaps.domain
    free = gaps.interior[:, None, :]
    start = np.where(free, 0.0, straight_lines(z, n))
    u = np.nan_to_num(gap_stack(z, n, start))
    for _ in range(iterations):
        neighbours = 0.25 * (u[:, :-2, 1:-1] + u[:, 2:, 1:-1] + u[:, 1:-1, :-2] + u[:, 1:-1, 2:])
        update = np.where(free[:, :, 1:-1], neighbours - u[:, 1:-1, 1:-1], 0.0)
        u[:, 1:-1, 1:-1] += update
        if tol is not None and np.abs(update).max(initial=0.0) < tol:
            break
    return np.where(domain[:, None, :], u[:, 1:-1], np.nan)


# --------------------------------------------------------------------------- laplace


def laplace_inserted(z, n, gaps, step, d2):
    """Inserted rows solving the 5-point Laplace equation with true steps, one band solve for all gaps.

    Dirichlet data: the two rows of each gap and the thesis's straight lines at the run ends.
    Unknowns are numbered gap by gap, column by column, row by row, so the negated Laplacian
    is a symmetric positive definite band of half-width n (the node beside one in the next
    column of its gap is n on): factored by ``band_factor``, the biharmonic's own Cholesky.
    """
    domain = gaps.domain
    free = np.broadcast_to(gaps.interior[:, None, :], (len(domain), n, z.shape[1]))
    known = np.nan_to_num(gap_stack(z, n, straight_lines(z, n)))
    order = np.full(known.shape, -1)
    gap, col, row = np.nonzero(np.pad(free, ((0, 0), (1, 1), (0, 0))).transpose(0, 2, 1))
    order[gap, row, col] = np.arange(len(gap))
    across, along = 1 / (step * step), 1 / (d2 * d2)
    band, rhs = np.zeros((len(gap), n + 1)), np.zeros(len(gap))
    band[:, 0] = 2 * across + 2 * along
    for (drow, dcol), weight, reach in (((-1, 0), across, 1), ((1, 0), across, -1), ((0, -1), along, n),
                                        ((0, 1), along, -n)):
        unknown = order[gap, row + drow, col + dcol] >= 0
        if reach > 0:   # the band holds each pair once, in the later unknown's row
            band[unknown, reach] = -weight
        rhs += np.where(unknown, 0.0, weight * known[gap, row + drow, col + dcol])
    inside = np.where(domain[:, None, :], known[:, 1:-1], np.nan)
    if len(gap):
        inside[gap, row - 1, col] = band_solve(band_factor(band), rhs)
    return inside


# --------------------------------------------------------------------------- biharmonic


def biharmonic_inserted(z, n, gaps, step, d2):
    """Inserted rows minimising the thin-plate energy over the whole dense grid.

    The energy's normal equations A u = b (``plate_equations``) couple the gaps only through
    the across-row second differences centred on the original rows; within a gap A is a
    band of half-width 2n (unknowns numbered column by column, row by row). The unknowns
    are numbered even gaps first, then odd ones, so each half is one band and the coupling
    only joins the halves (``solve_plate``).
    """
    domain = gaps.domain
    inside = np.where(domain[:, None, :], straight_lines(z, n), np.nan)
    if domain.any():
        first, evens = unknown_numbers(domain, n)
        band, rhs = plate_equations(z, n, gaps, step, d2, first)
        unknowns = inside.transpose(0, 2, 1)             # (gaps, cols, n) views: unknown first[g, c] + r
        start = np.empty(len(rhs))
        start.reshape(-1, n)[first[domain] // n] = unknowns[domain]
        solution = solve_plate(band, rhs, start, evens, coupled_pairs(domain, first, n, evens),
                                plate_weights(step, d2)[1])
        unknowns[domain] = solution.reshape(-1, n)[first[domain] // n]
    return inside


def unknown_numbers(domain, n):
    """(first, evens): the number of the first unknown (row 0) of each domain column of each
    gap (-1 elsewhere), its n rows numbered on from it, the even gaps' columns first, then the
    odd ones', each gap by gap and column by column; and how many unknowns the even gaps hold."""
    order = np.r_[np.arange(0, len(domain), 2), np.arange(1, len(domain), 2)]
    count = np.cumsum(domain[order]).reshape(domain.shape) - 1
    first = np.full(domain.shape, -1, dtype=np.int64)
    first[order] = np.where(domain[order], count * n, -1)
    return first, int(domain[::2].sum()) * n


def plate_equations(z, n, gaps, step, d2, first):
    """The normal equations A u = b of the discrete thin-plate energy (u_xx² + 2u_xy² + u_yy²,
    true steps) over the inserted nodes, the original rows held fixed: (band, rhs).

    Unknown first[g, c] + r is inserted row r (0..n-1) of gap g at column c. The energy has
    one term per stencil whose nodes all hold data (the free plate's natural boundary
    conditions) and that crosses no break along the rows: second differences along rows
    (/d2²) and across rows (/step²), and the twist over each 2x2 cell (/(step·d2), weight √2
    for the factor 2 of u_xy²); A sums weight·a_j·a_k over the stencils holding both nodes.
    ``band`` holds, per unknown j, A[j, j-k] for k = 0..2n (``_plate`` storage); b is ``rhs``.
    The across-row stencils centred on an original row join the last inserted node of the
    gap above to the first of the gap below, off the band: their share of the diagonal and of
    b is here, the pair is ``coupled_pairs``'s. Assembled by ``_plate.plate`` (C): numpy's
    products of stencil masks over the dense grid took 6x as long.
    """
    from mzc.ops import _plate

    size = int(first.max()) + n
    band, rhs = np.empty((size, 2 * n + 1)), np.empty(size)
    _plate.plate(np.ascontiguousarray(z, dtype=np.float64), first, np.ascontiguousarray(~gaps.rows_along),
                 np.ascontiguousarray(~gaps.along), len(first), z.shape[1], n, plate_weights(step, d2),
                 band, rhs)
    return band, rhs


def plate_weights(step, d2):
    """(1/d2^4, 1/step^4, 2/(step d2)^2): the weights of the plate's second differences along
    rows, across them and of its twist, as products (a C library's pow may round otherwise)."""
    along, across = 1 / (d2 * d2), 1 / (step * step)
    return along * along, across * across, 2 * along * across


def coupled_pairs(domain, first, n, evens):
    """The unknowns that the across-row stencils centred on an original row join (the last
    inserted node of gap g and the first of gap g+1, at each column in both domains): one in
    an even gap, one in an odd gap, the odd ones counted from the first odd one (the
    ``evens``-th unknown), as (even, odd)."""
    gap, col = np.nonzero(domain[:-1] & domain[1:])
    last, after = first[gap, col] + n - 1, first[gap + 1, col]
    even_above = gap % 2 == 0
    return np.where(even_above, last, after), np.where(even_above, after, last) - evens


def solve_plate(band, rhs, start, evens, pairs, weight, rtol=1e-12, max_steps=1000):
    """The solution of A u = b, A = [[E, C], [C^T, O]] with E and O the bands (``_plate``
    storage) of the first ``evens`` unknowns and of the rest, and C ``weight`` at each of
    ``pairs`` (``coupled_pairs``), from ``start``: until |residual| <= rtol |b|. ``band`` is
    spent (factored in place).

    The even gaps are eliminated: conjugate gradients solve the odd ones' Schur complement
    S = O - C^T E^-1 C, preconditioned by the exact Cholesky factor of O, then the even ones
    follow from one solve with E. Alternate gaps never touch, so E and O are bands. S's
    spectrum, so preconditioned, lies in [1 - rho², 1] when that of A preconditioned by E and
    O lies within rho of 1: half the steps (9 for n = 3 on a face) of conjugate gradients on
    the whole of A so preconditioned, at the same cost a step (a solve with E and one with
    O). O's product is taken once, at the start: the steps keep O p up to date as they go
    (O p = r + beta O p_before, since O z = r for the preconditioned residual z), so O's band
    is factored in place. Inner products are plain numpy sums, not BLAS: threaded BLAS on a
    busy machine costs more in synchronisation than these short vectors take to multiply.
    Solved on ``rhs`` and ``start`` scaled by a power of two (``unit_scaled``: the same numbers,
    and heights of 1e-162 as any others).
    """
    return unit_scaled(lambda b, first: plate_steps(band, b, first, evens, pairs, weight, rtol, max_steps), rhs, start)


def plate_steps(band, rhs, start, evens, pairs, weight, rtol, max_steps):
    """solve_plate's steps, on ``rhs`` and ``start`` as they are."""
    from mzc.ops import _plate

    even_factor, odd_band = band_factor(band[:evens]), band[evens:]
    coupled = lambda vector: weight * weight * carried(band_solve(even_factor, carried(vector, pairs, 1, 0, evens)),  # noqa: E731
                                                 pairs, 0, 1, len(vector))
    right = rhs[evens:] - weight * carried(band_solve(even_factor, rhs[:evens].copy()), pairs, 0, 1, len(rhs) - evens)
    odd = start[evens:].copy()
    image = np.empty_like(odd)
    _plate.product(odd_band, odd_band.shape[1] - 1, odd, image)
    odd_factor = band_factor(odd_band)
    residual = right - (image - coupled(odd))
    direction = band_solve(odd_factor, residual.copy())
    product, kept_image = inner(residual, direction), residual.copy()   # r.z, and O p (= r: p = z)
    goal = rtol * rtol * inner(rhs, rhs)
    for _ in range(max_steps):
        if inner(residual, residual) <= goal:
            break
        image = kept_image - coupled(direction)                        # S p
        length = product / inner(direction, image)
        odd += length * direction
        residual -= length * image
        smoothed = band_solve(odd_factor, residual.copy())
        product, previous = inner(residual, smoothed), product
        direction = smoothed + (product / previous) * direction
        kept_image = residual + (product / previous) * kept_image
    return np.concatenate([band_solve(even_factor, rhs[:evens] - weight * carried(odd, pairs, 1, 0, evens)), odd])


def carried(vector, pairs, source, target, size):
    """(size,): the sum at each pair's ``target`` end of ``vector`` at its ``source`` end (the
    coupling C or C^T of ``solve_plate`` without its weight)."""
    out = np.zeros(size)
    np.add.at(out, pairs[target], vector[pairs[source]])
    return out


def band_factor(band):
    """``band`` overwritten with the Cholesky factor of the symmetric positive definite band
    matrix it holds (``_plate`` storage: rows of A[j, j-k], k = 0..width)."""
    from mzc.ops import _plate

    failed = _plate.cholesky(band, band.shape[1] - 1)
    if failed >= 0:
        raise MzcError(f"the thin-plate equations are singular at unknown {failed} (try --method laplace)")
    return band


def band_solve(factor, vector):
    """``vector`` overwritten with A^-1 ``vector``, A the matrix whose Cholesky ``factor``
    (``band_factor``) is given."""
    from mzc.ops import _plate

    _plate.solve(factor, factor.shape[1] - 1, vector)
    return vector

