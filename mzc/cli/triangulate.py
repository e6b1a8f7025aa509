"""``mzc triangulate``: a z-grid (or any mzc file) to a triangle mesh in the input's frame."""

import click

from mzc.cli.options import input_argument, jump_angle_option, output_option, read_grid
from mzc.limits import MAX_NODES

FORMATS = ("obj", "ply", "vtk", "stl", "off")


@click.command(help="""Turn a z-grid into a triangle mesh.

Each grid cell gives the thesis's triangles 1-2-3 and 2-3-4 wherever their corners are
valid and none of their edges is a depth jump (an edge within --jump-angle degrees of the
node lines: the step between a person and the wall behind, spec/zgrid.md); vertices are
placed back in the input surface's frame. The output format follows the -o extension or
--format; OBJ text goes to stdout when there is no -o.""")
@input_argument
@output_option
@click.option("--format", "file_format", type=click.Choice(FORMATS),
              help="Mesh format (default: from the -o extension; obj on stdout).")
@jump_angle_option
@click.option("--vertices", type=click.IntRange(4, MAX_NODES), metavar="N",
              help="About N vertices (within 20%), fewer where the surface is flat (quadric edge collapse) "
                   "[default: one at every valid node].")
def command(input, output, file_format, jump_angle, vertices):
    from mzc.errors import about
    from mzc.meshes import write_mesh
    from mzc.ops.triangulation import grid_to_mesh, mesh_of
    from mzc.streams import check_not_input, display_name

    check_not_input(output, input)
    grid = read_grid(input)
    with about(display_name(input), "triangulating it"):
        if vertices is None:
            write_mesh(output, mesh_of(grid, jump_angle), file_format)   # a grid's mesh is made as it is written
            return
        from mzc.ops.simplify import simplified

        write_mesh(output, simplified(grid_to_mesh(grid, jump_angle), vertices), file_format)
