"""Cutting surfaces (METHOD.md §1, in ../shared/reference): turn a triangle mesh or point cloud into a z-grid.

Every grid node stands for the line where two cutting surfaces meet: on the thesis's
planes the vertical line where a "horizontal" plane (constant y, one grid row) meets a
"vertical" one (constant x, one column), on central grids a ray (``mzc.projections``).
Its value is the exact outermost intersection of that line with the surface
(``mzc.ops.raster`` for planes, ``mzc.ops.rays`` for rays); the projection comes from
``mzc.ops.views``.
"""

import numpy as np

from mzc.errors import MzcError
from mzc.georef import grid_crs
from mzc.grid import ZGrid
from mzc.limits import MAX_DIMENSION, check_grid_size, length_problem
from mzc.ops.delaunay import triangulate_point_cloud
from mzc.ops.raster import rasterize
from mzc.ops.rays import cast
from mzc.vectors import dotted, inner, length, lengths, rotated, symmetric_eigen

DEFAULT_ROWS = 72           # the thesis cuts a face with about 70 horizontal planes (--thesis-grid)
COLUMN_STEP_RATIO = 10      # and uses about 10x as many vertical planes: d2 = d1/10
DATA_SPACING_FRACTION = 0.5   # default spacing: half the median edge of the surface's triangles,
MIN_NODES_ACROSS = 200        # and at least 200 nodes along the longest side
SPACING_DIGITS = 3            # significant digits of a spacing from the data (within_longest_side)
CHART_EDGE_FRACTION = 0.5     # a multi-chart grid's (chart_spacing): half a mesh's median edge,
CHART_AREA_FRACTION = 0.6     # or 0.6 of the side of its area per vertex when that is longer,
CHART_MIN_NODES_ACROSS = 100  # with at least 100 nodes along the longest side
CHART_CAP_NODES_ACROSS = 300  # a mesh of few large triangles: its charts take 300 nodes along the longest side
                              # when at 200 (MIN_NODES_ACROSS) their uncoded rebuild misses a floor (meets_floors):
FLOOR_RMS = 0.02              # % of D (the box's diagonal): issue 28's floors, whole-surface RMS distance,
FLOOR_HAUSDORFF = 0.5         # % of D: its Hausdorff distance,
FLOOR_NEAR = 0.1              # % of D: and the share of the source's area this close to the rebuild
FLOOR_COVERAGE = 99.5         # at least this % of it
FLOOR_MARGIN = 0.9            # a rebuild meets a floor within this share of it (FLOOR_COVERAGE: of the area missed)
FLOOR_SAMPLES = 50_000        # area-weighted samples each way, seeded (FLOOR_SEED): the same choice on every machine
FLOOR_SEED = 0
SNAP_TOLERANCE = 1e-3       # a spacing this close (relative) to a lattice's own step snaps to it
LATTICE_TOLERANCE = 1e-6    # coordinates this close (in steps) to a multiple of the step lie on a lattice
PRINTED_TOLERANCE = 0.05    # a lon/lat export's: 6 decimals of a degree are 0.011 of a 1/3 arc-second step
LONLAT_RELIEF = 1000        # a lon/lat lattice: z spans at least 1000 of its steps and its whole width
MIN_NODES = 4               # a cloud of MIN_CLOUD_POINTS points or more gridded to fewer nodes on an axis
MIN_CLOUD_POINTS = 1000     # is refused (its spacing is not the cloud's)
LATTICE_FILL = 0.1          # and the points fill at least this share of its nodes (not a LAS cloud's 0.01 quanta)
BIN_POINTS = 100_000        # clouds of more points are binned (mzc.ops.binning) when dense at the grid's spacing
CLOUD_METHODS = ("auto", "bin", "delaunay")
TAP_TOLERANCE = 1e-9        # steps: a point this close to a cell's edge is on it (--tap)
ROUND_STEPS = ("1", "2", "2.5", "5")   # a map grid's default spacing: one of these times a power of ten


# --------------------------------------------------------------------------- alignment


def pca_frame(points, triangles):
    """Rotation R and shift t with input = R @ grid_point + t, from principal axes.

    The centroid goes to the origin; the direction of least spread becomes z, of most
    spread y (rows stack along the long side, as the thesis's planes cut a face top to
    bottom), and x = y × z so R is a proper rotation. z is turned so the surface faces +z:
    the area-weighted mean triangle normal (point clouds: the input z axis) has positive
    z; y is turned to agree with the input y axis.
    """
    points = np.asarray(points, dtype=np.float64)
    shift = points.mean(axis=0)
    offsets = np.ascontiguousarray((points - shift).T)
    spread = [[inner(offsets[i], offsets[j]) for j in range(3)] for i in range(3)]   # the covariance, times n - 1
    _spread, axes = symmetric_eigen(spread)
    z_axis, y_axis = axes[:, 0], axes[:, 2]
    if dotted(z_axis, facing_direction(points, triangles)) < 0:
        z_axis = -z_axis
    if y_axis[1] < 0:
        y_axis = -y_axis
    rotation = np.column_stack([np.cross(y_axis, z_axis), y_axis, z_axis])
    return rotation, shift


def facing_direction(points, triangles):
    """Where the surface looks: the summed (area-weighted) triangle normal, or +z without triangles."""
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if not len(triangles):
        return np.array([0.0, 0.0, 1.0])
    a, b, c = (points[triangles[:, i]] for i in range(3))
    return np.cross(b - a, c - a).sum(axis=0)


# --------------------------------------------------------------------------- slicing


