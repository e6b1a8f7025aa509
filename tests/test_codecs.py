"""Numerics of the per-row codecs: round trips, quality behaviour, holes, polynomial bases."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.codecs.rows import dct, dft, dwt, poly, spans
from mzc.codecs.rows import transforms as T
from mzc.formats import read_any
from mzc.grid import ZGrid

from conftest import face_path

TRANSFORM_CODECS = [(dct, {}), (dft, {}), (dwt, {}), (dwt, {"wavelet": "db4", "level": 5})]


def generated_grid(seed=0, rows=12, cols=90):  # cols >= 61
    """A smooth-plus-noise grid with ragged spans, holes, an empty row and a one-node row."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0, 3, cols)
    z = 50 + 10 * np.sin(x)[None, :] + np.cumsum(rng.normal(0, 0.1, (rows, cols)), axis=1)
    z[0, :7] = np.nan
    z[1, 30:34] = np.nan
    z[1, 50] = np.nan
    z[2] = np.nan
    z[3, :-1] = np.nan
    z[4, 60:] = np.nan
    z[5, 2:4] = np.nan
    z[5, 20:] = np.nan
    return ZGrid(z, 3.0, 0.25)


@pytest.fixture(scope="module")
def face_grid():
    """f18 sliced like the thesis: rows 3 mm apart, columns 0.25 mm."""
    from mzc.meshes import read_mesh
    from mzc.ops.slicing import slice_surface

    return slice_surface(read_mesh(face_path("f18.ply")), d1=3, d2=0.25, projection="planar")


def round_trip(module, grid, **options):
    """Decode(encode(grid)), checking the invalid nodes are exactly the input's."""
    decoded = read_any(module.write(grid, **options), "test").z
    np.testing.assert_array_equal(np.isnan(decoded), np.isnan(grid.z))
    return decoded


def rmse(a, b):
    return float(np.sqrt(np.nanmean((a - b) ** 2)))


@pytest.mark.parametrize("module, options", TRANSFORM_CODECS)
def test_quality_100_round_trips_generated_grid(module, options):
    grid = generated_grid()
    decoded = round_trip(module, grid, quality=100, **options)
    assert np.nanmax(np.abs(decoded - grid.z)) < 1e-3


@pytest.mark.parametrize("module, options", TRANSFORM_CODECS)
def test_quality_100_round_trips_face(face_grid, module, options):
    # The DFT series is not orthonormal: rounding error grows like sqrt(L) (spec/dft.md),
    # so its 700-sample rows need 5 decimals to stay within 1e-3.
    precision = 5 if module is dft else 4
    decoded = round_trip(module, face_grid, quality=100, precision=precision, **options)
    assert np.nanmax(np.abs(decoded - face_grid.z)) < 1e-3


@pytest.mark.parametrize("basis", ["chebyshev", "power"])
def test_polynomial_of_full_degree_round_trips_short_rows(basis):
    z = generated_grid().z[:, :9].copy()
    z[6, 3] = z[7, 5:7] = np.nan
    grid = ZGrid(z, 3.0, 0.25)
    decoded = round_trip(poly, grid, degree=8, basis=basis)
    assert np.nanmax(np.abs(decoded - grid.z)) < 1e-3


@pytest.mark.parametrize("length", [1, 2, 3, 4, 7, 8, 63, 64])
def test_dft_exact_for_odd_and_even_lengths(length):
    signal = np.random.default_rng(length).normal(size=(2, length))
    restored = T.dft_inverse(*T.dft_forward(signal), length)
    np.testing.assert_allclose(restored, signal, atol=1e-12)


@pytest.mark.parametrize("wavelet", ["db1", "db2", "sym4"])
@pytest.mark.parametrize("length", [1, 2, 5, 8, 13, 100])
def test_dwt_lengths_vector_and_inverse(wavelet, length):
    signal = np.random.default_rng(length).normal(size=length)
    lengths = T.dwt_lengths(length, wavelet, 3)
    coefficients = T.dwt_forward(signal, wavelet, 3)
    assert coefficients.size == sum(lengths[:-1]) and lengths[-1] == length
    np.testing.assert_allclose(T.dwt_inverse(coefficients, lengths, wavelet), signal, atol=1e-10)


def test_dwt_drops_finest_details_first():
    signal = np.random.default_rng(1).normal(size=64)
    grid = ZGrid(signal[None, :], 1, 1)
    lengths = T.dwt_lengths(64)  # [8, 8, 16, 32, 64]
    # Q = 50 keeps 28 of the 56 details: A3, D3 and the first 12 of D2; D1 is gone.
    decoded = read_any(dwt.write(grid, quality=50, precision=17), "t").z[0]
    kept = T.dwt_forward(signal)
    kept[lengths[0] + 28:] = 0
    np.testing.assert_allclose(decoded, T.dwt_inverse(kept, lengths), atol=1e-12)


