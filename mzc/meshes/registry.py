"""The mesh formats mzc writes, listed for the writers (mzc.formats reads every format).

A format is a module (or, for the meshio ones, an object in ``meshio_fallback``) with
``NAME``, ``EXTENSIONS``, ``read(data, source) -> Mesh`` and ``write(mesh) -> bytes`` (None for
a format mzc reads only). Modules are imported on first use, so importing ``mzc.meshes`` stays
light.
"""

import importlib

# name -> "module" or "module:attribute", in the order the writable ones are offered.
FORMATS = {
    "obj": "mzc.meshes.obj",
    "ply": "mzc.meshes.ply",
    "vtk": "mzc.meshes.meshio_fallback:VTK",
    "stl": "mzc.meshes.stl",
    "off": "mzc.meshes.meshio_fallback:OFF",
    "xyz": "mzc.meshes.xyz",
    "pcd": "mzc.meshes.pcd",
    "las": "mzc.meshes.las",
}


def format_named(name: str):
    """The format module (or object) called ``name``."""
    module, _, attribute = FORMATS[name].partition(":")
    found = importlib.import_module(module)
    return getattr(found, attribute) if attribute else found


def writable() -> tuple[str, ...]:
    """The names of the formats mzc writes."""
    return tuple(name for name in FORMATS if format_named(name).write is not None)