def slice_surface(surface, d1=None, d2=None, rows=None, cols=None, align="none", units=None,
                  projection="auto", center=None, axis=None, view="auto", thesis_grid=False, classes=None,
                  cloud="auto", charts="auto", tap=False, colour_scale=1):
    """Cut ``surface`` (a Mesh; no triangles = point cloud) into a ZGrid; a ZGrid (a raster's, or
    one read from a z-grid or compressed file) is its own grid (``grid_as_sliced``).

    ``projection`` names the cutting surfaces (``mzc.projections``); ``auto`` picks the
    one that sees the surface best, ``view`` the direction a planar grid looks along (auto
    or +x, -x, +y, -y, +z, -z of the ``align`` frame), and ``center``/``axis`` fix those of a
    central one (``mzc.ops.views``). The grid covers the extent of the surface in (u, v) with
    node (0, 0) at its low corner, a full turn of a surface that goes all the way round.
    Spacings come from ``d1``/``d2`` or from counts ``rows`` (across v) and ``cols``
    (across u), else from the data (``spacings``); ``thesis_grid``: 72 rows, as the
    thesis's ~70 planes, and d2 = d1/10. ``classes`` (ASPRS codes) keeps only the points of
    those classes of a LAS/LAZ cloud (``Mesh.with_classes``); ``cloud`` says how a cloud
    becomes a surface (``slice_in_frame``). A planar grid keeps the cloud's CRS (``grid_crs``);
    a cloud without one that is terrain in longitude and latitude (``lonlat_lattice``) is
    gridded at its own steps in WGS 84, and a cloud whose CRS is geographic (a LAS cloud in
    EPSG:4326) in its CRS, both as terrain in degrees (``lonlat_grid``). A cloud gridded to fewer than
    MIN_NODES nodes along an axis is refused (``check_cloud_grid``). ``colour_scale`` K > 1 samples
    a coloured surface's colour K times finer than the nodes (one grid only: ``colouring.fine_colours``).

    ``charts``: 1 for one grid, N for a multi-chart grid of at most N charts (``mzc.ops.charts``),
    ``auto`` for one grid when it holds SINGLE_COVER of the surface's area (a face, terrain, a
    star-shaped ball) and charts otherwise (a closed or many-part object); cutting options that
    shape one grid (projection, view, centre, axis, counts, the thesis's grid) ask for one.
    Warns (MzcWarning) when one grid's lines meet less than SEEN_WARNING of the area well.

    ``tap`` (target-aligned pixels, as gdalwarp -tap): a map grid, planar and looking down the
    input's z, whose cells (each node the centre of a d2 x d1 cell, as a GeoTIFF holds it) have
    their edges on whole multiples of the spacings (``tap_extent``); its default spacing is
    round (``round_spacing``), as a cloud with a CRS's is.
    """
    from mzc.limits import check_magnitude
    from mzc.ops.charts import SINGLE_COVER, single_grid_cover
    from mzc.ops.views import SEEN_WARNING, choose_view

    if isinstance(surface, ZGrid):
        return grid_as_sliced(surface, units, d1=d1, d2=d2, rows=rows, cols=cols, center=center, axis=axis,
                                thesis_grid=thesis_grid or None, align=None if align == "none" else align,
                                projection=None if projection in ("auto", "planar") else projection,
                                view=None if view in ("auto", "+z") else view,
                                charts=None if charts in ("auto", 1) else charts, tap=tap or None,
                                colour_scale=None if colour_scale == 1 else colour_scale)
    mesh = surface if classes is None else surface.with_classes(classes)
    check_magnitude(mesh.points, "coordinates")
    if tap:
        check_tap(rows=rows is not None, cols=cols is not None, thesis_grid=thesis_grid, align=align != "none",
                  projection=projection not in ("auto", "planar"), view=view not in ("auto", "+z"),
                  center=center is not None, axis=axis is not None, charts=charts not in ("auto", 1))
        projection, view = "planar", "+z"
    lonlat = lonlat_lattice(mesh)
    if lonlat is not None or geographic_cloud(mesh):
        return from_source(mesh, lonlat_grid(mesh, lonlat, units, d1=d1, d2=d2, rows=rows, cols=cols, tap=tap,
                                          thesis_grid=thesis_grid, align=align, projection=projection, view=view,
                                          center=center, axis=axis, charts=charts, cloud=cloud), colour_scale)
    one_grid = one_grid_option(projection=projection != "auto", view=view != "auto", center=center is not None,
                               axis=axis is not None, thesis_grid=thesis_grid, rows=rows is not None,
                               cols=cols is not None, tap=tap)
    count = chart_count(charts, one_grid)
    if count is not None and count > 1:
        return from_source(mesh, charted(mesh, align, d1, d2, units, count), colour_scale)
    chosen = choose_view(mesh, frame_for(mesh, align), projection, center, axis, view)
    grid = slice_in_frame(mesh, chosen.rotation, chosen.shift, d1=d1, d2=d2, rows=rows, cols=cols, units=units,
                          projection=chosen.projection, radius=chosen.radius, full_turn=chosen.full_turn,
                          thesis_grid=thesis_grid, cloud=cloud, tap=tap,
                          round_default=tap or (mesh.is_point_cloud and mesh.crs is not None))
    check_cloud_grid(mesh, grid)
    if np.isnan(grid.z).all():
        raise MzcError("no grid node meets the surface (seen edge-on? try --view or --align pca)")
    if count is None and not one_grid and (single_grid_cover(grid, mesh) or 1.0) < SINGLE_COVER:
        return from_source(mesh, charted(mesh, align, d1, d2, units), colour_scale)
    crs = grid_crs(mesh.crs) if grid.projection == "planar" else None
    if crs is not None:
        grid = grid.with_z(grid.z, crs=crs)   # the transform maps the grid to the cloud's frame, the CRS's
    if chosen.seen is not None and chosen.seen < SEEN_WARNING:
        import warnings

        from mzc.errors import MzcWarning

        warnings.warn(MzcWarning(
            f"the {chosen.projection} grid meets only {100 * chosen.seen:.0f}% of the surface's area within "
            f"60 degrees of its node lines; the rest comes back coarse or not at all (try --projection auto, "
            f"--view or --align pca)"), stacklevel=2)
    return from_source(mesh, grid, colour_scale)


