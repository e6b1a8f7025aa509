"""The distance and error measures that diff and the benchmarks trust."""

import numpy as np
import pytest

from mzc.grid import ZGrid
from mzc.measure.metrics import distance_to_mesh, grid_error_stats, surface_distance
from mzc.ops.triangulation import grid_to_mesh


def point_triangle_distance(p, a, b, c):
    """Distance from each point p[i] to the triangle (a[i], b[i], c[i]), all (n, 3), by the
    distance search's own formula: the search over a mesh of that one triangle."""
    return np.array([distance_to_mesh(p[i:i + 1], np.stack([a[i], b[i], c[i]]), [[0, 1, 2]])[0]
                     for i in range(len(p))])


def brute_force_distance(p, a, b, c, steps=300):
    """Distance to a dense sampling of each triangle: an upper bound that converges to the truth."""
    best = np.full(len(p), np.inf)
    for u in np.linspace(0, 1, steps):
        for v in np.linspace(0, 1 - u, max(2, int(steps * (1 - u)))):
            best = np.minimum(best, np.linalg.norm(p - (a + u * (b - a) + v * (c - a)), axis=1))
    return best


def test_point_triangle_distance_matches_brute_force():
    rng = np.random.default_rng(3)
    p, a, b, c = (rng.normal(size=(500, 3)) for _ in range(4))
    exact = point_triangle_distance(p, a, b, c)
    reference = brute_force_distance(p, a, b, c)
    assert (exact <= reference + 1e-12).all()
    assert np.abs(exact - reference).max() < 0.01


def test_point_triangle_distance_known_regions():
    a, b, c = np.array([[0, 0, 0.0]]), np.array([[1, 0, 0.0]]), np.array([[0, 1, 0.0]])
    cases = {(0.2, 0.2, 3): 3, (-1, -1, 0): np.sqrt(2), (0.5, -2, 0): 2, (1, 1, 0): np.sqrt(0.5)}
    for point, expected in cases.items():
        assert point_triangle_distance(np.array([point], float), a, b, c)[0] == pytest.approx(expected)


def plane_mesh(shift=0.0, size=20):
    y, x = np.mgrid[0:size, 0:size].astype(float)
    mesh = grid_to_mesh(ZGrid(0.1 * x + 0.05 * y + shift, 1, 1))
    return mesh.points, mesh.triangles


def test_a_mesh_against_itself_is_zero():
    mesh = plane_mesh()
    result = surface_distance(mesh, mesh, samples=5000)
    assert result["rms"] < 1e-12 and result["hausdorff"] < 1e-12


def test_a_shift_in_z_is_measured_as_the_normal_distance():
    shifted = surface_distance(plane_mesh(), plane_mesh(0.1), samples=5000)
    normal_distance = 0.1 / np.sqrt(1 + 0.1**2 + 0.05**2)
    # Interior samples see the normal distance; samples near the border see a little more.
    assert shifted["rms"] == pytest.approx(normal_distance, rel=0.05)


def test_grid_error_stats_on_a_known_error():
    reference = np.array([[0.0, 1.0], [2.0, np.nan]])
    other = reference + np.array([[0.1, -0.1], [0.1, 5.0]])
    stats = grid_error_stats(reference, other)
    assert stats["count"] == 3
    assert stats["rmse"] == pytest.approx(0.1) and stats["max"] == pytest.approx(0.1)
    assert stats["bias"] == pytest.approx(0.1 / 3)
    assert stats["r2"] == pytest.approx(1 - 0.03 / 2)


def test_zero_area_triangles_are_measured_as_their_edges():
    a = np.array([[0, 0, 0.0], [0, 0, 0.0]])
    b = np.array([[2, 0, 0.0], [0, 0, 0.0]])
    c = np.array([[1, 0, 0.0], [0, 0, 0.0]])  # a collinear triangle, and one collapsed to a point
    p = np.array([[1, 1, 0.0], [3, 4, 0.0]])
    np.testing.assert_allclose(point_triangle_distance(p, a, b, c), [1, 5])
