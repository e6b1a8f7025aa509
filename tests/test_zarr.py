"""The numcodecs codec (mzc.zarr) in a real Zarr store: a terrain in chunks within its bound."""

import os
from pathlib import Path

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


@pytest.mark.parametrize("bad", [np.zeros((4, 4), np.int64), np.zeros((4, 4), bool), np.zeros(3, complex),
                                 np.zeros(()), np.zeros((1,) * 33, np.int16)])
def test_chunks_of_types_or_dimensions_the_codec_does_not_code_are_refused(bad):
    with pytest.raises(MzcError, match="mzc_dwt2d codes chunks of 1 to 32 dimensions"):
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


# --- integer and N-D chunks: a time stack of DEMs, on a Dask cluster ---------------------------


def dem_stack(dtype, times=6, rows=256, cols=384, seed=0):
    """A time stack of DEMs (times x rows x columns, metres): a terrain moving slowly, with noise;
    whole metres for an integer ``dtype``, NaN patches (no data) for a float one."""
    rng = np.random.default_rng(seed)
    t, r, c = np.mgrid[0:times, 0:rows, 0:cols]
    z = 800 + 50 * np.sin(r / 17 + t / 3) * np.cos(c / 23) + rng.normal(0, 1, r.shape)
    if np.dtype(dtype).kind in "iu":
        return np.round(z).astype(dtype)
    z[1, 40:60, 100:130] = np.nan
    return z.astype(dtype)


def within(back, z, bound):
    """True when ``back`` has ``z``'s type, shape and no-data, every value within ``bound`` of it
    (integers: within floor(bound), exactly integers of their type)."""
    valid = ~np.isnan(z) if z.dtype.kind == "f" else np.ones(z.shape, bool)
    if back.dtype.newbyteorder("=") != z.dtype.newbyteorder("=") or back.shape != z.shape:
        return False
    if z.dtype.kind == "f" and not np.array_equal(np.isnan(back), ~valid):
        return False
    error = np.abs(back[valid].astype(float) - z[valid].astype(float))
    slack = np.spacing(np.abs(z[valid]).max()) / 2 if z.dtype == np.float32 else 0
    return bool(error.max(initial=0) <= (np.floor(bound) if z.dtype.kind in "iu" else bound + slack))


@pytest.mark.parametrize("shape", [(6, 40, 50), (2, 3, 20, 30), (300,), (17, 23)])
@pytest.mark.parametrize("dtype", ["int16", "<u2", ">i4", "uint8", "int8", "float32", ">f8"])
def test_integer_and_n_d_chunks_come_back_in_their_type_within_the_bound(shape, dtype):
    rng = np.random.default_rng(1)
    info = np.iinfo(dtype) if np.dtype(dtype).kind in "iu" else None
    z = rng.integers(info.min, info.max, shape, endpoint=True).astype(dtype) if info else \
        rng.normal(100, 30, shape).astype(dtype)
    codec = Dwt2d(max_error=2.5)
    data = codec.encode(z)
    assert data[:1] == (b"N" if info or len(shape) != 2 else {"float32": b"f", ">f8": b"D"}[dtype])
    assert within(codec.decode(data), z, 2.5)
    out = np.empty(shape, dtype)
    assert codec.decode(data, out=out) is out and within(out, z, 2.5)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.sampled_from(["int16", "uint8", "int32", "float32", "float64"]).flatmap(
           lambda dtype: arrays(dtype, st.lists(st.integers(1, 7), min_size=1, max_size=4).map(tuple))),
       st.sampled_from([0.3, 1.0, 4.0]))
def test_any_small_chunk_of_any_dimensions_round_trips(z, bound):
    if z.dtype.kind == "f":
        z = np.where(np.isfinite(z) & (np.abs(z) < 1e6), z, np.nan).astype(z.dtype)
    codec = Dwt2d(max_error=bound)
    assert within(codec.decode(codec.encode(z)), z, bound)