def from_source(mesh, grid, colour_scale=1):
    """``grid``, sliced from ``mesh``, with what it keeps of it: the colours at its nodes, or
    ``colour_scale`` times finer (``mzc.ops.colouring``), and the count of its vertices, which the
    rebuild comes back near."""
    from mzc.ops.colouring import coloured

    grid = coloured(mesh, grid, colour_scale)
    return grid.with_z(grid.z, source_vertices=len(mesh.points))


def lonlat_lattice(mesh):
    """(step in longitude, step in latitude) of a point cloud without a CRS that is terrain in
    degrees: a GIS export of a geographic DEM as x y z. Its x lie within [-180, 360] and its y
    within [-90, 90], its (x, y) on a lattice (``lattice_steps``, within PRINTED_TOLERANCE of a
    step: the export rounds the coordinates it prints), and its heights span at least its
    width and LONLAT_RELIEF of its steps: a metre of relief a degree, where a lattice in one
    unit spanning as much in z as across is no terrain. Each step is the round angle it was
    printed from (``round_angle``). Else None."""
    if not mesh.is_point_cloud or mesh.crs is not None or len(mesh.points) < 4:
        return None
    x, y, z = np.asarray(mesh.points, dtype=float).T
    if x.min() < -180 or x.max() > 360 or y.min() < -90 or y.max() > 90:
        return None
    steps = lattice_steps(np.column_stack([x, y]), PRINTED_TOLERANCE)
    relief = float(np.ptp(z))
    if steps is None or relief < max(np.ptp(x), np.ptp(y)) or relief < LONLAT_RELIEF * max(steps):
        return None
    return tuple(round_angle(np.unique(values), step) for values, step in zip((x, y), steps))


def geographic_cloud(mesh):
    """True for a point cloud whose CRS is geographic: x and y in degrees of longitude and
    latitude, heights in metres (a LAS cloud in EPSG:4326, its CRS spelled out as WKT)."""
    from mzc.georef import crs_kind

    return mesh.is_point_cloud and mesh.crs is not None and crs_kind(mesh.crs) == "geographic"


def round_angle(values, step):
    """The angle with the fewest significant digits in degrees, arc-seconds or ninths of an
    arc-second (0.006 degrees, 1", 1/3", 7.5") that puts the printed ``values`` on a lattice as
    well as the measured ``step`` does or as their printed digits allow (their deviations from
    it spread at most twice as far as from ``step``, ``spread``, or at most their last printed
    digit, ``printed_quantum``: the digits tell the step no closer), else ``step``."""
    limit = max(2 * spread(values, step), printed_quantum(values, step) / step) + 1e-9
    for digits in range(1, 10):
        for scale in (1, 3600, 32400):
            candidate = float(f"{step * scale:.{digits}g}") / scale
            if spread(values, candidate) <= limit:
                return candidate
    return step


def printed_quantum(values, step):
    """10^-D, under ``step``, for the fewest decimals D (up to 12) that every one of ``values`` was
    printed with (each within 0.001 of a whole number of them), or 0: each value is then off its
    node by up to half of it, and two values' deviations lie at most this far apart."""
    for decimals in range(13):
        scaled = values * 10.0 ** decimals
        if 10.0 ** -decimals < step and np.abs(scaled - np.round(scaled)).max() < 1e-3:
            return 10.0 ** -decimals
    return 0.0


def spread(values, step):
    """How far apart (in steps) the deviations of ``values`` from a lattice of ``step`` through the
    first one lie: 0 on the lattice, the printed rounding on an export of it."""
    position = (values - values[0]) / step
    deviation = position - np.round(position)
    return float(deviation.max() - deviation.min())


def onto_lattice(points, steps):
    """``points`` with x and y moved onto the nodes of a lattice of ``steps`` that they were printed
    from: through the lowest x and y, or the nearest multiple of half a step to them when they lie
    within the points' own spread of it (a DEM's nodes at whole or half steps of a round angle)."""
    moved = np.array(points, dtype=float)
    for axis, step in enumerate(steps):
        values = moved[:, axis]
        low = float(values.min())
        aligned = shortest(float(np.round(low / (step / 2))) * (step / 2))
        if abs(aligned - low) <= spread(np.unique(values), step) * step + 1e-12 * abs(low):
            low = aligned
        moved[:, axis] = low + np.round((values - low) / step) * step
    return moved


def shortest(value):
    """The decimal with the fewest significant digits within 4 ulp of ``value`` (7 for the
    7.000000000000001 that 16800 half-steps of 3 arc-seconds make), else ``value``."""
    import math

    return next((short for digits in range(1, 18) if abs((short := float(f"{value:.{digits}g}")) - value)
                 <= 4 * math.ulp(value)), value)


