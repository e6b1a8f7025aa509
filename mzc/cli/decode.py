"""``mzc decode``: any compressed mzc file (or a thesis file with --legacy) back to a z-grid, or to
the raster (GeoTIFF, ESRI ASCII grid) it was read from."""

import click

from mzc.cli.options import (
    RASTER_OUTPUT_HELP,
    grid_output_options,
    grid_writer,
    input_argument,
    output_option,
    read_grid,
)

LEGACY_KINDS = ("poly", "dft", "dct", "dwt")


@click.command(help=f"""Decompress an mzc file into a z-grid.

The codec is recognised by the file's magic line (mzc-poly, mzc-dft, mzc-dct, mzc-dwt, ...);
a z-grid or a raster (GeoTIFF, ESRI ASCII grid) is read as the grid it is. Files written by
the thesis's MATLAB code have no magic line: name their kind with --legacy. Invalid nodes
(outside each row's span, and recorded holes) come back as nan. The heights are written
exactly by default (raw), the grid the codec's error bounds speak of; --plain writes text,
which --precision rounds.

{RASTER_OUTPUT_HELP}""")
@input_argument
@output_option
@click.option("--legacy", type=click.Choice(LEGACY_KINDS),
              help="Read a thesis file (Tables 6.1, 7.1, 7.2, §5.3.1) of this kind.")
@grid_output_options
def command(input, output, legacy, file_format, plain, float32, precision):
    from mzc.streams import check_not_input, display_name, read_input

    write = grid_writer(output, file_format, plain, float32, precision)
    check_not_input(output, input)
    if legacy:
        from mzc.codecs.rows.legacy import read_legacy

        grid = read_legacy(read_input(input), display_name(input), legacy)
    else:
        grid = read_grid(input)
    write(grid)
