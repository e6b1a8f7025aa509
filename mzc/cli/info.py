"""``mzc info FILE``: one screen about any file that holds a grid."""

import click

from mzc.cli.options import input_argument


@click.command(help="""Describe any mzc file: format, version, grid size, spacings, bytes, header lines.

Reads the header only (and checks the file's checksum), so it is quick on any file;
--decode also decodes the file to count its valid nodes and give their range. A raster
(GeoTIFF, ESRI ASCII grid) is read whole and described as the grid it is, with the
header lines its z-grid would carry.""")
@input_argument
@click.option("--decode", "decode", is_flag=True, help="Decode the file: valid nodes, value range, bits per node.")
def command(input, decode):
    from mzc.codecs.dwt2d.tiles import is_tiled
    from mzc.formats import GRIDS, identified, read_as
    from mzc.formats.header import grid_header_lines
    from mzc.streams import display_name, read_input

    data = read_input(input)
    source = display_name(input)
    row = identified(data, source, GRIDS)
    tiles = []
    if row.kind == "raster":
        grid = read_as(row, data, source, input)
        format_line, header, chart_count = f"{row.name} (a raster, read as its grid)", grid_header_lines(grid), None
    elif row.name in ("prior", "residual"):
        grid, format_line, header, chart_count, tiles = prior_header(row, data, source, decode)
    elif row.name == "dwt2d" and is_tiled(data):
        grid, format_line, header, tiles = tiled_header(data, source, decode)
        chart_count = None
    else:
        grid, format_line, header, chart_count, tiles = mzc_header(row, data, source, decode)
    rows, cols = grid.shape
    lines = [
        f"file      {source}",
        f"format    {format_line}",
        f"bytes     {len(data)}",
        f"grid      {rows} rows x {cols} cols, d1 {grid.d1:g} d2 {grid.d2:g}{' ' + grid.units if grid.units else ''}",
        *metric_lines(grid),
        f"cut by    {cutting_surfaces(grid, chart_count is not None)}",
        *chart_lines(grid, chart_count),
        *source_lines(grid),
        *tiles,
    ]
    if decode:
        lines += decoded_lines(grid, len(data))
    lines.append("header")
    lines += [f"  {line}" for line in header]
    click.echo("\n".join(lines))


def source_lines(grid):
    """The size of the mesh or cloud the grid was sliced from, which ``triangulate`` rebuilds near by
    default, when the file records it."""
    if grid.source_vertices is None:
        return []
    return [f"source    {grid.source_vertices:,} vertices (triangulate's default size)"]


def metric_lines(grid):
    """For a geographic grid, its spacings in metres at its centre on its CRS's ellipsoid
    (``mzc.georef``): what a degree of it is on the ground; else none."""
    from mzc.georef import centre_of, is_geographic, metres_per_unit

    if not is_geographic(grid):
        return []
    latitude = centre_of(grid)[1]
    east, north = metres_per_unit(grid.crs, latitude)
    return [f"          in metres d1 {grid.d1 * north:.4g} d2 {grid.d2 * east:.4g} at its centre "
            f"(longitude and latitude, at latitude {latitude:.4f} on the CRS's ellipsoid)"]


def mzc_header(row, data, source, decode):
    """(grid, format line, header lines, chart count, colour lines) of an mzc file of the format ``row``,
    from its header alone (its checksum checked), the grid decoded only with ``decode``; the chart
    count is a charted dwt2d file's ``chart_count`` (its records are in its payload), else None; the
    colour lines say what a 7.0 file's colour section holds (``colour_lines``)."""
    import numpy as np

    from mzc.codecs.dwt2d import compact
    from mzc.formats import header_versions, read_as
    from mzc.formats.header import read_grid_fields, read_header, split_magic
    from mzc.grid import ZGrid

    kind, major, minor = split_magic(data, source)
    colour = None
    sections = None
    if row.name == "dwt2d" and compact.major(data) == compact.PROGRESSIVE_MAJOR:
        sections = compact.read_progressive(data, source)
        header, colour = sections.header, sections.colour
    elif row.name == "dwt2d" and compact.is_compact(data):   # binary fields, shown as the lines they stand for
        header, _payload, colour = compact.read(data, source)
    else:
        header, _body, _line = read_header(data, source, kind, major, **header_versions(row))
    fields, rows, cols = read_grid_fields(header)
    levels = level_lines(sections, (rows, cols)) if sections else []
    grid = read_as(row, data, source) if decode else ZGrid(z=np.broadcast_to(np.nan, (rows, cols)), **fields)
    lines = [f"{keyword} {' '.join(values)}" for keyword, (values, _) in header.fields.items()]
    chart_count = " ".join(header.tokens("chart_count")) if header.charted and header.has("chart_count") else None
    scaled = kind == "zgrid" and major >= 6   # a z-grid 6.0's colour_scale line
    lines_of_colour = (scale_lines(header.integer("colour_scale"), rows, cols, "colour    rgb8 samples, ") if scaled
                       else colour_lines(header, colour, rows, cols))
    return grid, f"mzc-{kind} {major}.{minor}", lines, chart_count, levels + lines_of_colour