def test_fill_holes_is_linear_across_the_hole():
    filled = T.fill_holes(np.array([1.0, np.nan, np.nan, 4.0, np.nan, 8.0]))
    np.testing.assert_allclose(filled, [1, 2, 3, 4, 6, 8])


def expected_lossy(module, span, quality):
    """What the transform layer alone gives for a span at ``quality`` (the format's oracle)."""
    m = span.size
    if module is dct:
        return T.dct_inverse(T.dct_forward(span)[:T.kept(quality, m)], m)
    if module is dft:
        a0, a_last, an, bn = T.dft_forward(span)
        count = T.kept(quality, an.size)
        return T.dft_inverse(a0, a_last, an[:count], bn[:count], m)
    lengths = T.dwt_lengths(m)
    coefficients = T.dwt_forward(span)
    coefficients[lengths[0] + T.kept(quality, sum(lengths[1:-1])):] = 0
    return T.dwt_inverse(coefficients, lengths)


@st.composite
def grids(draw):
    """Small random grids with random invalid nodes (holes, empty rows, short spans)."""
    rows = draw(st.integers(1, 5))
    cols = draw(st.integers(1, 24))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    z = rng.uniform(-50, 50, (rows, cols))
    z[rng.random((rows, cols)) < draw(st.floats(0, 0.6))] = np.nan
    return ZGrid(z, 1.5, 0.5)


@settings(max_examples=60, deadline=None)
@given(grid=grids(), quality=st.integers(1, 100), module=st.sampled_from([dct, dft, dwt]))
def test_any_quality_decodes_as_the_transform_says_and_keeps_holes(grid, quality, module):
    decoded = round_trip(module, grid, quality=quality, precision=10)
    first, last = spans(grid.z)
    for r in np.flatnonzero(first >= 0):
        span = T.fill_holes(grid.z[r, first[r]:last[r] + 1])
        expected = expected_lossy(module, span, quality)
        valid = ~np.isnan(grid.z[r, first[r]:last[r] + 1])
        np.testing.assert_allclose(decoded[r, first[r]:last[r] + 1][valid], expected[valid], atol=1e-6)


@settings(max_examples=30, deadline=None)
@given(grid=grids(), degree=st.integers(0, 30), basis=st.sampled_from(["chebyshev", "power"]))
def test_polynomial_keeps_holes_at_any_degree(grid, degree, basis):
    round_trip(poly, grid, degree=degree, basis=basis)


@pytest.mark.parametrize("module", [dct, dft, dwt])
def test_error_shrinks_and_size_grows_with_quality_on_a_face(face_grid, module):
    qualities = [5, 10, 20, 50, 100]
    files = [module.write(face_grid, quality=q) for q in qualities]
    errors = [rmse(read_any(f, "t").z, face_grid.z) for f in files]
    sizes = [len(f) for f in files]
    assert sizes == sorted(sizes) and len(set(sizes)) == len(sizes)
    assert all(later <= earlier for earlier, later in zip(errors, errors[1:]))
    assert errors[-1] < 1e-3 < errors[0]


def test_chebyshev_degree_30_fits_where_thesis_power_coefficients_blow_up(face_grid):
    first, last = spans(face_grid.z)
    r = int(np.argmax(last - first))
    span = T.fill_holes(face_grid.z[r, first[r]:last[r] + 1])
    m = span.size
    chebyshev = T.poly_inverse(np.round(T.poly_forward(span, 30), 4), m)
    power = T.poly_forward(span, 30, "power", first[r] + 1, face_grid.d2)
    as_thesis_saved = np.array([float(f"{c:.7e}") for c in power])  # MATLAB save -ASCII
    power_error = np.sqrt(np.mean((T.poly_inverse(as_thesis_saved, m, "power", first[r] + 1,
                                                  face_grid.d2) - span) ** 2))
    chebyshev_error = np.sqrt(np.mean((chebyshev - span) ** 2))
    assert chebyshev_error < 5 and power_error > 100 * chebyshev_error


def test_polynomial_error_shrinks_with_degree_on_a_face(face_grid):
    errors = [rmse(read_any(poly.write(face_grid, degree=d), "t").z, face_grid.z) for d in (5, 10, 20, 40)]
    assert errors == sorted(errors, reverse=True)
