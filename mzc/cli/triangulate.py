"""``mzc triangulate``: a z-grid (or any mzc file) to a triangle mesh in the input's frame."""

import click

from mzc.cli.options import input_argument, jump_angle_option, output_option, read_grid
from mzc.limits import MAX_NODES

FORMATS = ("obj", "ply", "vtk", "stl", "off")


class VertexCount(click.ParamType):
    """``--vertices``: a count (4 up to MAX_NODES) or ``all``."""

    name = "vertices"

    def convert(self, value, param, ctx):
        if isinstance(value, int) or str(value).strip().lower() != "all":
            return click.IntRange(4, MAX_NODES).convert(value, param, ctx)
        return "all"


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
@click.option("--vertices", type=VertexCount(), metavar="N|all",
              help="About N vertices (within 20%), fewer where the surface is flat (quadric edge collapse); "
                   "all: one at every valid node [default: about the vertex count of the mesh the grid was "
                   "sliced from, which its files record; all when they record none].")
@click.option("--texture", metavar="FILE.png",
              help="Write the grid's colours as this PNG, the OBJ's vertices with texture coordinates into it "
                   "and its material file (-o NAME.obj and NAME.mtl) [default: vertex colours].")
def command(input, output, file_format, jump_angle, vertices, texture):
    from mzc.errors import about
    from mzc.meshes import write_mesh
    from mzc.ops.simplify import rebuilt
    from mzc.streams import check_not_input, display_name

    check_not_input(output, input)
    if texture is not None:
        check_texture_request(input, output, file_format, vertices, texture)
    grid = read_grid(input)
    with about(display_name(input), "triangulating it"):
        if texture is not None:
            write_textured(grid, jump_angle, output, texture)
            return
        write_mesh(output, rebuilt(grid, jump_angle, vertices, streamed=True), file_format)


def check_texture_request(input, output, file_format, vertices, texture):
    """Refuse --texture, before any work, without an OBJ file to write beside it or with
    --vertices N (a simplified mesh has no grid nodes to place in the image: the textured mesh
    keeps every node); refuse outputs that
    are inputs or one file."""
    import os

    from mzc.streams import check_distinct, check_not_input, is_stdio

    if output is None or is_stdio(output) or (file_format or os.path.splitext(output)[1].lstrip(".").lower()) != "obj":
        raise click.UsageError("--texture writes an OBJ with its material and image: give -o NAME.obj")
    if vertices not in (None, "all"):
        raise click.UsageError("--texture places each grid node in the image: it takes no --vertices N")
    material = os.path.splitext(output)[0] + ".mtl"
    check_not_input(texture, input)
    check_not_input(material, input)
    check_distinct({"-o": output, "material": material, "--texture": texture})


def write_textured(grid, jump_angle, output, texture):
    """Write the grid's mesh as an OBJ with texture coordinates, its material file and the PNG of
    its colours (``mzc.meshes.obj.textured``), all or none of them."""
    from mzc.meshes.obj import textured
    from mzc.ops.triangulation import node_mesh
    from mzc.streams import write_outputs

    write_outputs(*textured(grid, node_mesh(grid, jump_angle), output, texture))
