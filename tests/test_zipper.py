"""The zipper (mzc.ops.zipper): the charts of a closed surface zip into a closed surface, with no
folds and as near the surface as the charts; open rims stay open; the same triangles every time.

The charts come from tests/charts.py (a small stand-in for issue 28's segmentation).
"""

import hashlib
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from mzc.measure.metrics import nearest_triangles, surface_distance_parts
from mzc.meshes import read_mesh
from mzc.ops.zipper import CANDIDATES, Neighbours, boundary_edges, zip_charts
from mzc.samples import icosphere

from charts import chart_meshes
from conftest import REPO, edge_counts, sliced_shared_object
from test_unchanged_outputs import OTHER_MACHINES, switched_off_environment

OBJECTS = REPO.parent / "shared" / "data" / "objects"
DIVISIONS = (150, 300)   # spacings D/150 and D/300, D the bounding box's diagonal


def sphere():
    return icosphere(4)


def cube():
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    return box.vertices, box.faces


def torus():
    ring = trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=96, minor_sections=48)
    return ring.vertices, ring.faces


def two_spheres():
    points, triangles = icosphere(4)
    return np.vstack([points, 0.6 * points + (2.2, 0.3, 0.1)]), np.vstack([triangles, triangles + len(points)])


def bored_box(around=64):
    """A 2 x 2 x 1.2 box with a round bore of radius 0.5 through it (genus 1, sharp edges)."""
    angle = 2 * np.pi * np.arange(around) / around
    ring = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    square = ring / np.maximum(np.abs(ring[:, 0]), np.abs(ring[:, 1]))[:, None]
    points = np.concatenate([np.c_[flat, np.full(around, z)] for z in (0.6, -0.6) for flat in (0.5 * ring, square)])
    bore_top, side_top, bore_bottom, side_bottom = (np.arange(around) + k * around for k in range(4))
    after = np.roll(np.arange(around), -1)
    quads = [(bore_top, side_top, side_top[after], bore_top[after]),           # top face
             (bore_bottom, bore_bottom[after], side_bottom[after], side_bottom),   # bottom face
             (side_bottom, side_bottom[after], side_top[after], side_top),     # outer walls
             (bore_bottom, bore_top, bore_top[after], bore_bottom[after])]     # the bore
    return points, np.concatenate([np.concatenate([np.c_[a, b, c], np.c_[a, c, d]]) for a, b, c, d in quads])


def hemisphere():
    points, triangles = icosphere(5)
    return points, triangles[(points[triangles][:, :, 2] >= -1e-9).all(axis=1)]


def shared_object(name):
    """(points, triangles) of a shared object, its duplicate vertices merged (skips when absent)."""
    path = OBJECTS / name
    if not path.is_file():
        pytest.skip(f"shared object data not available ({path})")
    mesh = read_mesh(path)
    points, index = np.unique(mesh.points, axis=0, return_inverse=True)
    triangles = index.ravel()[mesh.triangles]
    keep = (triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2]) & \
        (triangles[:, 2] != triangles[:, 0])
    return points, triangles[keep]


def zipped(points, triangles, division):
    """(input, chart mesh, zipped mesh, spacing) at spacing D / division."""
    points = np.asarray(points, dtype=float)
    spacing = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) / division
    chart_points, chart_triangles, chart = chart_meshes(points, triangles, spacing)
    return (points, np.asarray(triangles)), (chart_points, chart_triangles), \
        zip_charts(chart_points, chart_triangles, chart, spacing), spacing


def runs_each_edge_once(triangles):
    """Whether no directed edge is run by two triangles."""
    tails, heads = triangles.ravel(), triangles[:, [1, 2, 0]].ravel()
    return len(np.unique(tails * (triangles.max(initial=0) + 1) + heads)) == len(tails)