def lonlat_grid(mesh, steps, units, d1=None, d2=None, rows=None, cols=None, tap=False, **cutting):
    """The planar grid of a lon/lat cloud, looking down z: of an export on a lattice of
    ``steps`` (``lonlat_lattice``), in WGS 84 (``georef.WGS84_WKT``; the export names no datum,
    and the ellipsoids of the others move its metres by under 0.1%), its points moved onto the
    nodes they were printed from (``onto_lattice``), node for node at its own steps unless
    spacings or counts are given; of a cloud with a geographic CRS (``steps`` None: a LiDAR
    cloud, on no lattice), in that CRS, at its median point spacing in degrees made round
    (``lonlat_spacing``) unless given. ``tap`` aligns the cells (``slice_surface``); a dense
    cloud is binned with its depth jumps measured in metres at its middle latitude. An option
    that would cut it otherwise (``cutting``, not at its default) is refused: it is terrain."""
    from mzc.georef import WGS84_WKT, metres_per_unit

    defaults = {"thesis_grid": False, "align": "none", "projection": ("auto", "planar"), "view": ("auto", "+z"),
                "center": None, "axis": None, "charts": ("auto", 1), "cloud": ("auto",)}
    refused = next((name for name, value in cutting.items()
                    if value != defaults[name] and not (isinstance(defaults[name], tuple) and value in defaults[name])),
                   None)
    if refused:
        raise MzcError("the cloud is terrain in longitude and latitude (a lattice in degrees, heights spanning "
                       "thousands of its steps, or a geographic CRS), gridded looking down z at its own steps or "
                       "--d1/--d2 in degrees: this option does not apply", field=refused)
    from mzc.meshes import Mesh

    crs = WGS84_WKT if steps is not None else mesh.crs
    on_nodes = Mesh(onto_lattice(mesh.points, steps) if steps is not None else mesh.points)
    if steps is None and d1 is None and d2 is None and rows is None and cols is None:
        d1 = d2 = lonlat_spacing(on_nodes.points[:, :2])
    latitude = float(on_nodes.points[:, 1].min() + np.ptp(on_nodes.points[:, 1]) / 2)   # binning's jumps in metres
    grid = slice_in_frame(on_nodes, np.eye(3), np.zeros(3), d1=d1, d2=d2, rows=rows, cols=cols, units=units,
                          lattice=steps, tap=tap, cell_metres=metres_per_unit(crs, latitude))
    check_cloud_grid(on_nodes, grid)
    return grid.with_z(grid.z, crs=crs)


def lonlat_spacing(lonlat):
    """The default spacing in degrees of a cloud in longitude and latitude on no lattice: its
    median point spacing (``cloud_data_spacing``, measured across x and y alone: a Delaunay edge
    over x, y and z would add metres of height to degrees) made round (``round_spacing``)."""
    return round_spacing(cloud_data_spacing(lonlat, lonlat))


def check_cloud_grid(mesh, grid):
    """Refuse a point cloud of MIN_CLOUD_POINTS or more gridded to fewer than MIN_NODES nodes
    along an axis: its spacing is not the cloud's (say, one taken from heights in metres over
    x and y in degrees), and such a grid would hold almost nothing of it."""
    if not mesh.is_point_cloud or len(mesh.points) < MIN_CLOUD_POINTS or min(grid.shape) >= MIN_NODES:
        return
    rows, cols = grid.shape
    raise MzcError(f"{len(mesh.points)} points gridded to {rows} x {cols} nodes at spacings d1 {grid.d1:.6g} and "
                   f"d2 {grid.d2:.6g}: the spacing is not the cloud's (x and y in degrees and z in metres? "
                   f"give --d1 and --d2 in the unit of x and y)", field="d1")


def check_tap(**given):
    """Refuse with ``tap`` the first option ``given`` (True when set) that cuts anything but one
    planar grid looking down the input's z: cells aligned on a map need the map's frame, and a
    spacing (a count would leave it to the extent)."""
    refused = one_grid_option(**given)
    if refused:
        raise MzcError(f"--tap aligns the cells of one planar grid looking down z, at a spacing (--d1/--d2 or the "
                       f"default): {refused.replace('_', ' ')} does not go with it", field="tap")


def tap_extent(low, high, d2, d1):
    """(low, high) of the nodes of a grid whose cells have their edges on whole multiples of the
    spacings (gdalwarp's -tap): the first and last cells are those holding ``low`` and ``high``
    (a point on an edge is the cell's above it, the last one's below), each node its cell's centre."""
    step = np.array([d2, d1])
    first = np.floor(low / step + TAP_TOLERANCE)   # a point on an edge within rounding is on it
    last = np.maximum(np.ceil(high / step - TAP_TOLERANCE) - 1, first)
    return (first + 0.5) * step, (last + 0.5) * step


def round_spacing(spacing):
    """The spacing of ROUND_STEPS times a power of ten nearest to ``spacing`` in ratio (the 0.5,
    1, 2, 2.5, 5 m of DEM products): a map grid's default. Decimal digits and comparisons alone,
    so every machine picks the same."""
    exponent = int(f"{spacing:.6e}".split("e")[1])
    candidates = [float(f"{mantissa}e{power}") for power in (exponent, exponent + 1) for mantissa in ROUND_STEPS]
    return min(candidates, key=lambda value: max(value / spacing, spacing / value))


def one_grid_option(**given):
    """The name of the first cutting option that shapes one grid (True in ``given``), or None."""
    return next((name for name, value in given.items() if value), None)


def chart_count(charts, one_grid):
    """``charts`` as a count (None for auto), refused when not a positive count or when more than
    one chart meets an option that shapes one grid (``one_grid``, its name)."""
    if charts == "auto":
        return None
    if isinstance(charts, bool) or not isinstance(charts, (int, np.integer)) or charts < 1:
        raise MzcError(f"{charts!r} is not auto or a positive number of charts", field="charts")
    if charts > 1 and one_grid:
        raise MzcError(f"charts are planar grids along the frame's axes: {one_grid.replace('_', ' ')} shapes one "
                       "grid (give --charts 1, or leave it out)", field="charts")
    return int(charts)


