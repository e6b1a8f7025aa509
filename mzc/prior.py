"""Shared priors for collections of like surfaces (issue 33): ``mzc train``, ``encode --prior``,
``decode --prior``; the formats ``mzc-prior 1.0`` and ``mzc-residual 1.0`` (spec/prior.md).

A prior is the mean of a collection's surfaces on ONE lattice (a z-grid header: projection, centre,
axis, spacings, extent), every node holding a value, so that a decoder adds two grids node by node:
no ray is cast at decode. ``train`` takes the lattice of the surfaces' union's default slice grown by
whole nodes to cover them all, cuts every surface on it (``slice_on``), averages the values each
node has and fills the nodes none has from the nearest that has one. A grid cut on the lattice is
coded twice, alone and as its residual (grid - mean, at its valid nodes) in a residual file, and
the smaller is written: a plain file needs no prior. A residual file names its prior by the
SHA-256 of the prior file's bytes; its inner stream is any dwt2d file of the residual as a planar
grid of the lattice's rows, columns and spacings (the rest of the lattice is the prior's: no bytes
for it), read by dwt2d's reader.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from mzc.errors import MzcError
from mzc.grid import ZGrid

PRIOR_MAGIC = b"mzc-prior 1.0\n"
RESIDUAL_MAGIC = b"mzc-residual 1.0\n"
DIGEST_BYTES = 32   # SHA-256
LATTICE = ("projection", "radius", "transform", "origin", "d1", "d2", "shape", "charts", "crs")   # what must match
SURFACES = re.compile(rb"surfaces ([1-9][0-9]{0,8})")
WHOLE_ONLY = ("tile", "progressive")   # dwt2d options a residual file does not take: it codes the grid whole


@dataclass(frozen=True)
class Prior:
    """A prior: its ``mean`` grid (every node valid), the count of ``surfaces`` it was trained on,
    and the bytes of its file (``data``), whose SHA-256 names it."""

    mean: ZGrid
    surfaces: int
    data: bytes

    @property
    def digest(self) -> bytes:
        """SHA-256 of the prior file's bytes: what a residual file names it by."""
        return hashlib.sha256(self.data).digest()

    @property
    def name(self) -> str:
        """The digest in hexadecimal, as messages and ``mzc info`` show it."""
        return self.digest.hex()


def prior_of(mean: ZGrid, surfaces: int) -> Prior:
    """The Prior of a ``mean`` grid of ``surfaces`` surfaces, with the bytes of its file."""
    from mzc.formats import zgrid

    return Prior(mean, surfaces, PRIOR_MAGIC + b"surfaces %d\n" % surfaces + zgrid.write(mean, raw="float64"))


def read_prior(data: bytes, source: str = "<bytes>") -> Prior:
    """The Prior of a prior file's bytes; bad input is an MzcError naming the line."""
    from mzc.formats import zgrid
    from mzc.limits import check_grid_magnitudes

    if not data.startswith(PRIOR_MAGIC):
        found = data[:40].split(b"\n", 1)[0].decode("ascii", "replace")
        raise MzcError(f"not a prior file (mzc-prior 1.0, written by mzc train): it starts {found!r}",
                       source=source, line=1)
    line, _, rest = data[len(PRIOR_MAGIC):].partition(b"\n")
    count = SURFACES.fullmatch(line)
    if count is None:
        raise MzcError("must be 'surfaces N' (N >= 1)", source=source, line=2, field="surfaces")
    mean = zgrid.read(rest, source)
    check_grid_magnitudes(mean, source=source)
    if not mean.valid.all() or mean.charts is not None or mean.colors is not None:
        raise MzcError("a prior's mean grid holds a value at every node, and no charts or colours",
                       source=source, field="data")
    return Prior(mean, int(count[1]), bytes(data))


def as_prior(prior: Any, name: str = "prior") -> Prior:
    """A ``prior`` argument as a Prior: a Prior, the bytes of a prior file, or its path."""
    import os

    if isinstance(prior, Prior):
        return prior
    if isinstance(prior, (bytes, bytearray, memoryview)):
        return read_prior(bytes(prior))
    if isinstance(prior, (str, os.PathLike)):
        from mzc.streams import display_name, path_of, read_input

        path = path_of(prior, name)
        return read_prior(read_input(path), display_name(path))
    raise MzcError(f"must be a prior (its path, its bytes or a mzc.prior.Prior), not a {type(prior).__name__}",
                   field=name)


