"""LAS and LAZ, the ASPRS formats of airborne and terrestrial LiDAR, read through laspy
(and lazrs for LAZ), the optional extra ``las`` (``pip install 'mzc[las]'``).

x, y and z are the stored integers with the header's scale and offset applied. Each
point's ASPRS classification (2 = ground, 6 = building, 9 = water, ...) goes with the
cloud, so ``mzc slice --classes 2`` keeps the ground alone (as PDAL's filters.range on
Classification does); the coordinate reference system the header names, if any, is kept
as ``Mesh.crs`` (a WKT string, or ``EPSG:code`` from GeoTIFF keys; a geographic CRS as WKT,
so that a cloud in longitude and latitude is gridded as terrain in degrees). Points are read in
chunks, so memory grows with the points the file really holds, whatever its header
declares: a file with fewer points than it declares is refused as truncated, and one with
fewer bytes than its declared variable-length records take is refused before laspy reads
it (laspy reads records past the end of the file: a 34 KB file declaring 4e9 of them took
68 s and 1.4 GB before it ran out of memory), and so is a LAZ file whose chunk table declares
more chunks than it has bytes (lazrs reserves room for them all first: 28 GB for an 18 KB
file, and the process aborted).
"""

import contextlib
import io
import os
import struct
import sys

import numpy as np

from mzc.colours import to_8_bits
from mzc.errors import MzcError, first_line
from mzc.meshes import Mesh

NAME = "las"
EXTENSIONS = (".las", ".laz")
write = None   # mzc reads LiDAR clouds; what it writes are meshes
CHUNK_POINTS = 1_000_000
GEO_KEYS_CRS = (3072, 2048)   # ProjectedCSTypeGeoKey, then GeographicTypeGeoKey
MODEL_TYPE_KEY, MODEL_GEOGRAPHIC = 1024, 2   # GTModelTypeGeoKey: 2 = longitude and latitude
MISSING_EXTRA = "reading LAS/LAZ needs laspy and lazrs: pip install 'mzc[las]'"
# the public header block's fields that place and count records: (struct format, offset)
HEADER_SIZE, VLR_COUNT, EVLR_START, EVLR_COUNT = ("<H", 94), ("<I", 100), ("<Q", 235), ("<I", 243)
POINTS_START, POINT_FORMAT = ("<I", 96), ("<B", 104)
COMPRESSED = 0xC0   # the bits LAZ sets in the point format of compressed points
PANIC_MODULE = "pyo3_runtime"   # where pyo3 makes PanicException, a BaseException no module exports
VLR_HEADER, EVLR_HEADER, EVLR_HEADER_SIZE = 54, 60, 375   # bytes of a record's header; LAS 1.4's header size


def read(data: bytes, source: str) -> Mesh:
    """The point cloud of LAS or LAZ ``data``, with its classes, CRS and, when its point format
    has them, RGB colours (``las_colours``; the other dimensions are the survey's, not the
    surface's)."""
    try:
        import laspy
    except ImportError:
        raise MzcError(MISSING_EXTRA, source=source) from None
    check_records(data, source)
    chunks: list = []
    declared = None
    try:
        with panics_unprinted(), laspy.open(io.BytesIO(data)) as reader:
            declared = int(reader.header.point_count)
            check_room(reader.header, len(data), declared, source)
            coloured = "red" in set(reader.header.point_format.dimension_names)
            for chunk in reader.chunk_iterator(min(CHUNK_POINTS, max(declared, 1))):
                if not len(chunk):
                    break
                chunks.append((np.column_stack([np.asarray(chunk.x), np.asarray(chunk.y), np.asarray(chunk.z)]),
                               np.asarray(chunk.classification, dtype=np.uint8),
                               np.column_stack([np.asarray(chunk[name]) for name in ("red", "green", "blue")])
                               if coloured else np.empty((len(chunk), 3), dtype=np.uint16)))
            crs, geographic = header_crs(reader.header)
    except MzcError:
        raise
    except BaseException as error:   # a PanicException is one: lazrs's Rust panics on damaged points
        if not isinstance(error, reading_errors()) and type(error).__module__ != PANIC_MODULE:
            raise
        held = sum(len(chunk[0]) for chunk in chunks)
        raise MzcError(las_problem(error, held, declared), source=source) from None
    held = sum(len(chunk[0]) for chunk in chunks)
    if held < declared:
        raise MzcError(f"truncated: the header declares {declared} points, the file holds {held}", source=source)
    if geographic:
        crs = geographic_wkt(crs)
    points = np.concatenate([chunk[0] for chunk in chunks] or [np.empty((0, 3))])
    classes = np.concatenate([chunk[1] for chunk in chunks] or [np.empty(0, dtype=np.uint8)])
    colors = las_colours(np.concatenate([chunk[2] for chunk in chunks])) if coloured and chunks else None
    return Mesh(points, classification=classes, crs=crs, colors=colors)


def las_colours(rgb):
    """(n, 3) uint8 colours of a LAS cloud's 16-bit ``red green blue`` (the specification's range
    0..65535, scaled: ``mzc.colours.to_8_bits``); a file whose values all lie within 0..255 was
    written with 8-bit colours in the 16-bit fields, as some writers do, and keeps them."""
    return to_8_bits(rgb, 8 if int(rgb.max(initial=0)) <= 255 else 16)


