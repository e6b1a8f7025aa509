"""What a grid's coordinate reference system says about its lengths, read from its WKT alone.

A grid read from a raster keeps the raster's CRS as one line of WKT (spec/zgrid.md, ``crs``).
Most of mzc needs one thing from it: whether x and y are lengths in the unit of the heights
(a projected CRS: metres east and north) or angles (a geographic CRS: longitude and latitude
in degrees, the heights in metres). That is read from the WKT's own keywords, so no CRS
library is loaded to encode, densify or triangulate a grid (only a cloud's EPSG code is
spelled out as WKT by one, ``grid_crs``).

A geographic grid is never measured as if degrees were metres. Its errors are vertical, in
the height unit (a DEM's accuracy is stated so: the rate control of ``--rmse`` and ``--size``
measures its heights alone, whose decoder needs no metric), and the operations that need
lengths across x, y and z measure it in metres through a local projection
(``metric_frame``): an equirectangular projection about the grid's centre on the
CRS's ellipsoid, x = (lon - lon0) N cos(lat0), y = (lat - lat0) M, with M and N the
ellipsoid's meridional and prime-vertical radii of curvature at lat0. It keeps the grid a
regular grid (each axis scales by one factor), so densify and triangulate run on the same
nodes; its scale along x is off by cos(lat)/cos(lat0) - 1 away from the centre row (0.9% at
0.5 degrees of latitude from it at 45 degrees north), and along y by the change of M (under
0.02% over a degree).
"""

import math
import re

from mzc.errors import MzcError

QUOTED = re.compile(r'"(?:[^"]|"")*"')
# The keywords that open a CRS in WKT 1 (OGC 01-009) and WKT 2 (ISO 19162), by what x and y are.
KINDS = {
    "geographic": ("GEOGCS", "GEOGCRS", "GEOGRAPHICCRS"),
    "projected": ("PROJCS", "PROJCRS", "PROJECTEDCRS"),
    "geodetic": ("GEODCRS", "GEODETICCRS", "GEOCCS"),   # WKT 2 geographic or geocentric: see crs_kind
    "engineering": ("LOCAL_CS", "ENGCRS", "ENGINEERINGCRS"),
}
FIRST_CRS = re.compile(r"\b(" + "|".join(k for kinds in KINDS.values() for k in kinds) + r")\s*\[", re.IGNORECASE)
ELLIPSOID = re.compile(r"\b(?:SPHEROID|ELLIPSOID)\s*\[\s*\"[^\"]*\"\s*,\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)",
                       re.IGNORECASE)
ANGLE_UNIT = re.compile(r"\bANGLEUNIT\s*\[\s*\"[^\"]*\"\s*,\s*([-+0-9.eE]+)", re.IGNORECASE)
WKT1_UNIT = re.compile(r"\bUNIT\s*\[\s*\"[^\"]*\"\s*,\s*([-+0-9.eE]+)", re.IGNORECASE)
WGS84 = (6378137.0, 298.257223563)   # when the WKT names no ellipsoid
# the CRS of a cloud recognised as longitude and latitude (mzc.ops.slicing.lonlat_lattice), as GDAL writes EPSG:4326
WGS84_WKT = ('GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],'
             'AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],'
             'UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AXIS["Latitude",NORTH],'
             'AXIS["Longitude",EAST],AUTHORITY["EPSG","4326"]]')


def crs_kind(wkt):
    """``geographic``, ``projected``, ``geocentric``, ``engineering`` or ``unknown``: the kind of
    the horizontal CRS of ``wkt`` (the first CRS it opens, so a compound CRS's horizontal part
    and a bound CRS's source). Quoted names are skipped, so a name cannot fool it."""
    found = FIRST_CRS.search(QUOTED.sub('""', wkt))
    if not found:
        return "unknown"
    keyword = found[1].upper()
    kind = next(name for name, keywords in KINDS.items() if keyword in keywords)
    if kind == "geodetic":   # WKT 2 names a geographic CRS GEODCRS too: its coordinate system says which
        rest = wkt[found.end():]
        return "geographic" if keyword != "GEOCCS" and re.search(r"\bCS\s*\[\s*ellipsoidal", rest, re.I) \
            else "geocentric"
    return kind