def charted(mesh, align, d1, d2, units, count=None):
    """The multi-chart grid of ``mesh`` in the ``align`` frame (``mzc.ops.charts.chart_surface``, at
    most ``count`` charts) at ``chart_spacing``; a mesh of few large triangles (``low_poly``) at its
    default takes 1/CHART_CAP_NODES_ACROSS of its longest side instead of 1/MIN_NODES_ACROSS where
    that grid's uncoded rebuild misses a floor (``meets_floors``).

    Why measured: a low-poly mesh's triangles say nothing of the detail its charts need, and its
    dihedral angles cannot tell a machined part from a smooth scan (the dragon and featuretype are
    unwelded: a vertex per corner). At 1/200 the cycloidal (long stitches across the gaps between its
    many small charts) and the dragon (its fins) miss floors that they meet at 1/300, while fran and
    the fuze meet them at 1/200 with 2.2x fewer nodes than at 1/300 (issues 28 and 32). The check
    costs one rebuild of the coarser grid and a distance search (fran 0.3 s CPU, the cycloidal 7.7 s);
    a mesh that is not low-poly (the ogre, the hand) is charted once, as before."""
    from mzc.ops.charts import chart_surface

    frame, spacing, points = frame_for(mesh, align), chart_spacing(d1, d2, mesh), np.asarray(mesh.points, dtype=float)
    grid = chart_surface(mesh, *frame, spacing, units, count)
    longest = longest_side(points)   # low_poly last: a mesh whose spacing is not 1/200 skips its median edge again
    low_poly_default = d1 is None and d2 is None and len(mesh.triangles) \
        and spacing == shortened(longest / MIN_NODES_ACROSS) and low_poly(points, mesh.triangles)
    if not low_poly_default or meets_floors(points, mesh.triangles, grid):
        return grid
    return chart_surface(mesh, *frame, shortened(longest / CHART_CAP_NODES_ACROSS), units, count)


def meets_floors(points, triangles, grid):
    """Whether the uncoded rebuild of ``grid`` (a vertex at every valid node, the charts zipped: what
    ``mzc.triangulate(grid, vertices="all")`` gives) meets issue 28's floors against the mesh
    (``points``, ``triangles``) within FLOOR_MARGIN: whole-surface RMS and Hausdorff distance of
    FLOOR_SAMPLES area-weighted samples each way, and the share of the mesh's area within FLOOR_NEAR
    of the rebuild, as benchmarks/objects.py measures them (its 100,000 samples find a Hausdorff
    distance a little above these fewer samples' (fran 0.416 against 0.373% D with 20,000): the
    margin's share)."""
    from mzc.measure.metrics import surface_distance_samples
    from mzc.ops.triangulation import grid_to_mesh

    rebuilt = grid_to_mesh(grid)
    there, back = surface_distance_samples((points, triangles), (rebuilt.points, rebuilt.triangles),
                                           {"whole": (None, None)}, FLOOR_SAMPLES, FLOOR_SEED)["whole"]
    unit = length(np.ptp(points, axis=0)) / 100   # 1% of D, the box's diagonal
    both = np.concatenate([there, back]) / unit
    missed = 100 * float(np.mean(there > FLOOR_NEAR * unit))
    return bool(np.sqrt(np.mean(both * both)) <= FLOOR_MARGIN * FLOOR_RMS
                and both.max() <= FLOOR_MARGIN * FLOOR_HAUSDORFF and missed <= FLOOR_MARGIN * (100 - FLOOR_COVERAGE))


def chart_spacing(d1, d2, mesh):
    """The one spacing of a multi-chart grid: d1 or d2 as given (equal when both are), else a
    cloud's ``source_spacing`` and a mesh's ``mesh_chart_spacing``."""
    if d1 is not None and d2 is not None and d1 != d2:
        raise MzcError("charts take one spacing: give --d1 alone (or equal --d1 and --d2)", field="d2")
    given = d1 if d1 is not None else d2
    if given is not None:
        return given
    if len(mesh.triangles):
        return mesh_chart_spacing(np.asarray(mesh.points, dtype=float), mesh.triangles)
    return source_spacing(mesh)


def low_poly(points, triangles):
    """Whether ``data_spacing``'s cap holds on the mesh: half its median edge is at least
    1/MIN_NODES_ACROSS of its longest side (a CAD part's or a decimated scan's few large triangles)."""
    return DATA_SPACING_FRACTION * median_edge(points, triangles) >= longest_side(points) / MIN_NODES_ACROSS


def longest_side(points):
    """The longest side of the box of ``points``."""
    return float(np.ptp(points, axis=0).max())


def mesh_chart_spacing(points, triangles):
    """The default spacing of a mesh's multi-chart grid: 1/MIN_NODES_ACROSS of the longest side of a
    ``low_poly`` mesh (``charted`` refines it to 1/CHART_CAP_NODES_ACROSS where its rebuild misses a
    floor), else the longer of CHART_EDGE_FRACTION of the median edge and
    CHART_AREA_FRACTION of sqrt(area / vertices), at most 1/CHART_MIN_NODES_ACROSS of the
    longest side (a guard: no measured object comes near it).

    Why: at ``data_spacing`` (half the median edge) a closed object's charts hold 3-24 nodes per
    vertex, and bytes grow with nodes. benchmarks/chart-spacing-results.md measured the
    whole-surface error and dwt2d bytes at multiples k of that spacing: the hand keeps every
    floor target of issue 28 (RMS <= 0.02% D, Hausdorff <= 0.5% D, 99.5% of the area within
    0.1% D) to k = 1.5 with 30,000 samples, but benchmarks/objects.py's 100,000 find its Hausdorff
    0.544% D there (0.154 at k = 1): so the edge's fraction stays 1/2 and the hand takes the area
    term, k = 1.11; the
    ogre (dense triangles in a few places, sqrt(area / vertices) 3.5x half its median edge) to
    k = 2 (here k = 2.08: 634,003 -> 146,071 nodes, 34% / 31% fewer bytes); the low-poly objects
    (cycloidal, featuretype, dragon) and the armadillo (a cloud) lose a target they meet, or
    meet none, already at k = 1.5. At 1/MIN_NODES_ACROSS the cycloidal and the dragon missed floor
    targets (cycloidal RMS 0.0257% D, Hausdorff 1.46% D: long stitches across the gaps between its
    many small charts; dragon RMS 0.0243% D, 98.6% of its area within 0.1% D); at 1/300 the
    cycloidal meets all three (0.0070% D, 0.315% D, 99.89%), the dragon
    its RMS and area (0.0129% D, 99.62%), for 6-33% more dwt2d bytes at one rmse
    (benchmarks/objects.py's floor, 100,000 samples)."""
    from mzc.measure.metrics import triangle_areas

    longest = longest_side(points)
    if low_poly(points, triangles):
        return shortened(longest / MIN_NODES_ACROSS)
    per_vertex = float(np.sqrt(np.sum(triangle_areas(points, triangles)) / len(np.unique(triangles))))
    return shortened(min(max(CHART_EDGE_FRACTION * median_edge(points, triangles), CHART_AREA_FRACTION * per_vertex),
                         longest / CHART_MIN_NODES_ACROSS))