def train(meshes: list, d1: float | None = None, d2: float | None = None) -> Prior:
    """The prior of ``meshes`` (Mesh objects): their mean on the lattice of their union's default
    slice (spacings ``d1``, ``d2`` when given) grown to cover them all (``covering``); a node no
    surface meets takes the value of the nearest node one meets (ties broken by
    scipy.ndimage.distance_transform_edt, deterministically)."""
    from scipy.ndimage import distance_transform_edt

    from mzc.ops.slicing import slice_surface

    if not meshes:
        raise MzcError("training takes at least one surface", field="surfaces")
    lattice = covering(slice_surface(union(meshes), d1=d1, d2=d2, charts=1), meshes)
    total, count = np.zeros(lattice.shape), np.zeros(lattice.shape, dtype=np.int64)
    for mesh in meshes:
        z = slice_on(mesh, lattice).z
        valid = ~np.isnan(z)
        total[valid] += z[valid]
        count += valid
    missing = count == 0
    mean = total / np.maximum(count, 1)
    nearest = distance_transform_edt(missing, return_distances=False, return_indices=True)
    return prior_of(ZGrid(mean[tuple(nearest)], lattice.d1, lattice.d2, origin=lattice.origin,
                          transform=lattice.transform, units=lattice.units, projection=lattice.projection,
                          radius=lattice.radius), len(meshes))


def union(meshes: list) -> Any:
    """One Mesh of all ``meshes``' points and triangles: slice's default choices made on it (view,
    centre, axis, spacing) suit the collection, not its first surface."""
    from mzc.meshes import Mesh

    offsets = np.cumsum([0] + [len(mesh.points) for mesh in meshes[:-1]])
    return Mesh(np.concatenate([mesh.points for mesh in meshes]),
                np.concatenate([mesh.triangles + offset for mesh, offset in zip(meshes, offsets)]))


def covering(grid: ZGrid, meshes: list) -> ZGrid:
    """``grid``'s lattice grown by whole nodes on each side to cover every mesh's extent in its
    (u, v), a full turn kept as it is and a spherical grid's v within its poles."""
    from mzc.projections import to_nodes

    steps = np.array([grid.d2, grid.d1])
    origin = np.array(grid.origin, dtype=float)
    low, high = origin.copy(), origin + steps * (np.array(grid.shape[::-1]) - 1)
    for mesh in meshes:
        nodes = to_nodes(grid.projection, grid.radius, grid.to_grid_frame(mesh.points))[:, :2]
        low, high = np.minimum(low, nodes.min(axis=0)), np.maximum(high, nodes.max(axis=0))
    if grid.projection == "spherical":
        pole = np.pi / 2 * (grid.radius or 0.0)
        low[1], high[1] = max(low[1], -pole), min(high[1], pole)
    before = np.minimum(np.floor((low - origin) / steps), 0)
    start = origin + before * steps
    counts = np.maximum(np.floor((high - start) / steps + 1e-9) + 1, np.array(grid.shape[::-1]) - before)
    if grid.periodic:   # a full turn has all its columns already
        start[0], counts[0] = origin[0], grid.shape[1]
    return ZGrid(np.full((int(counts[1]), int(counts[0])), np.nan), grid.d1, grid.d2, origin=tuple(start.tolist()),
                 transform=grid.transform, units=grid.units, projection=grid.projection, radius=grid.radius)


# the options of ``mzc slice`` that apply beside a prior: the others shape a grid, as its lattice does
UNSHAPING = frozenset({"classes", "cloud", "units"})


def refuse_shaping(options: Any) -> None:
    """Refuse the first of ``options`` (the names of slice's options given, away from their
    defaults) that shapes a grid: beside a prior, its lattice shapes it."""
    refused = next((name for name in options if name not in UNSHAPING), None)
    if refused:
        raise MzcError("the prior's lattice shapes the grid, so this option does not apply beside it",
                       field=refused, options=(refused,))


def sliced(surface: Any, prior: Prior, classes: Any = None, units: str | None = None) -> ZGrid:
    """``surface`` (a mesh or cloud, or a grid taken as its mesh, a vertex at every node) cut on
    ``prior``'s lattice (``mzc slice --prior``), keeping the ASPRS ``classes`` of a LAS cloud when
    given, its values in ``units`` when given: the one home of the API's and the batch's."""
    if isinstance(surface, ZGrid):
        from mzc.ops.triangulation import grid_to_mesh

        surface = grid_to_mesh(surface)
    mesh = surface if classes is None else surface.with_classes(classes)
    grid = slice_on(mesh, prior.mean)
    return grid if units is None else grid.with_z(grid.z, units=units)


