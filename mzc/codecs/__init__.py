"""The codecs that compress a z-grid, registered in one place.

The thesis's per-row codecs live in ``rows/`` (poly, dft, dct, dwt), the 2D wavelet in
``dwt2d/``. Each codec module builds a ``mzc.codecs.base.Codec`` named ``CODEC``; the
built-in ones are imported on first use (start-up stays fast), others come in through
``register_codec`` or the ``mzc.codecs`` entry-point group of an installed package, as
numcodecs finds its codecs. Every codec is a row of the one table of file formats
(``mzc.formats``): the compressed format its files are in, read by the codec.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from mzc.errors import MzcError

if TYPE_CHECKING:
    from mzc.codecs.base import Codec

BUILT_IN = {
    "poly": "mzc.codecs.rows.poly",
    "dft": "mzc.codecs.rows.dft",
    "dct": "mzc.codecs.rows.dct",
    "dwt": "mzc.codecs.rows.dwt",
    "dwt2d": "mzc.codecs.dwt2d",
}
DEFAULT_CODEC = "dwt2d"   # the best one: what `mzc encode` and mzc.encode use when none is named
ENTRY_POINT_GROUP = "mzc.codecs"
registered: dict[str, Codec] = {}


def register_codec(codec: Codec) -> Codec:
    """Make ``codec`` known to ``mzc encode``, ``mzc decode``, ``mzc info`` and ``mzc.encode``."""
    from mzc.codecs.base import Codec

    if not isinstance(codec, Codec):
        raise MzcError(f"a codec is a mzc.Codec, not a {type(codec).__name__}", field="codec")
    registered[codec.name] = codec
    return codec


def unregister_codec(name: str) -> None:
    """Forget a codec registered with ``register_codec`` (built-in ones stay)."""
    registered.pop(name, None)


def plugin_names() -> dict[str, object]:
    """The codecs that installed packages declare in the ``mzc.codecs`` entry-point group."""
    from importlib.metadata import entry_points  # here: it imports email, zipfile, socket ... (10-15 ms)

    return {point.name: point for point in entry_points(group=ENTRY_POINT_GROUP)}


def codec_names() -> list[str]:
    """The names of every codec: built-in, registered, then declared by installed packages."""
    return list(dict.fromkeys([*BUILT_IN, *registered, *plugin_names()]))


def get_codec(name: str) -> Codec:
    """The codec called ``name``."""
    if name in registered:
        return registered[name]
    if name in BUILT_IN:
        return register_codec(importlib.import_module(BUILT_IN[name]).CODEC)
    plugins = plugin_names()
    if name in plugins:
        return register_codec(plugins[name].load())  # type: ignore[attr-defined]
    raise MzcError(f"unknown codec {name!r} (known: {', '.join(codec_names())})", field="codec")


def registered_codecs() -> list[Codec]:
    """The codecs registered in this process that are not built in (a built-in one registers
    itself once loaded): rows of the table of formats (``mzc.formats``)."""
    return [codec for name, codec in registered.items() if name not in BUILT_IN]


def installed_codecs() -> list[Codec]:
    """The codecs installed packages declare that this process has not registered, loaded now."""
    return [get_codec(name) for name in plugin_names() if name not in registered and name not in BUILT_IN]
