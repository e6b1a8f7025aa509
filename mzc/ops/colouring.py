"""Colour at the grid's nodes: each valid node's colour sampled from the surface it was cut from.

A node's value puts it on the surface (the hit of its line with a triangle, or the point(s) of a
cloud that made it), so the surface's colour there is the node's: for a mesh, the colour of the
triangle nearest the node's point (the one its line hit, at distance 0 but for rounding; on an
edge or vertex the triangles that share it agree), interpolated from its corners' colours with
the point's barycentric weights (of a textured mesh, its image at the texture coordinates so
interpolated: detail finer than the triangles); for a cloud, the colour of the point nearest the
node's point. Densified rows mix their rows' colours (``densified_colours``). With a colour
scale K > 1 (``slice --colour-scale``) the colour is sampled K times finer than the nodes
(``fine_colours``): at each sample's point between the nodes, on the surface's nearest point.
The nearest triangle is found by mzc's exact search (``mzc.measure.metrics.nearest_triangles``,
the one ``mzc diff`` uses), a point of a cloud as the triangle of one corner repeated thrice,
so projections, charts, binned and Delaunay clouds all are sampled one way. Vectorised, with
IEEE arithmetic only (no BLAS, no SIMD-dependent loops): the same bytes on every CPU.
"""

import numpy as np

from mzc import projections
from mzc.errors import MzcError
from mzc.vectors import dotted


def coloured(mesh, grid, scale=1):
    """``grid`` with its nodes' colours sampled from ``mesh`` (``sampled_colours``), or with
    ``scale`` > 1 its colour image that much finer (``fine_colours``), or as it is when the mesh
    has none."""
    if scale > 1:
        return grid.with_z(grid.z, fine_colors=fine_colours(grid, mesh, scale))
    colours = sampled_colours(grid, mesh)
    return grid if colours is None else grid.with_z(grid.z, colors=colours)


def fine_colours(grid, mesh, scale):
    """((rows - 1) K + 1, (cols - 1) K + 1, 3) uint8 colours of a grid's surface sampled K =
    ``scale`` times finer than its nodes, 0 where invalid (``mzc.grid.fine_mask``); a multi-chart
    grid's charts each sample their own block (``chart_fine_colours``), and the samples between
    two charts' blocks are invalid."""
    from mzc.grid import fine_shape
    from mzc.limits import check_colour_scale

    check_colour_scale(scale, *grid.shape, field="colour_scale")
    if mesh.colors is None:
        raise MzcError("a colour scale samples the source's colours, and it has none", field="colour_scale")
    if grid.charts is None:
        return chart_fine_colours(grid, mesh, scale)
    colours = np.zeros((*fine_shape(grid.shape, scale), 3), dtype=np.uint8)
    for chart, part in zip(grid.charts, grid.chart_grids()):
        colours[chart.block(scale)] = chart_fine_colours(part, mesh, scale)
    return colours


def chart_fine_colours(grid, mesh, scale):
    """The colours of one grid (no charts) ``scale`` K times finer than its nodes: sample (a, b) at
    node position (a / K, b / K), whose value is the bilinear mix of its cell's nodes' values
    (along the node lines: a point between the grid mesh's, on any projection), coloured as a
    node is at the surface's point nearest it (``surface_colours``). Node (r, c)'s is sample (rK, cK),
    the colour ``sampled_colours`` gives it."""
    from mzc.grid import fine_lattice

    (row_low, row_high, t), (col_low, col_high, s) = (fine_lattice(n, scale) for n in grid.shape)
    t, s, z = t[:, None], s[None, :], grid.z
    values = ((1 - t) * ((1 - s) * z[np.ix_(row_low, col_low)] + s * z[np.ix_(row_low, col_high)])
              + t * ((1 - s) * z[np.ix_(row_high, col_low)] + s * z[np.ix_(row_high, col_high)]))
    us = grid.origin[0] + grid.d2 * (np.arange(values.shape[1]) / scale)
    vs = grid.origin[1] + grid.d1 * (np.arange(values.shape[0]) / scale)
    points = projections.to_points(grid.projection, grid.radius, us[None, :], vs[:, None], values)
    valid = ~np.isnan(values)
    colours = np.zeros((*values.shape, 3), dtype=np.uint8)
    if valid.any():
        colours[valid] = surface_levels(grid.to_input_frame(points[valid]), mesh)
    return colours


def sampled_colours(grid, mesh):
    """(rows, cols, 3) uint8 colours of ``grid``'s valid nodes (0 at invalid ones) sampled from
    ``mesh``, the surface it was cut from (in the mesh's frame), or None when it has no colours;
    a multi-chart grid's charts each place their own nodes."""
    if mesh.colors is None:
        return None
    colours = np.zeros((*grid.shape, 3), dtype=np.uint8)
    blocks = [chart.block() for chart in grid.charts] if grid.charts is not None else [(slice(None), slice(None))]
    for block, part in zip(blocks, grid.chart_grids()):
        valid = part.valid
        if not valid.any():
            continue
        colours[block][valid] = surface_levels(part.to_input_frame(part.node_points()[valid]), mesh)
    return colours


