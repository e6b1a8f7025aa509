"""The mesh formats mzc knows, listed in one place.

A format is a module (or, for the meshio ones, an object in ``meshio_fallback``) with
``NAME``, ``EXTENSIONS``, ``sniff(data) -> bool``, ``read(data, source) -> Mesh`` and
``write(mesh) -> bytes`` (None for a format mzc reads only). Modules are imported on first
use, so importing ``mzc.meshes`` stays light.
"""

import importlib
import os

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
# The order sniffing tries them: magic words first, then OBJ's loose ``v`` lines (a binary
# PLY body may hold one), and x y z text last (almost any text starts with a number).
SNIFF_ORDER = ("ply", "las", "pcd", "vtk", "off", "stl", "obj", "xyz")


def format_named(name: str):
    """The format module (or object) called ``name``."""
    module, _, attribute = FORMATS[name].partition(":")
    found = importlib.import_module(module)
    return getattr(found, attribute) if attribute else found


def writable() -> tuple[str, ...]:
    """The names of the formats mzc writes."""
    return tuple(name for name in FORMATS if format_named(name).write is not None)


def by_extension(source: str | None) -> str | None:
    """The format whose extensions include that of ``source``, or None."""
    extension = os.path.splitext(str(source))[1].lower() if source else ""
    return next((name for name in FORMATS if extension and extension in format_named(name).EXTENSIONS), None)


def by_content(data: bytes) -> str | None:
    """The first format (in SNIFF_ORDER) whose sniff accepts ``data``, or None."""
    return next((name for name in SNIFF_ORDER if format_named(name).sniff(data)), None)