def folded(points, triangles, first):
    """How many of the triangles from ``first`` on make more than 120 degrees with a neighbour
    across an edge (a triangle laid back over another)."""
    corners = points[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    tails, heads = triangles.ravel(), triangles[:, [1, 2, 0]].ravel()
    owner = np.repeat(np.arange(len(triangles)), 3)
    key = tails * (triangles.max() + 1) + heads
    order = np.argsort(key)
    across = np.searchsorted(key[order], heads * (triangles.max() + 1) + tails)
    across = np.minimum(across, len(key) - 1)
    found = key[order][across] == heads * (triangles.max() + 1) + tails
    neighbour = owner[order][across]
    cosine = np.where(found, np.sum(normal[owner] * normal[neighbour], axis=1), 1.0)
    return int(np.count_nonzero(np.bincount(owner, weights=cosine < -0.5)[first:]))


def whole_distance(surface, rebuilt):
    """The symmetric whole-surface distance of two meshes (rms and hausdorff)."""
    return surface_distance_parts(surface, rebuilt, {"all": (None, None)}, samples=20_000)["all"]


def farthest_stitch(surface, rebuilt, first):
    """How far from ``surface`` the farthest corner or middle of a stitch (the triangles of
    ``rebuilt`` from ``first`` on) lies."""
    corners = rebuilt[0][rebuilt[1][first:]]
    distance, _nearest = nearest_triangles(np.concatenate([corners.mean(axis=1), corners.reshape(-1, 3)]), *surface)
    return distance.max(initial=0.0)


@pytest.mark.parametrize("division", DIVISIONS)
@pytest.mark.parametrize("shape", [sphere, cube, torus, two_spheres, bored_box])
def test_the_charts_of_a_closed_surface_zip_into_a_closed_surface(shape, division):
    surface, charts, (points, triangles), spacing = zipped(*shape(), division)
    assert edge_counts(triangles) == (0, 0)
    assert runs_each_edge_once(triangles)
    assert folded(points, triangles, len(charts[1])) == 0
    distance = whole_distance(surface, (points, triangles))
    assert distance["hausdorff"] < spacing and distance["rms"] < 0.1 * spacing
    assert farthest_stitch(surface, (points, triangles), len(charts[1])) < spacing


@pytest.mark.parametrize("division", DIVISIONS)
@pytest.mark.parametrize("name", ["hand.ply", "featuretype.ply"])
def test_the_charts_of_closed_shared_objects_zip_closed(name, division):
    surface, charts, (points, triangles), spacing = zipped(*shared_object(name), division)
    assert edge_counts(surface[1]) == (0, 0)   # the input is closed
    assert edge_counts(triangles) == (0, 0)
    assert runs_each_edge_once(triangles)
    assert folded(points, triangles, len(charts[1])) < 0.005 * (len(triangles) - len(charts[1]))
    distance = whole_distance(surface, (points, triangles))
    assert distance["hausdorff"] < spacing and distance["rms"] < 0.1 * spacing
    assert farthest_stitch(surface, (points, triangles), len(charts[1])) < spacing


def test_the_charts_of_a_degenerate_closed_object_zip_closed():
    """The dragon is closed and edge-manifold, but its fins are sheets of coincident opposite
    triangles: at D/150 its charts still zip closed (finer, the far side of a fin can be a
    chart whose only neighbour is the near side, facing it across no gap, and stays apart)."""
    surface, charts, (points, triangles), spacing = zipped(*shared_object("dragon.ply"), 150)
    assert edge_counts(surface[1]) == (0, 0)
    assert edge_counts(triangles) == (0, 0) and runs_each_edge_once(triangles)
    assert farthest_stitch(surface, (points, triangles), len(charts[1])) < 1.5 * spacing


@pytest.mark.parametrize("name", ["ogre.obj", "cycloidal.ply"])
def test_the_charts_of_objects_that_are_not_closed_manifolds_zip_without_harm(name):
    """The ogre has holes (200 open edges) and 43 small bodies (teeth, nails, claws) besides its
    skin; the cycloidal gear is 100 bodies touching along 242 edges in four triangles each:
    their rebuilds put no edge in three triangles and run each edge once each way; the ogre's
    stays open only near its own holes."""
    surface, _charts, rebuilt, spacing = zipped(*shared_object(name), 300)
    assert edge_counts(rebuilt[1])[1] == 0 and runs_each_edge_once(rebuilt[1])
    if len(boundary_edges(surface[1], len(surface[0]))):
        farthest, _count = open_edges_off_the_rim(surface, rebuilt)
        assert farthest < 8 * spacing


def open_edges_off_the_rim(surface, rebuilt):
    """How far the farthest vertex of an open edge of ``rebuilt`` lies from an open edge of
    ``surface`` (both (points, triangles)), and how many open edges ``rebuilt`` has."""
    rim = boundary_edges(surface[1], len(surface[0]))
    along = np.linspace(0.0, 1.0, 9)[:, None, None]
    rim_points = (surface[0][rim[:, 0]] * (1 - along) + surface[0][rim[:, 1]] * along).reshape(-1, 3)
    open_ = boundary_edges(rebuilt[1], len(rebuilt[0]))
    distance, _index = cKDTree(rim_points).query(rebuilt[0][np.unique(open_[:, :2])])
    return distance.max(initial=0.0), len(open_)


@pytest.mark.parametrize("division", DIVISIONS)
def test_a_hemisphere_keeps_its_rim_open_and_its_seams_closed(division):
    surface, _charts, rebuilt, spacing = zipped(*hemisphere(), division)
    assert runs_each_edge_once(rebuilt[1]) and edge_counts(rebuilt[1])[1] == 0
    farthest, count = open_edges_off_the_rim(surface, rebuilt)
    assert count and farthest < 2 * spacing


def test_a_face_keeps_its_outer_rim_open_and_its_seams_closed(f18):
    mesh = read_mesh(f18)
    surface, _charts, rebuilt, spacing = zipped(mesh.points, mesh.triangles, 150)
    farthest, count = open_edges_off_the_rim(surface, rebuilt)
    assert count and farthest < 5 * spacing


def test_the_same_triangles_every_time():
    points, triangles, chart = chart_meshes(*torus(), 0.02)
    first, second = zip_charts(points, triangles, chart, 0.02), zip_charts(points, triangles, chart, 0.02)
    assert np.array_equal(first[0], second[0]) and np.array_equal(first[1], second[1])


def zipped_digest():
    """The SHA-256 of the zipped charts of the bored box at D/150 (points, then triangles)."""
    _surface, _charts, (points, triangles), _spacing = zipped(*bored_box(), 150)
    return hashlib.sha256(points.tobytes() + triangles.tobytes()).hexdigest()


@pytest.mark.parametrize("case", OTHER_MACHINES)
def test_the_same_triangles_with_numpys_simd_loops_switched_off(case):
    """What an AVX2 machine and an SSE4 one would zip: the same points and triangles."""
    environment, _off = switched_off_environment(case)
    script = f"import sys; sys.path.insert(0, {str(REPO / 'tests')!r}); import test_zipper; " \
             "print(test_zipper.zipped_digest())"
    result = subprocess.run([sys.executable, "-c", script], env=environment, capture_output=True, text=True)
    if "cannot disable" in result.stderr or "baseline" in result.stderr:
        pytest.skip(f"{case}: this numpy cannot switch those loops off")
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == zipped_digest()


@pytest.mark.parametrize("seed", range(5))
def test_equally_far_neighbours_are_taken_by_number(seed):
    """Boundary vertices on a square lattice (a flat face), numbered at random: each one's
    candidates are the nearest, equally far ones by number (spec/zgrid.md, Zipping the
    charts), not in the order a KD-tree happens to visit them. Every inner vertex has itself,
    four at one spacing and four at sqrt(2), of which the three lowest-numbered are kept."""
    rng = np.random.default_rng(seed)
    side = 24
    lattice = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), axis=-1).reshape(-1, 2)
    points = np.c_[lattice, np.zeros(len(lattice))][rng.permutation(len(lattice))] + (100.0, 200.0, 5.0)
    boundary = np.stack([np.arange(len(points)), np.roll(np.arange(len(points)), -1), np.zeros(len(points), int)], 1)
    near = Neighbours(points, boundary, 1.0)
    offset = points[:, None, :2] - points[None, :, :2]
    squared = np.sum(offset * offset, axis=-1)
    inner = np.flatnonzero(np.all((points[:, :2] > (100, 200)) & (points[:, :2] < (100 + side - 1, 200 + side - 1)), 1))
    for v in inner:
        diagonal = sorted(np.flatnonzero(squared[v] == 2))[:CANDIDATES - 5]
        assert near.candidate[v].tolist() == [v, *sorted(np.flatnonzero(squared[v] == 1)), *diagonal]
    assert np.array_equal(near.distance[inner], np.tile([0.0, 1, 1, 1, 1] + [np.sqrt(2.0)] * 3, (len(inner), 1)))