def slice_on(mesh: Any, lattice: ZGrid) -> ZGrid:
    """The grid of ``mesh`` cut on ``lattice``'s node lines (its header: projection, frame, spacings,
    extent), the outermost hit of each as ``mzc slice`` takes it; a point cloud is triangulated in
    the lattice's (u, v) first."""
    from mzc.ops.slicing import values_along
    from mzc.projections import to_nodes

    local = lattice.to_grid_frame(mesh.points)
    triangles = mesh.triangles
    if mesh.is_point_cloud:
        from mzc.ops.delaunay import triangulate_point_cloud

        triangles = triangulate_point_cloud(to_nodes(lattice.projection, lattice.radius, local)[:, :2])
    z = values_along(lattice.projection, lattice.radius, local, triangles, lattice.xs(), lattice.ys())
    if np.isnan(z).all():
        raise MzcError("no node of the prior's lattice meets the surface (is it a surface of the prior's kind, "
                       "in the same frame?)")
    return ZGrid(z, lattice.d1, lattice.d2, origin=lattice.origin, transform=lattice.transform, units=lattice.units,
                 projection=lattice.projection, radius=lattice.radius, source_vertices=len(mesh.points))


def lattice_field(grid: ZGrid, prior: Prior) -> str | None:
    """The first field of LATTICE in which ``grid``'s header differs from the prior's mean's, or None."""
    for name in LATTICE:
        mine, theirs = getattr(grid, name), getattr(prior.mean, name)
        if name == "transform" or name == "origin":
            mine, theirs = np.asarray(mine, dtype=float), np.asarray(theirs, dtype=float)
            if mine.shape != theirs.shape or not np.array_equal(mine, theirs):
                return name
        elif mine != theirs:
            return name
    return None


def check_fits(grid: ZGrid, prior: Prior, source: str | None = None) -> None:
    """Refuse, in one line, a grid that is not on the prior's lattice (which field differs, and the
    fix), or that holds what a residual file does not code: colours, a raster's samples."""
    field = lattice_field(grid, prior)
    if field is not None:
        raise MzcError(f"the grid's {field} differs from the prior's ({prior.name[:12]}): cut the surface on its "
                       "lattice with mzc slice --prior", source=source)
    if grid.colors is not None or grid.raster is not None:
        what = "colours" if grid.colors is not None else "a raster's samples"
        raise MzcError(f"encode --prior codes a sliced surface's heights alone, and this grid holds {what}",
                       source=source)


def encode(grid: ZGrid, prior: Prior, source: str | None = None, **options: Any) -> bytes:
    """The smaller of ``grid``'s dwt2d file and its residual file against ``prior`` (``options``:
    dwt2d's; targets hold on the rebuilt grid, the mean plus the decoded residual)."""
    from mzc.codecs import get_codec

    check_fits(grid, prior, source)
    codec = get_codec("dwt2d")
    options = codec.checked(options)
    whole = next((name for name in WHOLE_ONLY if options.get(name)), None)
    if whole:
        raise MzcError("a residual file codes the grid whole: leave it out with a prior", field=whole)
    plain = codec.encode(grid, **options)
    contained = residual_file(grid, prior, options)
    return contained if contained is not None and len(contained) < len(plain) else plain


def residual_file(grid: ZGrid, prior: Prior, options: dict[str, Any]) -> bytes | None:
    """The residual file of ``grid`` against ``prior``: the residual, as a planar grid of the lattice's
    shape and spacings, coded by dwt2d with equal steps
    unless ``slope_limit`` is given (its lean is not the surface's), the rmse target measured on
    ``grid``'s surface, a max_error target tightened by the float rounding of the subtraction and
    the decoder's addition; None when the rebuilt grid would break a max_error target all the same."""
    from mzc.codecs.dwt2d import encode_whole
    from mzc.limits import check_grid_magnitudes

    valid = grid.valid
    residual = ZGrid(np.where(valid, grid.z - prior.mean.z, np.nan), grid.d1, grid.d2, units=grid.units,
                     nodata=grid.nodata, source_vertices=grid.source_vertices)   # planar: the lattice is the prior's
    check_grid_magnitudes(residual)
    settings = {name: value for name, value in options.items() if name not in WHOLE_ONLY}
    settings["slope_limit"] = options.get("slope_limit", 1.0)
    bound = settings.get("max_error")
    if bound is not None:
        largest = float(np.max(np.abs(grid.z[valid]), initial=0.0)) + bound
        settings["max_error"] = bound - 2 * float(np.spacing(largest))
        if settings["max_error"] <= 0:
            return None
    data, decoded = encode_whole(residual, **settings, surface=grid)
    if bound is not None and np.any(np.abs(prior.mean.z[valid] + decoded[valid] - grid.z[valid]) > bound):
        return None
    return RESIDUAL_MAGIC + prior.digest + data


