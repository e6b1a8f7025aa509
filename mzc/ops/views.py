"""Where to cut from: the projection, centre and axis of a slice, and the ``auto`` rule.

A z-grid represents the part of a surface that its node lines meet at a fair angle; a
face sliced with parallel planes keeps only the half that faces +z (48% of the area of
``f18`` has a normal within 60 degrees of +z), while rays from a centre behind it meet 97%
of it that well. ``auto`` measures exactly that: the share of the surface area whose
normal lies within 60 degrees of the node line through it, for the planar grid of the
slicing frame and for central projections around candidate centres and axes, and keeps
the best. The normals count with the orientation most of the area has along the lines,
so the inside of a fold, or the near side of a closed surface seen from outside, which
the outermost hit cannot see, does not count. Planar wins unless a central projection sees more than
PLANAR_MARGIN more of the area, so terrain stays on the thesis's planes.

The planar grid looks along an axis of the slicing frame (``--align``): its z, unless its
y or x sees VIEW_MARGIN more of the area (a part lying in the xz plane), from the side the
surface faces (the sign of its area-weighted normal, so a scan facing -z is seen from -z;
a cloud without normals in its file from the + side); ``--view`` sets it. Central
candidates, in the frame of that view (planar grids look along its z): centres
on the line from the centre of the bounding box backwards along -z, 0 to 2 half-diagonals
of the box behind it; the axis of a spherical grid is the frame's y (its score does not
depend on the axis: rays from one centre are the same rays), a cylinder's the frame's y,
x or z. Of the centre with the best share along the line and the farthest whose share is
within SHARE_SLACK of it, the one whose distances to the surface spread least is taken:
node spacing on the surface grows with the distance, so that grid samples the surface
most evenly (for a face, the farther centre: its rays are closer to parallel and hide
fewer folds; measured on the 13 faces at 0.5 mm, the same mean whole-surface floor on 9%
fewer nodes than the best share's centre; for a closed surface, the one inside). Azimuth
0 looks at the middle of the azimuths the surface covers; if no gap of FULL_TURN_GAP is
left between them the grid makes a full turn (periodic columns), and a spherical full
turn runs from pole to pole.
"""

from dataclasses import dataclass
from decimal import Decimal

import numpy as np

from mzc import elementary
from mzc.errors import MzcError
from mzc.projections import PLANAR_VIEWS, view_rotation
from mzc.vectors import dotted, inner, length, lengths, matrix_product, symmetric_eigen

FACING_COSINE = 0.5          # 60 degrees between the normal and the node line
PLANAR_MARGIN = 0.05         # a central projection must see 5% more of the area than planar
FULL_TURN_GAP = np.pi / 4    # azimuth gaps narrower than this do not stop a full turn
OFFSETS = (0.0, 0.25, 0.5, 1.0, 1.5, 2.0)   # candidate centres, in half-diagonals behind the box centre
REFINE_STEPS = 8             # golden-section and bisection steps of the offset search
SHARE_SLACK = 0.01           # the farthest centre within 1% of the best share: more even sampling
SCORE_TRIANGLES = 4096       # triangles scored (a seeded random sample of the mesh's)


@dataclass
class View:
    """How to slice: ``projection``, the grid frame (input = rotation @ p + shift; for central
    projections ``shift`` is the centre and rotation's second column the axis), the
    reference ``radius``, whether the columns make a ``full_turn``, and the share of the
    area its node lines meet within 60 degrees (``seen``; None when not scored)."""

    projection: str
    rotation: np.ndarray
    shift: np.ndarray
    radius: float | None = None
    full_turn: bool = False
    seen: float | None = None


VIEW_MARGIN = 0.05           # another axis must see 5% more of the area than the frame's z
SEEN_WARNING = 0.5           # say so when the grid sees less than half the area well
NEIGHBOURS = 10              # points whose spread gives a cloud point's normal