def prior_header(row, data, source, decode):
    """``mzc_header``'s five of a prior file (its mean z-grid's header, the surfaces it was trained on
    and its SHA-256) or of a residual file (its inner dwt2d stream's header, a planar grid of the
    residual, and the prior it names, which holds the lattice: info reads the file alone, so
    --decode describes the residual)."""
    import hashlib

    from mzc.formats import named
    from mzc.prior import DIGEST_BYTES, PRIOR_MAGIC, RESIDUAL_MAGIC, read_prior, residual_digest

    if row.name == "prior":
        prior = read_prior(data, source)
        inner = data[len(PRIOR_MAGIC) + len(data[len(PRIOR_MAGIC):].split(b"\n", 1)[0]) + 1:]
        grid, _line, header, count, lines = mzc_header(named("zgrid"), inner, source, decode)
        about = [f"prior     the mean of {prior.surfaces} surfaces, sha256 {hashlib.sha256(data).hexdigest()}"]
        return grid, "mzc-prior 1.0 (a z-grid inside)", header, count, about + lines
    digest = residual_digest(data, source)
    inner = data[len(RESIDUAL_MAGIC) + DIGEST_BYTES:]
    grid, line, header, count, lines = mzc_header(named("dwt2d"), inner, source, decode)
    about = [f"prior     sha256 {digest.hex()}: the grid above is the residual from its mean, planar, and the "
             "surface lies on the prior's lattice (decode --prior FILE)"]
    return grid, f"mzc-residual 1.0 ({line} inside)", header, count, about + lines


def level_lines(sections, shape):
    """The lines of a 9.0 file's base and level sections (compact.Sections, of a grid of ``shape``): each one's
    bytes, and the prefix of the file that decodes up to it (``mzc decode --levels K``'s surface); a cut file
    says so."""
    from mzc.codecs.dwt2d import wavelet

    header, bodies = sections.header, sections.bodies
    total = header.integer("levels", required=False,
                           default=wavelet.default_levels(shape, wavelet.TRANSFORMS[header.major].coarsest))
    names = ["the mask and band 0 (section 4)", *(f"detail level {k} (section 5)" for k in range(1, len(bodies)))]
    lines = [f"{'level ' + str(k):10s}{len(body)} bytes, {name}: the first {end} bytes decode to here"
             for k, (body, name, end) in enumerate(zip(bodies, names, sections.ends))]
    if sections.cut or len(bodies) - 1 < total:
        lines.append(f"cut       the file is cut short: it holds {len(bodies) - 1} of its {total} detail levels whole, "
                     "and decodes to them")
    return lines


def colour_lines(header, colour, rows, cols):
    """The lines of a 7.0 file's colour section (none without one): its bytes and the target its
    encoder aimed at (the header's ``colour_psnr`` or ``colour_max_error``), and the colour scale of
    colours finer than the ``rows`` x ``cols`` nodes (a version 2 section's header)."""
    if colour is None:
        return []
    from mzc.codecs.dwt2d import compact
    from mzc.codecs.dwt2d.colour import read_header

    targets = [f"{keyword} {' '.join(header.tokens(keyword))}" for keyword in ("colour_psnr", "colour_max_error")
               if header.has(keyword)]
    fields = read_header(colour, header.source)
    where = "after the payload" if header.major >= compact.TIGHT_MAJOR else "section 3"
    return [f"colour    {len(colour)} bytes ({where}), {', '.join(targets) or 'no target given'}",
            *scale_lines(fields[-1], rows, cols)]


def scale_lines(scale, rows, cols, lead="          "):
    """The line (after ``lead``) of colours sampled ``scale`` times finer than a ``rows`` x ``cols``
    grid's nodes (none at 1)."""
    if scale == 1:
        return []
    return [f"{lead}colour scale {scale} ({(rows - 1) * scale + 1} x {(cols - 1) * scale + 1} samples, "
            f"{scale} a node spacing)"]


def tiled_header(data, source, decode):
    """(grid, format line, header lines, tile lines) of a tiled dwt2d file from its header and index
    (their checksums checked), the grid decoded only with ``decode`` (the tiles' checksums then too)."""
    import numpy as np

    from mzc.codecs.dwt2d.tiles import Bytes, TiledFile
    from mzc.formats.header import split_magic
    from mzc.grid import ZGrid
    from mzc.limits import MAX_NODES

    tiled = TiledFile(Bytes(data), source)
    rows, cols = tiled.frame.shape
    if decode:
        grid = tiled.window()
    else:   # a header's grid, whose values are never read: one NaN seen as many, or its fields alone
        grid = (ZGrid(z=np.broadcast_to(np.nan, (rows, cols)), **tiled.frame.fields) if rows * cols <= MAX_NODES
                else tiled.frame.described())
    lines = [f"{keyword} {' '.join(values)}" for keyword, (values, _) in tiled.header.fields.items()]
    (tile_rows, tile_cols), sizes = tiled.counts, np.diff(tiled.offsets)
    coloured = " with its nodes' colours" if tiled.coloured else ""
    tile_lines = [f"tiles     {tile_rows} x {tile_cols} of {tiled.tile} x {tiled.tile} nodes, each a dwt2d "
                  f"file{coloured} of {int(sizes.min())}..{int(sizes.max())} bytes (index {int(tiled.offsets[0])} "
                  "bytes in)"]
    _kind, major, minor = split_magic(data, source)
    return grid, f"mzc-dwt2d {major}.{minor} (tiled)", lines, tile_lines


def chart_lines(grid, chart_count=None):
    """A multi-chart grid's charts: how many, and each one's view, block and nodes' lattice place
    (a dwt2d file's records are in its payload: ``chart_count`` alone without --decode)."""
    if grid.charts is None:
        return [f"charts    {chart_count} (records in the payload: --decode lists them)"] if chart_count else []
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
