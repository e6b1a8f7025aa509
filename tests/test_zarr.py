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


def store_array(folder, z, bound, zarr_format):
    """A Zarr array of ``z`` in 128 x 128 chunks in a directory store, coded within ``bound``."""
    from mzc.zarr import Dwt2dV3

    codecs = ({"compressors": Dwt2d(max_error=bound)} if zarr_format == 2 else
              {"serializer": Dwt2dV3(max_error=bound), "compressors": None})
    array = zarr.create_array(store=str(folder), shape=z.shape, chunks=(128, 128), dtype=z.dtype,
                              zarr_format=zarr_format, fill_value=np.nan, **codecs)
    array[:] = z
    return array


@pytest.mark.filterwarnings("ignore:Numcodecs codecs are not in the Zarr version 3")
@pytest.mark.parametrize("zarr_format", [2, 3])
@pytest.mark.parametrize("dtype", ["<f8", "<f4", ">f8"])
def test_a_chunked_terrain_comes_back_within_the_bound_and_smaller(tmp_path, dtype, zarr_format):
    z, bound = terrain(dtype), 0.25
    store_array(tmp_path, z, bound, zarr_format)
    reopened = zarr.open_array(str(tmp_path), mode="r")
    assert reopened.nchunks == 12   # 3 x 4 chunks, the last row and column of chunks partly outside
    codec = reopened.compressors[0] if zarr_format == 2 else reopened.serializer
    config = codec.get_config() if zarr_format == 2 else codec.codec_config
    assert config == {"id": "mzc_dwt2d", "max_error": bound, "wavelet": "bior4.4", "level": None}
    back = reopened[:]
    # the version-3 format keeps the byte order in a codec, not the dtype: native order comes back
    assert back.dtype == (z.dtype if zarr_format == 2 else z.dtype.newbyteorder("=")) and back.shape == z.shape
    assert np.array_equal(np.isnan(back), np.isnan(z))
    valid = ~np.isnan(z)
    rounding = np.spacing(np.abs(z[valid]).max()) / 2   # the decoded values rounded to the dtype
    assert np.abs(back[valid].astype(float) - z[valid].astype(float)).max() <= bound + rounding
    # measured: 9.6x smaller than the raw float64 values, 4.8x than float32, in both formats
    assert stored_bytes(tmp_path) * 4 < z.nbytes


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


def test_a_chunk_decodes_into_out_and_an_empty_chunk_is_refused():
    z = np.linspace(0, 1, 48).reshape(6, 8)
    codec = Dwt2d(max_error=0.01)
    out = np.empty(48)   # zarr may hand a flat buffer of the chunk's size
    assert codec.decode(codec.encode(z), out=out) is out and np.abs(out.reshape(6, 8) - z).max() <= 0.01
    with pytest.raises(MzcError, match="empty"):
        codec.encode(np.zeros((0, 4)))


@pytest.mark.filterwarnings("ignore:Numcodecs codecs are not in the Zarr version 3")
def test_the_version_3_serializer_checks_its_config_and_pickles():
    import pickle

    from mzc.zarr import Dwt2dV3

    codec = Dwt2dV3(max_error=0.5)
    assert codec.to_dict() == {"name": "numcodecs.mzc_dwt2d",
                               "configuration": {"max_error": 0.5, "wavelet": "bior4.4", "level": None}}
    assert pickle.loads(pickle.dumps(codec)) == codec   # dask and process pools pickle codecs
    assert pickle.loads(pickle.dumps(Dwt2d(max_error=0.5))) == Dwt2d(max_error=0.5)
    with pytest.raises(MzcError, match="max_error"):
        Dwt2dV3(max_error=-1)


def test_importing_the_codec_does_not_import_zarr():
    import subprocess
    import sys

    code = "import sys, mzc.zarr; assert 'zarr' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.sampled_from([np.float64, np.float32]).flatmap(
           lambda dtype: arrays(dtype, st.tuples(st.integers(1, 24), st.integers(1, 24)),
                                elements=st.floats(-1e3, 1e3, width=32) | st.just(np.nan))),
       st.sampled_from([0.001, 0.1, 5.0]))
def test_any_small_array_round_trips_within_the_bound(z, bound):
    codec = Dwt2d(max_error=bound)
    back = codec.decode(codec.encode(z))
    assert back.dtype == z.dtype and back.shape == z.shape and np.array_equal(np.isnan(back), np.isnan(z))
    if not np.isnan(z).all():
        rounding = np.spacing(np.nanmax(np.abs(z)).astype(z.dtype)) / 2 if z.dtype == np.float32 else 0
        assert np.nanmax(np.abs(back.astype(float) - z.astype(float))) <= bound + rounding