def source_spacing(mesh):
    """The spacing the source's own sampling suggests: ``data_spacing`` of a mesh, a cloud's
    DATA_SPACING_FRACTION of its median nearest-point distance (at most 1/MIN_NODES_ACROSS of
    its longest side)."""
    points = np.asarray(mesh.points, dtype=float)
    if len(mesh.triangles):
        return data_spacing(points, mesh.triangles)
    from scipy.spatial import cKDTree

    distance, _near = cKDTree(points).query(points, k=2)
    return within_longest_side(DATA_SPACING_FRACTION * float(np.median(distance[:, 1])), points)


def grid_as_sliced(grid, units, **given):
    """A ``grid`` (a raster's, or any z-grid's) as slice gives it: itself, node for node (with
    ``units`` when given), once no cutting option is ``given`` (not None): one would need the
    raster resampled, or the z-grid's surface cut anew from its mesh."""
    refused = next((name for name, value in given.items() if value is not None), None)
    if refused:
        what, advice = (("a raster", "resample the raster first (gdalwarp -tr, -tap, -t_srs)")
                        if grid.raster is not None
                        else ("a z-grid", "to cut its surface anew, triangulate it and slice the mesh"))
        raise MzcError(f"{what} is sliced as its own grid, node for node, so this option does not apply: {advice}",
                       field=refused)
    return grid if units is None else grid.with_z(grid.z, units=units)


def slice_in_frame(mesh, rotation, shift, d1=None, d2=None, rows=None, cols=None, units=None,
                   projection="planar", radius=None, full_turn=False, thesis_grid=False, cloud="auto", lattice=None,
                   tap=False, round_default=False, cell_metres=None):
    """The z-grid of ``mesh`` in the frame where input = rotation @ p + shift, over its (u, v) extent.

    Shared by ``slice_surface`` and ``mzc diff``, which samples surfaces in a given frame.
    A planar grid of points that lie on a lattice, at the lattice's own spacings, holds
    exactly their values, node for node (a DEM as x y z text). Any other cloud is
    triangulated in (u, v) (Delaunay) or binned (``mzc.ops.binning``), as ``cloud`` says:
    ``auto`` bins a cloud of more than BIN_POINTS points that is dense at the grid's spacing
    (``binning.window_radius``), whose default spacing is then its own median point spacing
    (a node per point, where Delaunay's grid takes half of it). ``lattice``: the cloud's lattice
    steps when the caller has found them (``lonlat_lattice``). ``round_default``: a spacing from
    the data is made round (``round_spacing``); ``tap``: the cells are aligned (``tap_extent``),
    and a lattice cloud whose points then miss the nodes is triangulated. ``cell_metres``: the
    metres of a unit of u and of v where they are not lengths in the values' unit (degrees of a
    lon/lat cloud), for binning's depth-jump height.
    """
    from mzc.projections import to_nodes

    if cloud not in CLOUD_METHODS:
        raise MzcError(f"unknown cloud method {cloud!r} (choose {', '.join(CLOUD_METHODS)})", field="cloud")
    local = rotated(mesh.points - shift, rotation.T)
    nodes = to_nodes(projection, radius, local)
    low, high = nodes[:, :2].min(axis=0), nodes[:, :2].max(axis=0)
    if lattice is None and projection == "planar":
        lattice = lattice_steps(nodes[:, :2])
    binned = mesh.is_point_cloud and lattice is None and \
        (cloud == "bin" or (cloud == "auto" and len(mesh.points) > BIN_POINTS))
    triangles = mesh.triangles
    if mesh.is_point_cloud and lattice is None and not binned:   # a lattice cloud at its own steps needs none
        triangles = triangulate_point_cloud(nodes[:, :2])
    if projection != "planar":   # central grids start on a round (u, v): shorter headers, the same cover
        from mzc.ops.views import rounded

        low = rounded(low, np.max(high - low), down=True)
        if projection == "spherical":
            low[1] = max(low[1], -np.pi / 2 * radius)   # never below the south pole
    pole_to_pole = full_turn and projection == "spherical"
    if full_turn:
        low[0], high[0] = -np.pi * radius, np.pi * radius
    if pole_to_pole:
        low[1], high[1] = -np.pi / 2 * radius, np.pi / 2 * radius
    if rows is None and cols is None:
        d1, d2 = spacings(d1, d2, lattice, local, triangles, thesis_grid, nodes[:, :2] if binned else None,
                          round_default)
    if tap:
        low, high = tap_extent(low, high, d2, d1)
    d1, d2, n_rows, n_cols = grid_size(high - low, d1, d2, rows, cols, full_turn, pole_to_pole, thesis_grid)
    xs, ys = low[0] + d2 * np.arange(n_cols), low[1] + d1 * np.arange(n_rows)
    on_lattice = mesh.is_point_cloud and lattice == (d2, d1) and \
        (not tap or on_nodes(nodes[:, :2].min(axis=0), low, (d2, d1)))   # a cloud's own lattice: its values as they are
    binnable = mesh.is_point_cloud and not on_lattice
    window = cloud_window(nodes, low, d1, d2, (n_rows, n_cols), cloud) if binnable else None
    if on_lattice:
        z = lattice_values(nodes, low, d1, d2, (n_rows, n_cols))
    elif window is not None:
        from mzc.ops.binning import JUMP_RISE, binned_values

        rise = None if cell_metres is None else JUMP_RISE * max(d2 * cell_metres[0], d1 * cell_metres[1])
        z = binned_values(nodes, low, d1, d2, (n_rows, n_cols), window, rise)
    else:
        if not len(triangles):
            triangles = triangulate_point_cloud(nodes[:, :2])
        z = values_along(projection, radius, local, triangles, xs, ys)
    return ZGrid(z, d1, d2, origin=tuple(low), transform=np.column_stack([rotation, shift]), units=units,
                 projection=projection, radius=radius)


