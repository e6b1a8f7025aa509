"""Shared pieces of the subcommands: the input argument, the -o option, reading grids.

Each subcommand is a thin module: it parses options, calls plain numeric functions and
writes through ``mzc.streams`` so output is atomic.
"""

import click

from mzc.errors import MzcError, about
from mzc.streams import display_name

input_argument = click.argument("input", required=False, default="-", metavar="[INPUT]")
output_option = click.option("-o", "--output", default="-", metavar="FILE",
                             help="Write here instead of stdout (atomically).")
jump_angle_option = click.option(
    "--jump-angle", type=click.FloatRange(0, 90), metavar="DEG",
    help="An edge within DEG degrees of the node lines is a depth jump, joined by no triangle "
         "(spec/zgrid.md; 0 joins every neighbour) [default: 3].")


def read_grid(path, surfaces=False):
    """Read a grid from ``path`` or stdin: a z-grid, a compressed mzc file (decoded) or a raster;
    with ``surfaces`` a mesh or point cloud too (a Mesh)."""
    from mzc.formats import GRIDS, KINDS, read_file

    with about(display_name(path), "reading it" if surfaces else "decoding it"):
        return read_file(path, KINDS if surfaces else GRIDS)


plain_option = click.option("--plain", is_flag=True,
                            help="Write the z-grid as text, one line of heights per row (mzc-zgrid 1.0/2.0) "
                                 "[default: raw, exact binary heights, mzc-zgrid 3.0].")
float32_option = click.option("--float32", is_flag=True,
                              help="Raw heights as float32: half the bytes, each rounded to the nearest float32.")
precision_option = click.option("--precision", type=click.IntRange(0, 17), metavar="DIGITS",
                                help="With --plain: round the written heights to DIGITS decimals [default: exact].")


def with_options(options, command):
    """``command`` with click ``options`` (decorators) applied in the order listed."""
    for option in reversed(options):
        command = option(command)
    return command


RASTER_FORMATS = ("tif", "asc")   # mzc.formats' rasters, spelled here so that --help imports no numpy
format_option = click.option("--format", "file_format", type=click.Choice(("zg", *RASTER_FORMATS)),
                             help="Output format: zg (z-grid), tif (GeoTIFF) or asc (ESRI ASCII grid) "
                                  "[default: from the -o extension, else zg].")
RASTER_OUTPUT_HELP = """--format tif or asc (or an -o name ending in .tif, .tiff or .asc) writes a planar grid
as a GeoTIFF or an ESRI ASCII grid instead (an ESRI grid's CRS in a .prj beside it), with
the georeferencing and no-data value of the raster it was read from, if any; the GeoTIFF's
samples keep the raster's type when it holds every value exactly (an integer raster coded
with --max-error decodes to integers), else float64 (--float32 for float32)."""


def keep_geotiff_option(context, parameter, value):
    """Keep --co or --cog in the context for grid_writer, which alone reads them: the commands
    that write a grid pass their options on without naming these."""
    context.meta[f"mzc.{parameter.name}"] = value


co_option = click.option("--co", multiple=True, metavar="KEY=VALUE", expose_value=False, callback=keep_geotiff_option,
                         help="A GeoTIFF creation option, as gdal_translate -co (COMPRESS=ZSTD, TILED=YES, "
                              "BLOCKXSIZE=256, ...); repeatable. GDAL refuses a key or value it does not take.")
cog_option = click.option("--cog", is_flag=True, expose_value=False, callback=keep_geotiff_option,
                          help="Write a Cloud Optimized GeoTIFF (GDAL's COG driver: tiles, overviews, the IFDs "
                               "first), DEFLATE with a predictor unless --co says otherwise.")


def given_geotiff_options():
    """(--co's KEY=VALUE strings, --cog) of the running command (co_option, cog_option)."""
    meta = click.get_current_context().meta
    return meta.get("mzc.co", ()), meta.get("mzc.cog", False)


def grid_output_options(command):
    """``command`` with --format, --plain, --float32 and --precision: how it writes its grid, and
    --co and --cog for a GeoTIFF (kept for grid_writer)."""
    return format_option(plain_option(float32_option(precision_option(co_option(cog_option(command))))))


def grid_writer(output, file_format, plain, float32, precision):
    """The function that writes a command's grid to ``output`` as its options say, the options
    checked now, before any work: a raster (--format tif|asc, or an -o name that ends so) or a
    z-grid with the body the body options give (``zgrid_body``)."""
    from functools import partial

    from mzc.formats import GRIDS, writer_for

    co, cog = given_geotiff_options()
    row = writer_for(output, file_format, GRIDS)
    if co or cog:
        from mzc.rasters import geotiff_options as checked

        co, cog = checked(co, cog, row.name if row is not None else "zgrid")
    if row is None or row.kind != "raster":
        return partial(write_grid, path=output, body=zgrid_body(plain, float32, precision))
    if plain or precision is not None:
        raise click.UsageError(f"--plain and --precision shape a z-grid's body; --format {row.name} writes a raster")
    return partial(write_raster_output, output=output, raster=row.name, float32=float32, options=co, cog=cog)


def write_raster_output(grid, output, raster, float32, options=(), cog=False):
    """Write ``grid`` as a ``raster`` (a GeoTIFF with GDAL's creation ``options`` and, with ``cog``,
    Cloud Optimized), a refusal naming the output; a GeoTIFF is binary, so not on a terminal."""
    from mzc.rasters import write_raster
    from mzc.streams import is_terminal, output_name

    if raster == "tif" and is_terminal(output):
        raise MzcError("a GeoTIFF is not written to a terminal: redirect it or give -o FILE", field="format")
    with about(output_name(output), f"writing it as {raster}"):
        write_raster(output, grid, raster, float32=float32, options=options, cog=cog)


def zgrid_body(plain, float32, precision=None):
    """The keyword arguments of ``mzc.formats.zgrid.write`` for the body options, checked before
    any work is done: --precision rounds text, so it needs --plain, and --float32 is raw."""
    if plain and float32:
        raise click.UsageError("--float32 is a raw body and --plain a text one: give one")
    if precision is not None and not plain:
        raise click.UsageError("--precision rounds the text of --plain; the default raw body is exact: add --plain")
    return {"precision": precision} if plain else {"raw": "float32" if float32 else "float64"}


def write_grid(grid, path, body):
    """Write ``grid`` as a z-grid to ``path`` or stdout, its body as ``body`` (zgrid_body) says;
    to a terminal the default raw body is written as text (--plain), for people to read."""
    from mzc.formats import zgrid
    from mzc.streams import is_terminal, write_output

    if is_terminal(path) and body == {"raw": "float64"}:
        body = {"precision": None}
    write_output(path, zgrid.write(grid, **body))
