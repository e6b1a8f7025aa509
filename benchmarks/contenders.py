"""The table of contenders of the rate-distortion benchmark: mzc's codecs and its peers.

A contender turns one input (the original mesh, mzc's 0.5 mm z-grid in its default
projection, or the planar thesis grid) into the bytes of a file, and those bytes back into
a triangle mesh in the input frame. Every setting of its ladder is one rate-distortion
point. Entries whose module or package is missing are left out and listed in ``missing``
with the reason, so the benchmark runs with whatever is installed. Ladders of error bounds
are in ``unit``s of the corpus item (1 mm for faces; a round fraction of the height range
for the DEMs).
"""

import importlib
import lzma
import struct
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mzc.grid import ZGrid
from mzc.ops.triangulation import grid_to_mesh
from mzc.projections import PROJECTIONS

BOUNDS = (0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0)   # absolute error bounds, in units
RMS_TARGETS = (0.01, 0.02, 0.03, 0.04, 0.06, 0.08, 0.11, 0.16, 0.23, 0.32, 0.64)   # dwt2d's --rmse targets
ZFP_TOLERANCES = (0.2, 0.5, 1.0, 2.0, 4.0)   # zfp's error stays far below its tolerance
DRACO_BITS = (6, 7, 8, 9, 10, 11, 12, 14)    # the 8..14, and 6, 7 to reach 0.2 mm
JPEG2K_PSNR_DB = (45, 50, 55, 58, 61, 64, 67, 70, 80, 90)
SPERR_PSNR_DB = (25, 30, 35, 38, 41, 44, 47, 50, 55, 60, 70, 80)   # lower than JPEG 2000's: on a face's filled
                                                            # grid SPERR overshoots (35 dB asked, 55 got)
HTJ2K_STEPS = BOUNDS + (8.0,)     # base quantisation steps in units (the RMS error is 5-20 times smaller)
HTJ2K_QSTEP_RANGE = (1e-5, 2.0)   # imagecodecs turns smaller steps into lossless; OpenJPH documents <= 2
THESIS_GRID = {"d1": 3.0, "d2": 0.25}         # the thesis's face grid (mm)
THESIS_DENSIFY = 3                            # rows inserted between its planes
GRID_HEADER = struct.Struct("<2I4d12dBd")     # rows cols d1 d2 u0 v0 transform[3x4] projection radius
QUANTISER = struct.Struct("<2d")              # z offset and step of a 16-bit image


class NotApplicable(ValueError):
    """A ladder setting the codec cannot take on this item (reported apart from failures)."""


@dataclass
class Contender:
    """One codec at one ladder of settings.

    ``source`` names the input it codes: "mesh", "grid" (mzc's 0.5 mm grid in its default
    projection: spherical for the faces) or "thesis" (planar, d1 = 3, d2 = 0.25 mm).
    ``encode(input, setting, unit) -> bytes`` and ``decode(bytes) -> (points, triangles)``;
    ``ladder`` runs from coarse to fine.
    """

    name: str
    family: str
    source: str
    knob: str
    ladder: tuple
    encode: Callable
    decode: Callable
    scaled: bool = False   # True when the ladder is in units (error bounds), not raw settings


# --------------------------------------------------------------------------- mzc


