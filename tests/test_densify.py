"""mzc.ops.densify and ``mzc densify``: analytic solutions, holes, layout, speed and the CLI."""

import time

import numpy as np
import pytest

from mzc.errors import MzcError
from mzc.grid import ZGrid
from mzc.ops.densify import METHODS, densify, densify_grid

D1, D2, N = 3.0, 0.25, 3
STEP = D1 / (N + 1)


def dense_coordinates(rows, cols, step=STEP, d2=D2):
    """(y, x) of a dense grid with ``rows`` original rows and N rows inserted between them."""
    y = np.arange((rows - 1) * (N + 1) + 1)[:, None] * step
    x = np.arange(cols)[None, :] * d2
    return y + 0 * x, x + 0 * y


def sparse(dense_heights):
    """The original rows of a dense grid."""
    return dense_heights[:: N + 1]


def converged(method):
    """Options that run the thesis iteration to convergence (ignored by the direct methods)."""
    return {"iterations": 20_000, "tol": 1e-14} if method == "thesis" else {}


@pytest.mark.parametrize("method", METHODS)
def test_a_plane_is_exact_for_every_method(method):
    y, x = dense_coordinates(8, 50)
    truth = 1.5 + 0.3 * x - 0.7 * y
    result = densify(sparse(truth), N, D1, D2, method=method, **converged(method))
    np.testing.assert_allclose(result, truth, atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_a_bilinear_twist_is_exact_for_every_method(method):
    """x*y is harmonic, has straight sides and zero thin-plate curvature across planes."""
    y, x = dense_coordinates(8, 50)
    truth = 0.2 * x * y
    result = densify(sparse(truth), N, D1, D2, method=method, **converged(method))
    np.testing.assert_allclose(result, truth, atol=1e-9)


def middle_columns(cols, margin):
    """Columns far enough from the straight-line sides that their influence has died out."""
    return slice(margin, cols - margin)


def test_laplace_reproduces_a_function_harmonic_for_the_true_steps():
    y, x = dense_coordinates(8, 241)
    truth = x**2 - y**2
    middle = middle_columns(241, 80)    # side error decays like exp(-pi x / D1): ~1e-9 at 20 mm
    laplace = densify(sparse(truth), N, D1, D2, method="laplace")
    thesis = densify(sparse(truth), N, D1, D2, method="thesis", **converged("thesis"))
    np.testing.assert_allclose(laplace[:, middle], truth[:, middle], atol=1e-6)
    assert np.abs(thesis - truth)[:, middle].max() > 0.1   # equal steps: wrong operator


def test_thesis_reproduces_a_function_harmonic_in_index_space():
    y, x = dense_coordinates(8, 241)
    truth = (x / D2) ** 2 - (y / STEP) ** 2
    middle = middle_columns(241, 80)
    thesis = densify(sparse(truth), N, D1, D2, method="thesis", **converged("thesis"))
    laplace = densify(sparse(truth), N, D1, D2, method="laplace")
    np.testing.assert_allclose(thesis[:, middle], truth[:, middle], atol=1e-6)
    assert np.abs(laplace - truth)[:, middle].max() > 1.0


def test_thesis_stops_after_the_given_iterations_and_starts_from_zero():
    y, x = dense_coordinates(3, 20)
    truth = 10 + 0 * x
    untouched = densify(sparse(truth), N, D1, D2, method="thesis", iterations=0)
    assert np.all(untouched[1:N + 1, 1:-1] == 0)                 # interior starts at 0
    np.testing.assert_array_equal(untouched[1:N + 1, [0, -1]], 10)  # straight-line sides
    one = densify(sparse(truth), N, D1, D2, method="thesis", iterations=1)
    assert one[2, 5] == 0 and one[1, 5] == 2.5                   # one average of 4 neighbours


def test_thesis_tolerance_ends_the_iteration_early():
    y, x = dense_coordinates(6, 80)
    truth = np.sin(x) + y
    loose = densify(sparse(truth), N, D1, D2, method="thesis", iterations=100_000, tol=1e-3)
    tight = densify(sparse(truth), N, D1, D2, method="thesis", iterations=100_000, tol=1e-13)
    exact = densify(sparse(truth), N, D1, D2, method="thesis", iterations=100_000)
    assert 0 < np.abs(loose - exact).max() < 1e-1
    assert np.abs(tight - exact).max() < 1e-11


def test_biharmonic_reproduces_a_cubic_across_planes_away_from_the_far_edge():
    """(y/10)^3 has zero curvature at the first plane, so the thin plate's natural condition
    holds there; at the last plane it does not, and that error shrinks ~4x per plane away
    from it. Laplace bends a cubic wherever it has curvature."""
    y, x = dense_coordinates(30, 41)
    truth = (y / 10) ** 3
    near_first = slice(0, 12 * (N + 1))
    biharmonic = densify(sparse(truth), N, D1, D2, method="biharmonic")
    laplace = densify(sparse(truth), N, D1, D2, method="laplace")
    np.testing.assert_allclose(biharmonic[near_first], truth[near_first], atol=1e-8)
    assert np.abs(laplace - truth)[near_first].max() > 1e-2
    far_error = np.abs(biharmonic - truth).max(axis=1)[2 :: N + 1]
    assert far_error[-1] > 10 * far_error[-3] > 100 * far_error[-5]


def test_biharmonic_is_smooth_across_planes_where_laplace_kinks():
    """Each Laplace gap is solved alone, so the slope across a plane jumps; the thin plate
    bends through the plane like the true surface does."""
    y, x = dense_coordinates(10, 41)
    truth = np.sin(y / 4)
    plane = 5 * (N + 1)

    def curvature_error(method):
        z = densify(sparse(truth), N, D1, D2, method=method)[:, 20] - truth[:, 20]
        return abs(z[plane + 1] - 2 * z[plane] + z[plane - 1])

    assert curvature_error("biharmonic") < 0.05 * curvature_error("laplace")


def thin_plate_minimiser(z, n, step, d2):
    """Dense grid minimising the thin-plate energy, by dense least squares over explicit stencil loops."""
    dense = np.full(((len(z) - 1) * (n + 1) + 1, z.shape[1]), np.nan)
    dense[:: n + 1] = z
    both = ~np.isnan(z[:-1]) & ~np.isnan(z[1:])
    for i in range(1, n + 1):
        dense[i :: n + 1][: len(both)][both] = 0.0
    inserted = [node for node in zip(*np.nonzero(~np.isnan(dense))) if node[0] % (n + 1)]
    unknown = {node: k for k, node in enumerate(inserted)}
    stencils = [([(0, -1), (0, 0), (0, 1)], [1, -2, 1], d2**-2),
                ([(-1, 0), (0, 0), (1, 0)], [1, -2, 1], step**-2),
                ([(0, 0), (0, 1), (1, 0), (1, 1)], [1, -1, -1, 1], np.sqrt(2) / (step * d2))]
    matrix, rhs = [], []
    for r in range(dense.shape[0]):
        for c in range(dense.shape[1]):
            for offsets, coefficients, scale in stencils:
                nodes = [(r + dr, c + dc) for dr, dc in offsets]
                if not all(0 <= a < dense.shape[0] and 0 <= b < dense.shape[1]
                           and not np.isnan(dense[a, b]) for a, b in nodes):
                    continue
                line, known = np.zeros(len(unknown)), 0.0
                for node, coefficient in zip(nodes, coefficients):
                    if node in unknown:
                        line[unknown[node]] += scale * coefficient
                    else:
                        known += scale * coefficient * dense[node]
                matrix.append(line)
                rhs.append(-known)
    solution = np.linalg.lstsq(np.array(matrix), np.array(rhs), rcond=None)[0]
    for node, k in unknown.items():
        dense[node] = solution[k]
    return dense


@pytest.mark.parametrize("n", [1, 2, 3])
def test_biharmonic_minimises_the_thin_plate_energy_with_holes(n):
    """The assembled normal equations match a plain least-squares solve of the stencils."""
    rng = np.random.default_rng(7)
    z = rng.normal(size=(5, 14))
    z[1, 4:6] = np.nan       # interior holes split gaps into runs
    z[3, 9] = np.nan
    z[0, :3] = np.nan        # ragged edges
    z[4, 11:] = np.nan
    step = D1 / (n + 1)
    result = densify(z, n, D1, D2, method="biharmonic")
    np.testing.assert_allclose(result, thin_plate_minimiser(z, n, step, D2), atol=1e-9, equal_nan=True)


@pytest.mark.parametrize("method", ["biharmonic", "laplace"])
@pytest.mark.parametrize("scale", [2.0 ** -540, 2.0 ** 300, 1e-162])
def test_heights_of_any_size_densify_as_the_same_numbers_scaled(method, scale):
    """Densifying is linear in the heights and works at the ends of the floats' range: heights of
    about 1e-162 once made the biharmonic's conjugate gradients divide by an inner product
    underflowed to 0. Scaled by a power of two, the dense grid is the same numbers, scaled."""
    rng = np.random.default_rng(3)
    z = rng.normal(size=(6, 25)).cumsum(axis=1)
    z[2, 5:9] = np.nan
    unit = densify(z, N, D1, D2, method=method)
    scaled = densify(z * scale, N, D1, D2, method=method)
    if np.log2(scale).is_integer():
        np.testing.assert_array_equal(scaled, unit * scale)
    else:
        np.testing.assert_allclose(scaled / scale, unit, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_holes_stay_holes_and_original_rows_are_untouched(method):
    rng = np.random.default_rng(1)
    z = rng.normal(size=(6, 40))
    z[2, 10:15] = np.nan     # an interior hole in one row
    z[4, :8] = np.nan        # a ragged edge
    z[0, 30:] = np.nan
    result = densify(z, N, D1, D2, method=method)
    assert result.shape == ((6 - 1) * (N + 1) + 1, 40)
    np.testing.assert_array_equal(result[:: N + 1], z)
    valid = ~np.isnan(z)
    both = valid[:-1] & valid[1:]
    inserted_valid = ~np.isnan(np.delete(result, np.s_[:: N + 1], axis=0)).reshape(5, N, 40)
    np.testing.assert_array_equal(inserted_valid, np.repeat(both[:, None, :], N, axis=1))


def holey_grid(rows, cols, seed):
    """A smooth random surface with ragged edges, interior holes (some spanning several rows)
    and random depth-jump breaks: (z, breaks)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[:rows, :cols]
    z = np.sin(x / 7 + rng.uniform(0, 6)) * np.cos(y / 5) * 20 + rng.normal(scale=0.3, size=(rows, cols))
    z[((x - cols / 2) / (cols / 2)) ** 2 + ((y - rows / 2) / (rows / 2)) ** 2 > 1.1] = np.nan
    for r, c, radius in zip(rng.integers(0, rows, 6), rng.integers(0, cols, 6), rng.uniform(0.5, 3, 6)):
        z[(y - r) ** 2 + (x - c) ** 2 <= radius**2] = np.nan
    z[5:9, 10] = np.nan       # a hole across several strip boundaries
    breaks = rng.random((rows - 1, cols)) < 0.02, rng.random((rows, cols - 1)) < 0.02
    return z, breaks


@pytest.mark.parametrize("method", ["thesis", "laplace"])
@pytest.mark.parametrize("gaps_a_strip", [1, 2, 5])
def test_strips_of_independent_gaps_equal_the_whole_grid_exactly(method, gaps_a_strip):
    """thesis (fixed sweeps) and laplace solve each gap alone: strips change no bit."""
    z, breaks = holey_grid(23, 31, 3)
    whole = densify(z, N, D1, D2, method=method, breaks=breaks)
    stripped = densify(z, N, D1, D2, method=method, breaks=breaks, strip=gaps_a_strip * N * 31)
    np.testing.assert_array_equal(stripped, whole)


def test_thesis_with_a_tolerance_is_one_strip():
    """Its sweeps stop when no node of the whole grid moves by tol: strips would stop earlier."""
    z, breaks = holey_grid(23, 31, 4)
    whole = densify(z, N, D1, D2, method="thesis", tol=1e-3, breaks=breaks)
    np.testing.assert_array_equal(densify(z, N, D1, D2, method="thesis", tol=1e-3, breaks=breaks, strip=1), whole)


@pytest.mark.parametrize("n", [1, 3, 7])
@pytest.mark.parametrize("gaps_a_strip", [1, 4, 10])
def test_biharmonic_strips_equal_the_whole_grid_within_its_tolerance(n, gaps_a_strip):
    """The halo brings every strip to the whole-grid solve within the solve's own tolerance."""
    z, breaks = holey_grid(80, 37, 5)
    whole = densify(z, n, D1, D2, breaks=breaks)
    stripped = densify(z, n, D1, D2, breaks=breaks, strip=gaps_a_strip * n * 37)
    np.testing.assert_array_equal(np.isnan(stripped), np.isnan(whole))
    np.testing.assert_array_equal(stripped[:: n + 1], z)
    np.testing.assert_allclose(stripped, whole, rtol=0, atol=1e-10 * np.nanmax(np.abs(z)))


def test_a_grid_within_one_strip_is_solved_whole():
    """The default strip holds a face (golden outputs unchanged): equal to a huge strip bit for bit."""
    z, breaks = holey_grid(80, 37, 6)
    np.testing.assert_array_equal(densify(z, 3, D1, D2, breaks=breaks), densify(z, 3, D1, D2, breaks=breaks,
                                                                                 strip=10**12))


@pytest.mark.parametrize("method", METHODS)
def test_rows_that_do_not_overlap_insert_nothing(method):
    z = np.full((3, 30), np.nan)
    z[0, :10] = 1.0
    z[1, 15:] = 2.0
    z[2, 15:] = 3.0
    result = densify(z, 2, D1, D2, method=method)
    assert np.isnan(result[1:3]).all()
    assert not np.isnan(result[4:6, 15:]).any()


@pytest.mark.parametrize("method", METHODS)
def test_n_zero_is_the_identity_and_one_row_stays_one_row(method):
    z = np.arange(12.0).reshape(3, 4)
    np.testing.assert_array_equal(densify(z, 0, D1, D2, method=method), z)
    np.testing.assert_array_equal(densify(z[:1], 5, D1, D2, method=method), z[:1])


@pytest.mark.parametrize("bad", [-1, 1.5, True, "3"])
def test_bad_n_is_refused(bad):
    with pytest.raises(MzcError) as error:
        densify(np.zeros((3, 3)), bad, D1, D2)
    assert error.value.field == "n"


def test_unknown_method_is_refused():
    with pytest.raises(MzcError):
        densify(np.zeros((3, 3)), 1, D1, D2, method="spline")


def test_densify_grid_divides_the_row_step_and_keeps_the_frame():
    grid = ZGrid(np.zeros((5, 7)), 3.0, 0.5, origin=(1.0, 2.0), units="mm")
    dense = densify_grid(grid, 2, "laplace")
    assert dense.shape == (13, 7)
    assert dense.d1 == pytest.approx(1.0) and dense.d2 == 0.5
    assert dense.origin == (1.0, 2.0) and dense.units == "mm"
    np.testing.assert_allclose(dense.ys()[::3], grid.ys())


@pytest.mark.parametrize("method", METHODS)
def test_a_face_sized_grid_densifies_quickly(method):
    y, x = dense_coordinates(70, 670)
    truth = np.sin(x / 10) * np.cos(y / 15) * 20
    outside = ((x - 84) / 84) ** 2 + ((y - 104) / 104) ** 2 > 1
    z = sparse(np.where(outside, np.nan, truth))
    densify(z, N, D1, D2, method=method)
    started = time.process_time()
    densify(z, N, D1, D2, method=method)
    assert time.process_time() - started < 1.0   # CPU: ~0.07 s thesis/laplace, ~0.10 s biharmonic here


def test_face_densified_is_close_to_the_face_sliced_densely(f18):
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    mesh = read_mesh(f18)
    sparse_grid = slice_surface(mesh, d1=3, d2=0.25, projection="planar")
    truth = slice_surface(mesh, d1=0.75, d2=0.25, projection="planar").z
    errors = {}
    for method in METHODS:
        dense = densify_grid(sparse_grid, 3, method).z
        rows = min(len(dense), len(truth))
        errors[method] = np.sqrt(np.nanmean((dense[:rows] - truth[:rows]) ** 2))
    assert errors["biharmonic"] < errors["thesis"] < errors["laplace"] < 1.5


# --------------------------------------------------------------------------- CLI


def zgrid_bytes(z, d1=D1, d2=D2):
    from mzc.formats import zgrid

    return zgrid.write(ZGrid(np.asarray(z, dtype=float), d1, d2))


def test_cli_densifies_stdin_to_stdout(mzc):
    from mzc.formats import read_any

    y, x = dense_coordinates(5, 12)
    truth = 2 + 0.5 * x - y
    result = mzc("densify", "-n", "3", input=zgrid_bytes(sparse(truth)), check=True)
    grid = read_any(result.stdout, "<stdout>")
    assert grid.shape == truth.shape and grid.d1 == pytest.approx(STEP)
    np.testing.assert_allclose(grid.z, truth, atol=1e-6)


@pytest.mark.parametrize("bad", ["-1", "x", "1.5"])
def test_cli_bad_n_is_a_usage_error(mzc, bad):
    result = mzc("densify", "-n", bad, input=zgrid_bytes(np.zeros((2, 2))))
    assert result.returncode == 2 and result.stdout == b""


def test_cli_bad_file_is_one_line(mzc, tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("not a grid\n")
    result = mzc("densify", "-n", "2", path, "-o", tmp_path / "out.zg")
    assert result.returncode == 1
    assert len(result.stderr.decode().strip().splitlines()) == 1
    assert not (tmp_path / "out.zg").exists()


def test_the_plate_kernels_check_their_buffers_and_refuse_what_is_not_positive_definite():
    """mzc.ops._plate checks every buffer's size and every unknown number before use (a
    mismatch is a ValueError, never a stray write), and its Cholesky factor names the row
    where a band is not positive definite, which densify reports as one MzcError."""
    from mzc.ops import _plate
    from mzc.ops.densify import band_factor

    band = np.zeros((4, 3))
    band[:, 0] = 2.0
    band[1:, 1] = -1.0                                   # the second difference matrix: SPD
    x = np.arange(4.0)
    out = np.empty(4)
    _plate.product(band, 2, x, out)
    np.testing.assert_array_equal(out, [-1.0, 0.0, 0.0, 4.0])
    factor = band_factor(band.copy())
    _plate.solve(factor, 2, out)
    np.testing.assert_allclose(out, x, atol=1e-12)
    for call in (lambda: _plate.solve(factor, 2, np.empty(5)), lambda: _plate.product(band, 2, x, np.empty(3)),
                 lambda: _plate.product(band, 2, x, x), lambda: _plate.cholesky(np.empty((4, 2)), 2),
                 lambda: _plate.cholesky(np.empty(12, dtype=np.float32), 2)):
        with pytest.raises(ValueError):
            call()
    z, first = np.zeros((3, 4)), np.array([[0, 3, -1, 6], [9, 12, 15, 18]], dtype=np.int64)
    ok = np.ones((3, 3), dtype=np.uint8)
    out_band, rhs = np.empty((21, 7)), np.empty(21)
    _plate.plate(z, first, ok, ok[:2], 2, 4, 3, (1.0, 1.0, 1.0), out_band, rhs)
    for bad in (first + 1, np.where(first == 18, 19, first), np.where(first == 0, -2, first)):
        with pytest.raises(ValueError):
            _plate.plate(z, bad, ok, ok[:2], 2, 4, 3, (1.0, 1.0, 1.0), out_band, rhs)
    singular = band.copy()
    singular[2, 0] = -1.0
    with pytest.raises(MzcError, match="singular at unknown 2"):
        band_factor(singular)