def geographic_wkt(crs):
    """The WKT of the geographic CRS a LAS header names (``header_crs``): its WKT record, or its
    EPSG code spelled out (``georef.grid_crs``), else WGS 84's, as a lon/lat export's (the keys
    say longitude and latitude, but name no datum mzc can spell). So the cloud is known to be in
    degrees and is sliced as terrain in them (``mzc.ops.slicing.lonlat_grid``)."""
    import warnings

    from mzc.errors import MzcWarning
    from mzc.georef import WGS84_WKT, crs_kind, grid_crs

    with warnings.catch_warnings():   # a code GDAL does not know is not dropped here: WGS 84 stands in
        warnings.simplefilter("ignore", MzcWarning)
        wkt = None if crs is None else grid_crs(crs)
    return wkt if wkt is not None and crs_kind(wkt) == "geographic" else WGS84_WKT


@contextlib.contextmanager
def panics_unprinted():
    """Standard error (file descriptor 2) to the null device inside: lazrs panics in Rust on
    some damaged compressed points (a capacity overflow), which Rust prints there, message and
    backtrace, before pyo3 raises it as a PanicException that ``read`` makes one MzcError."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def check_records(data, source):
    """Refuse a file too short for the variable-length records (and LAS 1.4's extended ones)
    its header declares, each at least its record header long, before laspy reads them."""
    if len(data) < VLR_COUNT[1] + 4:
        raise MzcError(f"not a LAS file: {len(data)} bytes, shorter than its public header block", source=source)
    header_size, vlrs = header_field(data, HEADER_SIZE), header_field(data, VLR_COUNT)
    if header_size + VLR_HEADER * vlrs > len(data):
        raise MzcError(f"truncated: the header declares {vlrs} variable length records, which take at least "
                       f"{VLR_HEADER * vlrs} bytes after its {header_size}, the file holds {len(data)}", source=source)
    if header_size >= EVLR_HEADER_SIZE and len(data) >= EVLR_HEADER_SIZE:
        start, evlrs = header_field(data, EVLR_START), header_field(data, EVLR_COUNT)
        if evlrs and start + EVLR_HEADER * evlrs > len(data):
            raise MzcError(f"truncated: the header declares {evlrs} extended variable length records from byte "
                           f"{start}, which take at least {EVLR_HEADER * evlrs} bytes, the file holds {len(data)}",
                           source=source)
    check_chunk_table(data, source)


def check_chunk_table(data, source):
    """Refuse a LAZ file whose chunk table (found through the 8 bytes where its points start)
    declares more chunks than the file has bytes: each takes at least one."""
    start = header_field(data, POINTS_START)
    if len(data) <= POINT_FORMAT[1] or not header_field(data, POINT_FORMAT) & COMPRESSED or start + 8 > len(data):
        return
    table = struct.unpack_from("<q", data, start)[0]
    if 0 <= table <= len(data) - 8:
        chunks = struct.unpack_from("<I", data, table + 4)[0]
        if chunks > len(data):
            raise MzcError(f"the LAZ chunk table declares {chunks} chunks, more than the file's {len(data)} bytes "
                           "hold", source=source)


def header_field(data, field):
    """The value of a field of the public header block, (struct format, offset)."""
    return struct.unpack_from(field[0], data, field[1])[0]


def check_room(header, size, declared, source):
    """Refuse an uncompressed file too short for the points its header declares, before they
    are read (LAZ is checked as it is decoded, a chunk at a time)."""
    if header.are_points_compressed:
        return
    end = size
    if getattr(header, "start_of_first_evlr", 0) and header.number_of_evlrs:
        end = min(end, int(header.start_of_first_evlr))
    held = max(end - int(header.offset_to_point_data), 0) // header.point_format.size
    if held < declared:
        raise MzcError(f"truncated: the header declares {declared} points of {header.point_format.size} bytes, "
                       f"the file holds {held}", source=source)


def reading_errors():
    """The exceptions laspy and lazrs raise on a damaged file."""
    import laspy

    errors = [laspy.errors.LaspyException, ValueError, EOFError, OverflowError, struct.error]
    try:
        import lazrs

        errors.append(lazrs.LazrsError)
    except ImportError:
        pass
    return tuple(errors)


def las_problem(error, held, declared):
    """One line for a laspy or lazrs error: a missing LAZ backend names the extra that brings
    it; a failure after some points (``held`` of ``declared``) is damaged or truncated data."""
    text = first_line(error)
    if "LazBackend" in text:
        return MISSING_EXTRA
    if declared is not None:
        return f"truncated or damaged point data after {held} of the {declared} points the header declares ({text})"
    return f"not a readable LAS/LAZ file: {text}"


def header_crs(header):
    """(the CRS a LAS header names, whether its x and y are longitude and latitude): its WKT VLR
    (geographic by its keywords, ``georef.crs_kind``), else the EPSG code of its GeoTIFF keys
    (geographic by the model type key, or a geographic code with no projected one), else None
    (also for a user-defined CRS, code 32767, which has no code to give)."""
    from laspy.vlrs.known import GeoKeyDirectoryVlr, WktCoordinateSystemVlr

    from mzc.georef import crs_kind

    records = list(header.vlrs) + list(getattr(header, "evlrs", None) or [])
    for record in records:
        if isinstance(record, WktCoordinateSystemVlr) and record.string.strip("\0 \n"):
            wkt = record.string.strip("\0 \n")
            return wkt, crs_kind(wkt) == "geographic"
    for record in records:
        if isinstance(record, GeoKeyDirectoryVlr):
            codes = {key.id: key.value_offset for key in record.geo_keys if key.tiff_tag_location == 0}
            code = next((codes[key] for key in GEO_KEYS_CRS if 0 < codes.get(key, 0) < 32767), None)
            geographic = codes.get(MODEL_TYPE_KEY) == MODEL_GEOGRAPHIC or (
                0 < codes.get(GEO_KEYS_CRS[1], 0) and not 0 < codes.get(GEO_KEYS_CRS[0], 0))
            if code is not None or geographic:
                return (None if code is None else f"EPSG:{code}"), geographic
    return None, False
