"""``mzc sample NAME``: write a built-in sample surface as a mesh."""

import click

from mzc.cli.options import output_option


@click.command(help="""Write a built-in sample surface as a mesh (OBJ on stdout, or -o FILE).

jacksboro and topobathy are real elevation models shipped with matplotlib (metres);
bump is a generated 160 x 120 mm patch with a hole; blob a closed, lobed ball about 100 mm
across and tube an open, fluted tube 200 mm long (mm), surfaces that go all the way round.""")
@click.argument("name", type=click.Choice(["jacksboro", "topobathy", "bump", "blob", "tube"]), default="jacksboro")
@output_option
@click.option("--format", "file_format", type=click.Choice(["obj", "ply", "vtk", "stl", "off"]),
              help="Mesh format (default: from the -o extension; obj on stdout).")
def command(name, output, file_format):
    from mzc.meshes import write_mesh
    from mzc.samples import sample_mesh
    from mzc.streams import check_not_input

    check_not_input(output)
    write_mesh(output, sample_mesh(name), file_format)