def mzc_contenders(missing, faces=True):
    """mzc's codecs: dwt2d (error-bounded 2D wavelets; max-error and RMS targets) and the thesis's row codecs.

    The row codecs run on the 0.5 mm grid and, for faces, as the thesis meant them: on
    its grid (3 mm planes, 0.25 mm along them) with n = 3 rows densified back in (see
    ``thesis_variants``). The lossless z-grid text format gives the gridding floor.
    """
    table = []
    dwt2d = load("mzc.codecs.dwt2d", missing, "mzc dwt2d")
    if dwt2d:
        table.append(Contender("mzc dwt2d", "mzc", "grid", "max_error", BOUNDS,
                               lambda g, s, u: dwt2d.write(g, max_error=s * u), grid_decoder(dwt2d), scaled=True))
        table.append(Contender("mzc dwt2d --rmse", "mzc", "grid", "rmse", RMS_TARGETS,
                               lambda g, s, u: dwt2d.write(g, rmse=s * u), grid_decoder(dwt2d), scaled=True))
    zgrid = load("mzc.formats.zgrid", missing, "mzc zgrid")
    if zgrid:
        table.append(Contender("mzc zgrid (lossless)", "mzc", "grid", "-", (None,),
                               lambda g, s, u: zgrid.write(g), grid_decoder(zgrid)))
    for kind, knob, ladder in [("dct", "quality", (10, 20, 50)), ("dft", "quality", (10, 20, 50)),
                               ("dwt", "quality", (10, 20, 50)), ("poly", "degree", (20, 40, 80))]:
        module = load(f"mzc.codecs.rows.{kind}", missing, f"mzc {kind}")
        if module:
            table.append(row_codec(module, kind, knob, ladder, "grid", grid_decoder(module)))
            if faces:
                table.extend(thesis_variants(module, kind, knob, ladder[:2], missing))
    return table


def row_codec(module, kind, knob, ladder, source, decoder, suffix=""):
    """A row codec (dct, dft, dwt, poly) at its quality (or degree) ladder."""
    return Contender(f"mzc {kind}{suffix}", "mzc", source, knob, ladder,
                     lambda g, s, u: module.write(g, **{knob: s}), decoder)


def thesis_variants(module, kind, knob, ladder, missing):
    """The row codec on the thesis grid, decoded then densified (n = 3): by every densify
    method for dct (the thesis's codec), by the default method for the others (to keep the
    full run within its time budget)."""
    densify = load("mzc.ops.densify", missing, "mzc densify (thesis-grid variants)")
    if not densify:
        return []
    methods = densify.METHODS if kind == "dct" else (densify.DEFAULT_METHOD,)
    return [row_codec(module, kind, knob, ladder, "thesis", grid_decoder(module, densify, method),
                      suffix=f" thesis+{method}") for method in methods]


def grid_decoder(module, densify=None, method=None):
    """bytes -> mesh through ``module.read`` (and densify n = 3 by ``method`` if given)."""
    def decode(data):
        grid = module.read(data, "<benchmark>")
        if densify:
            grid = densify.densify_grid(grid, THESIS_DENSIFY, method)
        return mesh_pair(grid)
    return decode


def mesh_pair(grid):
    """(points, triangles) of ``grid``'s derived mesh: the pair every contender decodes to."""
    mesh = grid_to_mesh(grid)
    return mesh.points, mesh.triangles


def load(name, missing, label):
    """Import ``name``; on failure record why under ``label`` and return None."""
    try:
        return importlib.import_module(name)
    except Exception as error:  # noqa: BLE001 - a half-written module must not stop the benchmark
        missing[label] = f"{type(error).__name__}: {error}"
        return None


# --------------------------------------------------------------------------- peers


def peer_contenders(missing):
    """Draco on the mesh, xz of the OBJ, and the scientific and image codecs on the grid."""
    table = [Contender("xz OBJ", "peer", "mesh", "decimals", (0, 1, 2), xz_obj_encode, xz_obj_decode)]
    draco = load("DracoPy", missing, "Draco (DracoPy)")
    if draco:
        table.append(draco_contender(draco))
    for label, package, build in [("SZ3", "pysz", sz3_contender), ("zfp", "zfpy", zfp_contender),
                                  ("LERC", "lerc", lerc_contender), ("SPERR", "imagecodecs", sperr_contenders),
                                  ("JPEG family", "imagecodecs", image_contenders)]:
        module = load(package, missing, f"{label} ({package})")
        if module:
            table.extend(build(module))
    return table