def choose_view(mesh, frame, projection="auto", center=None, axis=None, view="auto"):
    """The View of ``mesh`` (a Mesh) for ``projection`` (auto, planar, cylindrical, spherical).

    ``frame`` = (rotation, shift) of the slicing frame (``--align``); ``view`` (auto or one
    of PLANAR_VIEWS) the direction a planar grid looks along in it, and the one central
    centres are sought behind; ``center`` and ``axis`` (input-frame 3-vectors) fix those of
    a central projection, auto choosing the rest.
    """
    rotation, shift = frame
    if (center is not None or axis is not None) and projection == "planar":
        raise MzcError("--center and --axis need a central projection (cylindrical or spherical)",
                       field="projection")
    if center is not None:   # refused before any scoring divides by its distances
        from mzc.grid import finite

        center = finite(center, "center", 3)
    surface = Facets.of_mesh(mesh)
    rotation, planar_score = planar_view(surface, rotation, view)
    if projection == "planar" or (projection == "auto" and mesh.is_point_cloud):
        return View("planar", rotation, shift, seen=planar_score)
    if mesh.is_point_cloud:   # a cloud's central grid, about the middle of its box unless told
        low, high = mesh.points.min(axis=0), mesh.points.max(axis=0)
        return central_view(mesh.points, projection, (low + high) / 2 if center is None else center,
                            rotation[:, 1] if axis is None else axis, rotation[:, 2])
    kinds = ("cylindrical", "spherical") if projection == "auto" else (projection,)
    best = max((central_candidate(surface, kind, rotation, center, axis) for kind in kinds), key=lambda c: c[0])
    if projection == "auto" and planar_score >= best[0] - PLANAR_MARGIN:
        return View("planar", rotation, shift, seen=planar_score)
    score, kind, centre, direction = best
    if center is None:   # any centre near the best will do: one with short numbers keeps headers short
        centre = rounded(centre, surface.half_diagonal)
    chosen = central_view(mesh.points, kind, centre, direction, rotation[:, 2])
    chosen.seen = score
    return chosen


def planar_view(surface, rotation, view):
    """(rotation of the planar grid frame, its share) looking along ``view`` of the slicing
    frame ``rotation``; ``auto``: along the frame axis that sees most of the area (z unless
    another sees VIEW_MARGIN more), from the side the surface faces (``Facets.facing``)."""
    if view == "auto":
        shares = [surface.share_along(rotation[:, k]) for k in (2, 1, 0)]
        k = (2, 1, 0)[int(np.argmax(shares))] if max(shares) > shares[0] + VIEW_MARGIN else 2
        view = ("+" if surface.facing(rotation[:, k]) >= 0 else "-") + "xyz"[k]
    if view not in PLANAR_VIEWS:
        raise MzcError(f"unknown view {view!r} (choose auto or one of {', '.join(PLANAR_VIEWS)})", field="view")
    rotation = matrix_product(rotation, view_rotation(view))
    return rotation, surface.share_along(rotation[:, 2])


