"""The numcodecs codec (mzc.zarr) in a real Zarr store: a terrain in chunks within its bound."""

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

numcodecs = pytest.importorskip("numcodecs")
zarr = pytest.importorskip("zarr")

from mzc.errors import MzcError  # noqa: E402 - after the skips
from mzc.samples import jacksboro  # noqa: E402
from mzc.zarr import Dwt2d  # noqa: E402


def terrain(dtype):
    """matplotlib's Jacksboro DEM (344 x 403, metres) with two no-data patches."""
    z = jacksboro().z.astype(dtype)
    z[10:14, 20:30] = np.nan
    z[200:260, 390:] = np.nan
    return z


def stored_bytes(folder):
    """The bytes of every file in a store."""
    return sum(os.path.getsize(os.path.join(root, name)) for root, _, names in os.walk(folder) for name in names)


@pytest.mark.parametrize("dtype", ["f8", "f4"])
def test_a_chunked_terrain_comes_back_within_the_bound_and_smaller(tmp_path, dtype):
    z, bound = terrain(dtype), 0.25
    array = zarr.create_array(store=str(tmp_path), shape=z.shape, chunks=(128, 128), dtype=z.dtype,
                              zarr_format=2, compressors=Dwt2d(max_error=bound), fill_value=np.nan)
    array[:] = z
    back = zarr.open_array(str(tmp_path), mode="r")[:]
    assert back.dtype == z.dtype
    assert np.array_equal(np.isnan(back), np.isnan(z))
    valid = ~np.isnan(z)
    rounding = np.abs(z[valid]).max() * np.finfo(z.dtype).eps
    assert np.abs(back[valid].astype(float) - z[valid].astype(float)).max() <= bound + rounding
    assert stored_bytes(tmp_path) * 4 < z.nbytes   # measured 4.8x smaller than raw float32, 9.6x than float64


def test_the_codec_is_found_by_its_id_through_the_entry_point():
    codec = numcodecs.get_codec({"id": "mzc_dwt2d", "max_error": 0.01, "level": 2})
    assert isinstance(codec, Dwt2d) and codec.get_config() == {"id": "mzc_dwt2d", "max_error": 0.01,
                                                                "wavelet": "bior4.4", "level": 2}
    assert numcodecs.get_codec(codec.get_config()) == codec


@pytest.mark.parametrize("bad", [np.zeros(10), np.zeros((2, 2, 2)), np.zeros((4, 4), dtype=np.int32)])
def test_chunks_that_are_not_2d_floats_are_refused(bad):
    with pytest.raises(MzcError):
        Dwt2d(max_error=0.1).encode(bad)


def test_a_bad_configuration_is_refused_at_once():
    with pytest.raises(MzcError, match="max_error"):
        Dwt2d(max_error=0)
    with pytest.raises(MzcError, match="wavelet"):
        Dwt2d(max_error=1, wavelet="db4")
    with pytest.raises(MzcError):
        Dwt2d(max_error=1).decode(b"x" + b"mzc-dwt2d 3.0\n")


@settings(max_examples=25, deadline=None, derandomize=True)
@given(arrays(np.float64, st.tuples(st.integers(2, 24), st.integers(2, 24)),
              elements=st.floats(-1e3, 1e3) | st.just(np.nan)),
       st.sampled_from([0.001, 0.1, 5.0]))
def test_any_small_array_round_trips_within_the_bound(z, bound):
    if np.isnan(z).all():
        z[0, 0] = 0.0
    codec = Dwt2d(max_error=bound)
    back = codec.decode(codec.encode(z))
    assert back.shape == z.shape and np.array_equal(np.isnan(back), np.isnan(z))
    assert np.nanmax(np.abs(back - z)) <= bound