def draco_contender(draco, ladder=DRACO_BITS):
    """Draco on the original (points, triangles) at a ladder of position quantisation bits."""
    return Contender("Draco", "peer", "mesh", "bits", ladder, lambda mesh, q, u: draco_encode(draco, mesh, q),
                     lambda data: draco_decode(draco, data))


def draco_encode(draco, mesh, bits):
    """Draco at ``bits`` position quantisation, compression level 10 (the slowest, smallest); a
    mesh without triangles is coded as Draco's point cloud."""
    points, triangles = mesh
    faces = triangles.astype(np.uint32) if len(triangles) else None
    return bytes(draco.encode(points.astype(np.float32), faces, quantization_bits=bits, compression_level=10))


def draco_decode(draco, data):
    """(points, triangles) of Draco's bytes; no triangles, shape (0, 3), for a point cloud."""
    mesh = draco.decode(data)
    faces = getattr(mesh, "faces", None)
    triangles = np.asarray([] if faces is None else faces, dtype=np.int64).reshape(-1, 3)
    return np.asarray(mesh.points, dtype=float), triangles


def xz_obj_encode(mesh, decimals, unit):
    """The trivial baseline: the mesh as OBJ text with ``decimals`` decimals, xz -9e."""
    points, triangles = mesh
    lines = [f"v {x:.{decimals}f} {y:.{decimals}f} {z:.{decimals}f}" for x, y, z in points.tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (triangles + 1).tolist()]
    return lzma.compress(("\n".join(lines) + "\n").encode(), preset=9 | lzma.PRESET_EXTREME)


def xz_obj_decode(data):
    rows = [line.split() for line in lzma.decompress(data).decode().splitlines()]
    points = np.array([r[1:] for r in rows if r[0] == "v"], dtype=float)
    triangles = np.array([r[1:] for r in rows if r[0] == "f"], dtype=np.int64) - 1
    return points, triangles


# --- grid peers: a small container of grid header, validity mask and payload -------------


def grid_file(grid, payload, with_mask=True, extra=b""):
    """The stored file of a grid peer: geometry, extra fields, mask (mzc's coder) and payload.

    The geometry is everything ``grid_to_mesh`` needs to place the nodes: shape, spacings,
    origin, transform, and the projection (its index in ``PROJECTIONS``) with its radius
    (0 for planar grids), so a central grid decodes to the same central grid.
    """
    mask = mask_bytes(grid.valid) if with_mask else b""
    header = GRID_HEADER.pack(*grid.shape, grid.d1, grid.d2, *grid.origin, *grid.transform.ravel(),
                              PROJECTIONS.index(grid.projection), grid.radius or 0.0)
    return header + extra + struct.pack("<I", len(mask)) + mask + payload


def read_grid_file(data, extra_size=0):
    """(grid with NaN heights, extra bytes, validity mask or None, payload) of ``grid_file`` bytes."""
    fields = GRID_HEADER.unpack_from(data)
    rows, cols = fields[:2]
    at = GRID_HEADER.size
    extra = data[at:at + extra_size]
    at += extra_size
    (mask_size,) = struct.unpack_from("<I", data, at)
    at += 4
    valid = read_mask(data[at:at + mask_size], rows, cols) if mask_size else None
    grid = ZGrid(np.full((rows, cols), np.nan), fields[2], fields[3], origin=fields[4:6],
                 transform=np.array(fields[6:18]).reshape(3, 4), projection=PROJECTIONS[fields[18]],
                 radius=fields[19])
    return grid, extra, valid, data[at + mask_size:]


def mask_bytes(valid):
    """The validity mask coded exactly as mzc's dwt2d codes it (8.0's predicted flips through rANS,
    ``flips.alone``): a peer pays for its mask what mzc pays."""
    from mzc.codecs.dwt2d import flips

    return flips.alone(valid)


def read_mask(data, rows, cols):
    from mzc.codecs.dwt2d import flips
    from mzc.codecs.dwt2d.entropy import Decoder

    return flips.decode(Decoder(data, "<mask>"), rows, cols)


