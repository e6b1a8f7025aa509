"""VTK and OFF through meshio, and the writer of ascii STL.

meshio wants file names, so bytes go through an in-memory file (a memfd on Linux, which
not even SIGKILL leaves on disk; a temporary file elsewhere); meshio is imported only when
one of these formats is read or written (it takes 0.2 s). Its warnings, log messages and
prints are silenced (stdout carries data only, stderr mzc's own messages), and any failure
becomes an MzcError naming the file. meshio allocates what a header declares before it reads
(a 50-byte OFF declaring 10^8 vertices: 2.3 GB), so each count a header declares is first held
to the file's size, every value taking at least a byte (``declared_values``).
"""

import contextlib
import io
import logging
import os
import re
import tempfile
import warnings
from collections.abc import Callable, Iterator

import numpy as np

from mzc.errors import MzcError, first_line
from mzc.meshes import Mesh
from mzc.meshes.common import fan_triangulate
from mzc.numbers import unpadded


class MeshioFormat:
    """One format meshio reads and writes, declared like a format module."""

    def __init__(self, name: str, extensions: tuple[str, ...], sniff: Callable[[bytes], bool | None] | None,
                 is_text: Callable[[bytes], bool], counts: re.Pattern):
        self.NAME = name
        self.EXTENSIONS = extensions
        self.sniff = sniff
        self.is_text = is_text
        self.counts = counts

    def read(self, data: bytes, source: str) -> Mesh:
        """The mesh in ``data``, read by meshio once its header's counts fit the file; a text file
        without the NUL bytes that pad its end."""
        values = declared_values(self.counts, data)
        if values > len(data):
            raise MzcError(f"the {self.NAME.upper()} header declares {values} values, more than the file's "
                           f"{len(data)} bytes hold", source=source)
        return read_as(self.NAME, unpadded(data) if self.is_text(data) else data, source)

    def write(self, mesh: Mesh) -> bytes:
        """The bytes meshio writes for ``mesh``."""
        return write_as(self.NAME, mesh)


# the counts a header declares: of points (3 values each), or of values (a section's, its size):
# VTK's section lines (POINTS n, CELLS n size, ...), OFF's vertex and face counts after its keyword
VTK_COUNTS = re.compile(rb"^(?:POINTS[ \t]+(?P<points>\d+)|(?:CELLS|POLYGONS|TRIANGLE_STRIPS|LINES|VERTICES|"
                        rb"CELL_TYPES|OFFSETS|CONNECTIVITY)[ \t]+(?P<values>\d+)(?:[ \t]+(?P<size>\d+))?)",
                        re.MULTILINE)
OFF_COUNTS = re.compile(rb"\A\s*[NCST4]*OFF\b(?:\s*#[^\n]*)*(?:\s*BINARY)?(?:\s*#[^\n]*)*"
                        rb"\s*(?P<points>\d+)\s+(?P<values>\d+)")
VTK = MeshioFormat("vtk", (".vtk",), None,   # identified by its magic (mzc.formats)
                   lambda data: data[:1024].split(b"\n", 3)[2:3] == [b"ASCII"], VTK_COUNTS)   # the third line
OFF = MeshioFormat("off", (".off",), lambda data: True if re.match(rb"\s*[NCST4]*OFF\b", data[:4096]) else None,
                   lambda data: b"BINARY" not in data[:64], OFF_COUNTS)


def declared_values(counts, data):
    """The largest count of values a header declares (``counts``' matches: points, 3 values
    each, or values)."""
    found = [3 * int(match["points"] or 0) + int(match["values"] or 0) + int(match.groupdict().get("size") or 0)
             for match in counts.finditer(data)]
    return max(found, default=0)


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence meshio's warnings, log messages and prints (to stdout, which carries data only,
    and to stderr, where its rich console writes 'Warning: ...')."""
    logging.disable(logging.CRITICAL)
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()):
            warnings.simplefilter("ignore")
            yield
    finally:
        logging.disable(logging.NOTSET)


@contextlib.contextmanager
def temporary_name(kind: str) -> Iterator[str]:
    """A file name for meshio: an in-memory file (``/proc/self/fd/N`` of a memfd) where Linux
    has one, so nothing is left on disk even by SIGKILL, else ``mesh.KIND`` in a fresh
    temporary directory; removed afterwards."""
    if hasattr(os, "memfd_create") and os.path.isdir("/proc/self/fd"):
        fd = os.memfd_create("mzc-mesh", os.MFD_CLOEXEC)
        try:
            yield f"/proc/self/fd/{fd}"
        finally:
            os.close(fd)
        return
    with tempfile.TemporaryDirectory(prefix="mzc-") as directory:
        yield os.path.join(directory, f"mesh.{kind}")


def read_as(kind: str, data: bytes, source: str) -> Mesh:
    """Read ``data`` as meshio's ``kind`` format; any failure becomes an MzcError."""
    import meshio

    if kind == "off" and not off_has_counts_line(data):
        raise MzcError("OFF file ends before its counts line 'vertices faces edges'", source=source)
    reader = getattr(meshio, kind).read  # meshio.read would print to stdout and sys.exit on failure
    try:
        with temporary_name(kind) as name, quiet():
            with open(name, "wb") as handle:
                handle.write(data)
            result = reader(name)
    except Exception as error:  # noqa: BLE001 - meshio raises many types on bad data
        raise MzcError(f"cannot read as {kind.upper()}: {first_line(error)}", source=source) from None
    return Mesh(xyz_of(result.points), surface_triangles(result.cells))


def off_has_counts_line(data: bytes) -> bool:
    """True when an OFF file has a line after ``OFF`` that is neither blank nor a comment.

    meshio's OFF reader skips such lines in a loop that never stops at the end of the file.
    """
    lines = data.split(b"\n")[1:]
    return any(line.strip() and not line.strip().startswith(b"#") for line in lines)


def xyz_of(points) -> np.ndarray:
    """(n, 3) coordinates of meshio points: 2D points get z = 0, nothing read gives (0, 3)."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.size == 0:
        return np.empty((0, 3))
    if points.shape[1] < 3:
        return np.hstack([points, np.zeros((len(points), 3 - points.shape[1]))])
    return points[:, :3]


def surface_triangles(cells) -> np.ndarray:
    """The triangles of meshio cell blocks: triangles, quads and polygons, fan-triangulated."""
    pieces = [fan_triangulate(block.data) for block in cells
              if (block.type in ("triangle", "quad") or block.type.startswith("polygon"))
              and np.asarray(block.data).ndim == 2 and np.asarray(block.data).shape[1] >= 3]
    if not pieces:
        return np.empty((0, 3), dtype=np.int64)
    return np.concatenate(pieces).astype(np.int64)


def write_as(kind: str, mesh: Mesh) -> bytes:
    """The bytes of ``mesh`` written by meshio as ``kind`` (stl, vtk or off); STL needs triangles.
    Its colours, which mzc writes to PLY and OBJ only, are named in one warning."""
    import meshio

    if kind == "stl" and not len(mesh.triangles):
        raise MzcError("STL cannot hold a point cloud (no triangles)")
    if mesh.colors is not None:
        from mzc.colours import warn_not_kept

        warn_not_kept("the vertex colours", f"{kind.upper()} as mzc writes it has none; write PLY or OBJ to keep them")
    cells = [("triangle", mesh.triangles.astype(np.int32))] if len(mesh.triangles) else []   # as mzc has always written
    with temporary_name(kind) as name:
        with quiet():
            meshio.write(name, meshio.Mesh(mesh.points, cells), file_format=kind)
        with open(name, "rb") as handle:
            return handle.read()
