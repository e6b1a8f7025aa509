"""mzc's own arithmetic (spec/arithmetic.md): elementary functions within 1-2 ulp of the C
library's, with the C library's special values and symmetries; eigenvectors, least squares
and products without BLAS or LAPACK, as accurate as numpy's. That these give the same bits
on every machine is tests/test_unchanged_outputs.py's to show (numpy's loops switched off)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc import elementary
from mzc.codecs.rows.transforms import least_squares
from mzc.vectors import determinant, inner, length, matrix_product, symmetric_eigen

RNG = np.random.default_rng(27)
FINITE = st.floats(allow_nan=False, allow_infinity=False)


def ulps(got, expected):
    """|got - expected| in units of the last place of ``expected``."""
    expected = np.asarray(expected, dtype=float)
    return np.abs(np.asarray(got) - expected) / np.spacing(np.abs(expected))


def library(function, *arrays):
    """The C library's ``function`` (Python's math) on each element."""
    return np.vectorize(function, otypes=[float])(*arrays)


CASES = {   # name: (mzc's, the C library's, inputs, ulps allowed)
    "sin": (elementary.sin, math.sin, RNG.uniform(-30, 30, 20000), 1),
    "cos": (elementary.cos, math.cos, RNG.uniform(-30, 30, 20000), 1),
    "sin of small angles": (elementary.sin, math.sin, RNG.uniform(-1, 1, 5000) * 10.0 ** RNG.uniform(-300, 0, 5000), 1),
    "cos far out": (elementary.cos, math.cos, RNG.uniform(-1e6, 1e6, 20000), 2),
    "exp": (elementary.exp, math.exp, RNG.uniform(-708, 709, 20000), 1),
    "exp near 0": (elementary.exp, math.exp, RNG.uniform(-1, 1, 20000), 1),
    "log": (elementary.log, math.log, 10.0 ** RNG.uniform(-307, 308, 20000), 1),
    "log near 1": (elementary.log, math.log, 1 + RNG.uniform(-0.3, 0.4, 20000), 1),
    "log2": (elementary.log2, math.log2, 10.0 ** RNG.uniform(-307, 308, 20000), 1),
    "log2 near 1": (elementary.log2, math.log2, 1 + RNG.uniform(-0.3, 0.4, 20000), 2),
}


@pytest.mark.parametrize("name", CASES)
def test_functions_are_within_an_ulp_or_two_of_the_c_librarys(name):
    ours, theirs, x, allowed = CASES[name]
    assert ulps(ours(x), library(theirs, x)).max() <= allowed


def test_atan2_is_within_two_ulps_in_every_quadrant_and_scale():
    y, x = (RNG.normal(size=(2, 20000)) * 10.0 ** RNG.uniform(-8, 8, (2, 20000)))
    assert ulps(elementary.atan2(y, x), library(math.atan2, y, x)).max() <= 2


@pytest.mark.parametrize("y", [0.0, -0.0, 1.0, -1.0, math.inf, -math.inf, math.nan])
@pytest.mark.parametrize("x", [0.0, -0.0, 1.0, -1.0, math.inf, -math.inf, math.nan])
def test_atan2_takes_the_c_librarys_special_values(y, x):
    got, expected = elementary.atan2(y, x), math.atan2(y, x)
    if math.isnan(expected):
        assert math.isnan(got)
    else:
        assert got == pytest.approx(expected, rel=4e-16) and math.copysign(1, got) == math.copysign(1, expected)


@pytest.mark.parametrize("function, argument, expected", [
    (elementary.exp, 0.0, 1.0), (elementary.exp, 710.0, math.inf), (elementary.exp, -746.0, 0.0),
    (elementary.exp, -math.inf, 0.0), (elementary.exp, math.inf, math.inf), (elementary.log, 1.0, 0.0),
    (elementary.log, 0.0, -math.inf), (elementary.log, math.inf, math.inf), (elementary.log2, 0.0, -math.inf),
    (elementary.sin, 0.0, 0.0), (elementary.cos, 0.0, 1.0), (elementary.log, 5e-324, math.log(5e-324)),
])
def test_special_values(function, argument, expected):
    assert function(argument) == expected


@pytest.mark.parametrize("function, argument", [(elementary.log, -1.0), (elementary.log2, -1e-300),
                                                (elementary.sin, math.inf), (elementary.cos, -math.inf),
                                                (elementary.exp, math.nan)])
def test_no_value_is_nan(function, argument):
    assert math.isnan(function(argument))


def test_log2_is_exact_at_powers_of_two():
    powers = np.arange(-1074, 1024)
    assert np.array_equal(elementary.log2(np.ldexp(1.0, powers)), powers)


@settings(max_examples=300)
@given(FINITE)
def test_sine_is_odd_and_cosine_even(x):
    assert elementary.sin(-x) == -elementary.sin(x) and elementary.cos(-x) == elementary.cos(x)
    assert abs(elementary.sin(x)) <= 1 and abs(elementary.cos(x)) <= 1


@settings(max_examples=300)
@given(FINITE, FINITE)
def test_atan2_mirrors_exactly(y, x):
    angle = elementary.atan2(y, x)
    assert elementary.atan2(-y, x) == -angle and -math.pi <= angle <= math.pi


def test_arrays_keep_their_shape_and_broadcast():
    assert isinstance(elementary.sin(1.0), float) and elementary.sin(np.zeros((2, 3))).shape == (2, 3)
    assert elementary.atan2(np.ones((4, 1)), np.ones(3)).shape == (4, 3)
    assert elementary.exp(np.arange(6.0).reshape(2, 3)[:, ::2]).shape == (2, 2)   # a strided view


def test_symmetric_eigen_matches_numpys():
    matrices = RNG.normal(size=(2000, 3, 3))
    matrices = matrices @ matrices.transpose(0, 2, 1)
    values, vectors = symmetric_eigen(matrices)
    expected_values, expected_vectors = np.linalg.eigh(matrices)
    np.testing.assert_allclose(values, expected_values, rtol=1e-12, atol=1e-12 * np.abs(expected_values).max())
    np.testing.assert_allclose(np.abs(np.einsum("nik,nik->nk", vectors, expected_vectors)), 1, atol=1e-9)
    residual = np.einsum("nij,njk->nik", matrices, vectors) - vectors * values[:, None, :]
    assert np.abs(residual).max() < 1e-12 * np.abs(matrices).max()


def test_symmetric_eigen_of_repeated_and_zero_spreads():
    values, vectors = symmetric_eigen(np.array([np.diag([3.0, 1.0, 2.0]), np.eye(3), np.zeros((3, 3))]))
    np.testing.assert_array_equal(values, [[1, 2, 3], [1, 1, 1], [0, 0, 0]])
    np.testing.assert_array_equal(np.abs(vectors[0]), [[0, 0, 1], [1, 0, 0], [0, 1, 0]])


def test_products_without_blas_equal_numpys_to_rounding():
    a, b, v = RNG.normal(size=(3, 3)), RNG.normal(size=(3, 3)), RNG.normal(size=1000)
    np.testing.assert_allclose(matrix_product(a, b), a @ b, rtol=1e-14, atol=1e-15)
    assert determinant(a) == pytest.approx(np.linalg.det(a), rel=1e-13)
    assert inner(v, v[::-1]) == pytest.approx(np.dot(v, v[::-1]), rel=1e-12)
    assert length(v) == pytest.approx(np.linalg.norm(v), rel=1e-14)


def test_least_squares_matches_lapack_on_well_posed_fits():
    basis = np.polynomial.chebyshev.chebvander(np.linspace(-1, 1, 300), 20)
    values = RNG.normal(size=(40, 300)).cumsum(axis=1)
    expected = np.linalg.lstsq(basis, values.T, rcond=None)[0].T
    np.testing.assert_allclose(least_squares(basis, values), expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


def test_least_squares_stops_at_the_degree_binary64_can_tell_apart():
    """x from 100 to 130 in powers up to 30 on 31 points: past some degree the columns are the
    ones before them to rounding, and the fit keeps the lower degrees (exact for data of those)
    with zeros above, instead of noise spread over all of them."""
    x = np.linspace(100, 130, 31)
    basis, line = np.vander(x, 31)[:, ::-1], 2 * x - 0.5
    fit = least_squares(basis, line[None, :])[0]
    dropped = np.flatnonzero(fit == 0)
    assert dropped.size and np.array_equal(dropped, np.arange(dropped[0], 31))
    np.testing.assert_allclose(basis @ fit, line, rtol=1e-12)
