"""Triangle meshes and point clouds at the edges of mzc: the one mesh type, and reading
and writing mesh files.

``read_mesh`` accepts OBJ, PLY (ascii and binary), VTK, STL and OFF, and point clouds (a
PLY with vertices only, ``x y z`` text, PCD, and LAS/LAZ through the ``las`` extra). Real
files come in many dialects, so OBJ, PLY and STL are read by mzc's own vectorised readers (meshio misreads negative OBJ
indices, refuses valid PLY files: vertex-only, ``vertex_index``, extra properties, and
reads truncated PLY and STL files as if complete); meshio reads VTK and OFF. Polygons are
fan-triangulated; other cell types are ignored. Every problem becomes an MzcError naming
the file, and the line where it is known: a file that breaks the counts it declares, or
holds anything but numbers where numbers belong, is refused, never read in part.

Each format is one module of this package, a row of the one table of file formats
(``mzc.formats``), which identifies a file and picks the module that reads or writes it; the
format modules see bytes only, and paths, stdin/stdout and atomic output are ``mzc.streams``'s.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mzc.colours import colour_array
from mzc.errors import MzcError
from mzc.meshes.common import as_indices
from mzc.numbers import real_array
from mzc.streams import is_stdio, is_stream, write_output

if TYPE_CHECKING:
    from mzc.grid import ZGrid
    from mzc.meshes.texture import Texture


@dataclass
class Mesh:
    """Vertices ``points`` (n, 3) and ``triangles`` (m, 3) indexing them; (0, 3) for a point
    cloud, whose file may give ``normals`` (n, 3) (they tell a slice which side it was seen
    from) and ``classification`` (n,), the ASPRS class of each point of a LAS/LAZ cloud
    (``with_classes``). ``colors`` (n, 3) uint8 is each vertex's red, green and blue, None when
    the file has none (``mzc.colours``; a texture is sampled at the vertices), and ``texture``
    a textured mesh's image and its triangles' corners' texture coordinates
    (``mzc.meshes.texture.Texture``), which slicing samples at every node. ``crs`` is the
    coordinate reference system the file names (a WKT
    string, or ``EPSG:code``), None when it names none. ``dropped`` names what the file held
    that mzc does not keep (a mesh's normals, alpha, other properties),
    so that slicing can say so in one warning rather than lose it without a word. ``grid`` is the z-grid the mesh was
    derived from, when it was (``grid_to_mesh``): ``mzc diff`` compares a grid at its own
    nodes and in its own frame."""

    points: np.ndarray
    triangles: np.ndarray = field(default_factory=lambda: np.empty((0, 3), dtype=np.int64))
    normals: np.ndarray | None = None
    grid: ZGrid | None = None
    classification: np.ndarray | None = None
    crs: str | None = None
    dropped: tuple[str, ...] = ()
    colors: np.ndarray | None = None
    texture: Texture | None = None

    def __post_init__(self):
        self.points = real_array(self.points, "points", in_threes("points")).reshape(-1, 3)
        self.triangles = vertex_indices(self.triangles)
        if self.normals is not None:
            self.normals = real_array(self.normals, "normals", in_threes("normals", len(self.points)))
            self.normals = self.normals.reshape(self.points.shape)
        if self.classification is not None:
            self.classification = np.asarray(self.classification).reshape(len(self.points))
        if self.colors is not None:
            self.colors = colour_array(self.colors, (len(self.points), 3))
        if self.texture is not None and self.texture.corner_uv.shape != (len(self.triangles), 3, 2):
            raise MzcError(f"a texture needs u v for the 3 corners of each of the {len(self.triangles)} triangles",
                           field="texture")

    def with_classes(self, classes) -> Mesh:
        """The cloud of the points whose ``classification`` is one of ``classes`` (ASPRS codes:
        2 = ground), as PDAL's filters.range on Classification keeps them; an MzcError when
        the points have no classes or none has one of those."""
        if self.classification is None or len(self.triangles):
            raise MzcError("the input has no point classes (a LAS/LAZ cloud has them)", field="classes")
        keep = np.isin(self.classification, np.asarray(list(classes)))
        if not keep.any():
            present = ", ".join(str(code) for code in np.unique(self.classification)[:20])
            raise MzcError(f"no point has class {', '.join(str(code) for code in classes)} "
                           f"(the cloud's classes: {present})", field="classes")
        normals = None if self.normals is None else self.normals[keep]
        colors = None if self.colors is None else self.colors[keep]
        return Mesh(self.points[keep], normals=normals, classification=self.classification[keep], crs=self.crs,
                    colors=colors)

    @property
    def is_point_cloud(self) -> bool:
        """True for points alone: no triangles, and not derived from a grid."""
        return len(self.triangles) == 0 and self.grid is None

    def to_trimesh(self) -> Any:
        """This mesh as a ``trimesh.Trimesh`` (vertices and faces as they are, nothing merged or
        dropped; its vertex colours, when it has them), or a ``trimesh.PointCloud`` for points alone;
        trimesh is not one of mzc's dependencies: an MzcError says so when it is missing."""
        trimesh = optional_module("trimesh")
        if self.is_point_cloud:
            return trimesh.PointCloud(self.points, colors=self.colors)
        return trimesh.Trimesh(self.points, self.triangles, vertex_normals=self.normals, vertex_colors=self.colors,
                               process=False)

    def to_meshio(self) -> Any:
        """This mesh as a ``meshio.Mesh``: its points, one triangle cell block (none for a cloud),
        its normals as the point data ``normals`` and its colours as ``red``, ``green`` and
        ``blue`` (uint8, the names meshio's PLY writer writes as PLY's) when it has them."""
        import meshio

        cells = [("triangle", self.triangles)] if len(self.triangles) else []
        point_data = {"normals": self.normals} if self.normals is not None else {}
        if self.colors is not None:
            point_data.update(zip(("red", "green", "blue"), self.colors.T))
        return meshio.Mesh(self.points, cells, point_data=point_data)

    def parts(self) -> tuple:
        """(vertex count, triangle count, the points in chunks, the triangles in chunks): what a
        writer that streams a mesh reads (one chunk each here; a grid's mesh,
        ``mzc.ops.triangulation.GridMesh``, makes them a strip of rows at a time)."""
        return len(self.points), len(self.triangles), [self.points], [self.triangles]


def warn_dropped(mesh):
    """One MzcWarning naming what the mesh's file held that a grid does not carry (a mesh's
    normals, alpha, other properties: ``Mesh.dropped``; its colours it carries), so that nothing
    is lost without a word (a grid, which has none, passes)."""
    if getattr(mesh, "dropped", ()):
        import warnings

        from mzc.errors import MzcWarning

        warnings.warn(MzcWarning(f"not kept, mzc codes the shape and colour alone: {'; '.join(mesh.dropped)}"),
                      stacklevel=2)


def optional_module(name):
    """The module ``name``, imported now; an MzcError naming it when it is not installed."""
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError:
        raise MzcError(f"this needs the package {name}: pip install {name}") from None


def in_threes(field, rows=None):
    """A shape check for ``real_array``: (n, 3) values, or as many as (``rows``, 3)."""
    def check(shape):
        size = int(np.prod(shape))
        if size % 3 or (rows is not None and size != 3 * rows):
            raise MzcError(f"must be {'an (n' if rows is None else f'a ({rows}'}, 3) array, not one of shape {shape}",
                           field=field)
    return check


def vertex_indices(values):
    """(m, 3) int64 triangles of ``values``: integers, or floats that are whole numbers (a
    fraction, NaN or a huge index is refused, not cast)."""
    array = np.asarray(values) if isinstance(values, np.ndarray) else real_or_integers(values)
    if array.dtype.kind in "iu":
        in_threes("triangles")(array.shape)
        return array.astype(np.int64, copy=False).reshape(-1, 3)
    return as_indices(real_array(array, "triangles", in_threes("triangles")), "a triangle's", None).reshape(-1, 3)


def real_or_integers(values):
    """``values`` as an array: whole numbers as integers, as numpy makes them."""
    try:
        return np.asarray(values)
    except (TypeError, ValueError, OverflowError):   # ragged lists: real_array says so
        return real_array(values, "triangles")


def read_mesh(path: str | os.PathLike | None) -> Mesh:
    """Read a mesh or point cloud from ``path`` (``-`` or None for stdin), its format identified
    as every file's is (``mzc.formats``)."""
    from mzc.formats import SURFACES, read_file

    return read_file(path, SURFACES)


def mesh_from_bytes(data: bytes, source: str = "<bytes>", file_format: str | None = None) -> Mesh:
    """The mesh or point cloud in ``data``, read as ``file_format`` (a format's name) or as the
    format ``mzc.formats`` identifies; ``source`` names the data in error messages."""
    from mzc.formats import SURFACES, read

    return read(data, source, SURFACES, name=file_format)


def checked(mesh: Mesh, source: str) -> Mesh:
    """Refuse a mesh with no points, non-finite coordinates or face indices out of range."""
    if len(mesh.points) == 0:
        raise MzcError("the mesh has no points", source=source)
    finite = np.isfinite(mesh.points).all(axis=1)
    if not finite.all():
        vertex = int(np.flatnonzero(~finite)[0]) + 1
        raise MzcError(f"vertex {vertex} has a NaN or infinite coordinate", source=source)
    if len(mesh.triangles):
        bad = (mesh.triangles < 0) | (mesh.triangles >= len(mesh.points))
        if bad.any():
            face = int(np.flatnonzero(bad.any(axis=1))[0])
            index = int(mesh.triangles[face][bad[face]][0])
            if index < 0:
                raise MzcError(f"triangle {face + 1} has a negative vertex index ({index})", source=source)
            raise MzcError(f"triangle {face + 1} refers to vertex {index + 1}, but there are only "
                           f"{len(mesh.points)} vertices", source=source)
    return mesh


def write_mesh(path: str | os.PathLike | None, mesh: Mesh, file_format: str | None = None) -> None:
    """Write ``mesh`` to ``path`` atomically, as ``file_format`` or the format of its extension.

    ``-`` or None writes OBJ text to stdout whatever ``file_format`` says; a device or FIFO
    (``/dev/null``) without ``file_format`` gets OBJ too. ``mesh`` may be a grid's mesh made
    as it is written (``mzc.ops.triangulation.GridMesh``): a PLY file is then written a strip
    of rows at a time.
    """
    if is_stdio(path):
        write_output(path, mesh_to_bytes(mesh, "obj"))
        return
    if file_format is None:
        file_format = os.path.splitext(str(path))[1].lower().lstrip(".")
        if not file_format:
            if not is_stream(path):
                raise MzcError("no mesh format: give the file an extension (.obj, .ply, .stl, .vtk, .off) "
                               "or --format", source=path)
            file_format = "obj"
    try:
        data = mesh_chunks(mesh, file_format)
    except MzcError as error:
        raise error.located(source=path) from None
    write_output(path, data)


def mesh_to_bytes(mesh: Mesh, file_format: str) -> bytes:
    """The bytes of ``mesh`` in ``file_format`` (obj, ply, vtk, stl or off; PLY is binary)."""
    data = mesh_chunks(mesh, file_format)
    return data if isinstance(data, bytes) else b"".join(data)


def mesh_chunks(mesh: Mesh, file_format: str) -> Any:
    """``mesh`` in ``file_format`` (a format's name or extension): its bytes, or (PLY) an iterator
    of bytes-like chunks that ``mzc.streams.write_output`` writes as they are made."""
    from mzc.formats import SURFACES, writable, writer_for

    row = writer_for(None, file_format, SURFACES)
    if row is None:
        raise MzcError(f"cannot write mesh format {file_format!r} (choose one of {', '.join(writable(SURFACES))})")
    return row.load().write(mesh)
