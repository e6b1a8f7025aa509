"""The transform of dwt2d 3.0: lifting with symmetric or periodic extension, and its relevance."""

import numpy as np
import pytest
import pywt
from hypothesis import given, settings
from hypothesis import strategies as st

from mzc.codecs.dwt2d import lifting

WAVELETS = ["bior4.4", "bior2.2"]
REFLECT_OFFSET = {"bior4.4": 2, "bior2.2": 1}


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40), st.integers(0, 6), st.sampled_from(WAVELETS), st.booleans(),
       st.integers(0, 2**32 - 1))
def test_the_inverse_restores_any_grid(rows, cols, levels, wavelet, periodic, seed):
    z = np.random.default_rng(seed).normal(size=(rows, cols)) * 100
    bands = lifting.forward(z, wavelet, levels, periodic)
    assert sum(b.size for b in [bands[0], *(b for level in bands[1:] for b in level)]) == z.size
    np.testing.assert_allclose(lifting.inverse(bands, wavelet, periodic), z, atol=1e-9)


@pytest.mark.parametrize("wavelet", WAVELETS)
@pytest.mark.parametrize("n", [2, 5, 6, 21, 64])
def test_one_level_is_pywavelets_filter_bank(wavelet, n):
    """Symmetric extension: pywt's 'reflect' coefficients on the signal; periodic: 'periodization'."""
    x = np.random.default_rng(n).normal(size=n)
    low, high = lifting.analyse(x[:, None], wavelet)
    a, d = pywt.dwt(x, wavelet, mode="reflect")
    offset = REFLECT_OFFSET[wavelet]
    np.testing.assert_allclose(low[:, 0], a[offset:offset + len(low)], atol=1e-12)
    np.testing.assert_allclose(high[:, 0], d[offset:offset + len(high)], atol=1e-12)
    if n % 2 == 0 and n > 2:
        low, high = lifting.analyse(x[:, None], wavelet, periodic=True)
        a, d = pywt.dwt(x, wavelet, mode="periodization")
        np.testing.assert_allclose(low[:, 0], a, atol=1e-12)
        np.testing.assert_allclose(high[:, 0], d, atol=1e-12)


def test_a_plane_has_detail_only_at_the_edges_and_a_periodic_signal_no_seam():
    """The 9/7 kills linear ramps (two vanishing moments on each side), so a plane leaves detail
    only where the symmetric extension folds it, next to the edges; periodisation would leave
    a false edge there instead, as wide as the plane's whole rise."""
    rows, cols = np.mgrid[0:33, 0:48]
    h, v, d = lifting.forward(3 + 0.5 * rows - 0.25 * cols, "bior4.4", 1)[1]
    for band in (h, v, d):
        assert np.abs(band[2:-2, 2:-2]).max() < 1e-9
    assert np.abs(v[:, 2:-2]).max() < 1e-9 and np.abs(h[2:-2, :]).max() < 1e-9
    ring = np.sin(2 * np.pi * cols / 48) + 0 * rows      # smooth across the wrap
    wrapped = lifting.forward(ring, "bior4.4", 1, periodic=True)[1][1]
    cut = lifting.forward(ring, "bior4.4", 1, periodic=False)[1][1]
    assert np.abs(wrapped).max() < 0.01 * np.abs(cut).max()


def reaches(valid, wavelet, levels, periodic):
    """(marks, reaches): per coefficient, lifting.relevance's mark and whether its inverse alone
    is nonzero at a valid node."""
    shapes = lifting.forward(np.zeros(valid.shape), wavelet, levels, periodic)
    flat_shapes = [shapes[0].shape] + [b.shape for level in shapes[1:] for b in level]
    marks = lifting.relevance(valid, wavelet, levels, periodic)
    flat_marks = [marks[0]] + [b for level in marks[1:] for b in level]
    found = []
    for index, shape in enumerate(flat_shapes):
        assert flat_marks[index].shape == shape
        for position in np.ndindex(*shape):
            flat = [np.zeros(s) for s in flat_shapes]
            flat[index][position] = 1.0
            bands = [flat[0]] + [tuple(flat[1 + 3 * i: 4 + 3 * i]) for i in range(levels)]
            touches = bool((np.abs(lifting.inverse(bands, wavelet, periodic)) > 1e-12)[valid].any())
            found.append((bool(flat_marks[index][position]), touches))
    return np.array(found).reshape(-1, 2).T


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 20), st.integers(1, 20), st.integers(0, 3), st.sampled_from(WAVELETS), st.booleans(),
       st.integers(0, 2**32 - 1))
def test_relevance_marks_every_coefficient_that_reaches_a_valid_node(rows, cols, levels, wavelet, periodic, seed):
    marks, touches = reaches(np.random.default_rng(seed).random((rows, cols)) < 0.2, wavelet, levels, periodic)
    assert not (touches & ~marks).any()


@pytest.mark.parametrize("wavelet, periodic", [("bior4.4", False), ("bior4.4", True), ("bior2.2", False)])
def test_relevance_is_the_exact_reach_away_from_folds(wavelet, periodic):
    """On a grid of some size the marks are exactly the coefficients that reach a valid node
    (extra marks come only from a short signal's mirror folding taps that cancel)."""
    marks, touches = reaches(np.random.default_rng(7).random((24, 32)) < 0.05, wavelet, 2, periodic)
    np.testing.assert_array_equal(marks, touches)