class Facets:
    """What scores a view: centroids, unit normals and areas of a sample of a surface's
    triangles (``of_mesh``), or of a point cloud's points, each with the normal its file
    gives or the spread of its neighbours (unoriented) shows and equal areas.
    ``oriented`` says whether the normals' signs mean anything."""

    def __init__(self, centroid, normal, area, points, oriented=True):
        self.centroid, self.normal, self.area, self.oriented = centroid, normal, area, oriented
        low, high = points.min(axis=0), points.max(axis=0)
        self.box_centre, self.half_diagonal = (low + high) / 2, length(high - low) / 2

    @classmethod
    def of_mesh(cls, mesh):
        """The Facets of a Mesh: a seeded sample of SCORE_TRIANGLES triangles (or points). A mesh
        none of whose (sampled) triangles has area (corners that coincide or lie on a line) has
        no surface to see, and is refused."""
        points = np.asarray(mesh.points, dtype=float)
        rng = np.random.default_rng(0)   # a seeded draw: a stride can follow the mesh's own order
        if mesh.is_point_cloud:
            return cls.of_cloud(points, mesh.normals, rng)
        triangles = np.asarray(mesh.triangles, dtype=np.int64)
        if len(triangles) > SCORE_TRIANGLES:
            triangles = triangles[rng.choice(len(triangles), SCORE_TRIANGLES, replace=False)]
        corners = points[triangles]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        doubled = lengths(normal)
        keep = doubled > 0
        if not keep.any():
            drawn = f" (of {len(triangles)} drawn at random)" if len(triangles) < len(mesh.triangles) else ""
            raise MzcError(f"the mesh has no area: the corners of each of its triangles{drawn} coincide or lie on "
                           "a line")
        return cls(corners[keep].mean(axis=1), normal[keep] / doubled[keep, None], doubled[keep], points)

    @classmethod
    def of_cloud(cls, points, normals, rng):
        """The Facets of a point cloud: SCORE_TRIANGLES of its points, equal areas, with the
        ``normals`` of its file (oriented) or those of their neighbourhoods (unoriented)."""
        count = min(SCORE_TRIANGLES, len(points))
        chosen = rng.choice(len(points), count, replace=False) if len(points) > count else np.arange(count)
        normal = normals[chosen] if normals is not None else cloud_normals(points, chosen)
        length = lengths(normal)
        keep = length > 0
        return cls(points[chosen][keep], normal[keep] / length[keep, None], np.ones(keep.sum()), points,
                   oriented=normals is not None)

    def facing(self, direction):
        """Which way along ``direction`` the surface faces: the sign of its area-weighted
        normal (its winding, or the normals a cloud's file gives); + when the normals are
        unoriented (a bare cloud: which side it was seen from is not in its points)."""
        return inner(self.area, dotted(self.normal, direction)) if self.oriented else 1.0

    def share(self, rays):
        """Area share of the facets whose normal is within 60 degrees of their (unit) ray.

        The normals' orientation is the one most of the area takes along the rays (a mesh
        may wind either way): a facet facing the other way is the inside of a fold or the
        near side of a closed surface seen from outside, hidden behind the outermost hit.
        """
        cosine = dotted(self.normal, rays)
        if not self.oriented:
            cosine = np.abs(cosine)
        cosine *= 1.0 if inner(self.area, cosine) >= 0 else -1.0
        total = self.area.sum()
        return float(self.area[cosine >= FACING_COSINE].sum() / total) if total > 0 else 0.0

    def share_along(self, view):
        """The share of a planar grid looking along ``view``."""
        return self.share(np.broadcast_to(view, self.normal.shape))

    def share_from(self, kind, centre, axis):
        """The share of a central grid of ``kind`` about ``centre`` (and ``axis``, for a cylinder)."""
        offset, length = self.rays_from(kind, centre, axis)
        return self.share(np.divide(offset, length[:, None], out=np.zeros_like(offset), where=length[:, None] > 0))

    def spread_from(self, kind, centre, axis):
        """How unevenly a central grid about ``centre`` samples the surface: the area-weighted
        coefficient of variation of the facets' distances from the centre (or axis), since a
        node's spacing on the surface grows with its distance."""
        _offset, length = self.rays_from(kind, centre, axis)
        mean = np.average(length, weights=self.area)
        return float(np.sqrt(np.average((length - mean) ** 2, weights=self.area)) / mean) if mean > 0 else np.inf

    def rays_from(self, kind, centre, axis):
        """(offsets of the facets from the centre, or from the axis for a cylinder; their lengths)."""
        offset = self.centroid - centre
        if kind == "cylindrical":
            offset = offset - dotted(offset, axis)[:, None] * axis
        return offset, lengths(offset)


def central_candidate(surface, kind, rotation, center, axis):
    """(score, kind, centre, axis) of the best central view of ``kind`` in the slicing frame ``rotation``."""
    view = rotation[:, 2]
    if axis is not None:
        axes = [unit(axis, "axis")]
    else:
        axes = [rotation[:, 1]] if kind == "spherical" else [rotation[:, 1], rotation[:, 0], view]
    best = None
    for direction in axes:
        candidate = axis_candidate(surface, kind, view, direction, center)
        if best is None or candidate[0] > best[0]:
            best = candidate
    return best


def axis_candidate(surface, kind, view, direction, center):
    """(score, kind, centre, axis) of the central view of ``kind`` about ``direction``: at ``center``
    when given, else at the best offset behind the surface's box centre along ``view``."""
    def score(centre):
        return surface.share_from(kind, centre, direction)

    def behind(s):
        return surface.box_centre - s * surface.half_diagonal * view

    if center is not None:
        centre = center
    else:
        along_axis = kind == "cylindrical" and abs(dotted(direction, view)) > 0.999
        centre = behind(0.0 if along_axis else best_offset(lambda s: score(behind(s)),
                                                           lambda s: surface.spread_from(kind, behind(s), direction)))
    return score(centre), kind, centre, direction


def best_offset(score, spread):
    """The centre offset (in half-diagonals behind the box centre): of the one with the highest
    score (the best of OFFSETS, refined by golden-section search between its neighbours) and
    the farthest whose score is within SHARE_SLACK of it (bisection beyond it), the one
    whose distances spread least."""
    scores = [score(s) for s in OFFSETS]
    k = int(np.argmax(scores))
    peak, top = golden_section(score, OFFSETS[max(k - 1, 0)], OFFSETS[min(k + 1, len(OFFSETS) - 1)])
    if scores[k] > top:
        peak, top = OFFSETS[k], scores[k]
    near, far = peak, OFFSETS[-1]
    if score(far) < top - SHARE_SLACK:
        for _ in range(REFINE_STEPS):
            middle = (near + far) / 2
            near, far = (middle, far) if score(middle) >= top - SHARE_SLACK else (near, middle)
        far = near
    return min((peak, far), key=spread)


