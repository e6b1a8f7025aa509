"""``mzc slice``: cut a mesh or point cloud into a z-grid with the thesis's cutting planes."""

import click

from mzc.cli.options import (
    RASTER_OUTPUT_HELP,
    grid_output_options,
    grid_writer,
    input_argument,
    output_option,
    with_options,
)


def one_word(value):
    """``--units`` as the one header token it must be (mzc.grid.check_token), or a usage error."""
    from mzc.errors import MzcError
    from mzc.grid import check_token

    try:
        check_token(value, "units")
    except MzcError as error:
        raise click.BadParameter(error.message) from None
    return value


def chart_count(value):
    """``--charts`` as auto or a positive count, or a usage error."""
    if value == "auto":
        return value
    if not (value.isascii() and value.isdigit() and 1 <= int(value) <= 65536):
        raise click.BadParameter(f"{value!r} is not auto or a number of charts 1..65536")
    return int(value)


def class_codes(value):
    """``--classes`` as a tuple of ASPRS class codes (0..255), or a usage error."""
    if value is None:
        return None
    words = [word.strip() for word in value.split(",")]
    if not all(word.isascii() and word.isdigit() and int(word) <= 255 for word in words):
        raise click.BadParameter(f"{value!r} is not a comma-separated list of class codes 0..255 (e.g. 2 or 2,9)")
    return tuple(sorted({int(word) for word in words}))


SLICE_OPTIONS = [   # the grid's options, shared with 'mzc batch encode'
    click.option("--d1", type=float, metavar="F",
                 help="Row spacing: distance between horizontal planes [default: from the data]."),
    click.option("--d2", type=float, metavar="F",
                 help="Column spacing along each row [default: from the data, else d1]."),
    click.option("--rows", type=int, metavar="N", help="Number of rows across y instead of --d1."),
    click.option("--cols", type=int, metavar="N", help="Number of columns across x instead of --d2."),
    click.option("--thesis-grid", is_flag=True,
                 help="The thesis's grid: 72 rows across the surface, columns ten times denser."),
    click.option("--align", type=click.Choice(["none", "pca"]), default="none", show_default=True,
                 help="pca: rotate so the least spread is z and the most spread is y."),
    click.option("--projection", type=click.Choice(["auto", "planar", "cylindrical", "spherical"]), default="auto",
                 show_default=True,
                 help="Cutting surfaces: the thesis's parallel planes, or planes and half-planes through an axis "
                      "(cylindrical), or half-planes and cones about a centre (spherical); auto picks what sees "
                      "the surface best."),
    click.option("--view", type=click.Choice(["auto", "+z", "-z", "+x", "-x", "+y", "-y"]), default="auto",
                 show_default=True,
                 help="The direction a planar grid looks along (the side it sees the surface from), in the "
                      "--align frame; auto: the axis that sees most of the surface, from the side it faces."),
    click.option("--center", type=float, nargs=3, metavar="X Y Z",
                 help="Centre of a central projection (a point of a cylinder's axis) [default: chosen]."),
    click.option("--axis", type=float, nargs=3, metavar="X Y Z",
                 help="Axis direction of a central projection [default: chosen]."),
    click.option("--units", metavar="TEXT", callback=lambda ctx, param, value: one_word(value),
                 help="Length unit to record, e.g. mm (one word)."),
    click.option("--classes", metavar="LIST", callback=lambda ctx, param, value: class_codes(value),
                 help="Keep only the points of these classes of a LAS/LAZ cloud: ASPRS codes, comma-separated "
                      "(2: ground; 2,9: ground and water)."),
    click.option("--charts", metavar="auto|N", default="auto", show_default=True,
                 callback=lambda ctx, param, value: chart_count(value),
                 help="1: one grid; N: at most N charts, planar grids along the frame's six axes, each seeing its "
                      "own piece of the surface within 60 degrees (a closed or many-part object); auto: charts "
                      "when one grid would hold less than 90% of the surface's area (spec/zgrid.md, Charts)."),
    click.option("--tap", is_flag=True,
                 help="Target-aligned cells, as gdalwarp -tap: one planar grid looking down z whose cells (a node "
                      "at each one's centre) have their edges on whole multiples of the spacing; the default "
                      "spacing is then round (1, 2, 2.5 or 5 times a power of ten)."),
    click.option("--cloud", type=click.Choice(["auto", "bin", "delaunay"]), default="auto", show_default=True,
                 help="How a point cloud becomes a surface: bin (a local plane fit at each node, for dense clouds) "
                      "or delaunay (triangles between its points); auto bins clouds of over 100,000 points that "
                      "are dense at the grid's spacing."),
    click.option("--colour-scale", type=click.IntRange(1, 8), default=1, show_default=True, metavar="K",
                 help="Sample a coloured surface's colour K times finer than the nodes (1..8), for texture detail "
                      "(triangulate --texture)."),
]


def slice_options(command):
    """``command`` with the slicing options (SLICE_OPTIONS) added."""
    return with_options(SLICE_OPTIONS, command)


SLICE_NAMES = tuple(param.name for param in slice_options(click.Command("slicing")).params)


def check_slice_options(d1, d2, rows, cols):
    """Refuse a spacing and a count given for the same direction."""
    if d1 is not None and rows is not None:
        raise click.UsageError("--d1 and --rows both set the rows: give one")
    if d2 is not None and cols is not None:
        raise click.UsageError("--d2 and --cols both set the columns: give one")


@click.command("slice", help=f"""Cut a mesh (OBJ, PLY, VTK, STL, OFF) or point cloud (LAS/LAZ, PCD, x y z text,
vertex-only PLY) into a z-grid: each node holds the outermost hit of its line with the
surface (the front-most height of planar grids, the farthest distance along a central ray).

A raster (GeoTIFF, ESRI ASCII grid) is its own z-grid: read node for node with its
no-data cells, georeferencing and CRS; so is a z-grid or compressed mzc file. The options
that would cut it otherwise are refused.

{RASTER_OUTPUT_HELP}""")
@input_argument
@output_option
@slice_options
@click.option("--prior", metavar="FILE",
              help="Cut on the lattice of this prior (mzc train), for encode --prior; the options that shape the "
                   "grid are refused beside it.")
@grid_output_options
def command(input, output, d1, d2, rows, cols, thesis_grid, align, projection, view, center, axis, units,
            classes, charts, tap, cloud, colour_scale, prior, file_format, plain, float32, precision):
    from mzc.api import slice as slice_surface
    from mzc.errors import about
    from mzc.streams import check_not_input, display_name

    check_slice_options(d1, d2, rows, cols)
    write = grid_writer(output, file_format, plain, float32, precision)
    check_not_input(output, input)
    with about(display_name(input), "slicing it"):
        grid = slice_surface(input, d1=d1, d2=d2, rows=rows, cols=cols, align=align, units=units,
                             projection=projection, center=center, axis=axis, view=view,
                             thesis_grid=thesis_grid, classes=classes, charts=charts, cloud=cloud, tap=tap,
                             colour_scale=colour_scale, prior=prior)
    write(grid)
