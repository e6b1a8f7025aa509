"""mzc: compress 3D surfaces into small, specified files and rebuild dense meshes.

The method follows a PhD thesis on cutting planes, per-row transforms and a PDE step (see
README.md and spec/). ``import mzc`` gives the Python API (``mzc.api``): slice, encode,
decode, densify, triangulate, compare, read and write, train (a shared prior), batch_encode and batch_decode (on
Dask), the ZGrid and Mesh types, the codec registry and the error types. The names are
imported on first use, so that ``import mzc`` (and the command line's start-up) stays free
of numpy and scipy until they are needed.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

HOMES = {
    **dict.fromkeys(("slice", "encode", "decode", "densify", "triangulate", "compare", "read", "write",
                      "sample", "batch_encode", "batch_decode", "train"), "mzc.api"),
    "ZGrid": "mzc.grid",
    "Mesh": "mzc.meshes",
    "Codec": "mzc.codecs.base",
    "Option": "mzc.codecs.base",
    **dict.fromkeys(("register_codec", "get_codec", "codec_names"), "mzc.codecs"),
    **dict.fromkeys(("MzcError", "MzcWarning"), "mzc.errors"),
}
__all__ = [  # the names of HOMES, spelled out so that linters and type checkers see them
    "__version__", "slice", "encode", "decode", "densify", "triangulate", "compare", "read", "write", "sample",
    "batch_encode", "batch_decode", "train", "ZGrid", "Mesh", "Codec", "Option", "register_codec", "get_codec",
    "codec_names", "MzcError", "MzcWarning",
]

if TYPE_CHECKING:
    from mzc.api import (
        batch_decode,
        batch_encode,
        compare,
        decode,
        densify,
        encode,
        read,
        sample,
        slice,
        train,
        triangulate,
        write,
    )
    from mzc.codecs import codec_names, get_codec, register_codec
    from mzc.codecs.base import Codec, Option
    from mzc.errors import MzcError, MzcWarning
    from mzc.grid import ZGrid
    from mzc.meshes import Mesh


def __getattr__(name: str) -> Any:
    """Import a public name from its home module on first use (PEP 562)."""
    if name not in HOMES:
        raise AttributeError(f"module 'mzc' has no attribute {name!r}")
    value = getattr(importlib.import_module(HOMES[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
