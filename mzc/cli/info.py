"""``mzc info FILE``: one screen about any mzc file."""

import click

from mzc.cli.options import input_argument


@click.command(help="""Describe any mzc file: format, version, grid size, spacings, valid nodes, bytes.

Every header line is shown as written; the file is decoded to count its valid nodes.""")
@input_argument
def command(input):
    from mzc.formats import read_any
    from mzc.formats.header import read_header, split_magic
    from mzc.streams import display_name, read_input

    data = read_input(input)
    source = display_name(input)
    kind, major, minor = split_magic(data, source)
    header, _body, _line = read_header(data, source, kind, major)
    grid = read_any(data, source)
    valid = int(grid.valid.sum())
    rows, cols = grid.shape
    lines = [
        f"file      {source}",
        f"format    mzc-{kind} {major}.{minor}",
        f"bytes     {len(data)}",
        f"grid      {rows} rows x {cols} cols, d1 {grid.d1:g} d2 {grid.d2:g}{' ' + grid.units if grid.units else ''}",
        f"cut by    {cutting_surfaces(grid)}",
        f"valid     {valid} of {grid.z.size} nodes ({100 * valid / grid.z.size:.1f}%)",
    ]
    if valid:
        lines.append(f"z range   {float(grid.z[grid.valid].min()):g} .. {float(grid.z[grid.valid].max()):g}")
        lines.append(f"bits/node {8 * len(data) / valid:.3f} (per valid node)")
    lines.append("header")
    lines += [f"  {keyword} {' '.join(values)}" for keyword, (values, _) in header.fields.items()]
    click.echo("\n".join(lines))


def cutting_surfaces(grid):
    """What cut the grid: the thesis's planes, or a central projection about its centre and axis."""
    if grid.projection == "planar":
        return "planar (parallel planes; values along the grid's z)"
    centre, axis = grid.transform[:, 3], grid.transform[:, 1]
    turn = ", full turn" if grid.periodic else ""
    poles = f", {int(grid.pole_rows().sum())} pole row(s)" if grid.pole_rows().any() else ""
    return (f"{grid.projection} (radius {grid.radius:g}, centre {' '.join(f'{v:g}' for v in centre)}, "
            f"axis {' '.join(f'{v:.4g}' for v in axis)}{turn}{poles})")