@given(st.lists(st.tuples(*[st.integers(-6, 6)] * 3), min_size=1, max_size=120), st.integers(1, 10),
       st.sampled_from([0.5, 1.0, 1.5, 2.0, 3.5]), st.sampled_from([1e-3, 1.0, 1e4]))
def test_the_nearest_kernel_keeps_what_sorting_all_pairs_keeps(lattice, columns, reach, scale):
    """``_zipper.nearest`` (points in cells of the space, each one's near ones kept in order) keeps
    in each row the points that a lexsort of all the pairs by row, squared distance and number
    puts first among those closer than ``reach``: points on a lattice, so that many are equally
    far (ties by number), some twice (at distance 0), at scales small and large."""
    from mzc.ops import _zipper

    points = np.array(lattice, dtype=float) * scale + (1e3, -7.0, 0.25)
    size, reach = len(points), reach * scale
    candidate, distance = np.full((size, columns), size), np.full((size, columns), np.inf)
    _zipper.nearest(points, reach, candidate, distance)
    here, there = np.repeat(np.arange(size), size), np.tile(np.arange(size), size)
    offset = points[there] - points[here]
    squared = offset[:, 0] * offset[:, 0] + offset[:, 1] * offset[:, 1] + offset[:, 2] * offset[:, 2]
    within = squared < reach * reach
    here, there, squared = here[within], there[within], squared[within]
    order = np.lexsort((there, squared, here))
    column = np.arange(len(order)) - np.searchsorted(here[order], here[order])
    kept, slot = order[column < columns], column[column < columns]
    expected, far = np.full((size, columns), size), np.full((size, columns), np.inf)
    expected[here[kept], slot], far[here[kept], slot] = there[kept], squared[kept]
    assert np.array_equal(candidate, expected) and np.array_equal(distance, far)