def surface_levels(points, mesh):
    """(n, 3) uint8: ``surface_colours`` rounded to 8-bit levels, what a grid node or a rebuilt
    vertex keeps."""
    return np.clip(np.round(surface_colours(points, mesh)), 0, 255).astype(np.uint8)


def surface_colours(points, mesh):
    """(n, 3) float colours of the coloured ``mesh`` at the point of its surface nearest each of
    ``points``: its triangle's vertex colours mixed by the point's barycentric weights, or of a
    textured mesh its image at the texture coordinates of its corners so mixed; of a cloud,
    the nearest point's colour (what slicing samples, and what benchmarks/coloured_scans.py measures
    a rebuilt colour against)."""
    from mzc.measure.metrics import nearest_triangles

    triangles = mesh.triangles if len(mesh.triangles) else point_triangles(len(mesh.points))
    nearest = nearest_triangles(points, mesh.points, triangles)[1]
    corners = triangles[nearest]
    weights = barycentric(points, *(mesh.points[corners[:, i]] for i in range(3)))
    mixed = sum(weights[:, i:i + 1] * mesh.colors[corners[:, i]].astype(np.float64) for i in range(3))
    if mesh.texture is not None:
        from mzc.meshes.texture import sampled_texels

        uv = mesh.texture.uv_at(nearest, weights)
        mapped = ~np.isnan(uv).any(axis=1)
        mixed[mapped] = sampled_texels(mesh.texture.image, uv[mapped])
    return mixed


def barycentric(points, a, b, c):
    """(n, 3) weights of the corners a, b, c (each (n, 3)) at the foot of each point on its
    triangle's plane, clamped into the triangle (none negative, summing to 1); a triangle of no
    area gives its first corner all the weight."""
    e1, e2, p = b - a, c - a, points - a
    d11, d12, d22, p1, p2 = dotted(e1, e1), dotted(e1, e2), dotted(e2, e2), dotted(p, e1), dotted(p, e2)
    area = d11 * d22 - d12 * d12
    flat = ~(area > 1e-12 * (d11 * d22))
    area = np.where(flat, 1.0, area)
    v = np.where(flat, 0.0, (d22 * p1 - d12 * p2) / area)
    w = np.where(flat, 0.0, (d11 * p2 - d12 * p1) / area)
    weights = np.clip(np.column_stack([1.0 - v - w, v, w]), 0.0, None)
    return weights / (weights[:, :1] + weights[:, 1:2] + weights[:, 2:])


def point_triangles(count):
    """(count, 3): each of ``count`` points as a triangle of one corner thrice, which the nearest
    triangle search measures as the point."""
    return np.repeat(np.arange(count), 3).reshape(-1, 3)


def nearest_sources(points, sources):
    """(n,) the number of the nearest of ``sources`` to each of ``points`` (the first of equals),
    by mzc's exact search: what a vertex the zipper adds (``mzc.ops.triangulation.every_node``)
    takes its colour and texel from."""
    from mzc.measure.metrics import nearest_triangles

    if not len(points):
        return np.empty(0, dtype=np.int64)
    return nearest_triangles(points, sources, point_triangles(len(sources)))[1]


def densified_colours(colours, dense_valid, n):
    """(rows', cols, 3) uint8 colours of a grid whose ``colours`` (rows, cols, 3) had ``n`` rows
    inserted between each pair of rows (``mzc.ops.densify``), ``dense_valid`` its new nodes'
    mask: node k of n between rows r and r + 1 mixes their colours linearly, (n + 1 - k) c_r +
    k c_r+1 over n + 1, rounded (the bilinear interpolation of the colour image to the finer
    grid, whose columns stay); where one of the two is invalid, the other's. 0 where invalid."""
    rows, cols, _ = colours.shape
    valid = dense_valid[::n + 1]
    step = np.arange(n + 1, dtype=np.float64)[None, :, None, None] / (n + 1)
    low, high = colours[:-1, None].astype(np.float64), colours[1:, None].astype(np.float64)
    low_valid, high_valid = valid[:-1, None, :, None], valid[1:, None, :, None]
    weight = np.where(low_valid & high_valid, step, np.where(high_valid, 1.0, 0.0))
    mixed = np.round(low + weight * (high - low)).reshape(-1, cols, 3)
    dense = np.concatenate([mixed, colours[-1:].astype(np.float64)]).astype(np.uint8)
    dense[~dense_valid] = 0
    return dense