def test_a_2d_float_chunk_is_coded_as_it_always_was():
    """A store written before integer and N-D chunks reads the same: 2D floats keep their layout."""
    import mzc

    z = terrain("<f8")[:64, :64]
    from mzc.codecs.dwt2d import encode_whole

    text = encode_whole(mzc.ZGrid(z, 1.0, 1.0), max_error=0.25, compact=False)[0]   # 3.1, not mzc encode's 7.0
    assert Dwt2d(max_error=0.25).encode(z) == b"d" + text


@pytest.mark.parametrize("edit, message", [
    (lambda data: data[:-1], "bytes|cut short|payload"),
    (lambda data: data + b"\x00", "bytes after"),
    (lambda data: data[:20], "cut short"),
    (lambda data: b"N<i8" + data[4:], "a stack of"),
    (lambda data: b"N<i2\x02" + data[5:], "cut short|unrecognised format|slice|bytes after"),
    (lambda data: data[:5] + (9).to_bytes(4, "little") + data[9:], "is 40 x 50, not|slice|cut short"),
])
def test_a_damaged_stack_is_refused(edit, message):
    data = Dwt2d(max_error=1).encode(dem_stack("int16", 3, 40, 50))
    with pytest.raises(MzcError, match=message):
        Dwt2d(max_error=1).decode(edit(data))


def test_an_int64_or_empty_chunk_is_refused():
    with pytest.raises(MzcError, match="not 2D int64"):
        Dwt2d(max_error=1).encode(np.zeros((4, 4), np.int64))
    with pytest.raises(MzcError, match="empty 3 x 0 x 4"):
        Dwt2d(max_error=1).encode(np.zeros((3, 0, 4), np.int16))


@pytest.mark.filterwarnings("ignore:Numcodecs codecs are not in the Zarr version 3")
@pytest.mark.parametrize("zarr_format", [2, 3])
@pytest.mark.parametrize("dtype, fill", [("int16", 0), ("float32", np.nan)])
def test_dask_to_zarr_codes_a_time_stack_on_a_local_cluster(tmp_path, zarr_format, dtype, fill):
    """dask.array.to_zarr with the codec, on dask.distributed's LocalCluster (threads in this
    process): each chunk (2 times x 128 x 128) coded on a worker, the store read back within the
    bound and smaller than the raw values."""
    da = pytest.importorskip("dask.array")
    distributed = pytest.importorskip("dask.distributed")
    from mzc.zarr import Dwt2dV3

    z, bound = dem_stack(dtype), 1.0
    codecs = ({"compressors": Dwt2d(max_error=bound)} if zarr_format == 2 else
              {"serializer": Dwt2dV3(max_error=bound), "compressors": None})
    store = zarr.create_array(store=str(tmp_path / "stack.zarr"), shape=z.shape, chunks=(2, 128, 128), dtype=dtype,
                              zarr_format=zarr_format, fill_value=fill, **codecs)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as \
            cluster, distributed.Client(cluster):
        da.to_zarr(da.from_array(z, chunks=(2, 128, 128)), store)
    back = zarr.open_array(str(tmp_path / "stack.zarr"), mode="r")
    assert back.nchunks == 18 and within(back[:], z, bound)
    assert stored_bytes(tmp_path) * 4 < z.nbytes


def test_the_spec_example_of_a_stacked_chunk_decodes_as_stated_and_is_what_the_codec_writes():
    """spec/zarr.md's worked example of the N layout: its bytes decode to the values it states,
    within 1 of its input, and the codec writes exactly those bytes for that input."""
    import ast
    import re

    page = (Path(__file__).resolve().parents[1] / "spec" / "zarr.md").read_text()
    example = page[page.index("## Worked example of `N`"):]
    chunk = np.array(ast.literal_eval(re.search(r"```\n(\[.*?\])\n```", example, re.S)[1]), dtype="<i2")
    data = bytes.fromhex(re.search(r"```zarr-chunk-hex\n(.*?)```", example, re.S)[1])
    stated = np.array(ast.literal_eval(re.search(r"```zarr-chunk-values\n(.*?)```", example, re.S)[1]))
    decoded = Dwt2d(max_error=1).decode(data)
    assert decoded.dtype == np.dtype("<i2") and np.array_equal(decoded, stated)
    assert np.abs(decoded.astype(int) - chunk).max() <= 1
    assert Dwt2d(max_error=1).encode(chunk) == data
