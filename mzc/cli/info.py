"""``mzc info FILE``: one screen about any mzc file."""

import click

from mzc.cli.options import input_argument


@click.command(help="""Describe any mzc file: format, version, grid size, spacings, bytes, header lines.

Reads the header only (and checks the file's checksum), so it is quick on any file;
--decode also decodes the file to count its valid nodes and give their range.""")
@input_argument
@click.option("--decode", "decode", is_flag=True, help="Decode the file: valid nodes, value range, bits per node.")
def command(input, decode):
    import numpy as np

    from mzc.formats import header_versions, read_any
    from mzc.formats.header import read_grid_fields, read_header, split_magic
    from mzc.grid import ZGrid
    from mzc.streams import display_name, read_input

    data = read_input(input)
    source = display_name(input)
    kind, major, minor = split_magic(data, source)
    header, _body, _line = read_header(data, source, kind, major, **header_versions(kind, source))
    fields, rows, cols = read_grid_fields(header)
    grid = read_any(data, source) if decode else ZGrid(z=np.broadcast_to(np.nan, (rows, cols)), **fields)
    lines = [
        f"file      {source}",
        f"format    mzc-{kind} {major}.{minor}",
        f"bytes     {len(data)}",
        f"grid      {rows} rows x {cols} cols, d1 {grid.d1:g} d2 {grid.d2:g}{' ' + grid.units if grid.units else ''}",
        f"cut by    {cutting_surfaces(grid, header.has('chart_count'))}",
        *chart_lines(grid, header),
    ]
    if decode:
        lines += decoded_lines(grid, len(data))
    lines.append("header")
    lines += [f"  {keyword} {' '.join(values)}" for keyword, (values, _) in header.fields.items()]
    click.echo("\n".join(lines))


def chart_lines(grid, header):
    """A multi-chart grid's charts: how many, and each one's view, block and nodes' lattice place
    (a dwt2d file's records are in its payload: their count without --decode)."""
    if grid.charts is None:
        return [f"charts    {' '.join(header.tokens('chart_count'))} (records in the payload: --decode lists them)"] \
            if header.charted and header.has("chart_count") else []
    from collections import Counter

    views = Counter(chart.view for chart in grid.charts)
    lines = [f"charts    {len(grid.charts)} ({', '.join(f'{count} {view}' for view, count in sorted(views.items()))})"]
    return lines + [f"  {chart.view} {chart.rows} x {chart.cols} at row {chart.row0}, column {chart.col0}; "
                    f"lattice {chart.i0} {chart.j0}" for chart in grid.charts]


def decoded_lines(grid, size):
    """Valid nodes, their value range and the bits each costs."""
    valid = int(grid.valid.sum())
    lines = [f"valid     {valid} of {grid.z.size} nodes ({100 * valid / grid.z.size:.1f}%)"]
    if valid:
        lines.append(f"z range   {float(grid.z[grid.valid].min()):g} .. {float(grid.z[grid.valid].max()):g}")
        lines.append(f"bits/node {8 * size / valid:.3f} (per valid node)")
    return lines


def cutting_surfaces(grid, charted=False):
    """What cut the grid: charts (``charted``: a dwt2d file's, whose records are in its payload),
    the thesis's planes, or a central projection about its centre and axis."""
    if grid.charts is not None or charted:
        return "charts (planar grids along the frame's axes, each its own piece of the surface)"
    if grid.projection == "planar":
        return "planar (parallel planes; values along the grid's z)"
    centre, axis = grid.transform[:, 3], grid.transform[:, 1]
    turn = ", full turn" if grid.periodic else ""
    poles = f", {int(grid.pole_rows().sum())} pole row(s)" if grid.pole_rows().any() else ""
    return (f"{grid.projection} (radius {grid.radius:g}, centre {' '.join(f'{v:g}' for v in centre)}, "
            f"axis {' '.join(f'{v:.4g}' for v in axis)}{turn}{poles})")