def cloud_window(nodes, low, d1, d2, shape, cloud):
    """The binning window's radius for a cloud's grid-frame ``nodes`` on this grid, or None for
    Delaunay: ``bin`` always bins, ``delaunay`` never; ``auto`` bins more than BIN_POINTS points
    when they are dense enough at these spacings (``mzc.ops.binning.window_radius``)."""
    if cloud == "delaunay" or (cloud == "auto" and len(nodes) <= BIN_POINTS):
        return None
    from mzc.ops.binning import MAX_RADIUS, density, node_bins, window_radius

    row, col, *_ = node_bins(nodes, low, d1, d2, shape)
    radius = window_radius(density(row, col, shape))
    return MAX_RADIUS if radius is None and cloud == "bin" else radius   # 0 is a radius: a dense cloud


def spacings(d1, d2, lattice, local, triangles, thesis_grid, binned_uv=None, round_default=False):
    """(d1, d2) from the data where not given: on a lattice (``lattice_steps``) its own steps,
    else ``data_spacing`` (half the median edge length of the ``triangles``, a cloud's
    Delaunay ones; for a cloud to bin, given as ``binned_uv``, its median point spacing,
    ``binning.cloud_spacing``), for both; one spacing given, the other equals it. A given
    spacing within SNAP_TOLERANCE of the lattice's own step is that step; with ``round_default``
    a spacing from the data is ``round_spacing``'s. ``thesis_grid`` leaves them to ``grid_size``
    (72 rows, d2 = d1/10)."""
    if lattice is not None:
        d2, d1 = (snapped(given, step, thesis_grid) for given, step in ((d2, lattice[0]), (d1, lattice[1])))
    if thesis_grid or (d1 is not None and d2 is not None):
        return d1, d2
    if d1 is None and d2 is None:
        d1 = d2 = data_spacing(local, triangles) if binned_uv is None else cloud_data_spacing(local, binned_uv)
        if round_default:
            d1 = d2 = round_spacing(d1)
    return (d1, d1) if d2 is None else (d2, d2)


def snapped(given, step, keep_open=False):
    """``step`` when ``given`` is within SNAP_TOLERANCE of it, or None (unless ``keep_open``),
    else ``given``."""
    if given is None:
        return None if keep_open else step
    return step if abs(given - step) <= SNAP_TOLERANCE * step else given


def data_spacing(points, triangles):
    """DATA_SPACING_FRACTION of the median edge length of ``triangles`` over ``points``, at
    most 1/MIN_NODES_ACROSS of the surface's longest side (a CAD part's few large
    triangles say nothing of the detail it needs)."""
    return within_longest_side(DATA_SPACING_FRACTION * median_edge(points, triangles), points)


def median_edge(points, triangles):
    """The median length of the edges of ``triangles`` over ``points`` (each triangle's three)."""
    corners = points[np.asarray(triangles, dtype=np.int64)]
    if not len(corners):
        raise MzcError("the surface has no triangles to measure its sampling: give --d1 and --d2")
    return float(np.median(lengths((corners - np.roll(corners, 1, axis=1)).reshape(-1, corners.shape[-1]))))


def cloud_data_spacing(points, uv):
    """The default spacing of a cloud to bin: its median point spacing in (u, v) (a node per
    point; ``binning.cloud_spacing``), at most 1/MIN_NODES_ACROSS of its longest side."""
    from mzc.ops.binning import cloud_spacing

    step = cloud_spacing(uv)
    if step is None:
        raise MzcError("the point cloud is degenerate in the grid's plane (all points on a line?)")
    return within_longest_side(step, points)


def within_longest_side(spacing, points):
    """``spacing``, at most 1/MIN_NODES_ACROSS of the longest side of ``points``' box, ``shortened``."""
    return shortened(min(spacing, longest_side(points) / MIN_NODES_ACROSS))


def shortened(spacing):
    """A spacing from the data to SPACING_DIGITS significant digits: a file's header writes it in its
    shortest decimal form, and f18's 0.747 takes 4 bytes of a dwt2d 8.0 header where
    0.7466035520003038 took 11 (twice, d1 and d2: 2% of its 0.2 mm file), for a grid 0.05% coarser
    or finer."""
    return float(f"{spacing:.{SPACING_DIGITS}g}")


def lattice_steps(uv, tolerance=LATTICE_TOLERANCE):
    """(step in u, step in v) when every point's u and v lie on a regular lattice (within
    ``tolerance`` of a step; whole lines may be missing) whose nodes the points fill to
    at least LATTICE_FILL (a DEM with its holes; not a LiDAR cloud, whose coordinates are
    all multiples of its file's 0.01 m quantum), else None."""
    steps, nodes = [], 1.0
    for values in (uv[:, 0], uv[:, 1]):
        distinct = np.unique(values)
        extent = distinct[-1] - distinct[0]
        gaps = np.diff(distinct)
        gaps = gaps[gaps > LATTICE_TOLERANCE * extent]
        if len(gaps) < 2:
            return None
        count = np.round(extent / gaps.min())
        nodes *= count + 1
        if count > MAX_DIMENSION or len(uv) < LATTICE_FILL * nodes:
            return None
        step = extent / count
        position = (distinct - distinct[0]) / step
        if np.abs(position - np.round(position)).max() > tolerance:
            return None
        steps.append(float(step))
    return tuple(steps)


