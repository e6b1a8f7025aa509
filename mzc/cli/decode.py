"""``mzc decode``: any compressed mzc file (or a thesis file with --legacy) back to a z-grid, or to
the raster (GeoTIFF, ESRI ASCII grid) it was read from."""

import click

from mzc.cli.options import input_argument, output_option, read_grid, write_grid, zgrid_body, zgrid_output_options

LEGACY_KINDS = ("poly", "dft", "dct", "dwt")
RASTER_FORMATS = ("tif", "asc")   # mzc.rasters.FORMATS, spelled here so that --help imports no numpy
FORMATS = ("zg", *RASTER_FORMATS)


@click.command(help="""Decompress an mzc file into a z-grid.

The codec is recognised by the file's magic line (mzc-poly, mzc-dft, mzc-dct, mzc-dwt, ...).
Files written by the thesis's MATLAB code have no magic line: name their kind with
--legacy. Invalid nodes (outside each row's span, and recorded holes) come back as nan.
The heights are written exactly by default (raw), the grid the codec's error bounds speak
of; --plain writes text, which --precision rounds.

--format tif or asc (or an -o name ending in .tif, .tiff or .asc) writes the grid as a
GeoTIFF or an ESRI ASCII grid instead, with the georeferencing, CRS and no-data value of
the raster it was sliced from; the GeoTIFF's samples keep the raster's type when it holds
every decoded value exactly, else float64 (--float32 for float32).""")
@input_argument
@output_option
@click.option("--legacy", type=click.Choice(LEGACY_KINDS),
              help="Read a thesis file (Tables 6.1, 7.1, 7.2, §5.3.1) of this kind.")
@click.option("--format", "file_format", type=click.Choice(FORMATS),
              help="Output format: zg (z-grid), tif (GeoTIFF) or asc (ESRI ASCII grid) [default: from the -o "
                   "extension, else zg].")
@zgrid_output_options
def command(input, output, legacy, file_format, plain, float32, precision):
    from mzc.rasters import format_for
    from mzc.streams import check_not_input, display_name, read_input

    raster = format_for(output) if file_format is None else None if file_format == "zg" else file_format
    if raster:
        check_raster_options(raster, plain, precision)
    else:
        body = zgrid_body(plain, float32, precision)
    check_not_input(output, input)
    if legacy:
        from mzc.codecs.rows.legacy import read_legacy

        grid = read_legacy(read_input(input), display_name(input), legacy)
    else:
        grid = read_grid(input)
    if raster:
        write_raster_output(grid, output, raster, float32)
    else:
        write_grid(grid, output, body)


def check_raster_options(raster, plain, precision):
    """Refuse the z-grid's body options with a raster output, before any work."""
    if plain or precision is not None:
        raise click.UsageError(f"--plain and --precision shape a z-grid's body; --format {raster} writes a raster")


def write_raster_output(grid, output, raster, float32):
    """Write ``grid`` as a ``raster``; a GeoTIFF is binary, so not on a terminal."""
    from mzc.errors import MzcError
    from mzc.rasters import write_raster
    from mzc.streams import is_terminal

    if raster == "tif" and is_terminal(output):
        raise MzcError("a GeoTIFF is not written to a terminal: redirect it or give -o FILE", field="format")
    write_raster(output, grid, raster, float32=float32)
