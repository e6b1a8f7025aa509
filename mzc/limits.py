"""The largest grid and the largest numbers this mzc reads, writes or builds: one home for
each limit and its message.

Declared sizes are checked against them before anything is allocated, so a file or a request
that asks for an absurd grid is refused at once, wherever it comes from (a header, a thesis
file, the slicer's spacings, densify's n). Heights and coordinates are bounded too: the
transforms, fits and PCA square and sum them, and past MAX_MAGNITUDE binary64 overflows, so
a finite 1e308 would be written as inf or NaN that no reader takes back.
"""

import math
import operator

from mzc.errors import MzcError

MAX_DIMENSION = 1_000_000     # rows or columns
MAX_NODES = 100_000_000       # rows x columns
MAX_MAGNITUDE = 1e100         # |height| or |coordinate|: squares and sums of 10^8 of them stay finite
MAX_LENGTH = 1e50             # spacings and radii within 1/MAX_LENGTH..MAX_LENGTH: densify's stencils take d^-4
MAX_INSERTED = 20             # densify's n: rows 21 times denser (a biharmonic -n 50 took 78 s on a thesis grid)
MAX_ITERATIONS = 100_000      # sweeps of the thesis's Jacobi densify (100 by default)
MAX_SAMPLES = 2_000_000       # diff --surface samples per surface (10^7 ran out of 8 GB)
LOSSY_GROWTH = 1e6            # a lossy codec's decoded heights stay within this factor of its input's
MAX_FIELD_VALUES = 1_000_000  # values of one PCD field a point (COUNT; descriptors hold a few hundred)
MAX_COLOUR_SCALE = 8          # colour samples a node spacing (slice --colour-scale): 64 a cell


def check_grid_size(rows: int, cols: int, advice: str = "", **where) -> None:
    """Refuse a grid of ``rows`` x ``cols`` nodes outside the limits; ``where`` locates the error
    (source, line, field) and ``advice`` says what to do instead."""
    if 1 <= rows <= MAX_DIMENSION and 1 <= cols <= MAX_DIMENSION and rows * cols <= MAX_NODES:
        return
    if min(rows, cols) < 1:
        raise MzcError(f"{rows} x {cols} nodes is empty: a grid has at least 1 row and 1 column", **where)
    raise MzcError(f"{rows} x {cols} nodes is too large: this mzc accepts 1..{MAX_DIMENSION} per side and "
                   f"at most {MAX_NODES} nodes{'; ' + advice if advice else ''}", **where)


def check_colour_scale(scale, rows: int, cols: int, **where) -> int:
    """``scale`` as an int in 1..MAX_COLOUR_SCALE whose colour image of a ``rows`` x ``cols`` grid,
    ((rows - 1) scale + 1) x ((cols - 1) scale + 1) samples, is within the grid limits; refused
    otherwise."""
    try:
        scale = None if isinstance(scale, bool) else operator.index(scale)   # an int or numpy integer
    except TypeError:
        scale = None
    if scale is None:
        raise MzcError(f"must be a whole number 1..{MAX_COLOUR_SCALE}", **where)
    if not 1 <= scale <= MAX_COLOUR_SCALE:
        raise MzcError(f"{scale} is not a whole number 1..{MAX_COLOUR_SCALE}", **where)
    check_grid_size((rows - 1) * scale + 1, (cols - 1) * scale + 1, "a smaller colour scale", **where)
    return scale


def check_magnitude(values, what: str, **where) -> float:
    """Refuse ``values`` (a numpy array; NaN ignored) holding a magnitude above MAX_MAGNITUDE;
    return the largest magnitude. Two reductions, no temporary array: a grid read from a
    file is checked whole, and a copy of its absolute values would double its memory."""
    import numpy as np

    values = np.asarray(values, dtype=float)
    largest = max(float(np.fmax.reduce(values, axis=None, initial=-math.inf)),
                  -float(np.fmin.reduce(values, axis=None, initial=math.inf)), 0.0)
    if largest > MAX_MAGNITUDE:
        raise MzcError(f"{what} reach {largest:.3g}: mzc computes with {what} up to {MAX_MAGNITUDE:.0e} in "
                       f"magnitude (beyond that its transforms overflow); rescale or change the unit", **where)
    return largest


def check_grid_magnitudes(grid, **where) -> float:
    """Refuse a ZGrid whose heights or coordinates (its origin, the translation of its transform)
    are beyond MAX_MAGNITUDE; return its largest height's magnitude. Every grid mzc reads or
    writes is checked here, so none that overflows its computations (a diff's ``rmse inf``)
    is taken in or given out."""
    import numpy as np

    check_magnitude(np.array(grid.origin), "coordinates", **{"field": "origin", **where})
    check_magnitude(grid.transform[:, 3], "coordinates", **{"field": "transform", **where})
    return check_magnitude(grid.z, "heights", **{"field": "data", **where})


def length_problem(value: float) -> str | None:
    """Why a spacing or radius ``value`` is out of range (None when it is a length mzc computes
    with: 1/MAX_LENGTH .. MAX_LENGTH, so that fourth powers of it and their quotients stay finite)."""
    if not (math.isfinite(value) and value > 0):
        return f"must be a positive number, not {value}"
    if not 1 / MAX_LENGTH <= value <= MAX_LENGTH:
        return f"must be a length from {1 / MAX_LENGTH:.0e} to {MAX_LENGTH:.0e}, not {value:g}"
    return None
