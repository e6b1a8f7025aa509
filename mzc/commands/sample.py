"""``mzc sample NAME``: write a built-in sample surface as a mesh."""

import click

from mzc.commands import output_option


@click.command(help="""Write a built-in sample surface as a mesh (OBJ on stdout, or -o FILE).

jacksboro and topobathy are real elevation models shipped with matplotlib (metres);
bump is a generated 160 x 120 mm patch with a hole.""")
@click.argument("name", type=click.Choice(["jacksboro", "topobathy", "bump"]), default="jacksboro")
@output_option
@click.option("--format", "file_format", type=click.Choice(["obj", "ply", "vtk", "stl", "off"]),
              help="Mesh format (default: from the -o extension; obj on stdout).")
def command(name, output, file_format):
    from mzc.meshes import Mesh, write_mesh
    from mzc.samples import SAMPLES
    from mzc.triangulation import grid_to_mesh

    write_mesh(output, Mesh(*grid_to_mesh(SAMPLES[name]())), file_format)