def filled(grid):
    """Heights with invalid nodes filled smoothly (the biharmonic fill mzc's own encoder codes), for
    codecs without a mask."""
    from mzc.codecs.dwt2d.wavelet import smooth_fill

    return smooth_fill(grid.z, grid.valid)


def masked_mesh(grid, z, valid):
    """The decoded mesh: heights ``z`` on the valid nodes."""
    return mesh_pair(grid.with_z(np.where(valid, z, np.nan)))


def sz3_contender(pysz):
    def encode(grid, bound, unit):
        config = pysz.szConfig()
        config.errorBoundMode = pysz.szErrorBoundMode.ABS
        config.absErrorBound = bound * unit
        payload, _ratio = pysz.sz.compress(np.ascontiguousarray(filled(grid)), config)
        return grid_file(grid, payload.tobytes())

    def decode(data):
        grid, _, valid, payload = read_grid_file(data)
        z, _config = pysz.sz.decompress(np.frombuffer(payload, dtype=np.uint8), np.float64, grid.shape)
        return masked_mesh(grid, z, valid)

    return [Contender("SZ3", "peer", "grid", "abs bound", BOUNDS, encode, decode, scaled=True)]


def zfp_contender(zfpy):
    def encode(grid, bound, unit):
        return grid_file(grid, zfpy.compress_numpy(np.ascontiguousarray(filled(grid)), tolerance=bound * unit))

    def decode(data):
        grid, _, valid, payload = read_grid_file(data)
        return masked_mesh(grid, zfpy.decompress_numpy(payload), valid)

    return [Contender("zfp", "peer", "grid", "tolerance", ZFP_TOLERANCES, encode, decode, scaled=True)]


def lerc_contender(lerc):
    """LERC with its own validity mask (coded inside its blob), so no mzc mask is added."""
    def encode(grid, bound, unit):
        z = np.where(grid.valid, grid.z, 0.0)
        code, size, blob = lerc.encode(z, 1, True, grid.valid, bound * unit, 1)
        if code:
            raise RuntimeError(f"lerc.encode failed with code {code}")
        return grid_file(grid, bytes(blob[:size]), with_mask=False)

    def decode(data):
        grid, _, _, payload = read_grid_file(data)
        code, z, valid = lerc.decode(payload)[:3]
        if code:
            raise RuntimeError(f"lerc.decode failed with code {code}")
        return masked_mesh(grid, z, np.ones(grid.shape, dtype=bool) if valid is None else valid)

    return [Contender("LERC", "peer", "grid", "max z error", BOUNDS, encode, decode, scaled=True)]


def sperr_contenders(imagecodecs):
    """SPERR (wavelets, SPECK coding and an outlier pass) on the filled float64 grid, mask as for SZ3.

    Two modes: its point-wise error bound at the absolute BOUNDS (as SZ3), and its PSNR
    target, its mode for an RMS target (SPERR has no RMS mode; the PSNR is over the filled
    grid's value range). SPERR's own 10-byte header (shape and type) is left out: the
    container carries the shape and the type is always float64.
    """
    if not imagecodecs.SPERR.available:
        return []

    def contender(name, knob, ladder, mode, level, scaled):
        def encode(grid, setting, unit):
            z = np.ascontiguousarray(filled(grid))
            return grid_file(grid, bytes(imagecodecs.sperr_encode(z, level(setting, unit), mode, header=False,
                                                                  numthreads=1)))

        def decode(data):
            grid, _, valid, payload = read_grid_file(data)
            z = imagecodecs.sperr_decode(payload, shape=grid.shape, dtype=np.float64, header=False, numthreads=1)
            return masked_mesh(grid, z, valid)

        return Contender(name, "peer", "grid", knob, ladder, encode, decode, scaled=scaled)

    return [contender("SPERR", "point-wise bound", BOUNDS, "pwe", lambda bound, unit: bound * unit, True),
            contender("SPERR psnr", "PSNR dB", SPERR_PSNR_DB, "psnr", lambda psnr, unit: psnr, False)]


