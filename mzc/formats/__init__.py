"""The mzc file formats, registered in one place.

Each format is a module with ``KIND`` (the word after ``mzc-`` in its magic line),
``VERSION`` (its version for planar grids), ``read(data, source)`` and ``write(obj, ...)``. ``read_any``
recognises an mzc file by its magic line and hands it to the right module. Meshes at the
edges (OBJ, PLY, STL, ...) are handled by ``mzc.meshes``, not here.
"""

import importlib

from mzc.errors import MzcError
from mzc.formats.header import split_magic

# kind -> module; imported on first use to keep start-up fast.
REGISTRY = {
    "zgrid": "mzc.formats.zgrid",
    "dwt2d": "mzc.codecs.dwt2d",
    "poly": "mzc.codecs.rows.poly",
    "dft": "mzc.codecs.rows.dft",
    "dct": "mzc.codecs.rows.dct",
    "dwt": "mzc.codecs.rows.dwt",
}


def module_for(kind):
    """The format module of an mzc kind."""
    return importlib.import_module(REGISTRY[kind])


def detect(data, source):
    """The format module of mzc file bytes ``data``, recognised by its magic line."""
    kind, _major, _minor = split_magic(data, source)
    if kind not in REGISTRY:
        raise MzcError(f"unknown mzc format 'mzc-{kind}' (known: {', '.join(sorted(REGISTRY))})",
                       source=source, line=1)
    return module_for(kind)


def is_mzc(data):
    """True when ``data`` starts with an mzc magic line."""
    return data[:4] == b"mzc-"


def read_any(data, source):
    """Read any mzc file into the object its format holds."""
    return detect(data, source).read(data, source)
