"""The mzc file container: the magic line and header every mzc file shares, and the z-grid.

Every mzc file starts with ``mzc-KIND MAJOR.MINOR``. ``read_any`` recognises the kind and
hands the file to the z-grid reader (``mzc.formats.zgrid``) or to the registered codec of
that kind (``mzc.codecs``), so a codec registered in-process is decoded like a built-in
one. Meshes at the edges (OBJ, PLY, STL, ...) are handled by ``mzc.meshes``, not here.
"""

import importlib

from mzc.codecs import BUILT_IN, codec_for_kind
from mzc.errors import MzcError
from mzc.formats.header import split_magic
from mzc.limits import check_grid_magnitudes

# kind -> module of the built-in formats (the z-grid and the built-in codecs), imported on first use
REGISTRY = {"zgrid": "mzc.formats.zgrid", **BUILT_IN}


def module_for(kind):
    """The module of a built-in format (its VERSION, PROJECTED_VERSION, OLDEST_MAJOR, read, write)."""
    return importlib.import_module(REGISTRY[kind])


def reader_for(data, source):
    """The ``read(data, source)`` of an mzc file's kind, recognised by its magic line."""
    kind, _major, _minor = split_magic(data, source)
    if kind == "zgrid":
        return module_for(kind).read
    return known_codec(kind, source).decode


def header_versions(kind, source):
    """{projected_major, charted_major}: the first major versions of ``kind`` whose files may hold
    a central projection and charts (a built-in format's own; for another codec, its newest
    version for projections and none for charts)."""
    if kind in REGISTRY:
        module = module_for(kind)
        return {"projected_major": module.PROJECTED_VERSION[0],
                "charted_major": getattr(module, "CHARTED_VERSION", (None,))[0]}
    return {"projected_major": known_codec(kind, source).version[0], "charted_major": None}


def known_codec(kind, source):
    """The registered codec of ``kind``, or a one-line error listing the known kinds."""
    codec = codec_for_kind(kind)
    if codec is None:
        from mzc.codecs import codec_names

        raise MzcError(f"unknown mzc format 'mzc-{kind}' (known: {', '.join(sorted(['zgrid', *codec_names()]))})",
                       source=source, line=1)
    return codec


def is_mzc(data):
    """True when ``data`` starts with an mzc magic line."""
    return data[:4] == b"mzc-"


def read_any(data, source):
    """Read any mzc file into the ZGrid it holds; one whose heights or coordinates are beyond
    mzc.limits' (a damaged header or payload that still passes its checksum) is refused, as the
    writers refuse them."""
    grid = reader_for(data, source)(data, source)
    check_grid_magnitudes(grid, source=source)
    return grid