def on_nodes(point, low, steps):
    """True when ``point`` (u, v) lies within LATTICE_TOLERANCE of a node of the grid from ``low`` at ``steps``."""
    position = (np.asarray(point) - low) / np.asarray(steps)
    return bool(np.abs(position - np.round(position)).max() <= LATTICE_TOLERANCE)


def lattice_values(nodes, low, d1, d2, shape):
    """The grid of lattice points ``nodes`` (u, v, value) with node (0, 0) at ``low``: each
    node holds its point's value (the outermost of several), NaN where there is none."""
    col = np.round((nodes[:, 0] - low[0]) / d2).astype(np.int64)
    row = np.round((nodes[:, 1] - low[1]) / d1).astype(np.int64)
    inside = (row >= 0) & (row < shape[0]) & (col >= 0) & (col < shape[1])
    z = np.full(shape, -np.inf)
    np.maximum.at(z, (row[inside], col[inside]), nodes[inside, 2])
    z[np.isinf(z)] = np.nan
    return z


def values_along(projection, radius, local, triangles, xs, ys):
    """Outermost hits of the node lines (u in xs, v in ys) on a grid-frame mesh: the front-most
    height for planar grids, the farthest distance along each ray for central ones."""
    if projection == "planar":
        return rasterize(local, triangles, xs, ys)
    return cast(local, triangles, projection, radius, xs, ys)


def frame_for(mesh, align):
    """(R, t) of the grid frame: identity for ``none``, principal axes for ``pca``."""
    if align == "none":
        return np.eye(3), np.zeros(3)
    if align == "pca":
        if len(mesh.points) < 3:
            raise MzcError("--align pca needs at least 3 points", field="align")
        return pca_frame(mesh.points, mesh.triangles)
    raise MzcError(f"unknown alignment {align!r} (choose none or pca)", field="align")


def grid_size(extent, d1, d2, rows, cols, full_turn=False, pole_to_pole=False, thesis_grid=False):
    """Resolve (d1, d2, rows, cols) from the options and the (u, v) ``extent`` (width, height).

    Counts and spacings left open: ``thesis_grid`` puts 72 rows across, d2 = d1/10;
    otherwise the cells are square (d2 = d1, or d1 = d2), a count gives the spacing that
    puts that many nodes end to end. With ``full_turn`` the width is a whole turn and the
    columns divide it evenly (the last column neighbours the first), their count a multiple of 2^k,
    k = min(5, floor(log2 n) - 3) for about n columns, so that the wavelet of dwt2d wraps
    round at every level down to about 8 columns (spec/dwt2d.md); with ``pole_to_pole`` the
    rows divide the height evenly with a row on each end. Either way the spacing is the
    nearest to the one asked that such a count allows.
    """
    width, height = float(extent[0]), float(extent[1])
    if d1 is not None and rows is not None:
        raise MzcError("give either a row spacing (--d1) or a row count (--rows), not both")
    if d2 is not None and cols is not None:
        raise MzcError("give either a column spacing (--d2) or a column count (--cols), not both")
    check_count(rows, "rows")
    check_count(cols, "cols")
    if d1 is None and (rows is not None or thesis_grid or cols is None):
        d1 = spacing_from_count(height, rows or DEFAULT_ROWS, "rows", "y")
    if d2 is None:
        d2 = spacing_from_count(width, cols, "cols", "x") if cols is not None else \
            d1 / COLUMN_STEP_RATIO if thesis_grid else d1
    if d1 is None:
        d1 = d2
    check_spacing(d1, "d1")
    check_spacing(d2, "d2")
    n_rows = rows or nodes_across(height, d1)
    n_cols = cols or nodes_across(width, d2)
    if full_turn:
        n_cols = cols or wrapping_count(even_count(width, d2))
        d2 = width / n_cols
    if pole_to_pole:
        n_rows = rows or max(3, even_count(height, d1) + 1)
        d1 = height / (n_rows - 1)
    check_grid_size(n_rows, n_cols, f"d1 {d1:g} and d2 {d2:g} are too fine: use larger spacings")
    return float(d1), float(d2), n_rows, n_cols


def check_count(count, name):
    """A node count must be at least 2 so it defines a spacing."""
    if count is not None and count < 2:
        raise MzcError(f"must be at least 2, not {count}", field=name)


def spacing_from_count(extent, count, name, axis):
    """The spacing that puts ``count`` nodes across ``extent``, first and last on its ends."""
    if extent <= 0:
        raise MzcError(f"the surface has no extent in {axis}: give a spacing instead of a count",
                       field=name)
    return extent / (count - 1)


def check_spacing(value, name):
    """Spacings must be lengths mzc computes with (mzc.limits.length_problem)."""
    problem = length_problem(float(value))
    if problem:
        raise MzcError(f"spacing {problem}", field=name)


def nodes_across(extent, step):
    """How many nodes of spacing ``step`` fit across ``extent``, counting both ends (a node
    past the end would miss the surface; a lattice's own step, which ``spacings`` snaps a
    spacing within SNAP_TOLERANCE of to, puts the last node on the last lattice line)."""
    count = extent / step
    if count >= MAX_DIMENSION:
        return MAX_DIMENSION + 1
    return int(np.floor(count + 1e-9)) + 1


def wrapping_count(count):
    """``count`` rounded to a multiple of 2^k, k = min(5, floor(log2 count) - 3): at least 3."""
    if count < 16:
        return max(3, count)
    multiple = 2 ** min(5, int(count).bit_length() - 4)   # bit_length - 1: floor(log2 count), exactly
    return int(round(count / multiple)) * multiple


def even_count(extent, step):
    """The whole number of steps nearest to extent / step (capped past the size limit)."""
    return int(min(round(extent / step), MAX_DIMENSION + 1))


