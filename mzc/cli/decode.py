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
from mzc.errors import about

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
@click.option("--window", type=click.IntRange(0), nargs=4, metavar="ROW COL ROWS COLS",
              help="Decode only rows ROW..ROW+ROWS-1 and columns COL..COL+COLS-1 of the grid (row 0 is its "
                   "first, a north-up raster's last); of a tiled file only the tiles they touch are read.")
@click.option("--levels", type=click.IntRange(0), metavar="K",
              help="Of a progressive file (mzc-dwt2d 9.0, encode --progressive): decode band 0 and the K coarsest "
                   "detail levels alone, a coarser surface (K from the file's level count on: all of it).")
@click.option("--prior", metavar="FILE",
              help="The prior (mzc train) a residual file (mzc-residual, encode --prior) was coded against.")
@grid_output_options
def command(input, output, legacy, window, levels, prior, file_format, plain, float32, precision):
    from mzc.streams import check_not_input, display_name, read_input

    write = grid_writer(output, file_format, plain, float32, precision)
    check_not_input(output, input)
    if legacy and levels is not None:
        raise click.UsageError("--levels decodes a progressive mzc-dwt2d 9.0 file, not a --legacy one")
    if prior is not None and (legacy or levels is not None):
        raise click.UsageError("--prior decodes a residual file (mzc-residual), not a --legacy or --levels one")
    if not legacy and levels is None and decoded_by_tiles(input, output, window or None, file_format, write,
                                                          float32):
        return
    if levels is not None:
        grid = read_levels(input, levels)
    elif prior is not None:
        grid = read_with_prior(input, prior)
    elif legacy:
        from mzc.codecs.rows.legacy import read_legacy

        grid = read_legacy(read_input(input), display_name(input), legacy)
    else:
        grid = read_grid(input)
    if window:
        from mzc.codecs.dwt2d.tiles import window_of

        with about(display_name(input), "cutting its window"):
            grid = window_of(grid, window)
    write(grid)


def read_with_prior(path, prior):
    """The grid of the file at ``path`` (or stdin), a residual file decoded with the prior at ``prior``
    (mzc.prior.decode); any other file as it decodes alone."""
    from mzc.prior import as_prior, read
    from mzc.streams import display_name, read_input

    data, source = read_input(path), display_name(path)
    with about(source, "decoding it"):
        return read(data, source, as_prior(prior), path)


def read_levels(path, levels):
    """The grid of a progressive file at ``path`` (or stdin) decoded to its ``levels`` coarsest detail levels."""
    from mzc.codecs.dwt2d import read
    from mzc.streams import display_name, read_input

    with about(display_name(path), "decoding it"):
        return read(read_input(path), display_name(path), wanted=levels)


def decoded_by_tiles(path, output, window, file_format, write, float32):
    """Decode a tiled file (mzc-dwt2d 5.0, not on stdin) by its tiles: the ``window``'s alone, or,
    to a GeoTIFF, every tile straight into its window of the raster; False, with nothing done, for
    any other file."""
    from mzc.codecs.dwt2d.tiles import open_tiled

    tiled = open_tiled(path)
    if tiled is None:
        return False
    from mzc.formats import GRIDS, writer_for

    try:
        row = writer_for(output, file_format, GRIDS)
        if window is None and row is not None and row.name == "tif":
            from mzc.rasters.windows import write_tiles

            with about(tiled.source, "decoding it tile by tile"):
                write_tiles(output, tiled, float32)
            return True
        with about(tiled.source, "decoding it"):
            grid = tiled.window(*window) if window else tiled.window()
    finally:
        tiled.close()
    write(grid)
    return True