def residual_digest(data: bytes, source: str) -> bytes:
    """The digest of the prior a residual file names; a file cut before it is an MzcError."""
    digest = data[len(RESIDUAL_MAGIC):len(RESIDUAL_MAGIC) + DIGEST_BYTES]
    if not data.startswith(RESIDUAL_MAGIC) or len(digest) < DIGEST_BYTES:
        raise MzcError("not a residual file (mzc-residual 1.0 and the prior's 32-byte digest)", source=source,
                       line=1)
    return digest


def decode(data: bytes, source: str, prior: Prior | None) -> ZGrid:
    """The grid of a residual file: its inner dwt2d stream decoded, plus ``prior``'s mean at its valid
    nodes; without the prior it names (or with another) one line saying which it needs."""
    from mzc.codecs.dwt2d import read

    digest = residual_digest(data, source)
    if prior is None:
        raise MzcError(f"was coded against the prior {digest.hex()}: give that prior file with --prior FILE "
                       "(mzc.decode(data, prior=...))", source=source)
    if prior.digest != digest:
        raise MzcError(f"was coded against the prior {digest.hex()}, not the one given ({prior.name})",
                       source=source)
    inner = read(data[len(RESIDUAL_MAGIC) + DIGEST_BYTES:], source)
    mean = prior.mean
    planar = ZGrid(np.zeros(mean.shape), mean.d1, mean.d2)
    field = next((name for name in ("shape", "d1", "d2", "origin", "projection", "transform", "charts", "crs")
                  if not np.array_equal(getattr(inner, name), getattr(planar, name))), None)
    if field is not None:
        raise MzcError(f"the residual's {field} is not the planar grid of its prior's lattice (corrupt file)",
                       source=source, field="data")
    valid = inner.valid
    z = np.full(inner.shape, np.nan)
    z[valid] = mean.z[valid] + inner.z[valid]
    return ZGrid(z, mean.d1, mean.d2, origin=mean.origin, transform=mean.transform, units=inner.units,
                 nodata=inner.nodata, projection=mean.projection, radius=mean.radius,
                 source_vertices=inner.source_vertices)


def read(data: bytes, source: str, prior: Prior, path: Any = None) -> ZGrid:
    """The grid of a grid file's bytes (from ``path``, when read from one): a residual file decoded
    with ``prior``, any other as it decodes alone (an encoder with a prior may write a plain file)."""
    if data.startswith(RESIDUAL_MAGIC):
        return decode(data, source, prior)
    from mzc.formats import GRIDS
    from mzc.formats import read as read_grid

    return read_grid(data, source, GRIDS, path)


class PriorFiles:
    """The formats table's row of prior files (mzc.formats): read as their mean grid."""

    EXTENSIONS: tuple[str, ...] = ()
    write = None

    @staticmethod
    def sniff(data: bytes) -> bool:
        """True for a prior file's bytes."""
        return data.startswith(PRIOR_MAGIC)

    @staticmethod
    def read(data: bytes, source: str = "<bytes>") -> ZGrid:
        """The mean grid of a prior file."""
        return read_prior(data, source).mean


class ResidualFiles:
    """The formats table's row of residual files: read without their prior, one line naming it."""

    EXTENSIONS: tuple[str, ...] = ()
    write = None

    @staticmethod
    def sniff(data: bytes) -> bool:
        """True for a residual file's bytes."""
        return data.startswith(RESIDUAL_MAGIC)

    @staticmethod
    def read(data: bytes, source: str = "<bytes>") -> ZGrid:
        """Refused in one line naming the prior the file needs (decode it with ``decode``)."""
        return decode(data, source, None)
