"""A mesh or point cloud coded for an RMS error over its whole surface (``mzc.encode(mesh, rmse=E)``,
``mzc encode a.obj --rmse E``).

A grid's spacing trades its floor (the distance between the surface and the grid's own mesh,
uncoded) against its count of nodes. The default spacing keeps the floor far below any error a
user asks of a coded file (issue 28: 0.016% D on the armadillo), and at a target of 0.05-0.1% D
that floor is bought dearly: twice the spacing codes the armadillo in 7.7 and 4.6 KB where the
default grid takes 11.6 and 7.5 (benchmarks/chart-spacing-results.md). So, given the surface and
a target E, the grid is cut at the coarsest of FACTORS times the default spacing whose measured
floor is at most FLOOR_SHARE E (the default grid when none is), and coded with the RMS budget
that brings the whole-surface error to E: sqrt(E^2 - floor^2) first, then once corrected by the
error its rebuild measures; the smaller file within E is kept.

The error is measured as ``mzc diff --surface`` does (``surface_distance``: symmetric,
SAMPLES points drawn by area each way, fixed seed) between a mesh and the grid's mesh at every
node; a cloud's points are measured to the grid's mesh (one way: a cloud has no surface of its
own to sample, and its scanner's noise counts).
"""

import numpy as np

FACTORS = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0)   # spacings tried, in times the default
FIRST = 2           # the index in FACTORS the search starts from
FLOOR_SHARE = 0.8   # of the target: the largest floor a grid coded for it may have
LEAST_BUDGET = 0.3  # of the target: the coding budget when the floor leaves less
MAX_CORRECTION = 4.0   # times a budget may grow or shrink at a correction
SAMPLES = 100_000   # drawn on each surface to measure an error (mzc diff's count)


def whole_rms(surface, grid):
    """RMS distance between ``surface`` (a Mesh: triangles, or a cloud) and ``grid``'s mesh: as ``mzc
    diff`` measures them, but for a cloud of more than SAMPLES points, which SAMPLES of them stand for."""
    from mzc.measure.metrics import distance_stats, distance_to_mesh, surface_distance
    from mzc.ops.triangulation import grid_to_mesh

    rebuilt = grid_to_mesh(grid)
    if len(surface.triangles):
        pair = (surface.points, surface.triangles), (rebuilt.points, rebuilt.triangles)
        return surface_distance(*pair, samples=SAMPLES)["rms"]
    points = surface.points
    if len(points) > SAMPLES:
        points = points[np.random.default_rng(0).choice(len(points), SAMPLES, replace=False)]
    return distance_stats(distance_to_mesh(points, rebuilt.points, rebuilt.triangles))["rmse"]


def sliced_for(surface, rmse):
    """[(grid, its floor)] of ``surface`` cut at the coarsest of FACTORS times the default spacing
    whose floor is at most FLOOR_SHARE ``rmse`` (the default spacing when none is), then at the
    next finer factor, when there is one: on a smooth surface the coarsest grid's file can be the
    larger (the blob's at 0.05: 259 bytes at 8 times, 237 at the default). The floor grows with the
    spacing, so the search walks from FIRST: up while the next factor passes, else down to one that
    does."""
    from mzc.ops.slicing import slice_surface

    default = slice_surface(surface)
    cuts = {}

    def cut(index):
        if index not in cuts:
            factor = FACTORS[index]
            grid = default if factor == 1 else slice_surface(surface, d1=factor * default.d1, d2=factor * default.d2)
            cuts[index] = grid, whole_rms(surface, grid)
        return cuts[index]

    def passes(index):
        return cut(index)[1] <= FLOOR_SHARE * rmse

    index = FIRST
    if passes(index):
        while index + 1 < len(FACTORS) and passes(index + 1):
            index += 1
    else:
        while index > 0 and not passes(index):
            index -= 1
    return [cut(i) for i in (index, index - 1) if i >= 0]


def encode_surface(surface, codec, prior, options):
    """The file of ``surface`` (a Mesh) coded by ``codec`` (a Codec) with its checked ``options``:
    for dwt2d's ``rmse``, within it over the whole surface (``encoded_for``); else its default grid's."""
    from mzc.colours import warn_uncoded
    from mzc.errors import MzcError
    from mzc.meshes import warn_dropped
    from mzc.ops.slicing import slice_surface

    if prior is not None:
        raise MzcError("a prior codes a grid cut on its lattice: slice the surface with the prior first",
                       field="prior")
    if codec.name == "dwt2d" and "rmse" in options:
        grid, data = encoded_for(surface, codec, **options)
    else:
        grid = slice_surface(surface)
        data = codec.encode(grid, **options)
    warn_dropped(surface)
    warn_uncoded(grid, codec, options)
    return data


def encoded_for(surface, codec, rmse, **options):
    """(grid, its file): the ``codec`` (dwt2d) file of ``surface`` whose rebuild is within ``rmse``
    of it over its whole surface in the fewest bytes, of the grids ``sliced_for`` gives, each coded
    at the two budgets ``attempts`` tries (the most accurate file when none is within ``rmse``);
    ``options`` the codec's others."""
    files = [(error > rmse, len(data) if error <= rmse else error, grid, data)
             for grid, floor in sliced_for(surface, rmse)
             for data, error in attempts(surface, codec, grid, floor, rmse, options)]
    return min(files, key=lambda file: file[:2])[2:]


def attempts(surface, codec, grid, floor, rmse, options):
    """[(file, its whole-surface error)] of ``grid`` (whose floor is ``floor``) coded at the budget
    ``wanted`` that sums with the floor to ``rmse`` (in squares), then at the budget that brings
    the coding error to ``wanted`` as the first file measured it (within MAX_CORRECTION times)."""
    def coded(budget):
        data, heights = codec.encode_with_decoded(grid, rmse=budget, **options)
        return data, whole_rms(surface, grid.with_z(heights))

    wanted = max(np.sqrt(max(rmse**2 - floor**2, 0.0)), LEAST_BUDGET * rmse)
    first = coded(wanted)
    coding = np.sqrt(max(first[1] ** 2 - floor**2, (LEAST_BUDGET * wanted) ** 2))
    return [first, coded(wanted * min(max(wanted / coding, 1 / MAX_CORRECTION), MAX_CORRECTION))]
