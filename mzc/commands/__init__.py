"""Shared pieces of the subcommands: the input argument, the -o option, reading grids.

Each subcommand is a thin module: it parses options, calls plain numeric functions and
writes through ``mzc.streams`` so output is atomic.
"""

import click

from mzc.errors import MzcError
from mzc.streams import display_name, read_input

input_argument = click.argument("input", required=False, default="-", metavar="[INPUT]")
output_option = click.option("-o", "--output", default="-", metavar="FILE",
                             help="Write here instead of stdout (atomically).")


def read_grid(path):
    """Read a z-grid, or any compressed mzc file (decoded), from ``path`` or stdin."""
    from mzc.formats import is_mzc, read_any

    data = read_input(path)
    source = display_name(path)
    if not data:
        raise MzcError("empty input: expected an mzc z-grid", source=source)
    if not is_mzc(data):
        raise MzcError("not an mzc file (expected a z-grid, e.g. from 'mzc slice')", source=source, line=1)
    return read_any(data, source)


def write_grid(grid, path, precision=None):
    """Write ``grid`` as a z-grid to ``path`` or stdout."""
    from mzc.formats import zgrid
    from mzc.streams import write_output

    write_output(path, zgrid.write(grid, precision=precision))