def grid_crs(crs):
    """The ``crs`` line of a planar grid sliced from a cloud with ``crs`` (``Mesh.crs``): WKT as it
    is; an ``EPSG:code`` (a LAS file's GeoTIFF keys) spelled out as WKT from GDAL's database
    through rasterio (the ``geo`` extra), or None with a warning that the CRS is not kept when
    rasterio is missing or does not know the code; None for no CRS."""
    if crs is None or crs_kind(crs) != "unknown":
        return crs
    if not re.fullmatch(r"EPSG:[0-9]+", crs):
        return None
    import warnings

    from mzc.errors import MzcWarning

    try:
        from rasterio.crs import CRS
        from rasterio.errors import CRSError
    except ImportError:
        warnings.warn(MzcWarning(f"the cloud's CRS ({crs}) is not kept in the grid: spelling it out as WKT needs "
                                 "rasterio (pip install 'mzc[geo]')"), stacklevel=2)
        return None
    try:
        return CRS.from_epsg(int(crs[5:])).to_wkt()
    except CRSError:
        warnings.warn(MzcWarning(f"the cloud's CRS ({crs}) is not kept in the grid: GDAL does not know the code"),
                      stacklevel=2)
        return None


def is_geographic(grid):
    """True when ``grid``'s x and y are longitude and latitude (its CRS is geographic)."""
    return grid.crs is not None and crs_kind(grid.crs) == "geographic"


def ellipsoid(wkt):
    """(semi-major axis, inverse flattening) of the WKT's ellipsoid, WGS 84's when it names none."""
    found = ELLIPSOID.search(wkt)
    if not found:
        return WGS84
    try:
        return float(found[1]), float(found[2])
    except ValueError:
        return WGS84


def radians_per_unit(wkt):
    """The angular unit of a geographic CRS's coordinates, in radians (a degree when the WKT
    names none)."""
    found = ANGLE_UNIT.search(wkt) or WKT1_UNIT.search(wkt)
    try:
        factor = float(found[1]) if found else math.pi / 180
    except ValueError:
        factor = math.pi / 180
    return factor if 0 < factor < 10 else math.pi / 180


def metres_per_unit(wkt, latitude):
    """(metres per unit of longitude, per unit of latitude) at ``latitude`` (in the CRS's unit),
    on the CRS's ellipsoid."""
    axis, inverse_flattening = ellipsoid(wkt)
    flattening = 1 / inverse_flattening if inverse_flattening > 0 else 0.0
    squared = flattening * (2 - flattening)
    unit = radians_per_unit(wkt)
    phi = latitude * unit
    from mzc import elementary

    sine = elementary.sin(phi)
    across = 1 - squared * sine * sine
    meridional = axis * (1 - squared) / (across * math.sqrt(across))
    prime_vertical = axis / math.sqrt(across)
    return prime_vertical * elementary.cos(phi) * unit, meridional * unit


def metric_frame(grid, centre=None):
    """``grid`` itself, or for a geographic grid the same nodes and values in metres of the local
    equirectangular projection about ``centre`` (longitude, latitude; by default the grid's own
    centre, ``centre_of``; module docstring), without its CRS, so that lengths mean one thing
    across x, y and z. Two grids compared are placed about one centre (``mzc.api.as_meshes``)."""
    if not is_geographic(grid):
        return grid
    import numpy as np

    from mzc.grid import IDENTITY_TRANSFORM

    if not np.array_equal(grid.transform, IDENTITY_TRANSFORM):
        raise MzcError("a geographic grid turned by a transform cannot be measured in metres", field="transform")
    centre = centre_of(grid) if centre is None else centre
    east, north = metres_per_unit(grid.crs, centre[1])
    origin = ((grid.origin[0] - centre[0]) * east, (grid.origin[1] - centre[1]) * north)
    return grid.with_z(grid.z, d1=grid.d1 * north, d2=grid.d2 * east, origin=origin, crs=None, raster=None)


def centre_of(grid):
    """(x, y) of the middle of ``grid``'s nodes: its longitude and latitude on a geographic grid."""
    rows, cols = grid.shape
    return grid.origin[0] + grid.d2 * (cols - 1) / 2, grid.origin[1] + grid.d1 * (rows - 1) / 2
