"""A rebuilt mesh of about the vertex count a user asks for (``triangulate --vertices N``).

A grid's mesh has a vertex at every valid node: a 30,000-vertex face scan sliced at its own
spacing comes back with 80,000, a 5,000-triangle sphere with a million triangles. Quadric
edge collapse (Garland and Heckbert 1997; fast-simplification's implementation of
Fast-Quadric-Mesh-Simplification) takes the vertices away where the surface is flat and keeps
them where it bends, so the count falls to the one asked for at little cost in distance. At
the originals' own vertex counts, against the whole-surface RMS distance of the full grid's
mesh: f18 1.01 times (30,585 vertices from 81,219, 0.28 s), the hand 1.03, the ogre 0.98 (62,208
from 156,213, 0.57 s); a smooth synthetic mesh whose grid is all but exact, the blob sample, 7.7
times (0.013 mm on a 100 mm ball: a new mesh's facets are not the original's). The simplifier
works in ``unit_scale``'s frame, so a mesh's units do not change what it keeps, and never
collapses an edge at the border of an open mesh: freed, the border of a scattered cloud's coded
grid (3,000 random points, coded at --rmse 0.0005) gave way a strip at a time, 4% of the area
gone and the rebuild 0.013 from the cloud where its every-node mesh is 0.0009 (0.00094 kept, at
4,124 vertices for the 3,000 asked: a jagged border keeps its every vertex); the 13 faces coded
at 0.05 mm come back 2.5-4.9% closer at 1.1-1.3% more vertices.

By default a rebuild comes back near the vertex count of the mesh or cloud the grid was sliced
from, which the grid and its files record (``source_vertices``, spec/zgrid.md): a round trip gives
back a mesh of the size that went in, as Draco's does. ``vertices="all"`` keeps every valid node.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.meshes import Mesh

PASSES = ((4.0, 9.0), (1.0, 7.0), (1.0, 9.0))   # (share of the target, fast-simplification's aggressiveness: 0
                      # careful and slow .. 10 fast, 7 its default), in ``unit_scale``'s frame: each pass runs
                      # while the count is over SLACK times its share of the target. A far reduction goes to 4
                      # times the target fast first: in one careful pass the cycloidal's 1.29 M grid vertices
                      # cut to its 21,384 came back 0.229% D from the part, the featuretype's 0.0106% D (1.7
                      # times its grid's); so 0.043% D in half the time, and 0.0060% D (the dragon's 0.0131
                      # where 0.0120, the blob's 1.02 times; reductions under 4x, the faces', as before)
UNIT_EDGE = 1.0       # the median edge in that frame. Against 5 then 7 in the meshes' own units, the RMS distance
                      # to the scan is 0.93 times on the hand, 1.00 on f18, 0.99 on m56, 1.03 on the 100k-vertex
                      # ogre (0.58 s on its decoded grid, 0.57 before), 0.48 on fran, a face in metres. The
                      # simplifier's care and work grow with the frame's scale: at 1/8 the ogre took 0.47 s,
                      # but the blob came back 1.18 times further and fran's colours 1 level further
UNIT_RANGE = 64       # ``unit_scale`` scales by 2^64 at most either way
UNIT_TRIANGLES = 1 << 16   # ``unit_scale`` measures every k-th triangle, k bringing them under twice this
SLACK = 1.2
ALL = "all"   # a vertex count asked for: every valid node of the grid


def vertex_target(grid, vertices=None):
    """The vertex count a rebuild of ``grid`` aims at, or None for a vertex at every valid node:
    ``vertices`` as asked (a count, or ALL), by default the count of the source the grid was
    sliced from, when it records one and has more valid nodes than that."""
    if vertices == ALL:
        return None
    if vertices is not None:
        return vertices
    if grid.source_vertices is None or np.count_nonzero(grid.valid) <= grid.source_vertices:
        return None
    return max(grid.source_vertices, 4)


def rebuilt(grid, jump_angle=None, vertices=None, streamed=False):
    """The mesh of ``grid`` with ``vertex_target``'s count of vertices: a Mesh, or when ``streamed``
    and every node is kept, what makes it as it is written (``mzc.ops.triangulation.mesh_of``)."""
    from mzc.ops.triangulation import grid_to_mesh, mesh_of

    target = vertex_target(grid, vertices)
    if target is not None:   # a count asked for and not reached is named; the default one is best effort
        return simplified(grid_to_mesh(grid, jump_angle), target, warn=vertices is not None)
    return mesh_of(grid, jump_angle) if streamed else grid_to_mesh(grid, jump_angle)


def simplified(mesh: Mesh, vertices: int, warn: bool = True) -> Mesh:
    """``mesh`` with about ``vertices`` vertices (quadric edge collapse); a mesh that has no more
    than that, or no triangles, as it is. The count of triangles asked for keeps the mesh's own
    ratio of triangles to vertices, so an open grid's mesh and a closed one both land near it.
    Colours stay: each kept vertex takes the mesh's colour at the point of its surface nearest it
    (``surface_levels``; the nearest vertex's colour left fran's coded face 0.3 levels further
    from its texture). With ``warn``, a count the simplifier cannot reach is named in a warning."""
    if vertices < 4:
        raise MzcError(f"must be at least 4, not {vertices}", field="vertices")
    if len(mesh.points) <= vertices or not len(mesh.triangles):
        return mesh
    import fast_simplification

    target = max(1, int(round(vertices * len(mesh.triangles) / len(mesh.points))))
    scale = unit_scale(mesh)
    points = np.ascontiguousarray(mesh.points * scale, dtype=np.float64)
    triangles = np.ascontiguousarray(mesh.triangles, dtype=np.int32)
    for share, aggressiveness in PASSES:
        if len(points) > SLACK * share * vertices:
            points, triangles = fast_simplification.simplify(points, triangles, target_count=round(share * target),
                                                             agg=aggressiveness, preserve_border=True)
    if warn and len(points) > SLACK * vertices:   # far reductions stall (the blob from 180,000 stops near 6,000)
        import warnings

        from mzc.errors import MzcWarning

        warnings.warn(MzcWarning(f"the mesh keeps {len(points)} vertices of the {vertices} asked for: the simplifier "
                                 "found no more edges to collapse without folding the surface or moving its border"),
                      stacklevel=2)
    points /= scale
    colors = None
    if mesh.colors is not None:   # a collapse moves a kept vertex: the colour of the surface where it now lies
        from mzc.ops.colouring import surface_levels

        colors = surface_levels(points, mesh)
    return Mesh(points, np.asarray(triangles, dtype=np.int64), colors=colors)


def unit_scale(mesh: Mesh) -> float:
    """The power of two that brings ``mesh``'s median edge (slicing's ``median_edge``) nearest
    UNIT_EDGE. The simplifier's thresholds are absolute (Fast-Quadric-Mesh-Simplification
    collapses the edges whose quadric error is below 1e-9 (iteration + 3) ^ aggressiveness), so
    in the mesh's own units a surface in metres and the same in millimetres were simplified
    differently: f18 in metres came back 16% further from its scan than in millimetres, the hand
    in its own units 7% further than in thousandths. Scaled by a power of two, the points go in
    and come back exactly; by 2^64 at most either way, so that no finite mesh's points overflow
    (a median edge of 0, or not finite, leaves the mesh as it is). A power of two needs no exact
    median: every k-th triangle's edges give it (UNIT_TRIANGLES), in 11 ms where all of them took
    74 ms on the grid mesh of the 100k-vertex ogre (7% of its decode + triangulate), the same scale."""
    from mzc.ops.slicing import median_edge

    edge = median_edge(mesh.points, mesh.triangles[::max(1, len(mesh.triangles) // UNIT_TRIANGLES)])
    if not 0 < edge < np.inf:
        return 1.0
    return float(np.ldexp(1.0, int(np.clip(-round(np.log2(edge / UNIT_EDGE)), -UNIT_RANGE, UNIT_RANGE))))
