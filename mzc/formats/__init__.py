"""The one table of the file formats mzc reads and writes, and the one way any file is identified,
read and written.

Every format is a row (``Format``): its name, the kind of what its files hold (KINDS), the module
that reads and writes them, named as a string and imported on first use, and the magic its files
start with, if they have one. The module says the rest, in the interface of mzc's mesh modules:
``EXTENSIONS``, ``sniff(data)`` for a format without magic (True: the bytes are its; None: it
cannot tell; False: they are not), ``read(data, source)`` and ``write(item)`` (None for a format
mzc only reads). FORMATS holds mzc's own; the codecs of the codec registry (``mzc.codecs``) are
the compressed rows, each codec the reader of its files; another package adds a format with
``register_format`` or through the ``mzc.formats`` entry-point group, as it adds a codec.

Every read identifies its file once, in one order (``identify``): the format named, else the one
whose magic the bytes start with (an mzc file's magic line names its kind), else the first format,
in rank order, whose module says the bytes are its, else the first format of the file's extension
whose module cannot tell; else one error lists the formats. The bytes decide before the name, as
GDAL's drivers do, so an ESRI grid named .txt is a raster and an .asc of x y z lines a cloud; the
name decides only what the bytes cannot (a cut STL, an OBJ without vertices). The formats of
mzc and of this process rank before those installed packages declare, which are loaded only
when a file is none of the others. What is read is held to what every item of its kind is
(CHECKS); a writer is chosen from the same rows (``writer_for``).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from mzc.errors import MzcError

GRIDS = ("grid", "compressed", "raster")   # what is read as a ZGrid: z-grids, compressed files, rasters
SURFACES = ("mesh", "cloud")               # what is read as a Mesh: meshes and point clouds
KINDS = (*GRIDS, *SURFACES)
NOUNS = {"grid": "z-grid", "compressed": "compressed mzc file", "raster": "raster", "mesh": "mesh",
         "cloud": "point cloud"}
CHECKS = {**dict.fromkeys(GRIDS, "mzc.limits:check_grid_magnitudes"), **dict.fromkeys(SURFACES, "mzc.meshes:checked")}
MZC_MAGIC = b"mzc-"   # an mzc file's magic line, mzc-KIND MAJOR.MINOR, names its format
ENTRY_POINT_GROUP = "mzc.formats"


@dataclass(frozen=True)
class Format:
    """One row of the table: a format's ``name`` (its --format word), the ``kind`` of what its files
    hold (KINDS), its ``module`` ("package.module" or "package.module:attribute", imported on first
    use; or, registered in process, the object itself), the ``magic`` its files start with, and the
    extension of the ``sidecar`` beside a file that holds its CRS as WKT (an ESRI grid's .prj)."""

    name: str
    kind: str
    module: Any
    magic: tuple[bytes, ...] = ()
    sidecar: str | None = None

    def load(self) -> Any:
        """The module (or object) that reads and writes this format's files."""
        return attribute(self.module) if isinstance(self.module, str) else self.module


FORMATS = (   # in rank order; the codecs' compressed formats follow the z-grid's
    Format("zgrid", "grid", "mzc.formats.zgrid", (b"mzc-zgrid",)),
    Format("prior", "grid", "mzc.prior:PriorFiles", (b"mzc-prior",)),   # read as its mean grid
    Format("residual", "compressed", "mzc.prior:ResidualFiles", (b"mzc-residual",)),   # decoded with its prior
    Format("tif", "raster", "mzc.rasters.geotiff", (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+")),   # and BigTIFF
    Format("asc", "raster", "mzc.rasters.asc", sidecar=".prj"),
    Format("ply", "mesh", "mzc.meshes.ply", (b"ply",)),
    Format("las", "cloud", "mzc.meshes.las", (b"LASF",)),
    Format("pcd", "cloud", "mzc.meshes.pcd"),
    Format("vtk", "mesh", "mzc.meshes.meshio_fallback:VTK", (b"# vtk DataFile",)),
    Format("off", "mesh", "mzc.meshes.meshio_fallback:OFF"),
    Format("stl", "mesh", "mzc.meshes.stl"),
    Format("obj", "mesh", "mzc.meshes.obj"),   # after the formats with a keyword: a binary PLY body may hold a v line
    Format("xyz", "cloud", "mzc.meshes.xyz"),  # last: most text starts like a number
)
registered: dict[str, Format] = {}


def attribute(name: str) -> Any:
    """The module ``package.module``, or the attribute of ``package.module:attribute``, imported now."""
    module, _, member = name.partition(":")
    found = importlib.import_module(module)
    return getattr(found, member) if member else found


def register_format(row: Format) -> Format:
    """Make a format known to every read and write of mzc, ranked after mzc's own."""
    if not isinstance(row, Format):
        raise MzcError(f"a format is a mzc.Format, not a {type(row).__name__}", field="format")
    if row.kind not in KINDS:
        raise MzcError(f"{row.kind!r} is no kind of file mzc reads (known: {', '.join(KINDS)})", field="format")
    if row.name not in registered and any(other.name == row.name for other in own_formats()):
        raise MzcError(f"a format called {row.name!r} exists already", field="format")
    registered[row.name] = row
    return row


def unregister_format(name: str) -> None:
    """Forget a format registered with ``register_format`` (mzc's own stay)."""
    registered.pop(name, None)


def own_formats() -> list[Format]:
    """mzc's formats and those of this process, in rank order: the z-grid, the built-in codecs', the
    rest of FORMATS, then the formats and the codecs registered."""
    from mzc.codecs import BUILT_IN, registered_codecs

    codecs = [Format(name, "compressed", module, (MZC_MAGIC + name.encode(),)) for name, module in BUILT_IN.items()]
    return [FORMATS[0], *codecs, *FORMATS[1:], *registered.values(), *map(codec_format, registered_codecs())]


def installed_formats() -> list[Format]:
    """The formats installed packages declare in the ``mzc.formats`` entry-point group, then their
    codecs (the ``mzc.codecs`` group), loaded now."""
    from importlib.metadata import entry_points  # here: it imports email, zipfile, socket ... (10-15 ms)

    from mzc.codecs import installed_codecs

    return [*(point.load() for point in entry_points(group=ENTRY_POINT_GROUP)), *map(codec_format, installed_codecs())]


def codec_format(codec: Any) -> Format:
    """A codec as the row of its compressed files, which it reads (``mzc.codecs.base.Codec.read``)."""
    return Format(codec.name, "compressed", codec, (MZC_MAGIC + codec.kind.encode(),))


def tables() -> Iterator[list[Format]]:
    """The rows in rank order, in two tables: mzc's and this process's, then the installed ones,
    loaded only when the first holds nothing that fits."""
    yield own_formats()
    yield installed_formats()


def named(name: str) -> Format:
    """The format called ``name``, or a one-line error listing the known ones."""
    for table in tables():
        row = next((row for row in table if row.name == name), None)
        if row is not None:
            return row
    raise MzcError(f"unknown format {name!r} (known: {', '.join(row.name for table in tables() for row in table)})",
                   field="format")


def module_for(name: str) -> Any:
    """The module (or object) that reads and writes the format called ``name``."""
    return named(name).load()


def identify(data: bytes, source: str, kinds: tuple[str, ...] = KINDS) -> Format:
    """The row of the format of ``data``, a file called ``source``: the one an mzc magic line names,
    else the first whose magic starts the bytes, else the first whose module says they are its, else
    the first of the file's extension whose module cannot tell; a file of none is refused in one
    line listing the formats of ``kinds``."""
    if is_mzc(data):
        return mzc_format(data, source)
    for table in tables():
        row = by_magic(data, table) or by_content(data, table) or by_extension(data, source, table)
        if row is not None:
            return row
    raise MzcError(f"unrecognised format: expected {expected(kinds)} (mzc reads {', '.join(names(kinds))})",
                   source=source)


def mzc_format(data: bytes, source: str) -> Format:
    """The row of an mzc file: the one whose magic is the ``mzc-KIND`` of its magic line; an unknown
    kind is refused, naming the known ones."""
    from mzc.formats.header import split_magic

    magic = MZC_MAGIC + split_magic(data, source)[0].encode()
    for table in tables():
        row = next((row for row in table if magic in row.magic), None)
        if row is not None:
            return row
    known = sorted(row.name for table in tables() for row in table if row.magic and is_mzc(row.magic[0]))
    raise MzcError(f"unknown mzc format '{magic.decode('ascii', 'replace')}' (known: {', '.join(known)})",
                   source=source, line=1)


def by_magic(data: bytes, table: list[Format]) -> Format | None:
    """The row of ``table`` whose magic starts ``data``."""
    return next((row for row in table if row.magic and data.startswith(row.magic)), None)


def by_content(data: bytes, table: list[Format]) -> Format | None:
    """The first row of ``table`` without magic whose module says ``data`` is its."""
    return next((row for row in table if not row.magic and row.load().sniff(data) is True), None)


def by_extension(data: bytes, source: str, table: list[Format]) -> Format | None:
    """The first row of ``table`` without magic that the extension of ``source`` names and whose
    module cannot tell ``data`` (a damaged file, named by the user)."""
    extension = os.path.splitext(source)[1].lower()
    return next((row for row in table if extension and not row.magic and extension in row.load().EXTENSIONS
                 and row.load().sniff(data) is None), None)


def starts_as(path: str | os.PathLike | None, name: str) -> bool:
    """True when ``path`` is a file (not stdin) whose first bytes are the magic of the format called ``name``."""
    from mzc.streams import is_stdio

    if path is None or is_stdio(path) or not os.path.isfile(path):
        return False
    with open(path, "rb") as file:
        head = file.read(64)
    return any(head.startswith(magic) for magic in named(name).magic)


def is_mzc(data: bytes) -> bool:
    """True when ``data`` starts as an mzc file's magic line does."""
    return data[:4] == MZC_MAGIC


def names(kinds: tuple[str, ...]) -> list[str]:
    """The names of mzc's formats (and this process's) of ``kinds``, in rank order."""
    return [row.name for row in own_formats() if row.kind in kinds]


def expected(kinds: tuple[str, ...]) -> str:
    """``kinds`` in words: ``a mesh or point cloud``."""
    nouns = [NOUNS[kind] for kind in kinds]
    return "a " + (nouns[0] if len(nouns) == 1 else f"{', '.join(nouns[:-1])} or {nouns[-1]}")


def identified(data: bytes, source: str, kinds: tuple[str, ...] = KINDS, name: str | None = None) -> Format:
    """The row of the format of ``data`` (the one called ``name``, else ``identify``'s) when its files
    hold one of ``kinds``; else a one-line error saying what they hold (or that there is nothing)."""
    if not data or data.isspace():
        raise MzcError(f"empty input: expected {expected(kinds)}", source=source)
    row = named(name) if name is not None else identify(data, source, kinds)
    if row.kind not in kinds:
        raise MzcError(f"holds a {NOUNS[row.kind]} ({row.name}), not {expected(kinds)}", source=source)
    return row


def read(data: bytes, source: str, kinds: tuple[str, ...] = KINDS, path: str | os.PathLike | None = None,
         name: str | None = None) -> Any:
    """What ``data`` holds, a file called ``source`` (read from ``path``, when it was), read by its
    format (``identified``): a ZGrid of a z-grid, compressed file or raster, a Mesh of a mesh or
    point cloud."""
    return read_as(identified(data, source, kinds, name), data, source, path)


def read_file(path: str | os.PathLike | None, kinds: tuple[str, ...] = KINDS) -> Any:
    """What the file at ``path`` (stdin for ``-`` or None) holds, as ``read`` reads it."""
    from mzc.streams import display_name, read_input

    return read(read_input(path), display_name(path), kinds, path)


def read_any(data: bytes, source: str) -> Any:
    """The ZGrid of the bytes of a grid: a z-grid, a compressed mzc file (decoded) or a raster."""
    return read(data, source, GRIDS)


def read_as(row: Format, data: bytes, source: str, path: str | os.PathLike | None = None) -> Any:
    """The item ``data`` holds, read by ``row``'s module (with the CRS of the sidecar beside
    ``path``, for a format that keeps it there) and held to what every item of its kind is
    (CHECKS: a grid within mzc.limits, a mesh of finite points that its triangles index)."""
    module = row.load()
    item = module.read(data, source, crs=sidecar_crs(path, row.sidecar)) if row.sidecar else module.read(data, source)
    attribute(CHECKS[row.kind])(item, source=source)
    return item


def sidecar_crs(path: str | os.PathLike | None, extension: str) -> str | None:
    """The one-line WKT of the sidecar beside the file at ``path`` (its name with ``extension``), or
    None: when there is none, or ``path`` is stdin's."""
    if path is None or path == "-":
        return None
    try:
        with open(os.path.splitext(os.fspath(path))[0] + extension, "rb") as file:
            text = file.read(1 << 20).decode("utf-8", "replace")
    except OSError:
        return None
    return " ".join(text.split()) or None


def header_versions(row: Format) -> dict[str, int | None]:
    """{projected_major, charted_major, georef_since, counted_since}: the first major versions of an mzc
    format whose files may hold a central projection and charts, and the first minor of each major
    that holds the crs and raster lines, and the source_vertices line (a built-in format's module
    names them; for a codec from elsewhere, its newest version holds projections and none charts,
    georeferencing or a source's count)."""
    module = row.load()
    if hasattr(module, "PROJECTED_VERSION"):
        return {"projected_major": module.PROJECTED_VERSION[0],
                "charted_major": getattr(module, "CHARTED_VERSION", (None,))[0],
                "georef_since": getattr(module, "GEOREF_SINCE", None),
                "counted_since": getattr(module, "COUNTED_SINCE", None)}
    return {"projected_major": module.version[0], "charted_major": None}


def writes(row: Format) -> bool:
    """True when mzc writes ``row``'s format from an item (a codec's file is encoded, with options)."""
    return row.kind != "compressed" and row.load().write is not None


def writable(kinds: tuple[str, ...]) -> list[str]:
    """The names of the formats of ``kinds`` that mzc writes, in rank order."""
    return [row.name for row in own_formats() if row.kind in kinds and writes(row)]


def writer_for(path: str | os.PathLike | None, file_format: str | None, kinds: tuple[str, ...]) -> Format | None:
    """The row of ``kinds`` that writes the format ``file_format`` names (a name or an extension:
    ply, tif, tiff, zg), else the one the extension of ``path`` names; None when they name none."""
    word = file_format if file_format is not None else os.path.splitext(os.fspath(path or ""))[1]
    word = word.lower().lstrip(".")
    return next((row for row in own_formats() if word and row.kind in kinds and writes(row)
                 and (row.name == word or "." + word in row.load().EXTENSIONS)), None)


def extensions(kinds: tuple[str, ...]) -> list[str]:
    """The extensions of mzc's formats of ``kinds`` (not compressed: a codec names its own), in rank order."""
    return [extension for row in own_formats() if row.kind in kinds for extension in row.load().EXTENSIONS]