def test_the_nearest_kernel_refuses_what_it_cannot_use():
    from mzc.ops import _zipper

    with pytest.raises(ValueError):   # a table of another number of rows
        _zipper.nearest(np.zeros((2, 3)), 1.0, np.zeros((3, 1), int), np.zeros((3, 1)))
    with pytest.raises(ValueError):
        _zipper.nearest(np.array([[0.0, np.nan, 0.0]]), 1.0, np.zeros((1, 1), int), np.zeros((1, 1)))
    with pytest.raises(ValueError):
        _zipper.nearest(np.zeros((1, 3)), 0.0, np.zeros((1, 1), int), np.zeros((1, 1)))


@given(st.integers(1, 60).flatmap(lambda k: st.lists(st.integers(-1, k - 1), min_size=k, max_size=k)))
def test_the_walks_are_the_weakly_connected_components_of_the_nexts(nexts):
    """``walks`` numbers the half-edges as scipy's weakly connected components of the graph of
    the nexts do (any nexts, not only a gap's, where no two share one)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    from mzc.ops.zipper import walks

    nexts = np.array(nexts, dtype=np.int64)
    follows = np.flatnonzero(nexts >= 0)
    graph = csr_matrix((np.ones(len(follows)), (follows, nexts[follows])), shape=(len(nexts),) * 2)
    assert np.array_equal(walks(nexts), connected_components(graph, connection="weak")[1])


def test_charts_that_coincide_on_a_lattice_edge_are_welded():
    points, triangles = cube()   # its edges on the lattice of spacing 0.1: the charts share their rims
    chart_points, chart_triangles, chart = chart_meshes(points, triangles, 0.1)
    zipped_points, zipped_triangles = zip_charts(chart_points, chart_triangles, chart, 0.1)
    assert edge_counts(zipped_triangles) == (0, 0) and runs_each_edge_once(zipped_triangles)
    corners = zipped_points[zipped_triangles]
    area = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    assert np.all(area > 0)


@pytest.mark.parametrize("turned", [False, True])
def test_a_chart_given_twice_never_runs_an_edge_three_times(turned):
    """Charts that overlap (a chart and a copy of it, either way round) are not welded into a
    mesh that runs an edge twice, and zip without any edge in three triangles."""
    points, triangles, chart = chart_meshes(*cube(), 0.1)
    copy = np.flatnonzero(chart == 0)
    index = np.full(len(points), -1)
    index[copy] = len(points) + np.arange(len(copy))
    again = index[triangles[(chart[triangles] == 0).all(axis=1)]]
    zipped_points, zipped_triangles = zip_charts(
        np.vstack([points, points[copy]]), np.vstack([triangles, again[:, ::-1] if turned else again]),
        np.r_[chart, np.full(len(copy), chart.max() + 1)], 0.1)
    assert edge_counts(zipped_triangles)[1] == 0 and runs_each_edge_once(zipped_triangles)


@st.composite
def bumpy_spheres(draw):
    """A closed star-shaped mesh: an icosphere with random radii, and a spacing."""
    points, triangles = icosphere(draw(st.integers(1, 3)))
    radius = 1 + np.array(draw(st.lists(st.floats(-0.3, 0.3), min_size=len(points), max_size=len(points))))
    return points * radius[:, None], triangles, draw(st.floats(0.03, 0.4))


@settings(max_examples=40, deadline=None)
@given(bumpy_spheres())
def test_zipping_never_runs_an_edge_three_times(case):
    points, triangles, spacing = case
    chart_points, chart_triangles, chart = chart_meshes(points, triangles, spacing)
    zipped_points, zipped_triangles = zip_charts(chart_points, chart_triangles, chart, spacing)
    assert edge_counts(zipped_triangles)[1] == 0 and runs_each_edge_once(zipped_triangles)
    assert np.isfinite(zipped_points).all() and np.all(zipped_triangles < len(zipped_points))


def edge_uses(triangles):
    """{(low, high): the number of triangles with that edge}."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return dict(zip(map(tuple, unique.tolist()), count.tolist()))