# --- image codecs on the grid quantised to 16 bits ---------------------------------------


def quantise16(grid):
    """(uint16 image of the filled heights, offset, step): the full height range on 65535 steps."""
    z = filled(grid)
    low, high = float(z.min()), float(z.max())
    step = max(high - low, 1e-12) / 65535
    return np.round((z - low) / step).astype(np.uint16), low, step


def htj2k_qstep(base_step, step):
    """OpenJPH's base quantisation step, a fraction of the 16-bit range, for a step of
    ``base_step`` in height units on an image of quantum ``step``."""
    qstep = base_step / (65536 * step)
    if not HTJ2K_QSTEP_RANGE[0] <= qstep <= HTJ2K_QSTEP_RANGE[1]:
        raise NotApplicable(f"a step of {base_step:g} is {qstep:.3g} of the 16-bit range; HTJ2K takes "
                            f"{HTJ2K_QSTEP_RANGE[0]:g} to {HTJ2K_QSTEP_RANGE[1]:g}")
    return qstep


def jpegls_near(bound, step):
    """JPEG-LS's NEAR (in quanta) for an error bound; the standard allows at most 255."""
    near = int(bound / step)
    if near > 255:
        raise NotApplicable(f"a bound of {bound:g} is {near} quanta; JPEG-LS allows NEAR <= 255")
    return near


def image_contenders(imagecodecs):
    """JPEG 2000, HTJ2K, JPEG-LS and JPEG XL on the 16-bit grid, those imagecodecs was built with.

    JPEG 2000 (OpenJPEG, which only decodes the HT block coder) allocates its rate to a
    PSNR; HTJ2K (OpenJPH, irreversible 9/7) has no rate allocation, only a base
    quantisation step, so its ladder is that step in units.
    """
    def contender(name, knob, ladder, code, decode_image, scaled=False):
        def encode(grid, setting, unit):
            image, low, step = quantise16(grid)
            return grid_file(grid, code(image, setting, unit, step), extra=QUANTISER.pack(low, step))

        def decode(data):
            grid, extra, valid, payload = read_grid_file(data, QUANTISER.size)
            low, step = QUANTISER.unpack(extra)
            return masked_mesh(grid, low + step * decode_image(payload).astype(float), valid)

        return Contender(name, "peer", "grid", knob, ladder, encode, decode, scaled=scaled)

    table = []
    if imagecodecs.JPEGLS.available:
        table.append(contender("JPEG-LS", "near bound", (0,) + BOUNDS[1:],
                               lambda im, s, u, step: imagecodecs.jpegls_encode(im, level=jpegls_near(s * u, step)),
                               imagecodecs.jpegls_decode, scaled=True))
    if imagecodecs.JPEG2K.available:
        table.append(contender("JPEG 2000", "PSNR dB", JPEG2K_PSNR_DB,
                               lambda im, s, u, step: imagecodecs.jpeg2k_encode(im, level=s, codecformat="j2k",
                                                                                numthreads=1),
                               imagecodecs.jpeg2k_decode))
    if imagecodecs.HTJ2K.available:
        table.append(contender("HTJ2K", "base step", HTJ2K_STEPS,
                               lambda im, s, u, step: imagecodecs.htj2k_encode(im, level=htj2k_qstep(s * u, step),
                                                                               reversible=False),
                               imagecodecs.htj2k_decode, scaled=True))
    if imagecodecs.JPEGXL.available:
        table.append(contender("JPEG XL", "distance", (4.0, 1.0, 0.3, 0.1, 0.0),
                               lambda im, s, u, step: imagecodecs.jpegxl_encode(
                                   im, distance=s, lossless=s == 0, effort=7, numthreads=1),
                               imagecodecs.jpegxl_decode))
    return table


def all_contenders(faces=True):
    """(contenders, missing): the whole table, and what could not be loaded and why."""
    missing = {}
    return mzc_contenders(missing, faces) + peer_contenders(missing), missing
