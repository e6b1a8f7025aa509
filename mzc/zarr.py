"""A numcodecs codec for arrays in Zarr stores: mzc's ``--dwt2d`` with a max-error bound.

``Dwt2d(max_error=E)`` stores each 2D float chunk (float32 or float64; NaN = no data) as one
``mzc-dwt2d`` file behind a one-byte code of its dtype and byte order, so that every
valid value comes back within E (for float32, within E plus the rounding to float32)
and no-data stays NaN. A chunk of integers (8 to 32 bits) or of any other number of
dimensions (a time stack of DEMs: time x rows x columns) is a stack of 2D slices along its
last two axes, each its own ``mzc-dwt2d`` file (``STACK``); integers are coded as a raster
of integer samples, so they come back integers within floor(E) <= E of their own, in their
type (spec/dwt2d.md, Rounding); spec/zarr.md gives a chunk's bytes. Every chunk is coded on its
own, so ``dask.array.to_zarr`` codes a store of any size chunk by chunk on a cluster.

It is registered under the codec id ``mzc_dwt2d`` through the
``numcodecs.codecs`` entry point, so ``numcodecs.get_codec({"id": "mzc_dwt2d",
"max_error": 0.01})`` finds it and a Zarr store that names it opens wherever mzc is
installed.

Why a dtype byte and not a config field: the mzc-dwt2d header already holds the rows and
columns, so the chunk's shape comes back from the file; the byte makes every chunk decode
on its own, whatever codec configuration reads it. A chunk is refused where it would land
in memory of another shape or type: ``decode(buf, out)`` into an ``out`` of other bytes,
another float type or another 2D shape (a flat buffer of its size is zarr's own), and
``Dwt2dV3`` into a chunk of the array's that is not its shape and type. Zarr's version-2
path hands a compressor no ``out`` and no shape, and reshapes what it returns itself: there
only the size is checked (by zarr), so a 32 x 128 chunk would land in a 64 x 64 one. Values are coded as float64, so the
bound holds exactly for float64 chunks and, for float32 ones, up to the rounding of the
decoded values to float32 (half a float32 unit in the last place of each value).

Zarr's version-2 format hands a compressor the chunk as an array, which this codec needs
(it codes the grid, not a byte string): use ``Dwt2d`` as the ``compressors`` of a
``zarr_format=2`` array. The version-3 format passes its compressors bytes only, so there
the codec must be the array's ``serializer`` (array to bytes), and zarr-python takes
numcodecs codecs only through its own wrapper classes: ``Dwt2dV3`` (zarr-python >= 3.1.3)
is such a wrapper, named ``numcodecs.mzc_dwt2d`` in the array's metadata and registered
through the ``zarr.codecs`` entry point, so ``serializer=Dwt2dV3(max_error=E)`` works and
the store reopens. Version-3 metadata naming ``numcodecs.*`` codecs is zarr-python's own
extension, not the Zarr specification: other Zarr implementations will not read it (zarr
warns so when the wrapper is made). ``Dwt2dV3`` builds on zarr-python's underscored base
class ``zarr.codecs.numcodecs._NumcodecsArrayBytesCodec``, which may change; it is made on
first use, so importing this module imports neither zarr nor its base class.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np
from numcodecs.abc import Codec
from numcodecs.compat import ensure_bytes, ensure_ndarray_like, ndarray_copy

from mzc.errors import MzcError

# the one-byte prefix of a chunk -> its dtype; the byte order is kept, since zarr's version-2
# format reads a decoded chunk's memory as the array's dtype
DTYPES: dict[bytes, np.dtype] = {b"f": np.dtype("<f4"), b"d": np.dtype("<f8"),
                                 b"F": np.dtype(">f4"), b"D": np.dtype(">f8")}
CODES = {dtype: code for code, dtype in DTYPES.items()}
# any other chunk: STACK, its dtype as numpy spells it (3 ASCII bytes, "<i2"), its number of
# dimensions (1 byte) and its shape (a little-endian uint32 each), then each 2D slice along its
# last two axes (a 1D chunk: one row), in C order, as a uint32 length and an mzc-dwt2d file
STACK = b"N"
STACKED = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")   # mzc.grid.SAMPLES
MAX_DIMENSIONS = 32


class Dwt2d(Codec):
    """mzc's 2D wavelet codec with a bound on the error of every value.

    Config: ``max_error`` (required, > 0, in the array's units), ``wavelet`` (one of
    mzc-dwt2d's, default bior4.4) and ``level`` (wavelet levels, default: from the chunk's
    size), the options of ``mzc encode --dwt2d`` of the same names.
    """

    codec_id = "mzc_dwt2d"

    def __init__(self, max_error: float | None = None, wavelet: str = "bior4.4", level: int | None = None) -> None:
        from mzc.codecs import get_codec

        if max_error is None:   # a config without it: numcodecs.get_codec({"id": "mzc_dwt2d"})
            raise MzcError("mzc_dwt2d needs max_error, the bound on every value's error", field="max_error")
        codec = get_codec("dwt2d")
        self.max_error, self.wavelet, self.level = codec.option("max_error").check(max_error), wavelet, level
        codec.checked(self.options())   # refuse a bad configuration now, not at the first chunk

    def options(self) -> dict[str, Any]:
        """The options of ``mzc.encode`` for this configuration."""
        return {"max_error": self.max_error, "wavelet": self.wavelet, "level": self.level}

    def encode(self, buf: Any) -> bytes:
        """One chunk as a dtype code and an mzc-dwt2d file (2D floats), else as a STACK."""
        array = np.asarray(buf)
        if array.dtype.name not in STACKED or not 1 <= array.ndim <= MAX_DIMENSIONS:
            raise MzcError(f"mzc_dwt2d codes chunks of 1 to {MAX_DIMENSIONS} dimensions of {', '.join(STACKED)}, "
                           f"not {array.ndim}D {array.dtype}")
        if array.size == 0:   # the file format has at least one row and column
            raise MzcError(f"mzc_dwt2d cannot code an empty {' x '.join(map(str, array.shape))} chunk")
        if array.ndim == 2 and array.dtype in CODES:   # as it always was: a store's chunks read the same
            return CODES[array.dtype] + self.slice_file(array)
        slices = array.reshape((-1, *array.shape[-2:]) if array.ndim > 1 else (1, 1, -1))
        files = [self.slice_file(values) for values in slices]
        head = STACK + array.dtype.str.encode() + struct.pack(f"<B{array.ndim}I", array.ndim, *array.shape)
        return head + b"".join(struct.pack("<I", len(file)) + file for file in files)

    def slice_file(self, values: np.ndarray) -> bytes:
        """The mzc-dwt2d file of one 2D slice: a grid of float values, or of a raster's integer
        samples, which the encoder keeps integers (spec/dwt2d.md, Rounding)."""
        from mzc.codecs.dwt2d import CODEC, encode_grid
        from mzc.grid import Raster, ZGrid
        from mzc.limits import check_grid_magnitudes

        raster = Raster(sample=values.dtype.name) if values.dtype.kind in "iu" else None
        grid = ZGrid(values.astype(np.float64), d1=1.0, d2=1.0, raster=raster)
        check_grid_magnitudes(grid)
        # the text-header versions (3.x, 6.0) spec/zarr.md's chunks hold, so a store's chunks stay the same bytes
        return encode_grid(grid, **CODEC.checked(self.options()), compact=False)

    def decode(self, buf: Any, out: Any = None) -> np.ndarray:
        """The chunk back, in its dtype and shape, into ``out`` when given: an array of its shape
        and type, a flat one of its type and size, or bytes of its size."""
        data = ensure_bytes(buf)
        if data[:1] in DTYPES:
            values = slice_values(data[1:]).astype(DTYPES[data[:1]], order="C")   # zarr flattens in memory order
        elif data[:1] == STACK:
            values = stack_values(data)
        else:
            raise MzcError("not an mzc_dwt2d chunk (no dtype code)")
        if out is not None:
            out = ensure_ndarray_like(out)
            check_fits(values, out.shape, out.dtype)
        return ndarray_copy(values, out)


def slice_values(data: bytes) -> np.ndarray:
    """The values of one mzc-dwt2d file of a chunk: one grid, not a multi-chart one."""
    import mzc

    grid = mzc.decode(data)
    if grid.charts is not None:
        raise MzcError(f"the chunk holds a multi-chart grid ({len(grid.charts)} charts): a Zarr chunk is one "
                       "grid of values", field="charts")
    return grid.z


def stack_values(data: bytes) -> np.ndarray:
    """The chunk of a STACK: its header checked, each slice decoded and checked against its shape,
    integers cast exactly (their files decode to integers in their type's range)."""
    try:
        dtype, ndim = np.dtype(data[1:4].decode("ascii")), data[4]
        shape = struct.unpack_from(f"<{ndim}I", data, 5)
    except (ValueError, TypeError, IndexError, UnicodeDecodeError, struct.error):
        raise MzcError("not an mzc_dwt2d chunk (a bad stack header)") from None
    if dtype.name not in STACKED or not 1 <= ndim <= MAX_DIMENSIONS or 0 in shape:
        raise MzcError(f"not an mzc_dwt2d chunk (a stack of {ndim}D {dtype})")
    plane = tuple(shape[-2:]) if ndim > 1 else (1, shape[0])
    count, position = int(np.prod(shape[:-2])) if ndim > 2 else 1, 5 + 4 * ndim
    slices: list[np.ndarray] = []
    for _ in range(count):
        (length,) = struct.unpack_from("<I", data, position) if position + 4 <= len(data) else (None,)
        if length is None or position + 4 + length > len(data):
            raise MzcError(f"the chunk is cut short: {len(slices)} of its {count} slices are there")
        values = slice_values(data[position + 4:position + 4 + length])
        if values.shape != plane:
            raise MzcError(f"a slice of the chunk is {values.shape[0]} x {values.shape[1]}, not "
                           f"{plane[0]} x {plane[1]}")
        slices.append(values)
        position += 4 + length
    if position != len(data):
        raise MzcError(f"the chunk has {len(data) - position} bytes after its {count} slices")
    return np.stack(slices).astype(dtype, order="C").reshape(shape)   # zarr flattens in memory order


def check_fits(values: np.ndarray, shape: tuple[int, ...], dtype: np.dtype) -> None:
    """Refuse to put a decoded chunk ``values`` where an array of ``shape`` and ``dtype`` goes when
    it has another size, type or shape (a flat buffer of its type, or of bytes, is zarr's own):
    numcodecs' copy and zarr's reshape would silently lay it out as another grid or read its
    bytes as other numbers."""
    same_type = dtype.newbyteorder("=") == values.dtype.newbyteorder("=") or (
        dtype.itemsize == 1 and values.dtype.itemsize > 1 and len(shape) <= 1)
    size = int(np.prod(shape)) * dtype.itemsize
    if size != values.nbytes or not same_type or (len(shape) > 1 and tuple(shape) != values.shape):
        raise MzcError(f"the chunk is {' x '.join(map(str, values.shape))} {values.dtype}, not the "
                       f"{' x '.join(map(str, shape))} {dtype} it is decoded into")


def _zarr3_codec() -> type:
    """The zarr-python 3 serializer (array to bytes) that runs ``Dwt2d`` in version-3 arrays."""
    from zarr.codecs.numcodecs import _NumcodecsArrayBytesCodec

    class Dwt2dV3(_NumcodecsArrayBytesCodec, codec_name=Dwt2d.codec_id):
        """``Dwt2d`` as a Zarr version-3 serializer: ``serializer=Dwt2dV3(max_error=E)``.

        The configuration is checked and completed with the defaults when made (the metadata
        then names every option), rather than at the first chunk.
        """

        def __init__(self, **codec_config: Any) -> None:
            codec_config.pop("id", None)
            super().__init__(**Dwt2d(**codec_config).get_config())

        async def _decode_single(self, chunk_data: Any, chunk_spec: Any) -> Any:
            """The chunk decoded into the array's chunk, which must be its shape and type."""
            values = self._codec.decode(chunk_data.to_bytes())
            check_fits(values, chunk_spec.shape, chunk_spec.dtype.to_native_dtype())
            return chunk_spec.prototype.nd_buffer.from_ndarray_like(values)

    Dwt2dV3.__module__, Dwt2dV3.__qualname__ = __name__, "Dwt2dV3"   # pickled as mzc.zarr.Dwt2dV3 (dask)
    return Dwt2dV3


def __getattr__(name: str) -> Any:
    """``Dwt2dV3`` is made on first use, so that importing this module does not import zarr."""
    if name == "Dwt2dV3":
        globals()[name] = _zarr3_codec()
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
