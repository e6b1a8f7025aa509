"""The exact point-to-mesh distance against an independent reference: Ericson's closest
point on a triangle, one point and one triangle at a time, minimised over every triangle."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.measure.metrics import distance_to_mesh

from conftest import face_path


def closest_on_triangle(p, a, b, c):
    """Ericson's ClosestPtPointTriangle (Real-Time Collision Detection, 5.1.5) for one point;
    a zero-area triangle is the nearest point of its three edges."""
    ab, ac, ap = b - a, c - a, p - a
    if np.linalg.norm(np.cross(ab, ac)) == 0:
        return min((closest_on_segment(p, x, y) for x, y in ((a, b), (b, c), (c, a))),
                   key=lambda q: np.linalg.norm(p - q))
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return a
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + d1 / (d1 - d3) * ab
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    denom = 1 / (va + vb + vc)
    return a + ab * (vb * denom) + ac * (vc * denom)


def closest_on_segment(p, a, b):
    """The nearest point of segment a-b (maybe a single point) to p."""
    ab = b - a
    length2 = ab @ ab
    return a if length2 == 0 else a + min(max((p - a) @ ab / length2, 0), 1) * ab


def reference_distance(samples, points, triangles):
    """The distance of each sample to its nearest triangle, by looking at every triangle."""
    return np.array([min(np.linalg.norm(p - closest_on_triangle(p, *points[t])) for t in triangles) for p in samples])


def point_triangle_distance(p, a, b, c):
    """Exact distance from points p to triangles (a, b, c), all (n, 3), vectorised over the
    pairs: the formula that the C search evaluates one pair at a time, in numpy. When p
    projects into the triangle (on the inner side of its three edges) the distance is to
    its plane, else to the nearest of its three edges; a zero-area triangle is only its
    edges (a segment, or a point)."""
    p, a, b, c = (np.asarray(x, dtype=float).T for x in (p, a, b, c))
    ab, bc, ca = b - a, c - b, a - c
    ap, bp, cp = p - a, p - b, p - c
    normal = cross(ab, -ca)
    norm2 = dot(normal, normal)
    inside = norm2 > 0
    for edge, start in ((ab, ap), (bc, bp), (ca, cp)):
        inside &= dot(cross(edge, start), normal) >= 0
    squared = np.minimum.reduce([segment_distance2(ap, ab), segment_distance2(bp, bc), segment_distance2(cp, ca)])
    with np.errstate(divide="ignore", invalid="ignore"):
        plane = dot(ap, normal) ** 2 / norm2
    return np.sqrt(np.where(inside, plane, squared))


def segment_distance2(start, edge):
    """Squared distance from points to segments a + t edge (t in [0, 1]), given start = p - a;
    components (3, n). A zero-length segment is its point."""
    length2 = dot(edge, edge)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(length2 > 0, np.clip(dot(start, edge) / length2, 0, 1), 0.0)
    offset = start - t * edge
    return dot(offset, offset)


def dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def cross(u, v):
    return np.stack([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]])


coordinate = st.integers(-4, 4).map(float)
corner = st.tuples(coordinate, coordinate, coordinate)


@st.composite
def mesh_and_samples(draw):
    """A small random mesh on a coarse lattice (so repeated corners, collinear and collapsed
    triangles come often) and samples: its corners, edge midpoints, points on its triangles,
    random points near it and points far away."""
    points = np.array(draw(st.lists(corner, min_size=3, max_size=12)))
    count = draw(st.integers(1, 16))
    triangles = np.array(draw(st.lists(st.tuples(*[st.integers(0, len(points) - 1)] * 3),
                                       min_size=count, max_size=count)))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    corners = points[triangles]
    weights = rng.dirichlet(np.ones(3), size=len(triangles))
    samples = np.concatenate([points, (corners[:, 0] + corners[:, 1]) / 2, np.einsum("tk,tkd->td", weights, corners),
                              rng.uniform(-6, 6, size=(10, 3)), rng.normal(size=(3, 3)) * 1e3])
    return points, triangles, samples


@settings(max_examples=300, deadline=None)
@given(mesh_and_samples())
def test_distance_to_mesh_equals_the_reference_on_every_sample(case):
    points, triangles, samples = case
    expected = reference_distance(samples, points, triangles)
    np.testing.assert_allclose(distance_to_mesh(samples, points, triangles), expected, rtol=1e-9, atol=1e-9)


def test_distance_to_a_fine_mesh_equals_the_reference():
    """Many small triangles (a wavy sheet, one collapsed) and samples on and off it: the
    spatial search must find the nearest of thousands of triangles."""
    from mzc.grid import ZGrid
    from mzc.ops.triangulation import grid_to_mesh

    y, x = np.mgrid[0:25, 0:30].astype(float)
    mesh = grid_to_mesh(ZGrid(np.sin(x / 3) * np.cos(y / 4) * 2, 0.5, 0.5))
    points, triangles = mesh.points, mesh.triangles.copy()
    triangles[7] = triangles[7, 0]
    rng = np.random.default_rng(5)
    samples = np.concatenate([points[::37], rng.uniform(points.min(axis=0) - 3, points.max(axis=0) + 3, (150, 3))])
    np.testing.assert_allclose(distance_to_mesh(samples, points, triangles),
                               reference_distance(samples, points, triangles), rtol=1e-9, atol=1e-12)


@st.composite
def mixed_sizes(draw):
    """Triangles of sizes from 1e-3 to 1e2 scattered over one region (tiny ones next to
    giant ones, some collapsed to a segment or a point) and samples on and around them:
    the radius groups and their bounds must still find every nearest triangle."""
    seed = draw(st.integers(0, 2**32 - 1))
    count = draw(st.integers(1, 40))
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-5, 5, size=(count, 1, 3))
    corners = centres + rng.normal(size=(count, 3, 3)) * 10.0 ** rng.uniform(-3, 2, size=(count, 1, 1))
    collapse = rng.random(count)
    corners[collapse < 0.1, 2] = corners[collapse < 0.1, 1]
    corners[collapse < 0.05, 1] = corners[collapse < 0.05, 0]
    points, triangles = corners.reshape(-1, 3), np.arange(3 * count).reshape(count, 3)
    weights = rng.dirichlet(np.ones(3), size=count)
    samples = np.concatenate([np.einsum("tk,tkd->td", weights, corners), rng.uniform(-8, 8, size=(20, 3)),
                              rng.normal(size=(3, 3)) * 1e4])
    return points, triangles, samples


@settings(max_examples=200, deadline=None)
@given(mixed_sizes())
def test_distance_to_mesh_with_very_different_triangle_sizes_equals_the_reference(case):
    points, triangles, samples = case
    np.testing.assert_allclose(distance_to_mesh(samples, points, triangles),
                               reference_distance(samples, points, triangles), rtol=1e-9, atol=1e-9)


def test_the_distances_do_not_depend_on_which_samples_come_along():
    """The samples are searched in Morton order, each from the previous one's nearest
    triangle: any subset, in any order, gets the same distances and nearest triangles."""
    from mzc.grid import ZGrid
    from mzc.measure.metrics import nearest_triangles
    from mzc.ops.triangulation import grid_to_mesh

    y, x = np.mgrid[0:20, 0:20].astype(float)
    mesh = grid_to_mesh(ZGrid(np.sin(x / 3) * np.cos(y / 4) * 2, 0.5, 0.5))
    rng = np.random.default_rng(8)
    samples = rng.uniform(mesh.points.min(axis=0) - 2, mesh.points.max(axis=0) + 2, (300, 3))
    distances, nearest = nearest_triangles(samples, mesh.points, mesh.triangles)
    some = rng.permutation(300)[:77]
    np.testing.assert_array_equal(distance_to_mesh(samples[some], mesh.points, mesh.triangles), distances[some])
    corners = mesh.points[mesh.triangles[nearest]]
    np.testing.assert_array_equal(point_triangle_distance(samples, *corners.transpose(1, 0, 2)), distances)


def test_distance_from_a_face_to_another_equals_every_triangle_looked_at():
    """Samples of f18 against the 59,697 triangles of m18, each measured against all of them."""
    from mzc.measure.metrics import sample_surface
    from mzc.meshes import read_mesh

    a, b = read_mesh(face_path("f18.ply")), read_mesh(face_path("m18.ply"))
    samples, _ = sample_surface(a.points, a.triangles, 60, np.random.default_rng(2))
    corners = b.points[b.triangles]
    expected = [point_triangle_distance(np.broadcast_to(p, (len(corners), 3)), *corners.transpose(1, 0, 2)).min()
                for p in samples]
    np.testing.assert_allclose(distance_to_mesh(samples, b.points, b.triangles), expected, rtol=1e-12)


def test_the_figures_of_two_faces_are_those_of_the_method_before_the_kd_tree_rewrite():
    """f18 against m18, 20,000 samples per side, seed 3: the figures main's method gave
    (candidates from query_ball_point lists) before the counted nearest-centroid search."""
    from mzc.measure.metrics import surface_distance
    from mzc.meshes import read_mesh

    a, b = read_mesh(face_path("f18.ply")), read_mesh(face_path("m18.ply"))
    figures = surface_distance((a.points, a.triangles), (b.points, b.triangles), samples=20_000, seed=3)
    expected = {"samples": 40000, "rms": 1.3161264207561567, "mean": 1.0414593143173285,
                "hausdorff": 4.89414476618984, "a_to_b_rms": 1.3164771625159952,
                "a_to_b_mean": 1.0384913195241123, "a_to_b_hausdorff": 4.89414476618984,
                "b_to_a_rms": 1.3157755855003006, "b_to_a_mean": 1.0444273091105452,
                "b_to_a_hausdorff": 3.9609337752819864}
    assert figures.keys() == expected.keys()
    for key, value in expected.items():
        assert figures[key] == pytest.approx(value, rel=1e-9), key


def test_the_search_refuses_indices_and_buffers_that_do_not_fit():
    """The C search checks every corner index and every buffer's size before it reads or
    writes: a bad one is refused and nothing is written."""
    from mzc.errors import MzcError
    from mzc.measure import _nearest

    points, samples = np.eye(3), np.ones((2, 3))
    for corner in (3, -1):
        with pytest.raises(MzcError, match="refers to a vertex that does not exist"):
            distance_to_mesh(samples, points, [[0, 1, 2], [0, corner, 1]])
    triangle = np.array([[0, 1, 2]])
    for arguments in [(points.ravel()[:7], triangle, samples), (points, triangle.ravel()[:2], samples),
                      (points, triangle, samples.ravel()[:5])]:
        distances, nearest = np.full(2, 7.0), np.full(2, 7)
        assert _nearest.nearest(*arguments, distances, nearest) == 1
        assert (distances == 7).all() and (nearest == 7).all()
    for distances, nearest in [(np.empty(3), np.empty(2, dtype=np.int64)), (np.empty(2), np.empty(1, dtype=np.int64))]:
        assert _nearest.nearest(points, triangle, samples, distances, nearest) == 1


def test_an_empty_mesh_is_infinitely_far():
    from mzc.measure.metrics import nearest_triangles

    distances, nearest = nearest_triangles(np.ones((2, 3)), np.eye(3), np.empty((0, 3), dtype=np.int64))
    assert np.isinf(distances).all() and (nearest == -1).all()