@settings(max_examples=300, deadline=None)
@given(st.integers(3, 30), st.integers(0, 40), st.integers(1, 4), st.sampled_from([1e-3, 0.1, 1.0, 10.0]),
       st.booleans(), st.integers(0, 2**32 - 1))
def test_any_triangles_zip_without_crashing_or_adding_an_edge_beyond_two_uses(count, size, charts, spacing, rounded,
                                                                               seed):
    """Triangle soups (repeated, degenerate, inconsistently wound, across charts, on coincident
    points): the zipper neither fails nor puts an edge in more triangles than two, or than the
    input had it in."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(count, 3))
    points = np.round(points, 1) if rounded else points
    triangles = rng.integers(0, count, (size, 3))
    zipped_points, zipped_triangles = zip_charts(points, triangles, rng.integers(0, charts, count), spacing)
    before = edge_uses(triangles) if size else {}
    assert all(uses <= max(2, before.get(edge, 0)) for edge, uses in edge_uses(zipped_triangles).items())
    assert np.isfinite(zipped_points).all() and np.all(zipped_triangles < len(zipped_points))


# --------------------------------------------------------------------------- creases


def box_and_its_edges(turn):
    """A 2 x 1.3 x 0.7 box off the lattice, turned by ``turn`` (degrees about x, y, z), as a Mesh,
    and points along its twelve edges (short of the corners)."""
    from scipy.spatial.transform import Rotation

    from mzc.meshes import Mesh

    box = trimesh.creation.box(extents=(2.0, 1.3, 0.7))
    rotation = Rotation.from_euler("xyz", turn, degrees=True).as_matrix()
    corners = box.vertices + (0.013, 0.027, 0.031)
    one, two = np.nonzero(np.triu(np.count_nonzero(np.abs(corners[:, None] - corners[None]) > 1e-9, axis=2) == 1))
    corners = corners @ rotation.T
    along = np.linspace(0.05, 0.95, 100)[:, None, None]
    return Mesh(corners, box.faces), (corners[one] * (1 - along) + corners[two] * along).reshape(-1, 3)


@pytest.mark.parametrize("turn", [(0, 0, 0), (12, -9, 17)])
def test_the_seams_on_a_boxs_edges_keep_its_edges(turn):
    """Charts part where the surface turns, so the seams of a box lie on its edges, where the
    stitches cut the corner by up to half a cell (0.48-0.52 spacings at the 95th percentile
    before the creases were put back): the rebuild runs along its edges, but near the corners,
    where three charts meet, and is still closed, each edge run once each way, no stitch
    turned over."""
    from mzc.measure.metrics import distance_to_mesh
    from mzc.ops.slicing import slice_surface
    from mzc.ops.triangulation import grid_to_mesh

    mesh, along = box_and_its_edges(turn)
    spacing = 0.05
    grid = slice_surface(mesh, d1=spacing, charts=6)
    rebuilt = grid_to_mesh(grid)
    distance = distance_to_mesh(along, rebuilt.points, rebuilt.triangles) / spacing
    assert len(along) == 1200 and np.percentile(distance, 95) < 0.01 and distance.max() < 0.3
    assert edge_counts(rebuilt.triangles) == (0, 0) and runs_each_edge_once(rebuilt.triangles)
    charted = sum(len(grid_to_mesh(chart, 30.0).triangles) for chart in grid.chart_grids())
    assert folded(rebuilt.points, rebuilt.triangles, charted) == 0


def test_the_dragons_seams_keep_its_creases():
    """The dragon, a coarse closed mesh of 1,634 vertices: its charts part at the creases between
    its facets. With the creases put back, its lossless floor at the default grid holds 98.3%
    of its area within 0.1% of D and a whole-surface RMS under 0.026% D (97.9% and 0.0269% D
    with straight stitches; 20,000 samples each way)."""
    from mzc.measure.metrics import distance_to_mesh, sample_surface, surface_distance

    mesh, rebuilt, diagonal = sliced_shared_object("dragon.ply")
    samples = sample_surface(mesh.points, mesh.triangles, 20_000, np.random.default_rng(0))[0]
    near = np.mean(distance_to_mesh(samples, rebuilt.points, rebuilt.triangles) <= 0.001 * diagonal)
    rms = surface_distance((mesh.points, mesh.triangles), (rebuilt.points, rebuilt.triangles), samples=20_000)["rms"]
    assert near >= 0.983 and rms <= 0.00026 * diagonal
