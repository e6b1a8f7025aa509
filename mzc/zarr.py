"""A numcodecs codec for 2D arrays in Zarr stores: mzc's ``--dwt2d`` with a max-error bound.

``Dwt2d(max_error=E)`` stores each 2D chunk (float32 or float64; NaN = no data) as one
``mzc-dwt2d`` file behind a one-byte dtype code, so that every valid value comes back
within E (for float32, within E plus the rounding to float32) and no-data stays NaN. It
is registered under the codec id ``mzc_dwt2d`` through the ``numcodecs.codecs`` entry
point, so ``numcodecs.get_codec({"id": "mzc_dwt2d", "max_error": 0.01})`` finds it and a
Zarr store that names it opens wherever mzc is installed.

Zarr's version-2 format hands a compressor the chunk as an array, which this codec needs
(it codes the grid, not a byte string): use it as the ``compressor`` of a ``zarr_format=2``
array. The version-3 format passes compressors bytes only and takes third-party numcodecs
codecs through its own wrappers, which this codec does not provide yet.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numcodecs.abc import Codec
from numcodecs.compat import ensure_bytes, ndarray_copy

from mzc.errors import MzcError

# the one-byte prefix of a chunk -> its dtype
DTYPES: dict[bytes, np.dtype] = {b"f": np.dtype("<f4"), b"d": np.dtype("<f8")}
CODES = {dtype: code for code, dtype in DTYPES.items()}


class Dwt2d(Codec):
    """mzc's 2D wavelet codec with a bound on the error of every value (``max_error``)."""

    codec_id = "mzc_dwt2d"

    def __init__(self, max_error: float, wavelet: str = "bior4.4", level: int | None = None) -> None:
        from mzc.codecs import get_codec

        self.max_error, self.wavelet, self.level = float(max_error), wavelet, level
        get_codec("dwt2d").checked(self.options())   # refuse a bad configuration now, not at the first chunk

    def options(self) -> dict[str, Any]:
        """The options of ``mzc.encode`` for this configuration."""
        return {"max_error": self.max_error, "wavelet": self.wavelet, "level": self.level}

    def encode(self, buf: Any) -> bytes:
        """One 2D float chunk as a dtype code and an mzc-dwt2d file."""
        import mzc

        array = np.asarray(buf)
        if array.ndim != 2 or array.dtype.newbyteorder("<") not in CODES:
            raise MzcError(f"mzc_dwt2d codes 2D float32 or float64 chunks, not {array.ndim}D {array.dtype}")
        return CODES[array.dtype.newbyteorder("<")] + mzc.encode(array.astype(np.float64), "dwt2d", **self.options())

    def decode(self, buf: Any, out: Any = None) -> np.ndarray:
        """The chunk back, in its dtype, into ``out`` when given."""
        import mzc

        data = ensure_bytes(buf)
        if data[:1] not in DTYPES:
            raise MzcError("not an mzc_dwt2d chunk (no dtype code)")
        values = mzc.decode(data[1:]).z.astype(DTYPES[data[:1]], order="C")   # zarr flattens in memory order
        return ndarray_copy(values, out)
