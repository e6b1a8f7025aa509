"""The largest grid this mzc reads, writes or builds: one home for the limit and its message.

Declared sizes are checked against it before anything is allocated, so a file or a request
that asks for an absurd grid is refused at once, wherever it comes from (a header, a thesis
file, the slicer's spacings, densify's n).
"""

from mzc.errors import MzcError

MAX_DIMENSION = 1_000_000     # rows or columns
MAX_NODES = 100_000_000       # rows x columns


def check_grid_size(rows: int, cols: int, advice: str = "", **where) -> None:
    """Refuse a grid of ``rows`` x ``cols`` nodes outside the limits; ``where`` locates the error
    (source, line, field) and ``advice`` says what to do instead."""
    if 1 <= rows <= MAX_DIMENSION and 1 <= cols <= MAX_DIMENSION and rows * cols <= MAX_NODES:
        return
    raise MzcError(f"{rows} x {cols} nodes is too large: this mzc accepts 1..{MAX_DIMENSION} per side and "
                   f"at most {MAX_NODES} nodes{'; ' + advice if advice else ''}", **where)
