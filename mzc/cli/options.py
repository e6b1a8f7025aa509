"""Shared pieces of the subcommands: the input argument, the -o option, reading grids.

Each subcommand is a thin module: it parses options, calls plain numeric functions and
writes through ``mzc.streams`` so output is atomic.
"""

import click

from mzc.errors import MzcError, about
from mzc.streams import display_name, read_input

input_argument = click.argument("input", required=False, default="-", metavar="[INPUT]")
output_option = click.option("-o", "--output", default="-", metavar="FILE",
                             help="Write here instead of stdout (atomically).")
jump_angle_option = click.option(
    "--jump-angle", type=click.FloatRange(0, 90), metavar="DEG",
    help="An edge within DEG degrees of the node lines is a depth jump, joined by no triangle "
         "(spec/zgrid.md; 0 joins every neighbour) [default: 3].")


def read_grid(path):
    """Read a z-grid, or any compressed mzc file (decoded), from ``path`` or stdin."""
    from mzc.formats import is_mzc, read_any

    data = read_input(path)
    source = display_name(path)
    if not data:
        raise MzcError("empty input: expected an mzc z-grid", source=source)
    if not is_mzc(data):
        raise MzcError("not an mzc file (expected a z-grid, e.g. from 'mzc slice')", source=source, line=1)
    with about(source, "decoding it"):
        return read_any(data, source)


def write_grid(grid, path, precision=None):
    """Write ``grid`` as a z-grid to ``path`` or stdout."""
    from mzc.formats import zgrid
    from mzc.streams import write_output

    write_output(path, zgrid.write(grid, precision=precision))
