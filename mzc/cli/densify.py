"""``mzc densify``: insert rows between the planes of a z-grid (the thesis's PDE step, §6.2.3)."""

import click

from mzc.cli.options import (
    RASTER_OUTPUT_HELP,
    grid_output_options,
    grid_writer,
    input_argument,
    jump_angle_option,
    output_option,
    read_grid,
)
from mzc.limits import MAX_INSERTED, MAX_ITERATIONS

METHODS = ("thesis", "laplace", "biharmonic")
DEFAULT_METHOD = "biharmonic"   # lowest error on the shared faces (see mzc.ops.densify)


@click.command(help=f"""Insert N rows between each pair of rows of a z-grid.

The row step becomes d1/(N+1) and there are (rows-1)(N+1)+1 rows; the original rows are
kept exactly. Rows are only inserted in columns valid in both neighbouring rows and not
across a depth jump (--jump-angle), and never smoothed across one.

\b
  biharmonic  thin-plate surface over the whole grid, smooth across planes (default)
  laplace     Laplace's equation between each pair of rows, true steps, solved exactly
  thesis      the thesis's Jacobi iteration (equal steps, --iterations sweeps)

{RASTER_OUTPUT_HELP}""")
@input_argument
@output_option
@click.option("-n", "count", required=True, type=click.IntRange(0, MAX_INSERTED), metavar="N",
              help="Rows to insert between each pair of rows (0 copies the grid).")
@click.option("--method", type=click.Choice(METHODS), default=DEFAULT_METHOD, show_default=True,
              help="How to fill the inserted rows.")
@click.option("--iterations", type=click.IntRange(0, MAX_ITERATIONS), default=100, show_default=True, metavar="K",
              help="Jacobi sweeps of --method thesis.")
@click.option("--tol", type=click.FloatRange(min=0, min_open=True), metavar="T",
              help="Stop the thesis sweeps once no node moves by T or more.")
@grid_output_options
@jump_angle_option
def command(input, output, count, method, iterations, tol, file_format, plain, float32, precision, jump_angle):
    from mzc.api import densify
    from mzc.errors import about
    from mzc.streams import check_not_input, display_name

    write = grid_writer(output, file_format, plain, float32, precision)
    check_not_input(output, input)
    grid = read_grid(input)
    with about(display_name(input), f"densifying it ({method}, n = {count})"):
        dense = densify(grid, count, method, iterations=iterations, tol=tol, jump_angle=jump_angle)
    write(dense)