def golden_section(score, low, high):
    """(argument, value) of the highest ``score`` between ``low`` and ``high`` (assumed unimodal)."""
    ratio = (np.sqrt(5) - 1) / 2
    left, right = high - ratio * (high - low), low + ratio * (high - low)
    score_left, score_right = score(left), score(right)
    for _ in range(REFINE_STEPS):
        if score_left >= score_right:
            high, right, score_right = right, left, score_left
            left = high - ratio * (high - low)
            score_left = score(left)
        else:
            low, left, score_left = left, right, score_right
            right = low + ratio * (high - low)
            score_right = score(right)
    return (left, score_left) if score_left >= score_right else (right, score_right)


def cloud_normals(points, chosen):
    """Unit normals (unoriented) of the ``chosen`` points of a cloud: the direction of least
    spread of each one's NEIGHBOURS nearest points."""
    from scipy.spatial import cKDTree

    count = min(NEIGHBOURS, len(points))
    _distance, neighbours = cKDTree(points).query(points[chosen], k=count)
    near = points[np.asarray(neighbours).reshape(len(chosen), count)]
    offsets = near - near.mean(axis=1, keepdims=True)
    _spread, axes = symmetric_eigen((offsets[:, :, :, None] * offsets[:, :, None, :]).sum(axis=1))
    return axes[:, :, 0]


def unit(vector, name):
    """``vector`` scaled to length 1, or an error naming the option."""
    vector = np.asarray(vector, dtype=float)
    size = length(vector)
    if vector.shape != (3,) or not np.isfinite(size) or size == 0:
        raise MzcError("must be a non-zero 3-vector", field=name)
    return vector / size


def central_view(points, kind, centre, axis, view):
    """The View of a central projection about ``centre`` and ``axis``, azimuth 0 towards the
    middle of the azimuths the surface covers (towards ``view`` for a full turn); ``centre`` is
    finite (``choose_view`` checked a given one)."""
    offset = np.asarray(points, dtype=float) - np.asarray(centre, dtype=float)
    axis = unit(axis, "axis")
    across = offset - dotted(offset, axis)[:, None] * axis
    reference = perpendicular(view, axis)
    side = np.cross(axis, reference)
    middle, full_turn = azimuth_middle(elementary.atan2(dotted(across, side), dotted(across, reference)))
    middle = np.radians(np.round(np.degrees(middle)))   # whole degrees: no turn at all when near the view
    front = reference if middle == 0 else elementary.cos(middle) * reference + elementary.sin(middle) * side
    rotation = np.column_stack([np.cross(axis, front), axis, front])
    distance = lengths(across if kind == "cylindrical" else offset).mean()
    radius = float(rounded(distance, distance)) if distance > 0 else 0.0
    if not radius > 0:
        raise MzcError("the surface has no extent around the centre", field="center")
    return View(kind, rotation, centre, radius, full_turn)


def rounded(values, scale, digits=4, down=False):
    """``values`` rounded (``down``: floored) to ``digits`` significant digits of ``scale`` (a
    length of the surface), each the float nearest its decimal, so that it is written short."""
    decimals = max(0, digits - 1 - Decimal(max(float(scale), 1e-300)).adjusted())   # adjusted: floor(log10)
    if down:
        values = np.floor(np.asarray(values, dtype=float) * 10.0 ** decimals) / 10.0 ** decimals
    return np.array([round(float(v), decimals) for v in np.ravel(values)]).reshape(np.shape(values))


def perpendicular(view, axis):
    """The unit component of ``view`` across ``axis`` (another axis of the frame when parallel)."""
    for candidate in (view, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])):
        across = candidate - dotted(candidate, axis) * axis
        if length(across) > 1e-6:
            return across / length(across)
    raise MzcError("cannot orient the axis", field="axis")


def azimuth_middle(azimuth):
    """(middle of the azimuths covered, whether they make a full turn): the middle is opposite
    the middle of the largest gap between neighbouring azimuths."""
    ordered = np.sort(azimuth)
    gaps = np.diff(np.concatenate([ordered, ordered[:1] + 2 * np.pi]))
    widest = int(np.argmax(gaps))
    if gaps[widest] < FULL_TURN_GAP:
        return 0.0, True
    gap_middle = ordered[widest] + gaps[widest] / 2
    return float(np.remainder(gap_middle, 2 * np.pi) - np.pi), False   # opposite the gap, in [-pi, pi)
